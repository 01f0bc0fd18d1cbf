"""damping-budget: with drag and spring damping the mechanical energy must
fall by exactly the work W_nc of those forces; what is left,
numerical = E - W_nc - E(0), is the integrator's own energy change. Drawn
like the energy figure: one row per case, one panel per family, as a
fraction of the physical dissipation |W_nc(T)| on a linear axis."""

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, fraction
from .common import FamilyGrid, case_panels, panel_title
from .energy import classify

KIND = "damping-budget"
TITLE = "Damping budget"
ABOUT = (
    "With drag and spring damping the mechanical energy must fall, by exactly the work W_nc the "
    "damping forces do. What is left over, E − W_nc − E(0), is the integrator's own "
    "contribution: theory says it is positive for a method that adds energy (explicit Euler), "
    "negative for one that damps on its own (implicit Euler), and small for an accurate one. It "
    "is shown as a fraction of the physical dissipation |W_nc(T)|, so a value of −0.3 means the "
    "integrator removed 30% more than the physics did. W_nc is integrated with the trapezoid "
    "rule on the output grid, which has an error of its own of order dt².")


def render(exp, ctx):
    integ = ctx.integrators
    db = Columns(exp.table(), numbers=("t", "mechanical", "work_nonconservative", "numerical"),
                 texts=("task", "scene", "integrator", "dt"))
    panels = case_panels(db.table)
    grid = FamilyGrid(integ, panels, "(E − W_nc − E(0)) / |W_nc(T)|")
    facts = []
    for row, ((scene, dt, case), series) in enumerate(panels.items()):
        t_max = max(float(db["t"][idx][-1]) for idx in series.values())
        best, scale = reference_dissipation(db, series, t_max)
        title = panel_title(scene, dt, case, panels)
        facts.append("%s: the physical dissipation |W_nc(T)| is %s J (from %s, the run with the "
                     "smallest numerical change)." % (title, fmt(scale, 4), best))
        groups = {}
        for col, family in enumerate(grid.families):
            names = grid.members(series, family)
            for k, name in enumerate(names):
                idx = series[name]
                t = db["t"][idx]
                y = db["numerical"][idx] / scale
                stopped = t[-1] < t_max * (1 - 1e-9)
                if stopped:
                    text = "stops at t = %s s" % fmt(float(t[-1]), 4)
                    groups.setdefault("stops", []).append("%s (t = %s s)" % (name,
                                                                             fmt(float(t[-1]), 4)))
                else:
                    behaviour, value = classify(t, y)
                    text = describe(behaviour, value)
                    groups.setdefault(behaviour, []).append((name, value))
                grid.line(grid.axes[row, col], name, k, t, y, "%s: %s" % (name, text), stopped)
            grid.finish(row, col, title, t_max, names)
        facts.append(case_sentence(title, groups))
    saved = ctx.figs.save(grid.fig, exp.name + ".png")
    caption = ("The integrator's own energy change E − W_nc − E(0) (positive: it added energy), "
               "as a fraction of the physical dissipation |W_nc(T)| of the case, one row per "
               "case, one panel per family, each on its own linear scale. Each label says what "
               "the run did (as in the energy figure); ✕ marks a run that stopped early.")
    return figure_html(saved, "damping budget", esc(caption)) + facts_html(facts)


def reference_dissipation(db, series, t_max):
    """|W_nc(T)| of the completed run with the smallest numerical change."""
    best, best_err = None, np.inf
    for name, idx in series.items():
        num = db["numerical"][idx]
        if db["t"][idx][-1] >= t_max * (1 - 1e-9) and np.all(np.isfinite(num)):
            err = float(np.max(np.abs(num)))
            if err < best_err or (err == best_err and name < best):
                best, best_err = name, err
    if best is None:
        best = sorted(series)[0]
    scale = abs(float(db["work_nonconservative"][series[best]][-1]))
    return best, scale if scale > 0 else 1.0


def describe(behaviour, value):
    pc = fraction(value)
    if behaviour == "flat":
        return "|.| ≤ %s" % pc
    if behaviour == "oscillates":
        return "oscillates within ±%s" % pc
    return "%s %s" % ("adds" if value > 0 else "removes", pc)


def case_sentence(title, groups):
    parts = []
    if groups.get("stops"):
        parts.append("stop early: %s" % ", ".join(groups["stops"]))
    for key, verb in (("gains", "add energy of their own"), ("loses", "remove energy of their own"),
                      ("oscillates", "oscillate without drift"), ("flat", "stay within 1e-6")):
        items = groups.get(key)
        if items:
            parts.append("%s: %s" % (verb, ", ".join("%s (%s)" % (n, describe(key, v).split(
                " ", 1)[-1] if key in ("gains", "loses") else describe(key, v)) for n, v in items)))
    return "%s, as a fraction of |W_nc(T)| — %s." % (title, "; ".join(parts))
