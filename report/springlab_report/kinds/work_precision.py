"""work-precision: error against cost (wall time, force evaluations) on one
scene, fixed-step methods over a step sweep, adaptive ones over a tolerance
sweep; and, computed from the points, who reaches a given accuracy for the
least work."""

import numpy as np

from ..data import Columns
from ..figures import (count, esc, facts_html, figure_html, finite_positive, fmt, legend_outside,
                       log_log, new_figure)

KIND = "work-precision"
TITLE = "Work against precision"
ABOUT = (
    "Which method reaches a given accuracy for the least work: further down and to the left is "
    "better. High-order methods pay off when high accuracy is wanted; explicit methods are "
    "cheap per step but need many steps on stiff scenes, implicit ones pay for Newton solves per "
    "step but can take large steps. Wall time is the minimum over repeats; force evaluations "
    "do not depend on the machine.")

ERROR_LABEL = "max |x − x_ref| at t_end [m]"
COSTS = (("wall_seconds", "wall time [s]", "wall time"),
         ("force_evals", "force evaluations", "force evaluations"))


def render(exp, ctx):
    integ = ctx.integrators
    wp = Columns(exp.table(), numbers=("value", "error", "wall_seconds", "force_evals"),
                 texts=("scene", "integrator", "status"))
    scenes = wp.groups("scene")
    fig = new_figure(13.5, 5.2 * len(scenes))
    axes = fig.subplots(len(scenes), 2, squeeze=False)
    skipped, facts = 0, []
    for row, ((scene,), sidx) in enumerate(scenes.items()):
        series = {}
        for r in sidx:
            series.setdefault(wp["integrator"][r], []).append(r)
        for col, (cost, xlabel, what) in enumerate(COSTS):
            ax = axes[row, col]
            drawn = {}
            for name in integ.sort(series):
                rows = np.asarray(series[name])
                rows = rows[np.argsort(wp["value"][rows], kind="stable")]
                err, x = wp["error"][rows], wp[cost][rows]
                ok = np.array([wp["status"][r] == "completed" for r in rows]) & \
                    finite_positive(err, x)
                if col == 0:
                    skipped += int((~ok).sum())
                drawn[name] = (x[ok], err[ok])
                ax.plot(x[ok], err[ok], ms=6, mfc="none", mew=1.3, lw=1.5,
                        label=name + ("" if ok.any() else "  (no valid point)"),
                        **integ.style(name))
            log_log(ax)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ERROR_LABEL)
            ax.set_title("%s — error against %s" % (scene, what), loc="left", fontweight="bold")
            ax.grid(True, which="major", alpha=0.3)
            ax.grid(True, which="minor", alpha=0.1)
            facts.extend(least_work(scene, drawn, what))
        legend_outside(axes[row, 1])
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = ("Accuracy against cost: fixed-step methods over a step sweep (solid), adaptive ones "
               "over a tolerance sweep (dashed). Lower left is better.")
    if skipped:
        caption += (" %d point%s not drawn (status not completed, or error/cost not a positive "
                    "finite number)." % (skipped, "" if skipped == 1 else "s"))
    return figure_html(saved, "work-precision", esc(caption)) + facts_html(facts)


def least_work(scene, drawn, what):
    """The cost each method needed for an error of at most a target: 1e-4 m
    and 1e-8 m when reached by some method; the three cheapest of each."""
    out = []
    for target in (1e-4, 1e-8):
        costs = []
        for name, (x, err) in drawn.items():
            ok = err <= target
            if ok.any():
                costs.append((float(np.min(x[ok])), name))
        if len(costs) < 2:
            continue
        costs.sort()
        shown = ", ".join("%s %s" % (n, fmt(c, 3) if what == "wall time" else count(c))
                          for c, n in costs[:3])
        missing = len(drawn) - len(costs)
        out.append("%s, error at most %s m, least %s: %s%s%s." % (
            scene, fmt(target), what, shown, " (%d more reached it)" % (len(costs) - 3)
            if len(costs) > 3 else "", "; %d method%s never did" % (
                missing, "" if missing == 1 else "s") if missing else ""))
    return out
