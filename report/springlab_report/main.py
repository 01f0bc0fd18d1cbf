"""Reading the data directory and writing the page (make_report.py's work)."""

import argparse
import multiprocessing
import os
import shutil
import sys
from pathlib import Path

import matplotlib.pyplot as plt

from . import bench as bench_section
from .data import DataError, load_experiments
from .figures import RC, Figures, esc
from .integrators import Integrators
from .kinds import KINDS
from .page import Context, DataFiles, attempt, integrators_html, page, section

PROG = "make_report.py"
INTEGRATORS_FILE = "integrators.json"
LAB_FILE = "lab.html"  # the lab page's name next to index.html


def collect_names(experiments, integrators):
    """Every integrator the data names; methods integrators.json does not
    list are learned from the settings' "own_integrators" (a plug-in's or a
    Python class's facts) or else from the tables (their `adaptive` column
    where there is one)."""
    names = set()
    for e in experiments:
        # Methods the experiment brought (plug-ins, Python classes): their facts.
        for entry in e.settings.get("own_integrators", []) or []:
            integrators.learn_entry(entry)
        for t in e.tables.values():
            if not t.has("integrator"):
                continue
            col = t.text("integrator")
            adaptive = t.num("adaptive") if t.has("adaptive") else None
            for r, n in enumerate(col):
                names.add(n)
                integrators.learn(n, None if adaptive is None else adaptive[r])
    return names


def lab_html(lab, outdir, notes):
    """The link to the lab page (docs/browser-lab.md) when `lab` is a file:
    copied to OUTDIR/lab.html, so the report folder stays self-contained;
    otherwise a note on how to build it."""
    if not lab:
        return ""
    source = Path(lab)
    if not source.is_file():
        notes.append("The lab page (%s) is not built: `cmake --workflow --preset web` builds it; "
                     "draw the report again to link it." % source)
        (outdir / LAB_FILE).unlink(missing_ok=True)  # no stale copy
        return ""
    shutil.copyfile(source, outdir / LAB_FILE)
    return ('<p class="lab-link"><a href="%s"><b>The lab</b></a>: the same models and '
            "integrators live in the browser (WebAssembly), side by side, with the step size on "
            "a slider and its stability limit marked; drag the cloth with the mouse.</p>\n"
            % LAB_FILE)


# What the forked workers of render_sections read (set just before the fork).
_SECTIONS = None


def _render_one(i):
    """Section i in a worker: its HTML, its errors, and the figures and data
    files it wrote (the parent adds them to its own lists)."""
    experiments, ctx, firsts = _SECTIONS
    errors = []
    saved, copied = len(ctx.figs.saved), len(ctx.files.copied)
    html = section(experiments[i], KINDS[experiments[i].kind], ctx, errors, firsts[i])
    return html, errors, ctx.figs.saved[saved:], ctx.files.copied[copied:]


