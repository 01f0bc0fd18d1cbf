#!/usr/bin/env python3
"""Render the springlab course experiments as one self-contained HTML page.

    python3 report/make_report.py --data DIR --out OUTDIR [--bench FILE.json]

Reads only the files `springlab experiment FILE.json --out DIR` writes (the
data contract is experiments/README.md): for each experiment `<name>.json`
(the settings used) and its tidy CSV tables, plus optionally springlab_bench's
Google Benchmark JSON (--bench FILE.json, or else benchmarks.json in DIR when it
is there). Writes one PNG per figure into OUTDIR and OUTDIR/index.html with
every figure embedded as a data URI, so the page alone is self-contained.

An experiment whose files are missing is skipped with a note in the page; a
malformed file stops the script with a message naming the file and line
(exit status 1). Without matplotlib/numpy the exit status is 2.

The output is deterministic: the same data gives byte-identical PNGs and HTML.
"""

import argparse
import base64
import csv
import html
import io
import json
import math
import os
import re
import sys
import traceback
from pathlib import Path

PROG = "make_report.py"


def _missing_module(module, exc):
    sys.stderr.write(
        "%s: error: cannot import %s (%s); install python3-matplotlib python3-numpy\n"
        % (PROG, module, exc))
    sys.exit(2)


try:
    import numpy as np
except Exception as _exc:  # noqa: BLE001 - any import failure means "not usable"
    _missing_module("numpy", _exc)
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import colors as mcolors
    from matplotlib import patheffects
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401 - registers the 3-D projection
    from mpl_toolkits.mplot3d.art3d import Line3DCollection
except Exception as _exc:  # noqa: BLE001
    _missing_module("matplotlib", _exc)


# --------------------------------------------------------------------------
# Errors

class DataError(Exception):
    """A malformed input file: message names the file and, if known, the line."""

    def __init__(self, path, line, message):
        where = str(path) if line is None else "%s:%d" % (path, line)
        super().__init__("%s: %s" % (where, message))


# --------------------------------------------------------------------------
# The data contract (experiments/README.md)

# Column kinds: "str" non-empty text, "int" integer, "float" number,
# "float?" number or empty (NaN), "int?" integer or empty, "bool" 0/1,
# "status" one of STATUSES.
STATUSES = ("completed", "diverged", "failed")

SCHEMAS = {
    "energy": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("dt", "float?"),
               ("t", "float"), ("kinetic", "float?"), ("spring", "float?"),
               ("gravity", "float?"), ("total", "float")],
    "energy-runs": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("dt", "float?"),
                    ("status", "status"), ("diverged_at", "float?"), ("steps", "int?"),
                    ("force_evals", "int?"), ("wall_seconds", "float?"),
                    ("energy_initial", "float?"), ("energy_final", "float?"),
                    ("energy_scale", "float?")],
    "stability": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("k", "float"),
                  ("w_max", "float?"), ("t_end", "float?"), ("max_stable_dt", "float?"),
                  ("bracket_lo", "float?"), ("bracket_hi", "float?"), ("theory_dt", "float?"),
                  ("ratio", "float?")],
    "stability-map": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("k", "float"),
                      ("dt", "float"), ("w_max", "float?"), ("energy_ratio", "float?"),
                      ("diverged", "bool")],
    "convergence": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("adaptive", "bool"),
                    ("parameter", "str"), ("value", "float"), ("error", "float?"),
                    ("steps", "int?"), ("force_evals", "int?"), ("wall_seconds", "float?"),
                    ("status", "status")],
    "convergence-orders": [("task", "int"), ("scene", "str"), ("integrator", "str"),
                           ("adaptive", "bool"), ("theoretical_order", "float?"),
                           ("fitted_order", "float?"), ("points", "int?")],
    "work-precision": [("task", "int"), ("scene", "str"), ("integrator", "str"),
                       ("adaptive", "bool"), ("parameter", "str"), ("value", "float"),
                       ("error", "float?"), ("wall_seconds", "float?"), ("force_evals", "int?"),
                       ("steps", "int?"), ("status", "status")],
    "damping-budget": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("dt", "float?"),
                       ("t", "float"), ("mechanical", "float"), ("work_nonconservative", "float"),
                       ("budget", "float?"), ("numerical", "float")],
    "cloth-showcase": [("task", "int"), ("scene", "str"), ("integrator", "str"), ("dt", "float?"),
                       ("t", "float"), ("i", "int"), ("x", "float"), ("y", "float"),
                       ("z", "float?")],
    "cloth-showcase-runs": [("task", "int"), ("scene", "str"), ("integrator", "str"),
                            ("dt", "float?"), ("status", "status"), ("diverged_at", "float?"),
                            ("steps", "int?"), ("wall_seconds", "float?")],
}

# Experiment kinds: table suffix -> schema; shipped names are the kind names.
KINDS = {
    "energy": {"": "energy", "-runs": "energy-runs"},
    "stability": {"": "stability", "-map": "stability-map"},
    "convergence": {"": "convergence", "-orders": "convergence-orders"},
    "work-precision": {"": "work-precision"},
    "damping-budget": {"": "damping-budget"},
    "cloth-showcase": {"": "cloth-showcase", "-runs": "cloth-showcase-runs"},
}
KIND_ORDER = list(KINDS)

# The course's order for legends; colours come from the sorted union of names.
KNOWN_ORDER = ["explicit-euler", "symplectic-euler", "verlet", "rk4", "implicit-euler",
               "linear-implicit-euler", "implicit-midpoint", "cvode-bdf", "cvode-adams", "ida",
               "arkode-erk", "arkode-dirk", "arkode-imex"]
ADAPTIVE_PREFIXES = ("cvode", "ida", "arkode")

MARKERS = ["o", "s", "^", "D", "v", "P", "X", "<", ">", "h", "p", "*", "d", "H", "8"]
ERROR_LABEL = "max |x − x_ref| at t_end [m]"
DPI = 100
SAVE_METADATA = {"Software": None}


# --------------------------------------------------------------------------
# Reading tables

def _parse_int(text):
    try:
        return int(text)
    except ValueError:
        value = float(text)  # accepts "1e3"; raises ValueError otherwise
        if not value.is_integer():
            raise ValueError(text) from None
        return int(value)


class Table:
    """A CSV table as columns: numpy float arrays for numbers, lists for text."""

    def __init__(self, path, columns, lines):
        self.path = path
        self.columns = columns
        self.lines = lines  # file line of each row, for messages
        self.n = len(lines)

    def __len__(self):
        return self.n

    def __getitem__(self, name):
        return self.columns[name]

    def has(self, name):
        return name in self.columns

    def groups(self, *names):
        """Row indices grouped by the values of the named columns, in order of
        first appearance (NaN becomes None so it can be a key)."""
        out = {}
        cols = [self.columns[n] for n in names]
        for r in range(self.n):
            key = tuple(_key(c[r]) for c in cols)
            out.setdefault(key, []).append(r)
        return {k: np.asarray(v, dtype=int) for k, v in out.items()}

    def row(self, r):
        return {name: (col[r] if isinstance(col, list) else float(col[r]))
                for name, col in self.columns.items()}


def _key(value):
    if isinstance(value, str):
        return value
    value = float(value)
    return None if math.isnan(value) else value


def read_table(path, schema_name):
    schema = SCHEMAS[schema_name]
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f, strict=True)
            try:
                header = next(reader)
            except StopIteration:
                raise DataError(path, 1, "file is empty (expected a header line)") from None
            header = [h.strip() for h in header]
            seen = set()
            for h in header:
                if h in seen:
                    raise DataError(path, 1, "column '%s' appears twice in the header" % h)
                seen.add(h)
            missing = [c for c, _ in schema if c not in seen]
            if missing:
                raise DataError(path, 1, "missing column%s %s (header is: %s; expected: %s)" % (
                    "s" if len(missing) > 1 else "", ", ".join("'%s'" % m for m in missing),
                    ",".join(header), ",".join(c for c, _ in schema)))
            index = {h: j for j, h in enumerate(header)}
            raw = {c: [] for c, _ in schema}
            lines = []
            for row in reader:
                line = reader.line_num
                if not row or (len(row) == 1 and not row[0].strip()):
                    continue  # blank line
                if len(row) != len(header):
                    raise DataError(path, line, "%d fields, but the header has %d columns" % (
                        len(row), len(header)))
                for c, kind in schema:
                    raw[c].append(_convert(path, line, c, kind, row[index[c]].strip()))
                lines.append(line)
    except OSError as exc:
        raise DataError(path, None, "cannot read (%s)" % exc.strerror) from None
    except UnicodeDecodeError:
        raise DataError(path, None, "not UTF-8 text") from None
    except csv.Error as exc:
        raise DataError(path, reader.line_num, "malformed CSV (%s)" % exc) from None
    columns = {}
    for c, kind in schema:
        if kind in ("str", "status"):
            columns[c] = raw[c]
        else:
            columns[c] = np.asarray(raw[c], dtype=float)
    return Table(path, columns, lines)


def _convert(path, line, column, kind, text):
    if kind == "str":
        if not text:
            raise DataError(path, line, "column '%s' is empty" % column)
        return text
    if kind == "status":
        if text not in STATUSES:
            raise DataError(path, line, "column '%s': '%s' is not one of %s" % (
                column, text, ", ".join(STATUSES)))
        return text
    if kind == "bool":
        if text in ("0", "false"):
            return 0.0
        if text in ("1", "true"):
            return 1.0
        raise DataError(path, line, "column '%s': '%s' is not 0 or 1" % (column, text))
    if text == "":
        if kind.endswith("?"):
            return math.nan
        raise DataError(path, line, "column '%s' is empty (a number is required)" % column)
    try:
        if kind.startswith("int"):
            return float(_parse_int(text))
        return float(text)
    except ValueError:
        raise DataError(path, line, "column '%s': '%s' is not %s" % (
            column, text, "an integer" if kind.startswith("int") else "a number")) from None


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as exc:
        raise DataError(path, None, "cannot read (%s)" % exc.strerror) from None
    except UnicodeDecodeError:
        raise DataError(path, None, "not UTF-8 text") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise DataError(path, exc.lineno, "malformed JSON: %s (column %d)" % (exc.msg, exc.colno)) \
            from None


# --------------------------------------------------------------------------
# Experiments found in the data directory

class Experiment:
    def __init__(self, kind, name, settings, settings_path):
        self.kind = kind
        self.name = name
        self.settings = settings          # dict or None
        self.settings_path = settings_path
        self.tables = {}                  # schema name -> Table
        self.notes = []                   # text notes about missing pieces

    def table(self, schema_name):
        return self.tables.get(schema_name)

    def title(self):
        s = self.settings or {}
        t = s.get("title") if isinstance(s.get("title"), str) else None
        return t or self.name

    def setting(self, *keys):
        """First value of any of the keys at the top level, then in the definition."""
        for where in (self.settings, (self.settings or {}).get("definition")):
            if isinstance(where, dict):
                for k in keys:
                    if k in where:
                        return where[k]
        return None


def experiment_kind(settings):
    for where in (settings, settings.get("definition") if isinstance(settings, dict) else None):
        if isinstance(where, dict) and isinstance(where.get("experiment"), str):
            return where["experiment"]
    return None


def load_data(data_dir):
    """All experiments in the directory (validated), plus page notes."""
    notes = []
    experiments = []
    claimed = set()
    json_files = sorted(p for p in data_dir.glob("*.json") if p.is_file())
    for p in json_files:
        settings = read_json(p)
        if is_bench_doc(settings):
            continue  # benchmarks.json: the step-cost section reads it
        kind = experiment_kind(settings) if isinstance(settings, dict) else None
        if kind is None and p.stem in KINDS:
            kind = p.stem
        if kind is None:
            notes.append("%s is not an experiment settings file (no \"experiment\" key): ignored."
                         % p.name)
            continue
        if kind not in KINDS:
            notes.append("%s: experiment kind '%s' is not known to this report: ignored."
                         % (p.name, kind))
            continue
        if not isinstance(settings, dict):
            raise DataError(p, None, "expected a JSON object")
        experiments.append(Experiment(kind, p.stem, settings, p))
        claimed.add(p.stem)
    for kind in KIND_ORDER:  # shipped names without a settings file
        if kind not in claimed and any((data_dir / (kind + sfx + ".csv")).is_file()
                                       for sfx in KINDS[kind]):
            e = Experiment(kind, kind, None, None)
            e.notes.append("%s.json (the settings used) is missing: scenes and settings are not "
                           "shown." % kind)
            experiments.append(e)
    for e in experiments:
        for sfx, schema in KINDS[e.kind].items():
            p = data_dir / (e.name + sfx + ".csv")
            if p.is_file():
                t = read_table(p, schema)
                if len(t) == 0:
                    e.notes.append("%s has a header but no rows." % p.name)
                else:
                    e.tables[schema] = t
            else:
                shards = sorted(data_dir.glob(e.name + sfx + ".shard-*-of-*.csv"))
                if shards:
                    e.notes.append("%s is missing, but %d shard file(s) are there: merge them "
                                   "with `springlab experiment ... --merge N`." % (p.name, len(shards)))
                else:
                    e.notes.append("%s is missing." % p.name)
    experiments.sort(key=lambda e: (KIND_ORDER.index(e.kind), e.name))
    return experiments, notes


