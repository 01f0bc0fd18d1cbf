"""What the report knows about integrators: only what `springlab list --json`
wrote into integrators.json (name, family, order, adaptive, stability,
colour, marker). Every figure draws a method with its own colour and marker
from there, so it looks the same in every figure of every report.

Without that file (data from an older springlab) the facts the tables carry
are used (the `adaptive` column) and colours come from a fixed palette by a
hash of the name: still the same in every report, but not the program's.
"""

import zlib

from .data import DataError, read_json

FAMILIES = ("explicit", "symplectic", "implicit", "adaptive")
FAMILY_TITLES = {"explicit": "explicit", "symplectic": "symplectic", "implicit": "implicit",
                 "adaptive": "adaptive (SUNDIALS)", "unknown": "unknown family"}
_FALLBACK_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                     "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#000000", "#393b79"]
_FALLBACK_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "<", ">", "h", "p", "*"]
# Colours for the methods an experiment brought (plug-ins, Python classes):
# none is a built-in's (the style table of experiments/cli/integrator_table.cc).
_OWN_COLOURS = ["#e6550d", "#3182bd", "#31a354", "#756bb1", "#d6616b", "#636363", "#fdae6b",
                "#9ecae1"]
_OWN_MARKERS = ["$a$", "$b$", "$c$", "$d$", "$e$", "$f$", "$g$", "$k$"]
# Colours for a second variant of one integrator in a figure (dark, so they
# read apart from the integrators' own colours).
_VARIANT_COLOURS = ["#000000", "#8c564b", "#1f77b4", "#ff7f0e", "#2ca02c", "#17becf",
                    "#393b79", "#7f7f7f"]


class Integrators:
    def __init__(self, entries, source):
        self.entries = entries    # name -> dict
        self.source = source      # the file read, or None
        self.order_index = {n: k for k, n in enumerate(sorted(entries))}

    @classmethod
    def load(cls, path):
        if not path.is_file():
            return cls({}, None)
        doc = read_json(path)
        items = doc.get("integrators") if isinstance(doc, dict) else None
        if not isinstance(items, list):
            raise DataError(path, None, "expected {\"integrators\": [...]} (springlab list --json)")
        entries = {}
        for j, e in enumerate(items):
            if not isinstance(e, dict) or not isinstance(e.get("name"), str):
                raise DataError(path, None, "integrators[%d]: expected an object with a name" % j)
            entries[e["name"]] = e
        return cls(entries, path)

    def learn(self, name, adaptive=None):
        """A method seen in the data but not in integrators.json."""
        if name not in self.entries:
            self.entries[name] = {"name": name, "missing": True}
            if adaptive is not None:
                self.entries[name]["adaptive"] = bool(adaptive)

    def learn_entry(self, entry):
        """A method an experiment brought (a plug-in's, a Python class's):
        the facts its settings file lists under "own_integrators", in the
        form of integrators.json's entries but without a colour. It gets a
        colour and marker no listed method has, so it reads apart from the
        built-in it lies on (in the order the experiments list them)."""
        name = entry.get("name") if isinstance(entry, dict) else None
        if not isinstance(name, str) or (name in self.entries
                                          and not self.entries[name].get("missing")):
            return
        used = {e.get("colour") for e in self.entries.values()}
        spare = [c for c in _OWN_COLOURS if c not in used]
        used_markers = {e.get("marker") for e in self.entries.values()}
        spare_markers = [m for m in _OWN_MARKERS if m not in used_markers]
        self.entries[name] = dict(entry, own=True)
        if spare:
            self.entries[name]["colour"] = spare[0]
        if spare_markers:
            self.entries[name]["marker"] = spare_markers[0]

    def missing(self):
        return sorted(n for n, e in self.entries.items() if e.get("missing"))

    def get(self, name, key, default=None):
        return self.entries.get(name, {}).get(key, default)

    def colour(self, name):
        c = self.get(name, "colour")
        if isinstance(c, str):
            return c
        return _FALLBACK_COLOURS[zlib.crc32(name.encode()) % len(_FALLBACK_COLOURS)]

    def marker(self, name):
        m = self.get(name, "marker")
        if isinstance(m, str):
            return m
        return _FALLBACK_MARKERS[zlib.crc32(name.encode()) // 7 % len(_FALLBACK_MARKERS)]

    def adaptive(self, name):
        return bool(self.get(name, "adaptive", False))

    def family(self, name):
        f = self.get(name, "family")
        if isinstance(f, str):
            return f
        return "adaptive" if self.adaptive(name) else "unknown"

    def order(self, name):
        return self.get(name, "order")

    def stability(self, name):
        s = self.get(name, "stability")
        return s if isinstance(s, dict) else {}

    def linestyle(self, name):
        return "--" if self.adaptive(name) else "-"

    def style(self, name, **extra):
        """matplotlib keywords: colour, marker, line style."""
        kw = dict(color=self.colour(name), marker=self.marker(name), ls=self.linestyle(name))
        kw.update(extra)
        return kw

    def variant_styles(self, runs):
        """Styles for runs (integrator, variant) drawn side by side: each
        integrator's first run in its own colour and marker, a further
        variant of the same integrator in a colour and marker no other run
        of the figure uses, so that no two runs look alike."""
        used_colours = {self.colour(n) for n, _ in runs}
        used_markers = {self.marker(n) for n, _ in runs}
        spare_colours = [c for c in _VARIANT_COLOURS if c not in used_colours]
        spare_markers = [m for m in _FALLBACK_MARKERS if m not in used_markers]
        seen, out, extra = set(), {}, 0
        for name, variant in runs:
            if name not in seen:
                seen.add(name)
                out[(name, variant)] = self.style(name)
                continue
            out[(name, variant)] = self.style(
                name,
                color=spare_colours[extra % len(spare_colours)] if spare_colours
                else self.colour(name),
                marker=spare_markers[extra % len(spare_markers)] if spare_markers
                else self.marker(name))
            extra += 1
        return out

    def sort(self, names):
        """By family (explicit, symplectic, implicit, adaptive), then by name."""
        def key(n):
            f = self.family(n)
            return (FAMILIES.index(f) if f in FAMILIES else len(FAMILIES), n)
        return sorted(set(names), key=key)
