"""energy: mechanical energy over time, every integrator on the same scene
and step. One row of panels per case, one panel per family (explicit,
symplectic, implicit, adaptive), the energy change divided by the scene's
energy scale E_s on a linear axis, each panel on its own scale; every line's
label and the sentences under the figure are computed from the data."""

import numpy as np

from ..figures import esc, facts_html, figure_html, fmt, fraction, note_html
from .common import FamilyGrid, case_panels, panel_title, runs_table

KIND = "energy"
TITLE = "Energy over time"
ABOUT = (
    "Every integrator runs the same scene with the same step. What theory predicts for an "
    "undamped linear mode: explicit Euler multiplies its energy by 1 + w²h² every step; the "
    "symplectic methods (symplectic Euler, Verlet, implicit midpoint) conserve a nearby modified "
    "energy, so their energy error oscillates without drift; implicit Euler multiplies it by "
    "1/(1 + w²h²), an artificial damping; RK4 loses a little every step; the adaptive methods "
    "bound each step's local error, not the energy, so small losses can add up. The figure and "
    "the sentences under it say what these runs did.")

DEFAULT_ENERGY_COLUMNS = ["kinetic", "spring", "gravity", "total"]
FLAT = 1e-6  # |dE| / E_s below this counts as flat


def energy_columns(exp):
    cols = exp.setting("energy_columns")
    if isinstance(cols, list) and all(isinstance(c, str) for c in cols) and cols:
        return cols
    return DEFAULT_ENERGY_COLUMNS


def total_energy(table, columns):
    """The total mechanical energy per row: the `total` column, or the sum of
    the named energy columns when there is none."""
    if "total" in columns and table.has("total"):
        return table.num("total")
    parts = [c for c in columns if table.has(c)]
    return np.sum([table.num(c) for c in parts], axis=0)