# --------------------------------------------------------------------------
# Integrator colours and line styles

def _palette():
    """tab10, then hues that stay apart from it (black, magenta, navy, ...), then
    tab20b/tab20c tones: 16 clearly different colours before any repeats."""
    tab10 = list(plt.get_cmap("tab10").colors)
    tab20b = list(plt.get_cmap("tab20b").colors)
    tab20c = list(plt.get_cmap("tab20c").colors)
    extra = ["#000000", "#e6007e", "#00008b", "#7cb518", "#8b0000", "#00a6a6"]
    more = [tab20b[i] for i in (0, 4, 8, 12, 16)] + [tab20c[i] for i in (0, 4, 8, 12)]
    return [mcolors.to_hex(c) for c in tab10 + extra + more]


class Styles:
    def __init__(self, names, adaptive_flags):
        palette = _palette()
        self.names = sorted(names)
        self.colors = {n: palette[i % len(palette)] for i, n in enumerate(self.names)}
        self.adaptive_flags = adaptive_flags

    def color(self, name):
        return self.colors.get(name, "#000000")

    def adaptive(self, name):
        if name in self.adaptive_flags:
            return self.adaptive_flags[name]
        return name.startswith(ADAPTIVE_PREFIXES)

    def marker(self, name):
        return MARKERS[self.names.index(name) % len(MARKERS)] if name in self.names else "o"

    def linestyle(self, name):
        return "--" if self.adaptive(name) else "-"

    def order(self, names):
        """Fixed-step methods first, each group in the course's order."""
        def key(n):
            known = KNOWN_ORDER.index(n) if n in KNOWN_ORDER else len(KNOWN_ORDER)
            return (self.adaptive(n), known, n)
        return sorted(set(names), key=key)


def collect_styles(experiments, bench):
    names = set()
    adaptive = {}
    for e in experiments:
        for t in e.tables.values():
            names.update(t["integrator"])
            if t.has("adaptive"):
                for n, a in zip(t["integrator"], t["adaptive"]):
                    adaptive[n] = bool(a)
    if bench:
        for b in bench["entries"]:
            names.add(b["integrator"])
            adaptive.setdefault(b["integrator"], b["kind"] == "adaptive")
    return Styles(names, adaptive)


# --------------------------------------------------------------------------
# Small helpers

def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return "%.*g" % (digits, x)


def esc(text):
    return html.escape(str(text), quote=True)


def finite(x):
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x)


def log_edges(values):
    """Cell edges on a log axis around sorted positive values."""
    v = np.log10(np.asarray(values, dtype=float))
    if len(v) == 1:
        e = np.array([v[0] - 0.15, v[0] + 0.15])
    else:
        mid = (v[1:] + v[:-1]) / 2
        e = np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])
    return 10.0 ** e


def find_key(obj, keys, skip=("definition", "particles", "springs")):
    """Depth-first search for the first of the keys in nested dicts/lists."""
    if isinstance(obj, dict):
        for k in keys:
            if k in obj:
                return obj[k]
        for k, v in obj.items():
            if k in skip:
                continue
            found = find_key(v, keys, skip)
            if found is not None:
                return found
    elif isinstance(obj, list):
        for v in obj:
            found = find_key(v, keys, skip)
            if found is not None:
                return found
    return None


def find_scenes(obj, path="", ctx=None):
    """Every scene-file-like object (one with a "particles" list) in the
    settings, outside the copied definition: (where, scene, numbers beside it)."""
    if isinstance(obj, dict):
        if isinstance(obj.get("particles"), list):
            return [(path or "scene", obj, ctx or {})]
        out = []
        for k, v in obj.items():
            if k == "definition":
                continue
            sub = None
            if isinstance(v, dict) and isinstance(v.get("particles"), list):
                sub = {kk: vv for kk, vv in obj.items() if kk != k and kk not in
                       ("name", "experiment", "title", "description") and
                       (isinstance(vv, (int, float)) and not isinstance(vv, bool) or
                        isinstance(vv, str) and len(vv) <= 40)}
            out.extend(find_scenes(v, "%s.%s" % (path, k) if path else k, sub))
        return out
    if isinstance(obj, list):
        out = []
        for j, v in enumerate(obj):
            out.extend(find_scenes(v, "%s[%d]" % (path, j)))
        return out
    return []


def compact_json(obj, indent=0):
    """Pretty JSON that keeps short arrays/objects (particles, springs) on one line."""
    flat = json.dumps(obj, separators=(", ", ": "))
    if len(flat) <= 100 or not isinstance(obj, (dict, list)):
        return flat
    pad = "  " * (indent + 1)
    if isinstance(obj, dict):
        items = ["%s%s: %s" % (pad, json.dumps(k), compact_json(v, indent + 1))
                 for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + "  " * indent + "}"
    items = [pad + compact_json(v, indent + 1) for v in obj]
    return "[\n" + ",\n".join(items) + "\n" + "  " * indent + "]"


class Figures:
    """Saves figures as PNG into the output directory (deterministically)."""

    def __init__(self, outdir):
        self.outdir = outdir
        self.saved = []  # (filename, png bytes)

    def save(self, fig, filename):
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=DPI, metadata=SAVE_METADATA, bbox_inches="tight",
                    pad_inches=0.12)
        plt.close(fig)
        data = buf.getvalue()
        (self.outdir / filename).write_bytes(data)
        self.saved.append((filename, data))
        return filename, data


def figure_html(saved, alt, caption):
    filename, data = saved
    uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    return ('<figure><img src="%s" alt="%s"><figcaption>%s <a href="%s">(%s)</a></figcaption>'
            '</figure>\n' % (uri, esc(alt), caption, esc(filename), esc(filename)))


def note_html(text, cls="report-note"):
    return '<p class="%s">%s</p>\n' % (cls, text)


def swatch(styles, name):
    return '<span class="sw" style="background:%s"></span>%s' % (styles.color(name), esc(name))


def outside_legend(ax, extra=(), **kw):
    handles, labels = ax.get_legend_handles_labels()
    for h, label in extra:
        handles.append(h)
        labels.append(label)
    if handles:
        opts = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False,
                    borderaxespad=0.0, handlelength=2.6)
        opts.update(kw)
        ax.legend(handles, labels, **opts)


def symlog_ticks(ax, linthresh, per_side=6):
    """Readable ticks on a symlog y axis: at most per_side labelled decades on
    each side of zero (every decade still gets a minor tick)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter
    lo, hi = ax.get_ylim()
    e0 = int(round(math.log10(linthresh)))
    major, minor = [0.0], []
    for sign, end in ((1, hi), (-1, -lo)):
        if end <= linthresh:
            continue
        top = int(math.floor(math.log10(end)))
        step = max(1, int(math.ceil((top - e0 + 1) / per_side)))
        exps = [e for e in range(top, e0 - 1, -step) if e != e0] or [e0]
        major += [sign * 10.0 ** e for e in exps]
        minor += [sign * 10.0 ** e for e in range(e0, top + 1) if e not in exps]

    def label(v, _pos):
        if v == 0:
            return "0"
        return "$%s10^{%d}$" % ("-" if v < 0 else "", int(round(math.log10(abs(v)))))
    ax.yaxis.set_major_locator(FixedLocator(sorted(major)))
    ax.yaxis.set_minor_locator(FixedLocator(sorted(minor)))
    ax.yaxis.set_major_formatter(FuncFormatter(label))
    ax.set_ylim(lo, hi)


def log_log(ax, empty_text="no points to draw (none finite and positive)"):
    """Log scales on both axes when the panel has something to show; otherwise
    a message instead of an empty (or unscalable) panel."""
    if any(len(line.get_xdata()) for line in ax.lines):
        ax.set_xscale("log")
        ax.set_yscale("log")
        return True
    ax.set_xticks([])
    ax.set_yticks([])
    ax.text(0.5, 0.5, empty_text, transform=ax.transAxes, ha="center", va="center", color="0.4")
    return False


def new_figure(width, height):
    return plt.figure(figsize=(width, height), layout="constrained")


# --------------------------------------------------------------------------
# Colour key

def colour_key(styles, figs):
    names = styles.order(styles.names)
    if not names:
        return ""
    ncol = 4
    rows = (len(names) + ncol - 1) // ncol
    fig = plt.figure(figsize=(12, 0.42 * rows + 0.5))
    handles = [Line2D([], [], color=styles.color(n), ls=styles.linestyle(n), lw=2.5,
                      marker=styles.marker(n), ms=8, mfc="none", mew=1.5) for n in names]
    labels = ["%s  (%s)" % (n, "adaptive" if styles.adaptive(n) else "fixed step") for n in names]
    fig.legend(handles, labels, loc="center", ncol=ncol, frameon=False, fontsize=10,
               handlelength=3.5, columnspacing=2.5)
    saved = figs.save(fig, "colour-key.png")
    return ('<section id="colours"><h2>Integrators and their colours</h2>\n'
            + figure_html(saved, "colour key",
                          "Every figure uses these colours (and, where points are drawn, these "
                          "markers); fixed-step methods are drawn solid, adaptive ones dashed.")
            + "</section>\n")


def case_panels(table):
    """Panels of a per-case table (energy, damping budget): rows grouped by
    task and integrator; the k-th run of an integrator on the same (scene, dt)
    belongs to the k-th case with that scene and dt (two cases may share a
    scene's name). Returns {(scene, dt, case number): {integrator: rows}}."""
    seen = {}
    panels = {}
    for (task, integ), idx in table.groups("task", "integrator").items():
        base = (table["scene"][idx[0]], _key(table["dt"][idx[0]]))
        k = seen.get((base, integ), 0)
        seen[(base, integ)] = k + 1
        panels.setdefault(base + (k,), {})[integ] = idx
    return panels


def panel_title(scene, dt, case, panels):
    title = scene
    if any(key[:2] == (scene, dt) and key[2] > 0 for key in panels):
        title += " (case %d)" % (case + 1)
    if dt is not None:
        title += "   (dt = %s s)" % fmt(dt, 6)
    return title


# --------------------------------------------------------------------------
# 1. energy

def energy_figure(exp, styles, figs):
    e = exp.table("energy")
    runs = exp.table("energy-runs")
    parts = []
    run_by = {}
    if runs is not None:
        for r in range(len(runs)):
            run_by[(int(runs["task"][r]), runs["integrator"][r])] = runs.row(r)
    else:
        parts.append(note_html("Without %s-runs.csv, E(0) is each run's first row, E_s = |E(0)|, "
                               "and a run that ends early is marked as stopped." % esc(exp.name)))
    panels = case_panels(e)
    linthresh = 1e-6
    fig = new_figure(12.5, 4.3 * len(panels))
    axes = fig.subplots(len(panels), 1, squeeze=False)[:, 0]
    fallback_scale = []
    for ax, ((scene, dt, case), series) in zip(axes, panels.items()):
        t_max = max(float(e["t"][idx][-1]) for idx in series.values())
        for integ in styles.order(series):
            idx = series[integ]
            t = e["t"][idx]
            total = e["total"][idx]
            run = run_by.get((int(e["task"][idx[0]]), integ), {})
            e0 = run.get("energy_initial", math.nan)
            if not finite(e0):
                e0 = float(total[0])
            es = run.get("energy_scale", math.nan)
            if not (finite(es) and es > 0):
                es = abs(e0) if e0 != 0 else 1.0
                fallback_scale.append("%s/%s" % (scene, integ))
            y = (total - e0) / es
            status = run.get("status", "completed")
            at = run.get("diverged_at", math.nan)
            label = integ
            stopped = None
            if status != "completed":
                stopped = at if finite(at) else float(t[-1])
                label += "  ✕ %s at t = %s s" % (status, fmt(stopped, 4))
            elif not run and t[-1] < t_max * (1 - 1e-9):
                stopped = float(t[-1])
                label += "  ✕ stops at t = %s s" % fmt(stopped, 4)
            ax.plot(t, y, color=styles.color(integ), ls=styles.linestyle(integ), lw=1.5,
                    label=label)
            if stopped is not None and len(y):
                ax.plot([stopped], [y[-1]], marker="x", ms=11, mew=2.5, color=styles.color(integ),
                        ls="none", zorder=5)
        ax.set_yscale("symlog", linthresh=linthresh, linscale=0.6)
        ax.axhspan(-linthresh, linthresh, color="0.9", zorder=0, lw=0)
        ax.axhline(0.0, color="0.45", lw=0.7, zorder=1)
        ax.set_xlim(0, t_max)
        symlog_ticks(ax, linthresh, per_side=8)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("(E(t) − E(0)) / E_s   [1]")
        ax.set_title(panel_title(scene, dt, case, panels), loc="left", fontweight="bold")
        ax.grid(True, which="major", alpha=0.3)
        outside_legend(ax, extra=[(Patch(facecolor="0.9", edgecolor="0.75"),
                                   "|ΔE|/E_s < %g: linear scale" % linthresh)])
    saved = figs.save(fig, exp.name + ".png")
    caption = ("Relative change of the mechanical energy E = kinetic + spring + gravity, divided "
               "by the scene's energy scale E_s (energy-runs.csv: energy_scale), on a symmetric "
               "log axis: growth goes up, loss goes down, anything within ±%g of E_s sits in the "
               "grey linear band. ✕ marks where a run diverged or failed (its rows stop at the "
               "last good state)." % linthresh)
    if fallback_scale:
        caption += (" No usable energy_scale for %s: |E(0)| was used instead."
                    % ", ".join(sorted(set(fallback_scale))))
    parts.insert(0, figure_html(saved, "energy over time", esc(caption)))
    if runs is not None:
        parts.append(runs_table(runs, styles, "Runs",
                                [("status", "status", None), ("diverged_at", "diverged at [s]", 4),
                                 ("steps", "steps", 10), ("force_evals", "force evals", 10),
                                 ("wall_seconds", "wall [s]", 3),
                                 ("energy_initial", "E(0) [J]", 5),
                                 ("energy_final", "E(end) [J]", 5),
                                 ("energy_scale", "E_s [J]", 4)]))
    return "".join(parts)


def runs_table(runs, styles, heading, cols):
    out = ['<details><summary>%s (%d)</summary>\n<table><tr><th>scene</th><th>integrator</th>'
           '<th>dt [s]</th>' % (esc(heading), len(runs))]
    out += ["<th>%s</th>" % esc(label) for _, label, _ in cols]
    out.append("</tr>\n")
    for r in range(len(runs)):
        row = runs.row(r)
        bad = row.get("status", "completed") != "completed"
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td>' % (
            ' class="off"' if bad else "", esc(row["scene"]), swatch(styles, row["integrator"]),
            fmt(row.get("dt"), 6)))
        for c, _, digits in cols:
            v = row.get(c)
            out.append("<td>%s</td>" % (esc(v) if digits is None else fmt(v, digits)))
        out.append("</tr>\n")
    out.append("</table></details>\n")
    return "".join(out)