def render_sections(experiments, ctx, firsts):
    """Every experiment's section, in order, drawn on up to two CPUs at once
    (forked workers: each section's figures depend only on its own data, so
    the page is the same byte for byte as drawn one by one)."""
    global _SECTIONS
    workers = min(2, len(os.sched_getaffinity(0)), len(experiments))
    if workers < 2 or "fork" not in multiprocessing.get_all_start_methods():
        results = []
        for i, e in enumerate(experiments):
            errors = []
            results.append((section(e, KINDS[e.kind], ctx, errors, firsts[i]), errors, [], []))
        return results
    _SECTIONS = (experiments, ctx, firsts)
    try:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            results = pool.map(_render_one, range(len(experiments)), chunksize=1)
    finally:
        _SECTIONS = None
    for _, _, saved, copied in results:
        ctx.figs.saved.extend(saved)
        ctx.files.copied.extend(c for c in copied if c not in ctx.files.copied)
    return results


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description="Render the springlab course experiments "
                                 "as one HTML page.")
    ap.add_argument("--data", required=True, help="directory with the experiment CSV/JSON files "
                    "and integrators.json")
    ap.add_argument("--out", required=True, help="output directory (index.html and PNGs)")
    ap.add_argument("--bench", help="Google Benchmark JSON file from springlab_bench (default: "
                    "%s in the data directory, when it is there)" % bench_section.BENCH_FILE)
    ap.add_argument("--lab", help="the lab page (build/web/lab.html): copied next to index.html "
                    "and linked from it when the file exists")
    args = ap.parse_args(argv)

    data_dir = Path(args.data)
    if not data_dir.is_dir():
        sys.stderr.write("%s: error: %s: not a directory\n" % (PROG, data_dir))
        return 1
    plt.rcParams.update(RC)
    try:
        integrators = Integrators.load(data_dir / INTEGRATORS_FILE)
        experiments, notes = load_experiments(data_dir, KINDS)
        bench_path = Path(args.bench) if args.bench else data_dir / bench_section.BENCH_FILE
        bench = bench_section.read_bench(bench_path) if args.bench or bench_path.is_file() \
            else None
    except DataError as exc:
        sys.stderr.write("%s: error: %s\n" % (PROG, exc))
        return 1
    outdir = Path(args.out)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        sys.stderr.write("%s: error: %s: cannot create (%s)\n" % (PROG, outdir, exc.strerror))
        return 1

    order = list(KINDS)
    experiments.sort(key=lambda e: (order.index(e.kind), e.name))
    try:
        names = collect_names(experiments, integrators)
    except DataError as exc:
        sys.stderr.write("%s: error: %s\n" % (PROG, exc))
        return 1
    if bench is not None:
        for b in bench["entries"]:
            names.add(b["integrator"])
            integrators.learn(b["integrator"], b["kind"] == "adaptive")
    if integrators.source is None:
        notes.append("%s is missing from the data directory (`springlab list --json > %s/%s` "
                     "writes it): colours come from a fixed palette and the families and "
                     "stability of the methods are unknown." % (INTEGRATORS_FILE, data_dir,
                                                                INTEGRATORS_FILE))
    elif integrators.missing():
        notes.append("%s does not list %s (data from another springlab?): drawn in palette "
                     "colours." % (INTEGRATORS_FILE, ", ".join(integrators.missing())))
    found = set(e.kind for e in experiments)
    for kind, module in KINDS.items():
        if kind not in found:
            notes.append("%s (%s): no settings file of this kind in the data directory: skipped."
                         % (module.TITLE, kind))

    figs = Figures(outdir)
    files = DataFiles(outdir)
    ctx = Context(integrators, figs, files)
    errors = []
    toc = [("integrators", "The integrators")]
    body = [attempt(errors, "integrator table", integrators_html, integrators, names)]
    first_of_kind, firsts = {}, []
    for e in experiments:
        firsts.append(first_of_kind.get(e.kind))
        first_of_kind.setdefault(e.kind, (e.name, e.title()))
    for e, (html, section_errors, _, _) in zip(experiments,
                                                render_sections(experiments, ctx, firsts)):
        toc.append((e.name, e.title()))
        body.append(html)
        errors.extend(section_errors)
    if bench is not None:
        toc.append(("bench", "Step cost (benchmarks)"))
        body.append('<section id="bench"><h2>Step cost <small>(%s)</small></h2>\n%s</section>\n'
                    % (esc(Path(bench["path"]).name),
                       attempt(errors, "benchmarks", bench_section.render, bench, ctx)))
    else:
        notes.append("Step cost: no benchmark file (%s in the data directory, or --bench "
                     "FILE.json): skipped. `cmake --workflow --preset bench` makes one."
                     % bench_section.BENCH_FILE)
    intro = ("<p>Experiment results from <code>%s/</code>, drawn by <code>report/"
             "make_report.py</code>. Each section says what theory predicts, shows the figure, "
             "lists what the data shows (every such sentence is computed from the data), and the "
             "scene and settings that produced it.</p>\n" % esc(data_dir.resolve().name))
    intro += lab_html(args.lab, outdir, notes)
    html = page("springlab — time integrators on springs, solids, rigid bodies and fluids", intro,
                notes, toc, body, errors)
    tmp = outdir / "index.html.tmp"
    tmp.write_text(html, encoding="utf-8")
    os.replace(tmp, outdir / "index.html")
    # Files of an earlier report that this page no longer links.
    if files.dir.is_dir():
        for p in files.dir.iterdir():
            if p.name not in files.copied and p.is_file():
                p.unlink()
    for e in errors:
        sys.stderr.write("%s: error: %s\n" % (PROG, e))
    print("%s: wrote %s (%d figures)%s" % (PROG, outdir / "index.html", len(figs.saved),
                                           "; %d part(s) failed" % len(errors) if errors else ""))
    return 1 if errors else 0