def classify(t, e):
    """What a completed run's relative energy change e(t) = (E - E(0)) / E_s
    did: ("flat", max |e|) below FLAT; ("oscillates", max |e|) when the band
    of its last quarter is at most 1.5 times its first quarter's and it still
    comes back to within a tenth of that band of E(0); else ("loses" or
    "gains", e at the end)."""
    amax = float(np.max(np.abs(e))) if len(e) else 0.0
    if amax < FLAT or len(e) < 8:
        return "flat", amax
    q = max(1, (len(e) - 1) // 4)
    first, last = e[1:q + 1], e[-q:]
    a1, a4 = float(np.max(np.abs(first))), float(np.max(np.abs(last)))
    if a4 <= 1.5 * a1 and float(np.min(np.abs(last))) <= 0.1 * amax:
        return "oscillates", amax
    return ("loses" if float(np.mean(last)) < 0 else "gains"), float(e[-1])


def relative(x):
    """A fraction of E_s: "6.9%" or "4e-15"."""
    return fraction(x)


def describe(behaviour, value, t_end):
    if behaviour == "flat":
        return "|ΔE| ≤ %s E_s" % relative(value)
    if behaviour == "oscillates":
        return "oscillates within ±%s E_s, no drift" % relative(value)
    return "%s: %s%s E_s at t = %s s" % (behaviour, "+" if value > 0 else "−",
                                          relative(abs(value)), fmt(t_end, 4))


def render(exp, ctx):
    e = exp.table()
    runs = exp.table("runs")
    if e is None:
        return ""
    e.require("task", "scene", "integrator", "dt", "t")
    columns = energy_columns(exp)
    total = total_energy(e, columns)
    run_by = {}
    if runs is not None:
        runs.require("task", "integrator", "status", "diverged_at", "energy_initial",
                     "energy_scale")
        status = runs.status()
        for r in range(len(runs)):
            run_by[(runs.text("task")[r], runs.text("integrator")[r])] = {
                "status": status[r], "diverged_at": runs.num("diverged_at")[r],
                "e0": runs.num("energy_initial")[r], "es": runs.num("energy_scale")[r]}
    integ = ctx.integrators
    panels = case_panels(e)
    grid = FamilyGrid(integ, panels, "(E(t) − E(0)) / E_s")
    facts = []
    for row, ((scene, dt, case), series) in enumerate(panels.items()):
        t_max = max(float(e.num("t")[idx][-1]) for idx in series.values())
        groups = {}
        for col, family in enumerate(grid.families):
            names = grid.members(series, family)
            for k, name in enumerate(names):
                idx = series[name]
                t = e.num("t")[idx]
                run = run_by.get((e.text("task")[idx[0]], name), {})
                e0 = run.get("e0", np.nan)
                e0 = e0 if np.isfinite(e0) else float(total[idx][0])
                es = run.get("es", np.nan)
                es = es if np.isfinite(es) and es > 0 else (abs(e0) if e0 != 0 else 1.0)
                y = (total[idx] - e0) / es
                status = run.get("status", "completed")
                if status != "completed":
                    at = run.get("diverged_at", np.nan)
                    at = at if np.isfinite(at) else float(t[-1])
                    text = "%s at t = %s s" % (status, fmt(at, 4))
                    groups.setdefault("%s at" % status, []).append("%s (t = %s s)"
                                                                   % (name, fmt(at, 4)))
                else:
                    behaviour, value = classify(t, y)
                    text = describe(behaviour, value, float(t[-1]))
                    groups.setdefault(behaviour, []).append((name, value, float(t[-1])))
                grid.line(grid.axes[row, col], name, k, t, y, "%s: %s" % (name, text),
                          status != "completed")
            grid.finish(row, col, panel_title(scene, dt, case, panels), t_max, names)
        facts.append(case_sentence(panel_title(scene, dt, case, panels), groups))
        facts.extend(coincidences(scene, series, e, total))
    saved = ctx.figs.save(grid.fig, exp.name + ".png")
    caption = ("Change of the mechanical energy E = %s, divided by the scene's energy scale E_s "
               "(energy-runs.csv: energy_scale, so that scenes whose E(0) is 0 compare too), "
               "one row per case, one panel per family, each on its own linear scale. Each label "
               "says what that run did (computed: \"oscillates\" when the band of the last "
               "quarter of the run is at most 1.5 times the first quarter's and the energy still "
               "returns near E(0), else the change at the end); ✕ marks a run that diverged."
               % " + ".join(c for c in columns if c != "total"))
    out = [figure_html(saved, "energy over time", esc(caption)), facts_html(facts)]
    if runs is None:
        out.append(note_html("Without %s-runs.csv, E(0) is each run's first row and E_s = |E(0)|."
                             % esc(exp.name)))
    else:
        out.append(runs_table(runs, ctx.integrators, "Runs", [
            ("status", "status", None), ("diverged_at", "diverged at [s]", 4),
            ("steps", "steps", 10), ("force_evals", "force evals", 10),
            ("wall_seconds", "wall [s]", 3), ("energy_initial", "E(0) [J]", 5),
            ("energy_final", "E(end) [J]", 5), ("energy_scale", "E_s [J]", 4)]))
    return "".join(out)


def case_sentence(title, groups):
    parts = []
    for key, verb in (("diverged at", "diverged"), ("failed at", "failed"),
                      ("gains", "gain energy"), ("loses", "lose energy"),
                      ("oscillates", "oscillate without drift"), ("flat", "stay flat")):
        items = groups.get(key)
        if not items:
            continue
        if key in ("diverged at", "failed at"):
            parts.append("%s: %s" % (verb, ", ".join(items)))
        elif key == "oscillates":
            parts.append("%s: %s" % (verb, ", ".join("%s (±%s E_s)" % (n, relative(v))
                                                       for n, v, _ in items)))
        elif key == "flat":
            parts.append("%s (|ΔE| < %g E_s): %s" % (verb, FLAT, ", ".join(
                "%s (%s)" % (n, relative(v)) for n, v, _ in items)))
        else:
            parts.append("%s: %s" % (verb, ", ".join("%s (%s%s E_s by t = %s s)" % (
                n, "+" if v > 0 else "−", relative(abs(v)), fmt(te, 4)) for n, v, te in items)))
    return "%s — %s." % (title, "; ".join(parts))


def coincidences(scene, series, e, total):
    """Pairs of runs whose energies agree to within 1e-9 of E_s-sized numbers
    at every output: said, so that a line hidden under another is known."""
    out = []
    names = sorted(series)
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            ia, ib = series[names[a]], series[names[b]]
            if len(ia) != len(ib) or len(ia) < 2:
                continue
            ta, tb = e.num("t")[ia], e.num("t")[ib]
            ea, eb = total[ia], total[ib]
            scale = max(float(np.max(np.abs(ea))), float(np.max(np.abs(eb))), 1e-300)
            diff = float(np.max(np.abs(ea - eb)))
            if np.array_equal(ta, tb) and diff <= 1e-9 * scale:
                out.append("On %s, %s and %s have the same energy at every output (largest "
                           "difference %s J): their lines coincide." % (
                               scene, names[a], names[b], fmt(diff, 2)))
    return out