# --------------------------------------------------------------------------
# 2. stability: limit against stiffness, and the map

def stability_dt_max(exp):
    v = find_key(exp.settings, ("dt_max", "dt-max")) if exp.settings else None
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def searched_to_max(st, dt_max):
    """Rows where no tested step diverged: max_stable_dt is the searched dt_max
    (the bracket collapsed onto it, or it reaches the dt_max of the settings)."""
    out = np.zeros(len(st), dtype=bool)
    for r in range(len(st)):
        m, lo, hi = st["max_stable_dt"][r], st["bracket_lo"][r], st["bracket_hi"][r]
        if not finite(m):
            continue
        collapsed = finite(lo) and finite(hi) and lo == hi == m
        out[r] = collapsed or (finite(m) and not finite(hi)) or \
            (dt_max is not None and m >= dt_max * (1 - 1e-9))
    return out


def no_limit_rows(st, dt_max):
    """Rows of methods without a limit: no theory, and nothing diverged."""
    return searched_to_max(st, dt_max) & np.isnan(st["theory_dt"])


def stability_figure(exp, styles, figs):
    st = exp.table("stability")
    dt_max = stability_dt_max(exp)
    nolimit = no_limit_rows(st, dt_max)
    scenes = st.groups("scene")
    fig = new_figure(12.5, 4.6 * len(scenes))
    axes = fig.subplots(len(scenes), 1, squeeze=False)[:, 0]
    for ax, ((scene,), idx) in zip(axes, scenes.items()):
        by_int = {}
        for r in idx:
            by_int.setdefault(st["integrator"][r], []).append(r)
        free = []
        for integ in styles.order(by_int):
            rows = np.asarray(by_int[integ])
            lim = rows[~nolimit[rows]]
            if len(lim) == 0:
                free.append(integ)
                continue
            lim = lim[np.argsort(st["k"][lim], kind="stable")]
            k = st["k"][lim]
            m = st["max_stable_dt"][lim]
            th = st["theory_dt"][lim]
            c = styles.color(integ)
            ok = np.isfinite(m) & (m > 0)
            okt = np.isfinite(th) & (th > 0)
            marker = styles.marker(integ)
            ax.plot(k[ok], m[ok], marker=marker, ms=9, mfc="none", mew=1.8, color=c, ls="none",
                    label=integ + ("" if okt.any() else "  (no theory)"), zorder=3)
            if okt.any():
                ax.plot(k[okt], th[okt], color=c, ls="--", lw=1.4, alpha=0.9, zorder=2,
                        marker="_" if okt.sum() == 1 else None, ms=16, mew=1.5)
            if (~nolimit[rows]).sum() < len(rows):
                ks = ", ".join(fmt(x) for x in st["k"][rows[nolimit[rows]]])
                free.append("%s (only at k = %s)" % (integ, ks))
        log_log(ax, "no integrator with a step limit on this scene")
        ax.set_xlabel("spring stiffness k [N/m]")
        ax.set_ylabel("largest stable step dt [s]")
        ax.set_title(scene, loc="left", fontweight="bold")
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", alpha=0.1)
        handles, labels = ax.get_legend_handles_labels()
        handles += [Line2D([], [], color="0.2", marker="o", mfc="none", ls="none"),
                    Line2D([], [], color="0.2", ls="--")]
        labels += ["measured (bisection)", "theory from w_max"]
        ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
                  frameon=False, borderaxespad=0.0, handlelength=2.6)
        if free:
            top = ("dt_max = %s s" % fmt(dt_max)) if dt_max else "the largest step searched"
            ax.text(1.01, 0.0, "No divergence up to\n%s:\n" % top
                    + "\n".join("  " + f for f in free),
                    transform=ax.transAxes, fontsize=8, va="bottom", ha="left")
    saved = figs.save(fig, exp.name + ".png")
    return figure_html(saved, "stability limit against stiffness", esc(
        "Largest stable step found by bisection (hollow markers) against the theoretical limit "
        "from the largest eigenfrequency w_max of the initial state (dashed, same colour). "
        "Methods that never diverged up to the largest step searched are listed beside the "
        "panel instead of being drawn."))


def stability_table(exp, styles):
    st = exp.table("stability")
    reached = searched_to_max(st, stability_dt_max(exp))
    out = ['<table><tr><th>scene</th><th>integrator</th><th>k [N/m]</th><th>w_max [rad/s]</th>'
           '<th>max stable dt [s]</th><th>theory dt [s]</th><th>ratio</th></tr>\n']
    scene_pos = {key[0]: j for j, key in enumerate(st.groups("scene"))}
    integ_pos = {n: j for j, n in enumerate(styles.order(set(st["integrator"])))}
    order = sorted(range(len(st)), key=lambda r: (
        scene_pos[st["scene"][r]], integ_pos[st["integrator"][r]], st["k"][r]))
    nbad = 0
    for r in order:
        row = st.row(r)
        ratio = row["ratio"]
        if not finite(ratio) and finite(row["theory_dt"]) and finite(row["max_stable_dt"]) \
                and row["theory_dt"] > 0:
            ratio = row["max_stable_dt"] / row["theory_dt"]
        bad = finite(row["theory_dt"]) and (not finite(ratio) or not 0.97 <= ratio <= 1.03)
        nbad += bad
        msd = fmt(row["max_stable_dt"], 4)
        if reached[r]:
            msd = "≥ %s (none diverged)" % msd
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>'
                   '<td>%s</td></tr>\n' % (
                       ' class="off"' if bad else "", esc(row["scene"]),
                       swatch(styles, row["integrator"]), fmt(row["k"], 6), fmt(row["w_max"], 4),
                       msd, fmt(row["theory_dt"], 4) if finite(row["theory_dt"]) else "– (none)",
                       fmt(ratio, 4) if finite(row["theory_dt"]) else "–"))
    out.append("</table>\n")
    head = ("<p>Measured against theoretical stability limit. Highlighted: a theoretical limit "
            "exists and the ratio measured / theory lies outside [0.97, 1.03] (%d row%s).</p>\n"
            % (nbad, "" if nbad == 1 else "s"))
    return head + "".join(out)


DIVERGED_COLOR, DIVERGED_HATCH, NONPOS_COLOR = "#2b2b2b", "#9a9a9a", "#c8c8c8"


def _cells(xe, ye, mask, **kw):
    """Rectangles of the grid cells where mask is set (rows: y, columns: x)."""
    from matplotlib.collections import PolyCollection
    verts = []
    for a, b in zip(*np.nonzero(mask)):
        x0, x1, y0, y1 = xe[b], xe[b + 1], ye[a], ye[a + 1]
        verts.append([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
    return PolyCollection(verts, linewidths=0.0, zorder=1.5, **kw)


def stability_map_figure(exp, styles, figs):
    sm = exp.table("stability-map")
    panels = []
    for (scene,), sidx in sm.groups("scene").items():
        by_int = {}
        for r in sidx:
            by_int.setdefault(sm["integrator"][r], []).append(r)
        for integ in styles.order(by_int):
            panels.append((scene, integ, np.asarray(by_int[integ])))
    nscenes = len(sm.groups("scene"))
    finite_logs = []
    for _, _, rows in panels:
        er = sm["energy_ratio"][rows]
        ok = (sm["diverged"][rows] == 0) & np.isfinite(er) & (er > 0)
        finite_logs.append(np.log10(er[ok]))
    allv = np.concatenate(finite_logs) if finite_logs else np.array([])
    span = float(np.max(np.abs(allv))) if len(allv) else 1.0
    lim = min(6.0, max(1.0, math.ceil(span)))
    clipped = span > lim
    ncol = min(4, len(panels))
    nrow = (len(panels) + ncol - 1) // ncol
    fig = new_figure(3.6 * ncol + 1.2, 3.3 * nrow + 0.9)
    axes = fig.subplots(nrow, ncol, squeeze=False)
    cmap = plt.get_cmap("RdBu_r").copy()
    cmap.set_bad("white")
    mesh = None
    any_div = any_nonpos = any_missing = False
    for j, (scene, integ, rows) in enumerate(panels):
        ax = axes[j // ncol, j % ncol]
        ks = np.unique(sm["k"][rows])
        dts = np.unique(sm["dt"][rows])
        z = np.full((len(ks), len(dts)), np.nan)
        div = np.zeros_like(z, dtype=bool)
        nonpos = np.zeros_like(z, dtype=bool)
        wmax = {}
        for r in rows:
            a = np.searchsorted(ks, sm["k"][r])
            b = np.searchsorted(dts, sm["dt"][r])
            er = sm["energy_ratio"][r]
            if finite(sm["w_max"][r]):
                wmax[float(sm["k"][r])] = float(sm["w_max"][r])
            if sm["diverged"][r]:
                div[a, b] = True
            elif finite(er) and er > 0:
                z[a, b] = math.log10(er)
            else:
                nonpos[a, b] = True
        xe, ye = log_edges(dts), log_edges(ks)
        mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(np.clip(z, -lim, lim)), cmap=cmap,
                             vmin=-lim, vmax=lim, shading="flat")
        if div.any():
            any_div = True
            ax.add_collection(_cells(xe, ye, div, facecolor=DIVERGED_COLOR, hatch="///",
                                     edgecolor=DIVERGED_HATCH))
        if nonpos.any():
            any_nonpos = True
            ax.add_collection(_cells(xe, ye, nonpos, facecolor=NONPOS_COLOR))
        missing = np.isnan(z) & ~div & ~nonpos
        if missing.any():
            any_missing = True
            ax.add_collection(_cells(xe, ye, missing, facecolor="white", hatch="..",
                                     edgecolor="#b0b0b0"))
        if wmax:
            kk = np.array(sorted(wmax))
            ww = np.array([wmax[k] for k in kk])
            halo = [patheffects.withStroke(linewidth=3.2, foreground="white")]
            ax.plot(2.0 / ww, kk, color="black", ls="--", lw=1.5, path_effects=halo)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
        ax.set_xlabel("dt [s]")
        ax.set_ylabel("k [N/m]")
        ax.set_title(integ if nscenes == 1 else "%s — %s" % (integ, scene), color=styles.color(integ),
                     fontweight="bold", fontsize=11)
    for j in range(len(panels), nrow * ncol):
        axes[j // ncol, j % ncol].set_visible(False)
    if mesh is not None:
        cb = fig.colorbar(mesh, ax=axes, shrink=0.9, extend="both" if clipped else "neither",
                          aspect=30)
        cb.set_label("log10 E(T)/E(0)")
    handles = [Line2D([], [], color="black", ls="--", lw=1.5), ]
    labels = ["dt = 2 / w_max (reference)"]
    if any_div:
        handles.append(Patch(facecolor=DIVERGED_COLOR, hatch="///", edgecolor=DIVERGED_HATCH))
        labels.append("diverged")
    if any_nonpos:
        handles.append(Patch(facecolor=NONPOS_COLOR))
        labels.append("E(T)/E(0) ≤ 0 (no log)")
    if any_missing:
        handles.append(Patch(facecolor="white", hatch="..", edgecolor="#b0b0b0"))
        labels.append("not run")
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=len(handles), fontsize=9, frameon=False)
    saved = figs.save(fig, exp.name + "-map.png")
    caption = ("Final over initial mechanical energy for every step dt (x) and stiffness k (y): "
               "white = kept, red = gained, blue = lost, dark hatched = diverged. The dashed line "
               "is dt = 2/w_max, w_max the largest eigenfrequency at the initial state.")
    if clipped:
        caption += " Colours are clipped at ±%g decades (arrows on the colour bar)." % lim
    return figure_html(saved, "stability map", esc(caption))


# --------------------------------------------------------------------------
# 3. convergence

def orders_by(exp):
    o = exp.table("convergence-orders")
    out = {}
    if o is not None:
        for r in range(len(o)):
            out[(o["scene"][r], o["integrator"][r], bool(o["adaptive"][r]))] = (
                o["fitted_order"][r], o["theoretical_order"][r])
    return out


def order_label(integ, orders):
    if orders is None:
        return integ
    fitted, theory = orders
    return "%s (%s / %s)" % (integ, "%.2f" % fitted if finite(fitted) else "–",
                            "%g" % theory if finite(theory) else "–")


def convergence_figure(exp, styles, figs):
    cv = exp.table("convergence")
    orders = orders_by(exp)
    scenes = cv.groups("scene")
    kinds = []
    adaptive_col = cv["adaptive"]
    if np.any(adaptive_col == 0):
        kinds.append(False)
    if np.any(adaptive_col == 1):
        kinds.append(True)
    fig = new_figure(6.6 * len(kinds) + 0.4, 6.2 * len(scenes))
    axes = fig.subplots(len(scenes), len(kinds), squeeze=False)
    skipped = 0
    for row, ((scene,), sidx) in enumerate(scenes.items()):
        for col, adaptive in enumerate(kinds):
            ax = axes[row, col]
            by_int = {}
            for r in sidx:
                if bool(cv["adaptive"][r]) == adaptive:
                    by_int.setdefault(cv["integrator"][r], []).append(r)
            for integ in styles.order(by_int):
                rows = np.asarray(by_int[integ])
                rows = rows[np.argsort(cv["value"][rows], kind="stable")]
                err = cv["error"][rows]
                ok = np.array([cv["status"][r] == "completed" for r in rows]) & \
                    np.isfinite(err) & (err > 0)
                skipped += int((~ok).sum())
                label = order_label(integ, orders.get((scene, integ, adaptive)) if orders else None)
                if not ok.any():
                    label += "  (no valid point)"
                ax.plot(cv["value"][rows][ok], err[ok], marker=styles.marker(integ), ms=6,
                        mfc="none", mew=1.3, lw=1.4,
                        color=styles.color(integ), ls=styles.linestyle(integ), label=label)
            log_log(ax)
            params = sorted(set(cv["parameter"][r] for r in sidx
                                if bool(cv["adaptive"][r]) == adaptive))
            if adaptive:
                ax.set_xlabel("relative tolerance %s [1]" % "/".join(params or ["rtol"]))
                ax.set_title("%s — adaptive: error against tolerance" % scene, loc="left",
                             fontweight="bold")
            else:
                ax.set_xlabel("step %s [s]" % "/".join(params or ["dt"]))
                ax.set_title("%s — fixed step: error against step" % scene, loc="left",
                             fontweight="bold")
            ax.set_ylabel(ERROR_LABEL)
            ax.grid(True, which="major", alpha=0.3)
            ax.grid(True, which="minor", alpha=0.1)
            if not by_int:
                ax.text(0.5, 0.5, "no %s runs on this scene" % ("adaptive" if adaptive else
                                                              "fixed-step"),
                        transform=ax.transAxes, ha="center", va="center")
            elif ax.get_legend_handles_labels()[0]:
                ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=8,
                          frameon=False, title="integrator (fitted / theoretical order)"
                          if orders else None, title_fontsize=8, handlelength=2.6)
    saved = figs.save(fig, exp.name + ".png")
    caption = ("Error of the final positions against the exact solution (oscillator) or a tight "
               "reference, on log-log axes: a method of order p is a line of slope p. Legend: "
               "fitted / theoretical order from convergence-orders.csv (against log dt, or log "
               "rtol for adaptive methods, where 1 means error proportional to tolerance).")
    if skipped:
        caption += (" %d point%s not drawn (diverged or failed run, or an error that is not a "
                    "positive finite number)." % (skipped, "" if skipped == 1 else "s"))
    if not orders:
        caption += " convergence-orders.csv is missing: no fitted orders."
    return figure_html(saved, "convergence", esc(caption))


def orders_table(exp, styles):
    o = exp.table("convergence-orders")
    out = ["<p>Fitted against theoretical order. Highlighted: |fitted − theoretical| &gt; 0.2.</p>\n"
           "<table><tr><th>scene</th><th>integrator</th><th>kind</th><th>theoretical</th>"
           "<th>fitted</th><th>|difference|</th><th>points</th></tr>\n"]
    scene_pos = {key[0]: j for j, key in enumerate(o.groups("scene"))}
    integ_pos = {n: j for j, n in enumerate(styles.order(set(o["integrator"])))}
    order = sorted(range(len(o)), key=lambda r: (
        scene_pos[o["scene"][r]], bool(o["adaptive"][r]), integ_pos[o["integrator"][r]]))
    for r in order:
        row = o.row(r)
        th, fi = row["theoretical_order"], row["fitted_order"]
        diff = abs(fi - th) if finite(th) and finite(fi) else math.nan
        bad = finite(diff) and diff > 0.2
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>'
                   '<td>%s</td></tr>\n' % (
                       ' class="off"' if bad else "", esc(row["scene"]),
                       swatch(styles, row["integrator"]),
                       "adaptive (vs rtol)" if row["adaptive"] else "fixed step (vs dt)",
                       "%g" % th if finite(th) else "–", "%.3f" % fi if finite(fi) else "–",
                       "%.3f" % diff if finite(diff) else "–", fmt(row["points"], 6)))
    out.append("</table>\n")
    return "".join(out)


# --------------------------------------------------------------------------
# 4. work-precision

def work_precision_figure(exp, styles, figs):
    wp = exp.table("work-precision")
    scenes = wp.groups("scene")
    fig = new_figure(13.5, 5.2 * len(scenes))
    axes = fig.subplots(len(scenes), 2, squeeze=False)
    skipped = 0
    for row, ((scene,), sidx) in enumerate(scenes.items()):
        by_int = {}
        for r in sidx:
            by_int.setdefault(wp["integrator"][r], []).append(r)
        for col, (cost, xlabel) in enumerate((("wall_seconds", "wall time [s]"),
                                              ("force_evals", "force evaluations [1]"))):
            ax = axes[row, col]
            for integ in styles.order(by_int):
                rows = np.asarray(by_int[integ])
                rows = rows[np.argsort(wp["value"][rows], kind="stable")]
                err = wp["error"][rows]
                x = wp[cost][rows]
                ok = np.array([wp["status"][r] == "completed" for r in rows]) & \
                    np.isfinite(err) & (err > 0) & np.isfinite(x) & (x > 0)
                if col == 0:
                    skipped += int((~ok).sum())
                ax.plot(x[ok], err[ok], marker=styles.marker(integ), ms=6, mfc="none", mew=1.3,
                        lw=1.4, color=styles.color(integ), ls=styles.linestyle(integ),
                        label=integ + ("" if ok.any() else "  (no valid point)"))
            log_log(ax)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ERROR_LABEL)
            ax.set_title("%s — error against %s" % (scene, "time" if col == 0 else
                                                     "force evaluations"),
                         loc="left", fontweight="bold")
            ax.grid(True, which="major", alpha=0.3)
            ax.grid(True, which="minor", alpha=0.1)
        outside_legend(axes[row, 1])
    saved = figs.save(fig, exp.name + ".png")
    caption = ("Accuracy against cost: fixed-step methods over a dt sweep (solid), adaptive ones "
               "over a tolerance sweep (dashed). Lower left is better. Wall time is the minimum "
               "over repeats.")
    if skipped:
        caption += (" %d point%s not drawn (status not completed, or error/cost not a positive "
                    "finite number)." % (skipped, "" if skipped == 1 else "s"))
    return figure_html(saved, "work-precision", esc(caption))


# --------------------------------------------------------------------------
# 5. damping budget

def damping_figure(exp, styles, figs):
    db = exp.table("damping-budget")
    panels = case_panels(db)
    fig = new_figure(12.5, 8.0 * len(panels))
    axes = fig.subplots(2 * len(panels), 1, squeeze=False)[:, 0]
    for p, ((scene, dt, case), series) in enumerate(panels.items()):
        ax_e, ax_n = axes[2 * p], axes[2 * p + 1]
        t_max = max(float(db["t"][idx][-1]) for idx in series.values())
        # The most accurate run (smallest numerical dissipation, reaching the end).
        best, best_err = None, math.inf
        for integ, idx in series.items():
            num = db["numerical"][idx]
            if db["t"][idx][-1] >= t_max * (1 - 1e-9) and np.all(np.isfinite(num)):
                err = float(np.max(np.abs(num)))
                if err < best_err or (err == best_err and integ < best):
                    best, best_err = integ, err
        if best is None:
            best = sorted(series)[0]
        bidx = series[best]
        e0 = float(db["mechanical"][bidx][0])
        w_t = db["t"][bidx]
        w = db["work_nonconservative"][bidx]
        phys_min = float(min(np.min(e0 + w), e0))
        phys_max = float(max(np.max(e0 + w), e0))
        span = max(phys_max - phys_min, 1e-12 * max(1.0, abs(e0)))
        lo, hi = phys_min - 0.25 * span, phys_max + 0.25 * span
        num_abs = []
        for integ in styles.order(series):
            idx = series[integ]
            t = db["t"][idx]
            mech = db["mechanical"][idx]
            num = db["numerical"][idx]
            c, ls = styles.color(integ), styles.linestyle(integ)
            label = integ
            stopped = t[-1] < t_max * (1 - 1e-9)
            if stopped:
                label += "  ✕ stops at t = %s s" % fmt(float(t[-1]), 4)
            label_e = label
            inside = (mech >= lo) & (mech <= hi)
            if not np.all(inside):
                label_e += "  (leaves the plot: %s … %s J)" % (fmt(float(np.min(mech))),
                                                               fmt(float(np.max(mech))))
            ax_e.plot(t, mech, color=c, ls=ls, lw=1.4, label=label_e)
            ax_n.plot(t, num, color=c, ls=ls, lw=1.4, label=label)
            if stopped:
                ax_n.plot([t[-1]], [num[-1]], marker="x", ms=11, mew=2.5, color=c, ls="none")
                if lo <= mech[-1] <= hi:
                    ax_e.plot([t[-1]], [mech[-1]], marker="x", ms=11, mew=2.5, color=c, ls="none")
            num_abs.append(np.abs(num[np.isfinite(num)]))
        ax_e.plot(w_t, e0 + w, color="black", ls=(0, (5, 2)), lw=2.2, alpha=0.8,
                  label="E(0) + W_nc: physical damping only\n(W_nc from %s)" % best, zorder=4)
        ax_e.set_ylim(lo, hi)
        ax_e.set_xlim(0, t_max)
        ax_e.set_xlabel("t [s]")
        ax_e.set_ylabel("mechanical energy E [J]")
        ax_e.set_title("%s — mechanical energy" % panel_title(scene, dt, case, panels),
                       loc="left", fontweight="bold")
        ax_e.grid(True, alpha=0.3)
        outside_legend(ax_e)
        ax_n.plot(w_t, w, color="black", ls=(0, (5, 2)), lw=2.2, alpha=0.8,
                  label="W_nc: work of drag and damping\n(physical, from %s)" % best, zorder=4)
        allnum = np.concatenate(num_abs + [np.abs(w)]) if num_abs else np.abs(w)
        allnum = allnum[allnum > 0]
        scale = float(np.max(allnum)) if len(allnum) else 1.0
        linthresh = max(scale * 1e-9, 1e-300)
        smallest = float(np.min(allnum)) if len(allnum) else scale
        linthresh = max(linthresh, min(smallest, scale * 1e-6))
        linthresh = 10.0 ** math.floor(math.log10(linthresh))
        ax_n.set_yscale("symlog", linthresh=linthresh, linscale=0.6)
        ax_n.axhspan(-linthresh, linthresh, color="0.9", zorder=0, lw=0)
        ax_n.axhline(0.0, color="0.45", lw=0.7)
        ax_n.set_xlim(0, t_max)
        symlog_ticks(ax_n, linthresh)
        ax_n.set_xlabel("t [s]")
        ax_n.set_ylabel("numerical = E − W_nc − E(0) [J]")
        ax_n.set_title("%s — the integrator's own energy change (positive: it added energy)"
                       % scene, loc="left", fontweight="bold")
        ax_n.grid(True, alpha=0.3)
        outside_legend(ax_n, extra=[(Patch(facecolor="0.9", edgecolor="0.75"),
                                     "|.| < %g J: linear scale" % linthresh)])
    saved = figs.save(fig, exp.name + ".png")
    return figure_html(saved, "damping budget", esc(
        "Top: mechanical energy of every run; the black dashed line is what it would be with "
        "only the physical dissipation (initial energy plus the work W_nc of drag and spring "
        "damping, taken from the most accurate run). Bottom: what is left, the integrator's own "
        "numerical energy change (symmetric log axis), next to the physical W_nc for scale."))


# --------------------------------------------------------------------------
# 6. cloth showcase

def cloth_figure(exp, styles, figs):
    cl = exp.table("cloth-showcase")
    runs = exp.table("cloth-showcase-runs")
    settings = exp.settings or {}
    parts = []
    n = find_key(settings, ("n",))
    n = int(n) if isinstance(n, (int, float)) and not isinstance(n, bool) and n >= 1 else None
    frames = find_key(settings, ("frames", "frame_times", "times"))
    if not (isinstance(frames, list) and frames and
            all(isinstance(f, (int, float)) and not isinstance(f, bool) for f in frames)):
        frames = None
    gravity = find_key(settings, ("gravity",))
    vertical = 1
    if isinstance(gravity, list) and len(gravity) == 3 and \
            all(isinstance(g, (int, float)) for g in gravity) and any(gravity):
        vertical = int(np.argmax(np.abs(gravity)))
    fixed = set()
    scenes = find_scenes(settings)
    if scenes:
        for j, p in enumerate(scenes[0][1].get("particles", [])):
            if isinstance(p, dict) and p.get("fixed") is True:
                fixed.add(j)
    run_by = {}
    if runs is not None:
        for r in range(len(runs)):
            run_by[(runs["scene"][r], runs["integrator"][r])] = runs.row(r)
    has_z = np.any(np.isfinite(cl["z"]))
    for (scene,), sidx in cl.groups("scene").items():
        series = {}
        for r in sidx:
            series.setdefault(cl["integrator"][r], []).append(r)
        data = {}
        for integ, rows in series.items():
            rows = np.asarray(rows)
            frames_of = {}
            for t, idx in _group_float(cl["t"][rows], rows).items():
                idx = idx[np.argsort(cl["i"][idx], kind="stable")]
                pts = np.stack([cl["x"][idx], cl["y"][idx],
                                cl["z"][idx] if has_z else np.zeros(len(idx))], axis=1)
                frames_of[t] = (cl["i"][idx].astype(int), pts)
            data[integ] = frames_of
        # Runs that got to the end (per the run table, or reaching the last time seen).
        t_end = max(max(d) for d in data.values())
        good = [integ for integ in data if
                (run_by[(scene, integ)]["status"] == "completed" if (scene, integ) in run_by
                 else max(data[integ]) >= t_end * (1 - 1e-9))] or list(data)
        times = [float(f) for f in frames] if frames else \
            sorted(set(t for integ in good for t in data[integ]))
        if len(times) > 8:
            pick = np.unique(np.round(np.linspace(0, len(times) - 1, 8)).astype(int))
            times = [times[k] for k in pick]
        npart = max(len(p[0]) for d in data.values() for p in d.values())
        nn = n
        if nn is None or nn * nn != npart:
            root = int(round(math.sqrt(npart)))
            nn = root if root * root == npart else None
        if n is not None and nn != n:
            parts.append(note_html("cloth-showcase.json gives n = %s but a frame has %d particles; "
                                   "%s." % (n, npart, "using n = %d" % nn if nn else
                                            "drawing points only")))
        segs = _grid_pairs(nn) if nn else None
        # Common cube limits from runs that did not diverge.
        allpts = np.concatenate([p[1] for integ in good for p in data[integ].values()])
        lims = _cube(allpts)
        order = styles.order(data)
        fig = plt.figure(figsize=(2.7 * len(times) + 0.9, 2.9 * len(order) + 0.3))
        gs = fig.add_gridspec(len(order), len(times), left=0.06, right=0.995, bottom=0.01,
                              top=1 - 0.35 / (2.9 * len(order) + 0.3), wspace=0.05, hspace=0.18)
        axis_names = ["x", "y", "z"]
        horiz = [a for a in range(3) if a != vertical]
        for row, integ in enumerate(order):
            frames_of = data[integ]
            run = run_by.get((scene, integ), {})
            status = run.get("status", "completed")
            known = sorted(frames_of)
            last_t = known[-1]
            shown_last = False
            for col, tf in enumerate(times):
                ax = fig.add_subplot(gs[row, col], projection="3d")
                match = [t for t in known if abs(t - tf) <= 1e-9 * max(1.0, abs(tf))]
                title, tcolor, frame, own = "t = %s s" % fmt(tf, 4), "black", None, False
                if match:
                    frame = frames_of[match[0]]
                elif tf > last_t and not shown_last and (status != "completed" or not run):
                    shown_last = True
                    frame = frames_of[last_t]
                    at = run.get("diverged_at", math.nan)
                    what = status if status != "completed" else "stopped"
                    title = "%s at t = %s s\n(last good frame, t = %s s)" % (
                        what, fmt(at if finite(at) else last_t, 4), fmt(last_t, 4))
                    tcolor = "#b00000"
                if frame is None:
                    ax.set_axis_off()
                    ax.text2D(0.5, 0.5, "—" if tf > last_t else "no frame at t = %s s" % fmt(tf),
                              transform=ax.transAxes, ha="center", va="center", color="0.5")
                    continue
                ids, pts = frame
                l = lims
                if np.any(pts < lims[0] - 0.1 * (lims[1] - lims[0])) or \
                        np.any(pts > lims[1] + 0.1 * (lims[1] - lims[0])):
                    l, own = _cube(pts), True
                P = pts[:, [horiz[0], horiz[1], vertical]]
                c = styles.color(integ)
                if segs is not None and len(ids) == nn * nn and np.all(ids == np.arange(nn * nn)):
                    ax.add_collection3d(Line3DCollection(np.stack([P[segs[:, 0]], P[segs[:, 1]]],
                                                                  axis=1),
                                                         colors=c, linewidths=0.8))
                else:
                    ax.scatter(P[:, 0], P[:, 1], P[:, 2], s=3, color=c, depthshade=False)
                fx = [k for k, pid in enumerate(ids) if int(pid) in fixed]
                if fx:
                    ax.scatter(P[fx, 0], P[fx, 1], P[fx, 2], s=14, color="black",
                               depthshade=False)
                ax.set_xlim(l[0][horiz[0]], l[1][horiz[0]])
                ax.set_ylim(l[0][horiz[1]], l[1][horiz[1]])
                ax.set_zlim(l[0][vertical], l[1][vertical])
                ax.set_box_aspect((1, 1, 1))
                ax.view_init(elev=18, azim=-60)
                for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                    axis.set_major_locator(MaxNLocator(3))
                    axis.set_pane_color((0.97, 0.97, 0.97, 1.0))
                ax.tick_params(labelsize=6, pad=-2)
                ax.set_xlabel("%s [m]" % axis_names[horiz[0]], fontsize=7, labelpad=-9)
                ax.set_ylabel("%s [m]" % axis_names[horiz[1]], fontsize=7, labelpad=-9)
                ax.set_zlabel("%s [m]" % axis_names[vertical], fontsize=7, labelpad=-9)
                if own:
                    title += "\n(own scale)"
                ax.set_title(title, fontsize=9, color=tcolor, pad=0)
            fig.text(0.012, 1 - (row + 0.5) / len(order) * (1 - 0.35 / (2.9 * len(order) + 0.3)),
                     integ, rotation=90, ha="center", va="center", fontsize=11, fontweight="bold",
                     color=styles.color(integ))
        saved = figs.save(fig, "%s%s.png" % (exp.name, "" if len(cl.groups("scene")) == 1
                                             else "-" + re.sub(r"[^A-Za-z0-9_.-]", "_", scene)))
        caption = ("Cloth '%s' (%s) at the frame times, one row per integrator, drawn as its "
                   "structural grid%s; all panels share one scale unless marked. A run that "
                   "diverged shows its last good frame in red." % (
                       scene, "%d x %d particles" % (nn, nn) if nn else "%d particles" % npart,
                       " (black dots: fixed particles)" if fixed else ""))
        parts.insert(0, figure_html(saved, "cloth showcase " + scene, esc(caption)))
    if runs is not None:
        parts.append(runs_table(runs, styles, "Runs", [
            ("status", "status", None), ("diverged_at", "diverged at [s]", 4),
            ("steps", "steps", 10), ("wall_seconds", "wall [s]", 3)]))
    return "".join(parts)


def _group_float(values, rows):
    out = {}
    for v, r in zip(values, rows):
        out.setdefault(float(v), []).append(r)
    return {k: np.asarray(v) for k, v in out.items()}


def _grid_pairs(n):
    pairs = []
    for r in range(n):
        for c in range(n):
            i = r * n + c
            if c + 1 < n:
                pairs.append((i, i + 1))
            if r + 1 < n:
                pairs.append((i, i + n))
    return np.asarray(pairs, dtype=int).reshape(-1, 2)


def _cube(pts):
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        return np.array([[-1.0] * 3, [1.0] * 3])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid = (lo + hi) / 2
    half = max(float(np.max(hi - lo)) / 2 * 1.05, 1e-6)
    return np.array([mid - half, mid + half])


# --------------------------------------------------------------------------
# Benchmarks (Google Benchmark JSON from springlab_bench, optional)
#
# Read from --bench FILE.json, or else from benchmarks.json in the data
# directory (where `cmake --build --preset bench` writes it). Families, by
# name (the size n is the scene's own parameter; counters carry the real
# size: particles, unknowns, springs):
#   BM_Step/<integrator>/<scene>/<n>        one step (adaptive: 1/60 s)
#   BM_OdeintStep/<method>/<scene>/<n>      Boost.Odeint's peer of a step
#   BM_OdeintPair/<method>/<scene>/<n>      both in alternation: the ratio
#   BM_Force/<scene>/<n>, BM_ForceJacobian/<scene>/<n>
#   BM_LinearSolver/<solver>/<scene>/<n>
# Times shown are CPU time of the (single) benchmark thread: a one-core
# figure that a busy machine disturbs less than wall time (both are in the
# step table).

BENCH_FILE = "benchmarks.json"
TIME_UNITS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}
BENCH_STANDARD_KEYS = {"name", "family_index", "per_family_instance_index", "run_name", "run_type",
                       "repetitions", "repetition_index", "threads", "iterations", "real_time",
                       "cpu_time", "time_unit", "aggregate_name", "aggregate_unit", "label",
                       "error_occurred", "error_message"}
# Family -> index of the size argument in the name.
BENCH_FAMILIES = {"BM_Step": 3, "BM_OdeintStep": 3, "BM_OdeintPair": 3, "BM_Force": 2,
                  "BM_ForceJacobian": 2, "BM_LinearSolver": 3}
# Performance targets (issue 5), shown beside the measured figures.
TARGET_FORCE_NS = 5.0            # force evaluation, cloth 128, ns per spring
TARGET_PEER_RATIO = 0.7          # springlab / odeint time, rk4 and symplectic-euler
TARGET_STEP_MS = {"implicit-euler": 15.0, "linear-implicit-euler": 8.0}  # cloth 64, dt 1/60
TARGET_EXPONENT_EXPLICIT = (0.85, 1.15)  # "about 1.0"
TARGET_EXPONENT_IMPLICIT = 1.3


def is_bench_doc(doc):
    """A Google Benchmark JSON file (not an experiment's settings)."""
    return isinstance(doc, dict) and isinstance(doc.get("benchmarks"), list) \
        and isinstance(doc.get("context"), dict)


def read_bench(path):
    """Every springlab_bench entry, by family; time per iteration in s."""
    doc = read_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("benchmarks"), list):
        raise DataError(path, None, "not a Google Benchmark JSON file (no \"benchmarks\" list)")
    raw = {}
    errors = []
    ignored = 0
    for j, b in enumerate(doc["benchmarks"]):
        if not isinstance(b, dict) or not isinstance(b.get("name"), str):
            raise DataError(path, None, "benchmarks[%d]: expected an object with a \"name\"" % j)
        base = b.get("run_name") if isinstance(b.get("run_name"), str) else b["name"]
        parts = base.split("/")
        k = BENCH_FAMILIES.get(parts[0])
        if k is None or len(parts) <= k or not re.fullmatch(r"\d+", parts[k]):
            ignored += 1
            continue
        key = (parts[0], parts[1] if k == 3 else "", parts[k - 1], int(parts[k]))
        if b.get("error_occurred"):
            if key not in [e[0] for e in errors]:
                errors.append((key, str(b.get("error_message", ""))))
            continue
        unit = b.get("time_unit", "ns")
        if unit not in TIME_UNITS:
            raise DataError(path, None, "benchmarks[%d] (%s): unknown time_unit '%s'"
                            % (j, b["name"], unit))
        for field in ("real_time", "cpu_time"):
            if not isinstance(b.get(field), (int, float)) or isinstance(b.get(field), bool):
                raise DataError(path, None, "benchmarks[%d] (%s): '%s' is not a number"
                                % (j, b["name"], field))
        run_type = b.get("run_type", "iteration")
        agg = b.get("aggregate_name") if run_type == "aggregate" else None
        if agg not in (None, "mean", "median"):
            continue  # stddev, cv, ...
        counters = {c: float(v) for c, v in b.items()
                    if c not in BENCH_STANDARD_KEYS and isinstance(v, (int, float))
                    and not isinstance(v, bool)}
        entry = {"family": key[0], "what": key[1], "scene": key[2], "n": key[3],
                 "real_time": float(b["real_time"]) * TIME_UNITS[unit],
                 "cpu_time": float(b["cpu_time"]) * TIME_UNITS[unit],
                 "counters": counters, "label": str(b.get("label", ""))}
        raw.setdefault(key, {}).setdefault(agg, []).append(entry)
    families = {f: [] for f in BENCH_FAMILIES}
    for key in sorted(raw):
        by_agg = raw[key]
        pick = by_agg.get("median") or by_agg.get("mean")
        if pick:
            e = dict(pick[0])
        else:
            its = by_agg[None]
            e = dict(its[0])
            e["real_time"] = float(np.mean([x["real_time"] for x in its]))
            e["cpu_time"] = float(np.mean([x["cpu_time"] for x in its]))
        e["size"] = e["counters"].get("particles", float(e["n"]))
        families[key[0]].append(e)
    entries = []
    for e in families["BM_Step"]:
        c = e["counters"]
        e["integrator"] = e["what"]
        e["kind"] = ("adaptive" if c.get("adaptive") else "implicit" if c.get("implicit")
                     else "explicit")
        entries.append(e)
    context = doc.get("context") if isinstance(doc.get("context"), dict) else {}
    return {"entries": entries, "families": families, "errors": errors, "ignored": ignored,
            "context": context, "path": path}


def _fit_exponent(points):
    """Least-squares slope of log(time) against log(size), or None."""
    pts = [(x, y) for x, y in points if finite(x) and finite(y) and x > 0 and y > 0]
    if len(set(x for x, _ in pts)) < 2:
        return None
    xs = np.log([x for x, _ in pts])
    ys = np.log([y for _, y in pts])
    return float(np.polyfit(xs, ys, 1)[0])


def _met(ok):
    return "met" if ok else "<b>not met</b>"


def _ms(seconds, digits=3):
    return fmt(seconds * 1e3, digits)


def _bench_context_html(bench):
    ctx = bench["context"]
    bits = []
    if ctx.get("date"):
        bits.append("run %s" % esc(ctx["date"]))
    if ctx.get("num_cpus"):
        bits.append("%s CPUs at %s MHz" % (esc(ctx["num_cpus"]), esc(fmt(ctx.get("mhz_per_cpu"), 4))))
    load = ctx.get("load_avg")
    if isinstance(load, list) and load:
        bits.append("load average at start %s" % esc(", ".join(fmt(x, 3) for x in load)))
    if ctx.get("library_build_type"):
        bits.append("Google Benchmark library built as %s" % esc(ctx["library_build_type"]))
    text = ("Measured by <code>springlab_bench</code> (%s). Times are the CPU time of the one "
            "benchmark thread (a one-core figure; wall time, which other processes on a busy "
            "machine inflate, is in the step table too)." % "; ".join(bits))
    return "<p>%s</p>\n" % text


def _exponents(entries):
    """{(integrator, scene): exponent} over the sizes measured (CPU time)."""
    out = {}
    for integ in set(e["integrator"] for e in entries):
        for scene in set(e["scene"] for e in entries):
            pts = [(e["size"], e["cpu_time"]) for e in entries
                   if e["integrator"] == integ and e["scene"] == scene]
            s = _fit_exponent(pts)
            if s is not None:
                out[(integ, scene)] = s
    return out


def _step_figure(entries, slopes, styles, figs):
    scenes = sorted(set(e["scene"] for e in entries))
    multi = [sc for sc in scenes if len(set(e["size"] for e in entries if e["scene"] == sc)) >= 2]
    scenes = multi or scenes
    fig = new_figure(12.5, 5.2 * len(scenes))
    axes = fig.subplots(len(scenes), 1, squeeze=False)[:, 0]
    for ax, scene in zip(axes, scenes):
        mine = [e for e in entries if e["scene"] == scene]
        for integ in styles.order(set(e["integrator"] for e in mine)):
            pts = sorted((e["size"], e["cpu_time"]) for e in mine if e["integrator"] == integ)
            n = np.array([p[0] for p in pts], dtype=float)
            t = np.array([p[1] for p in pts])
            ok = (n > 0) & np.isfinite(t) & (t > 0)
            label = integ
            if (integ, scene) in slopes:
                label += "  (exponent %.2f)" % slopes[(integ, scene)]
            ax.plot(n[ok], t[ok], marker=styles.marker(integ), ms=6, mfc="none", mew=1.3, lw=1.4,
                    color=styles.color(integ), ls=styles.linestyle(integ), label=label)
        has = log_log(ax)
        sizes = sorted(set(e["size"] for e in mine if e["size"] > 0))
        if has and len(sizes) >= 2:
            # A slope-1 guide (cost proportional to size) through the middle.
            times = [e["cpu_time"] for e in mine if e["cpu_time"] > 0]
            mid_t = math.exp(np.mean(np.log(times)))
            mid_n = math.exp(np.mean(np.log(sizes)))
            xs = np.array([sizes[0], sizes[-1]], dtype=float)
            ax.plot(xs, mid_t * xs / mid_n, color="0.55", lw=1.0, ls=":",
                    label="slope 1 (cost ∝ particles)")
        if has and 0 < len(sizes) <= 12:
            from matplotlib.ticker import NullFormatter, ScalarFormatter
            ax.set_xticks(sizes)
            ax.xaxis.set_major_formatter(ScalarFormatter())
            ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("free particles [1]")
        ax.set_ylabel("CPU time per step [s]")
        ax.set_title("%s — cost of one step (adaptive methods, dashed: cost of 1/60 s)" % scene,
                     loc="left", fontweight="bold")
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", alpha=0.1)
        outside_legend(ax)
    return figs.save(fig, "bench-cost.png")


def _step_table(entries, slopes, styles):
    order = styles.order(set(e["integrator"] for e in entries))
    out = ["<details open><summary>Step cost, every entry (%d)</summary>\n<table><tr>"
           "<th>integrator</th><th>scene</th><th>n</th><th>particles</th><th>step</th>"
           "<th>CPU / step [ms]</th><th>wall / step [ms]</th><th>CPU s per simulated s</th>"
           "<th>force evals / step</th><th>Newton / step</th><th>linear solves / step</th>"
           "<th>factorizations / step</th><th>internal steps / step</th><th>restarts</th>"
           "<th>exponent</th></tr>\n" % len(entries)]
    for e in sorted(entries, key=lambda e: (e["scene"], order.index(e["integrator"]), e["size"])):
        c = e["counters"]
        s = slopes.get((e["integrator"], e["scene"]))
        out.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                   "<td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                   "<td>%s</td><td>%s</td></tr>\n"
                   % (swatch(styles, e["integrator"]), esc(e["scene"]), e["n"],
                      fmt(e["size"], 6), esc(e["label"]), _ms(e["cpu_time"], 4),
                      _ms(e["real_time"], 4), fmt(c.get("cpu_per_sim_second"), 3),
                      fmt(c.get("force_evals_per_step"), 3), fmt(c.get("newton_per_step"), 3),
                      fmt(c.get("linear_solves_per_step"), 3),
                      fmt(c.get("factorizations_per_step"), 3),
                      fmt(c.get("internal_steps_per_step"), 3), fmt(c.get("restarts"), 3),
                      "%.2f" % s if s is not None else "–"))
    out.append("</table></details>\n")
    return "".join(out)


def _exponent_table(entries, slopes, styles):
    kinds = {e["integrator"]: e["kind"] for e in entries}
    rows = []
    for integ in styles.order(kinds):
        for scene in sorted(set(e["scene"] for e in entries)):
            s = slopes.get((integ, scene))
            if s is None:
                continue
            sizes = sorted(set(e["n"] for e in entries
                               if e["integrator"] == integ and e["scene"] == scene))
            kind = kinds[integ]
            if kind == "explicit":
                target = "≈ 1.0"
                verdict = _met(TARGET_EXPONENT_EXPLICIT[0] <= s <= TARGET_EXPONENT_EXPLICIT[1])
            elif kind == "implicit":
                target = "≤ %.1f" % TARGET_EXPONENT_IMPLICIT
                verdict = _met(s <= TARGET_EXPONENT_IMPLICIT)
            else:
                target, verdict = "– (cost of 1/60 s)", ""
            rows.append("<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%.2f</td><td>%s</td>"
                        "<td>%s</td></tr>\n" % (swatch(styles, integ), esc(kind), esc(scene),
                                                esc(", ".join(str(n) for n in sizes)), s,
                                                esc(target), verdict))
    if not rows:
        return ""
    return ("<h3>Step-cost exponents</h3>\n<p>Least-squares slope of log CPU time per step "
            "against log free particles (cost ∝ particles<sup>exponent</sup>).</p>\n"
            "<table><tr><th>integrator</th><th>kind</th><th>scene</th><th>n</th>"
            "<th>exponent</th><th>target</th><th></th></tr>\n%s</table>\n" % "".join(rows))


def _peer_ratios(bench, method=None):
    """{(method, scene, n): (paired ratio or None, separate-run CPU ratio or None)}."""
    fam = bench["families"]
    mine = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    peer = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintStep"]}
    pair = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintPair"]}
    out = {}
    for key in set(peer) | set(pair):
        if method is not None and key[0] != method:
            continue
        paired = pair[key]["counters"].get("ratio") if key in pair else None
        separate = None
        if key in peer and key in mine and peer[key]["cpu_time"] > 0:
            separate = mine[key]["cpu_time"] / peer[key]["cpu_time"]
        out[key] = (paired, separate)
    return out


def _peer_table(bench):
    fam = bench["families"]
    mine = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    peer = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintStep"]}
    pair = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintPair"]}
    ratios = _peer_ratios(bench)
    rows = []
    for key in sorted(ratios, key=lambda k: (k[0], k[1], k[2])):
        paired, separate = ratios[key]
        s, o, p = mine.get(key), peer.get(key), pair.get(key)
        best = paired if paired is not None else separate
        rows.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(key[0]), esc(key[1]), key[2],
                       fmt(s["cpu_time"] * 1e6, 4) if s else "–",
                       fmt(o["cpu_time"] * 1e6, 4) if o else "–", fmt(separate, 3),
                       fmt(p["counters"].get("springlab_us"), 4) if p else "–",
                       fmt(p["counters"].get("odeint_us"), 4) if p else "–", fmt(paired, 3),
                       _met(best <= TARGET_PEER_RATIO) if finite(best) else "–"))
    if not rows:
        return ""
    return ("<h3>springlab against Boost.Odeint</h3>\n<p>The same model, scene and step "
            "(dt = 0.5/w_max), odeint's <code>runge_kutta4</code> and "
            "<code>symplectic_euler</code> calling the model's own force function. Separate "
            "runs: BM_Step against BM_OdeintStep (CPU time, median of the repetitions). Paired: "
            "BM_OdeintPair, which alternates batches of both inside one benchmark (wall clock), "
            "so a change in the machine's load hits both alike; the verdict uses it when "
            "present. Target: springlab at most %.1f× odeint's time.</p>\n"
            "<table><tr><th>method</th><th>scene</th><th>n</th><th>springlab CPU / step [µs]"
            "</th><th>odeint CPU / step [µs]</th><th>ratio (separate)</th>"
            "<th>springlab / step, paired [µs]</th><th>odeint / step, paired [µs]</th>"
            "<th>ratio (paired)</th><th>≤ %.1f</th></tr>\n%s</table>\n"
            % (TARGET_PEER_RATIO, TARGET_PEER_RATIO, "".join(rows)))


def _force_table(bench):
    force = {(e["scene"], e["n"]): e for e in bench["families"]["BM_Force"]}
    jac = {(e["scene"], e["n"]): e for e in bench["families"]["BM_ForceJacobian"]}
    keys = sorted(set(force) | set(jac), key=lambda k: (k[0], k[1]))
    if not keys:
        return ""
    rows = []
    for k in keys:
        f, j = force.get(k), jac.get(k)
        any_e = f or j
        c = any_e["counters"]
        note = ""
        if f and k == ("cloth", 128):
            note = "target ≤ %g ns/spring: %s" % (TARGET_FORCE_NS, _met(
                f["counters"].get("ns_per_spring", math.inf) <= TARGET_FORCE_NS))
        rows.append("<tr><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(k[0]), k[1], fmt(c.get("springs"), 6), fmt(c.get("unknowns"), 6),
                       fmt(f["cpu_time"] * 1e6, 4) if f else "–",
                       fmt(f["counters"].get("ns_per_spring"), 3) if f else "–",
                       fmt(f["counters"].get("unknowns_per_second"), 3) if f else "–",
                       fmt(j["cpu_time"] * 1e6, 4) if j else "–",
                       fmt(j["counters"].get("ns_per_spring"), 3) if j else "–", note))
    return ("<h3>Force evaluation</h3>\n<p>One evaluation of all forces "
            "(<code>MassSpringModel::force</code>), and force plus both Jacobians on the "
            "model's fixed pattern (what an implicit method assembles per Newton iteration).</p>\n"
            "<table><tr><th>scene</th><th>n</th><th>springs</th><th>unknowns</th>"
            "<th>force [µs]</th><th>force ns / spring</th><th>unknowns / s</th>"
            "<th>force + Jacobians [µs]</th><th>ns / spring</th><th></th></tr>\n%s</table>\n"
            % "".join(rows))


def _linear_table(bench):
    lin = bench["families"]["BM_LinearSolver"]
    failed = [(key, msg) for key, msg in bench["errors"] if key[0] == "BM_LinearSolver"]
    if not lin and not failed:
        return ""
    rows = []
    keyed = [((e["scene"], e["n"], e["cpu_time"]), e, None) for e in lin]
    keyed += [((key[2], key[3], math.inf), {"what": key[1], "scene": key[2], "n": key[3]}, msg)
              for key, msg in failed]
    for _, e, msg in sorted(keyed, key=lambda r: r[0]):
        if msg is not None:
            rows.append('<tr class="off"><td>%s</td><td>%s</td><td>%d</td><td colspan="7">%s</td>'
                        '</tr>\n' % (esc(e["what"]), esc(e["scene"]), e["n"], esc(msg)))
            continue
        c = e["counters"]
        rows.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(e["what"]), esc(e["scene"]), e["n"], fmt(c.get("unknowns"), 6),
                       fmt(c.get("factor_nonzeros"), 4), fmt(c.get("factorize_ms"), 4),
                       fmt(c.get("solve_ms"), 4), _ms(e["cpu_time"], 4),
                       fmt(c.get("cg_iterations"), 4), fmt(c.get("initial_residual"), 3)))
    label = next((e["label"] for e in lin if e["label"]), "")
    return ("<h3>Linear solvers</h3>\n<p>The implicit methods' matrix A = M − h dF/dv − "
            "h² dF/dx of the same cloth state (%s), one Newton-iteration's worth of work per "
            "row: direct solvers factorize (symbolic analysis reused, except "
            "<code>ldlt-scratch</code>) and solve; CG sets up its Jacobi preconditioner and "
            "iterates to a relative residual of 1e-8 (warm: from the previous step's solution). "
            "Factorize and solve are the wall-clock split of one iteration, CPU total is the "
            "benchmark's CPU time. Sorted by size, fastest first.</p>\n"
            "<table><tr><th>solver</th><th>scene</th><th>n</th><th>unknowns</th>"
            "<th>factor nonzeros</th><th>factorize [ms]</th><th>solve [ms]</th>"
            "<th>CPU total [ms]</th><th>CG iterations</th><th>CG initial residual</th></tr>\n"
            "%s</table>\n" % (esc(label), "".join(rows)))


def _targets_table(bench, slopes):
    """The performance targets that this file can answer, with the measured figure."""
    fam = bench["families"]
    rows = []
    f = next((e for e in fam["BM_Force"] if (e["scene"], e["n"]) == ("cloth", 128)), None)
    if f and finite(f["counters"].get("ns_per_spring")):
        v = f["counters"]["ns_per_spring"]
        rows.append(("force evaluation, cloth 128: ns per spring", "≤ %g" % TARGET_FORCE_NS,
                     fmt(v, 3), v <= TARGET_FORCE_NS))
    steps = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    for method in ("rk4", "symplectic-euler"):
        ratios = []
        for key, (paired, separate) in _peer_ratios(bench, method).items():
            r = paired if paired is not None else separate
            if finite(r):
                ratios.append((r, "%s %d" % (key[1], key[2])))
        if ratios:
            worst = max(ratios)
            rows.append(("%s / odeint time, worst scene (%s)" % (method, worst[1]),
                         "≤ %.1f" % TARGET_PEER_RATIO, "%s (best %s)" % (
                             fmt(worst[0], 3), fmt(min(ratios)[0], 3)),
                         worst[0] <= TARGET_PEER_RATIO))
    for method, limit in TARGET_STEP_MS.items():
        e = steps.get((method, "cloth", 64))
        if e:
            ms = e["cpu_time"] * 1e3
            rows.append(("%s, cloth 64, dt 1/60: ms per step" % method, "≤ %g" % limit,
                         fmt(ms, 3), ms <= limit))
    kinds = {e["integrator"]: e["kind"] for e in bench["entries"]}
    for kind, test, target in (
            ("explicit", lambda s: TARGET_EXPONENT_EXPLICIT[0] <= s <= TARGET_EXPONENT_EXPLICIT[1],
             "≈ 1.0"),
            ("implicit", lambda s: s <= TARGET_EXPONENT_IMPLICIT,
             "≤ %.1f" % TARGET_EXPONENT_IMPLICIT)):
        found = sorted((s, integ) for (integ, scene), s in slopes.items()
                       if scene == "cloth" and kinds.get(integ) == kind)
        if found:
            rows.append(("step-cost exponent, %s methods (cloth)" % kind, target,
                         ", ".join("%s %.2f" % (integ, s) for s, integ in found),
                         all(test(s) for s, _ in found)))
    if not rows:
        return ""
    body = "".join('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n'
                   % ("" if ok else ' class="off"', esc(what), esc(target), esc(value), _met(ok))
                   for what, target, value, ok in rows)
    return ("<h3>Measured against the performance targets</h3>\n<table><tr><th>figure</th>"
            "<th>target</th><th>measured</th><th></th></tr>\n%s</table>\n" % body)


def bench_section(bench, styles, figs):
    entries = bench["entries"]
    out = [_bench_context_html(bench)]
    slopes = _exponents(entries)
    if entries:
        out.append(_targets_table(bench, slopes))
        saved = _step_figure(entries, slopes, styles, figs)
        out.append(figure_html(saved, "step cost against size", esc(
            "CPU time of one step against the number of free particles, log-log, per scene with "
            "more than one size; the exponent is the least-squares slope of log time against log "
            "particles (cost ~ particles^exponent), the dotted grey line has slope 1. Explicit "
            "methods step at dt = 0.5/w_max (which shrinks as the cloth gets finer), implicit "
            "ones at dt = 1/60 s; adaptive methods (dashed) show the cost of 1/60 s of "
            "simulated time at rtol 1e-6.")))
        out.append(_exponent_table(entries, slopes, styles))
        out.append(_step_table(entries, slopes, styles))
    else:
        out.append(note_html("The benchmark file %s has no BM_Step/&lt;integrator&gt;/&lt;scene&gt;/"
                             "&lt;n&gt; entries: no step-cost figure."
                             % esc(Path(bench["path"]).name)))
    out.append(_peer_table(bench))
    out.append(_force_table(bench))
    out.append(_linear_table(bench))
    other = [(key, msg) for key, msg in bench["errors"] if key[0] != "BM_LinearSolver"]
    if other:
        out.append(note_html("Entries that reported an error (not shown): %s." % esc("; ".join(
            "%s: %s" % ("/".join(str(p) for p in key if p != ""), msg) for key, msg in other))))
    if bench["ignored"]:
        out.append(note_html("%d benchmark entr%s with a name this report does not know %s "
                             "not shown." % (bench["ignored"],
                                             "y" if bench["ignored"] == 1 else "ies",
                                             "is" if bench["ignored"] == 1 else "are")))
    return "".join(out)


# --------------------------------------------------------------------------
# Settings and "About"

ABOUT = {
    "energy": (
        "Every integrator runs the same scene with the same step. Explicit Euler gains energy "
        "every step (by the factor 1 + w²h² on an oscillator) until the run is stopped as "
        "diverged; symplectic Euler and Verlet keep the error bounded — it oscillates but does "
        "not drift — and implicit midpoint conserves it. Implicit Euler and its linearized "
        "variant lose energy (artificial damping, the curve heads down), RK4 drifts slowly, and "
        "the adaptive SUNDIALS methods stay flat to within their tolerance."),
    "stability": (
        "For each stiffness k the largest step that does not blow up, found by bisection, next "
        "to the limit theory predicts from the highest frequency w_max (2/w_max for symplectic "
        "Euler and Verlet, 2√2/w_max for RK4). The points should sit on their dashed lines "
        "(ratio ≈ 1) and fall like 1/√k: a 100 times stiffer spring needs a 10 times smaller "
        "step. A-stable implicit methods have no limit, and the map shows how the energy "
        "behaves on both sides of the boundary: white kept, red gained, blue lost."),
    "convergence": (
        "The error at the end against the step on log-log axes is a straight line whose slope "
        "is the order: halving dt divides the error by 2 for Euler, 4 for Verlet and implicit "
        "midpoint, 16 for RK4. Adaptive methods are plotted against their tolerance and should "
        "have slope ≈ 1 (error proportional to tolerance); a flat floor is round-off or the "
        "reference's own accuracy, missing points at large dt are runs that diverged."),
    "work-precision": (
        "Which method reaches a given accuracy for the least work: further down and to the left "
        "is better. High-order methods win when high accuracy is wanted; explicit methods are "
        "cheap per step but need many steps on stiff scenes, implicit ones pay for Newton solves "
        "per step but can take large steps."),
    "damping-budget": (
        "With drag and spring damping the mechanical energy must fall, by exactly the work the "
        "damping forces did. What is left over is the integrator's own contribution: positive "
        "when it adds energy (explicit Euler), negative when it damps on its own (implicit "
        "Euler), and close to zero for accurate methods — compare it with the physical "
        "dissipation drawn in black."),
    "cloth-showcase": (
        "The same cloth, the same step, a few integrators, seen at a few instants. Explicit "
        "methods at a step this large blow up (the last good frame is shown), implicit Euler "
        "stays stable but its cloth looks sluggish and over-damped, and the accurate methods "
        "swing freely."),
    "bench": (
        "The CPU time of one step as the scene grows: on log-log axes the slope is the "
        "exponent with which the cost grows. Explicit methods should be close to linear in the "
        "number of particles; implicit ones pay for a sparse factorisation per Newton "
        "iteration, which grows faster. Beside it: springlab's explicit steps against "
        "Boost.Odeint's on the same model, the cost of one force evaluation per spring, and "
        "the linear solvers an implicit method can use, on the same matrix."),
}

KIND_TITLES = {
    "energy": "Energy over time",
    "stability": "Stability limit",
    "convergence": "Convergence order",
    "work-precision": "Work against precision",
    "damping-budget": "Damping budget",
    "cloth-showcase": "Cloth showcase",
}


def settings_html(exp, styles):
    s = exp.settings
    if s is None:
        return ""
    out = ["<h3>Scene and settings used <small>(%s)</small></h3>\n" % esc(exp.settings_path.name)]
    desc = s.get("description")
    if isinstance(desc, str) and desc:
        out.append("<p class=\"desc\">%s</p>\n" % esc(desc))
    integ = s.get("integrators")
    asked = (s.get("definition") or {}).get("integrators") if isinstance(s.get("definition"),
                                                                        dict) else None
    if isinstance(integ, list):
        names = [str(x) for x in integ]
        out.append("<p><b>Integrators</b>%s: %s</p>\n" % (
            " (asked for: %s)" % esc(json.dumps(asked)) if asked is not None and asked != integ
            else "", ", ".join(swatch(styles, n) for n in names)))
    elif integ is not None:
        out.append("<p><b>Integrators</b>: %s</p>\n" % esc(json.dumps(integ)))
    simple = []
    for k, v in s.items():
        if k in ("name", "experiment", "title", "description", "integrators", "definition"):
            continue
        if isinstance(v, (int, float, str)) and not isinstance(v, bool) or \
                (isinstance(v, list) and len(v) <= 40 and all(isinstance(x, (int, float, str))
                                                              for x in v)):
            simple.append("<tr><th>%s</th><td>%s</td></tr>" % (esc(k), esc(json.dumps(v))))
    if simple:
        out.append("<table class=\"kv\">%s</table>\n" % "".join(simple))
    scenes = find_scenes(s)
    seen = []
    for path, scene, ctx in scenes:
        text = compact_json(scene)
        name = scene.get("name", path) if isinstance(scene.get("name"), str) else path
        extra = ", ".join("%s = %s" % (k, json.dumps(v)) for k, v in ctx.items())
        npart, nspring = len(scene.get("particles") or []), len(scene.get("springs") or [])
        label = "Scene %s%s — %d particle%s, %d spring%s" % (
            esc(name), " (%s)" % esc(extra) if extra else "", npart, "" if npart == 1 else "s",
            nspring, "" if nspring == 1 else "s")
        if text in seen:
            out.append("<p>%s: as above.</p>\n" % label)
            continue
        seen.append(text)
        out.append("<details><summary>%s</summary><pre>%s</pre></details>\n" % (label, esc(text)))
    out.append("<details><summary>The complete settings file %s</summary><pre>%s</pre></details>\n"
               % (esc(exp.settings_path.name), esc(compact_json(s))))
    return "".join(out)


# --------------------------------------------------------------------------
# The page

CSS = """
body { font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 0 auto;
       max-width: 1400px; padding: 0 1.5em 3em; color: #222; line-height: 1.45; }
h1 { margin-top: 0.8em; } h2 { border-bottom: 2px solid #ddd; padding-bottom: 0.2em; margin-top: 2em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.92em; color: #444; max-width: 70em; }
table { border-collapse: collapse; margin: 0.6em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }
th { background: #f3f3f3; } td { font-variant-numeric: tabular-nums; }
tr.off td { background: #ffe1dc; }
table.kv th { font-weight: normal; color: #555; }
.sw { display: inline-block; width: 0.9em; height: 0.9em; margin-right: 0.35em;
      vertical-align: -0.1em; border-radius: 2px; }
.report-note { background: #fff8d6; border-left: 4px solid #e0b400; padding: 0.4em 0.8em; }
.report-error { background: #ffd9d9; border-left: 4px solid #c00000; padding: 0.4em 0.8em;
                white-space: pre-wrap; font-family: monospace; }
pre { background: #f7f7f7; padding: 0.6em; overflow-x: auto; font-size: 0.82em; max-height: 40em; }
details { margin: 0.4em 0; } summary { cursor: pointer; }
.about dt { font-weight: bold; margin-top: 0.6em; } .about dd { margin-left: 1.2em; }
#report-status { color: #888; font-size: 0.8em; margin-top: 3em; }
"""

# Marks the page for tests/report/check_report.py: counts images that did not
# load, and turns script errors and failed images into .report-error elements.
SCRIPT = """
(function () {
  function fail(text) {
    var d = document.createElement('div');
    d.className = 'report-error';
    d.textContent = text;
    (document.body || document.documentElement).appendChild(d);
  }
  window.addEventListener('error', function (e) {
    var t = e.target;
    if (t && t.tagName === 'IMG') fail('image failed to load: ' + (t.alt || t.src.slice(0, 60)));
    else fail('script error: ' + e.message);
  }, true);
  window.addEventListener('load', function () {
    var imgs = document.images, broken = [];
    for (var i = 0; i < imgs.length; i++) {
      if (!imgs[i].complete || imgs[i].naturalWidth === 0) broken.push(imgs[i].alt || ('#' + i));
    }
    document.body.dataset.imagesTotal = String(imgs.length);
    document.body.dataset.imagesBroken = String(broken.length);
    var s = document.getElementById('report-status');
    s.dataset.state = 'checked';
    s.textContent = 'Page check: ' + imgs.length + ' images, ' + broken.length + ' broken' +
      (broken.length ? ' (' + broken.join(', ') + ')' : '') + '.';
  });
})();
"""


def section(exp, styles, figs, errors):
    """One experiment's section; a failure in a figure shows as .report-error."""
    kind = exp.kind
    body = []
    for note in exp.notes:
        body.append(note_html(esc(note)))

    def attempt(what, fn, *args):
        try:
            body.append(fn(*args))
        except Exception:  # noqa: BLE001 - shown on the page and in the exit status
            plt.close("all")
            tb = traceback.format_exc()
            errors.append("%s (%s): %s" % (exp.name, what, tb.strip().splitlines()[-1]))
            body.append('<div class="report-error">%s failed:\n%s</div>\n' % (esc(what), esc(tb)))

    t = exp.tables
    if kind == "energy":
        if "energy" in t:
            attempt("energy figure", energy_figure, exp, styles, figs)
    elif kind == "stability":
        if "stability" in t:
            body.append("<h3>Largest stable step</h3>\n")
            attempt("stability figure", stability_figure, exp, styles, figs)
            attempt("stability table", stability_table, exp, styles)
        if "stability-map" in t:
            body.append("<h3>Stability map</h3>\n")
            attempt("stability map", stability_map_figure, exp, styles, figs)
    elif kind == "convergence":
        if "convergence" in t:
            attempt("convergence figure", convergence_figure, exp, styles, figs)
        if "convergence-orders" in t:
            attempt("orders table", orders_table, exp, styles)
    elif kind == "work-precision":
        if "work-precision" in t:
            attempt("work-precision figure", work_precision_figure, exp, styles, figs)
    elif kind == "damping-budget":
        if "damping-budget" in t:
            attempt("damping-budget figure", damping_figure, exp, styles, figs)
    elif kind == "cloth-showcase":
        if "cloth-showcase" in t:
            attempt("cloth figure", cloth_figure, exp, styles, figs)
    if not t:
        body.append(note_html("No data for this experiment: skipped."))
    attempt("settings", settings_html, exp, styles)
    head = '<section id="%s"><h2>%s <small>(%s: %s)</small></h2>\n' % (
        esc(exp.name), esc(exp.title()), esc(exp.kind), esc(exp.name))
    return head + "".join(body) + "</section>\n"


def build_page(data_dir, experiments, page_notes, bench, bench_note, styles, figs):
    errors = []
    sections = []
    found = set(e.kind for e in experiments)
    toc = []
    for e in experiments:
        toc.append('<li><a href="#%s">%s</a></li>' % (esc(e.name), esc(e.title())))
        sections.append(section(e, styles, figs, errors))
    missing = [k for k in KIND_ORDER if k not in found]
    if bench is not None:
        toc.append('<li><a href="#bench">Step cost (benchmarks)</a></li>')
        try:
            sections.append('<section id="bench"><h2>Step cost <small>(%s)</small></h2>\n%s'
                            '</section>\n' % (esc(Path(bench["path"]).name),
                                              bench_section(bench, styles, figs)))
        except Exception:  # noqa: BLE001
            plt.close("all")
            tb = traceback.format_exc()
            errors.append("benchmarks: %s" % tb.strip().splitlines()[-1])
            sections.append('<section id="bench"><h2>Step cost</h2><div class="report-error">'
                            'benchmark section failed:\n%s</div></section>\n' % esc(tb))
    try:
        key = colour_key(styles, figs)
    except Exception:  # noqa: BLE001
        plt.close("all")
        tb = traceback.format_exc()
        errors.append("colour key: %s" % tb.strip().splitlines()[-1])
        key = '<div class="report-error">colour key failed:\n%s</div>\n' % esc(tb)

    about = ['<section id="about"><h2>About: what to look for</h2>\n<dl class="about">\n']
    for k in KIND_ORDER:
        names = [e for e in experiments if e.kind == k]
        title = " / ".join(esc(e.title()) for e in names) if names else esc(KIND_TITLES[k])
        about.append("<dt>%s <small>(%s)</small></dt><dd>%s%s</dd>\n" % (
            title, esc(k), esc(ABOUT[k]), "" if names else " <i>(not in this data set)</i>"))
    about.append("<dt>Step cost <small>(benchmarks)</small></dt><dd>%s%s</dd>\n" % (
        esc(ABOUT["bench"]), "" if bench is not None else " <i>(no benchmark file)</i>"))
    about.append("</dl></section>\n")

    notes = []
    for k in missing:
        notes.append("%s: no files for this experiment in the data directory (%s.json, %s): "
                     "skipped." % (KIND_TITLES[k], k, ", ".join(k + s + ".csv" for s in KINDS[k])))
    notes += page_notes
    if bench_note:
        notes.append(bench_note)

    out = ["<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
           "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
           "<title>springlab report</title>\n<style>%s</style>\n<script>%s</script>\n</head>\n"
           "<body>\n" % (CSS, SCRIPT)]
    out.append("<h1>springlab — integrators on mass-spring systems</h1>\n")
    out.append("<p>Experiment results from <code>%s/</code>, rendered by "
               "<code>report/make_report.py</code>. Each section shows the figures, the "
               "measured against theoretical numbers, and the scene and settings that produced "
               "them.</p>\n" % esc(data_dir.name or str(data_dir)))
    if errors:
        out.append('<div class="report-error">%d part%s of this report failed to render: %s</div>\n'
                   % (len(errors), "" if len(errors) == 1 else "s", esc("; ".join(errors))))
    for n in notes:
        out.append(note_html(esc(n)))
    out.append("<nav><b>Contents</b><ul>%s<li><a href=\"#about\">About: what to look for</a>"
               "</li><li><a href=\"#colours\">Integrators and their colours</a></li></ul></nav>\n"
               % "".join(toc))
    out.append(about[0] + "".join(about[1:]))
    out.append(key)
    out.extend(sections)
    out.append('<p id="report-status" data-state="pending">Page check pending (needs '
               'JavaScript).</p>\n</body>\n</html>\n')
    return "".join(out), errors


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True, help="directory with the experiment CSV/JSON files")
    ap.add_argument("--out", required=True, help="output directory (index.html and PNGs)")
    ap.add_argument("--bench", help="Google Benchmark JSON file from springlab_bench (default: "
                    "%s in the data directory, when it is there)" % BENCH_FILE)
    args = ap.parse_args(argv)

    data_dir = Path(args.data)
    if not data_dir.is_dir():
        sys.stderr.write("%s: error: %s: not a directory\n" % (PROG, data_dir))
        return 1
    plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "svg.hashsalt": "springlab",
                         "path.simplify": True, "agg.path.chunksize": 20000})
    try:
        experiments, page_notes = load_data(data_dir)
        bench_path = Path(args.bench) if args.bench else data_dir / BENCH_FILE
        bench = read_bench(bench_path) if args.bench or bench_path.is_file() else None
    except DataError as exc:
        sys.stderr.write("%s: error: %s\n" % (PROG, exc))
        return 1
    bench_note = None if bench is not None else \
        ("Step cost: no benchmark file (%s in the data directory, or --bench FILE.json): "
         "skipped. `cmake --build --preset bench` makes one." % BENCH_FILE)
    outdir = Path(args.out)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        sys.stderr.write("%s: error: %s: cannot create (%s)\n" % (PROG, outdir, exc.strerror))
        return 1
    styles = collect_styles(experiments, bench)
    figs = Figures(outdir)
    page, errors = build_page(data_dir.resolve(), experiments, page_notes, bench, bench_note,
                              styles, figs)
    tmp = outdir / "index.html.tmp"
    tmp.write_text(page, encoding="utf-8")
    os.replace(tmp, outdir / "index.html")
    for e in errors:
        sys.stderr.write("%s: error: %s\n" % (PROG, e))
    print("%s: wrote %s (%d figures)%s" % (PROG, outdir / "index.html", len(figs.saved),
                                           "; %d part(s) failed" % len(errors) if errors else ""))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
