"""solver-error: the ways of solving implicit Euler's step at frame rate,
each from the same states of a tightly solved implicit Euler run (README
"solver-error"): its distance to that step (solver error) and to the true
motion over the step (total error), against its cost per step, next to
implicit Euler's own discretization error. The sentences are computed from
the rows."""

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, legend_outside, new_figure

KIND = "solver-error"
TITLE = "Solving the step: solver error against discretization error"
ABOUT = (
    "Newton, quasi-Newton, projective dynamics, XPBD and the linearized step all approximate the "
    "same implicit Euler step, with more or less work. Theory: solving that step more tightly "
    "than implicit Euler's own error (its distance to the true motion over one step, the "
    "discretization error) buys nothing, since the step itself is only that accurate; a fast "
    "solver whose solver error stays below it is as good as Newton. XPBD's substeps are smaller "
    "implicit Euler steps, so they lower the discretization error too, and can land closer to "
    "the true motion than the exact implicit Euler step; an adaptive method solves the ODE itself "
    "to its tolerance, at a price.")

FLOOR = 1e-12


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("case", "step", "solver_error", "total_error",
                                       "discretization_error", "wall_seconds", "iterations"),
                 texts=("scene", "integrator", "variant", "status", "failure"))
    integ = ctx.integrators
    html = []
    cases = sorted({int(c) for c in db["case"]})
    for case in cases:
        rows = [r for r in range(len(db)) if int(db["case"][r]) == case]
        html.append(case_figure(exp, ctx, db, rows, case, integ))
    return "".join(html)


def summaries(db, rows):
    """Per (integrator, variant): medians over the completed sampled steps."""
    groups = {}
    for r in rows:
        groups.setdefault((db["integrator"][r], db["variant"][r]), []).append(r)
    out = []
    for (name, variant), idx in groups.items():
        ok = [r for r in idx if db["status"][r] == "completed"]
        entry = {"name": name, "variant": variant, "samples": len(idx), "completed": len(ok)}
        if ok:
            for col in ("solver_error", "total_error", "wall_seconds", "iterations"):
                entry[col] = float(np.median([db[col][r] for r in ok]))
        else:
            entry["failure"] = db["failure"][idx[0]]
        out.append(entry)
    return out


def label(e):
    return e["name"] + (" (%s)" % e["variant"] if e["variant"] else "")


def family(e):
    """Variants drawn joined by one line: one integrator with one solver
    (quasi-Newton, Chebyshev acceleration: lines of their own)."""
    for extra in ("quasi-newton", "chebyshev"):
        if extra in e["variant"]:
            return e["name"] + " " + extra
    return e["name"]


def case_figure(exp, ctx, db, rows, case, integ):
    disc = float(np.median([db["discretization_error"][r] for r in rows
                            if np.isfinite(db["discretization_error"][r])]))
    scene = db["scene"][rows[0]]
    entries = summaries(db, rows)
    fig = new_figure(13.5, 5.0)
    axes = fig.subplots(1, 2)
    families = {}
    for e in entries:
        if e["completed"]:
            families.setdefault(family(e), []).append(e)
    for ax, col, title in ((axes[0], "solver_error", "distance to the implicit Euler step"),
                           (axes[1], "total_error", "distance to the true motion")):
        for fam, members in families.items():
            members = sorted(members, key=lambda e: e["wall_seconds"])
            name = members[0]["name"]
            style = integ.style(name)
            if fam != name:  # quasi-Newton, Chebyshev
                style["ls"] = ":"
            xs = [e["wall_seconds"] * 1e3 for e in members]
            ys = [max(e[col], FLOOR) for e in members]
            ax.plot(xs, ys, ms=7, mfc="none", mew=1.4, lw=1.1, label=fam, **style)
            for e, x, y in zip(members, xs, ys):
                # Points crowding the dashed line are left unlabelled.
                if e["variant"] and abs(np.log10(y / disc)) > 0.25:
                    ax.annotate(e["variant"].replace("newton-tol ", "tol ").replace(
                        "; quasi-newton", "").replace("iterations ", "N=").replace(
                        "substeps ", "S="), (x, y),
                        textcoords="offset points", xytext=(4, 3), fontsize=6.5, color="0.3")
        ax.axhline(disc, color="0.35", lw=1.2, ls="--")
        ax.text(0.99, disc, "implicit Euler's discretization error per step ", va="top",
                ha="right", fontsize=7.5, color="0.3", transform=ax.get_yaxis_transform())
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time per step [ms] (median)")
        ax.set_ylabel("max position error after one step [m] (median)")
        ax.set_title("%s — %s" % (scene, title), loc="left", fontweight="bold", fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
    legend_outside(axes[1])
    saved = ctx.figs.save(fig, "%s-%d.png" % (exp.name, case))

    facts = []
    samples = max(e["samples"] for e in entries)
    facts.append("%s: implicit Euler's own discretization error over one step of %s s is %s m "
                 "(the median over %d sampled steps: its tightly solved step against the true "
                 "motion)." % (scene, fmt(float(exp.setting("dt", 0.0)), 4), fmt(disc, 3), samples))
    # Adaptive methods solve the ODE, not the implicit Euler step: their
    # distance to that step is its own error, not a solver error.
    done = [e for e in entries if e["completed"] and not integ.adaptive(e["name"])]
    adaptive = [e for e in entries if e["completed"] and integ.adaptive(e["name"])]
    below = sorted((e for e in done if e["solver_error"] <= disc),
                   key=lambda e: e["wall_seconds"])
    above = sorted((e for e in done if e["solver_error"] > disc), key=lambda e: e["wall_seconds"])
    if below:
        facts.append("Solver error below it (as good as solving the step exactly), cheapest "
                     "first: %s." % "; ".join("%s %s ms (%s m)" % (
                         label(e), fmt(e["wall_seconds"] * 1e3, 3), fmt(e["solver_error"], 2))
                         for e in below))
    if above:
        facts.append("Solver error above it: %s." % "; ".join("%s %s ms (%s m)" % (
            label(e), fmt(e["wall_seconds"] * 1e3, 3), fmt(e["solver_error"], 2))
            for e in above))
    closer = sorted((e for e in done if e["total_error"] < 0.5 * disc),
                    key=lambda e: e["wall_seconds"])
    if closer:
        facts.append("Closer to the true motion than the exact implicit Euler step (less than "
                     "half its error), cheapest first: %s." % "; ".join("%s %s ms (%s m)" % (
                         label(e), fmt(e["wall_seconds"] * 1e3, 3), fmt(e["total_error"], 2))
                         for e in closer))
    if adaptive:
        facts.append("The adaptive methods solve the ODE itself, not the implicit Euler step: "
                     "%s." % "; ".join("%s %s ms per step, %s m from the true motion" % (
                         label(e), fmt(e["wall_seconds"] * 1e3, 3), fmt(e["total_error"], 2))
                         for e in sorted(adaptive, key=lambda e: e["wall_seconds"])))
    failed = [e for e in entries if not e["completed"]]
    if failed:
        facts.append("Failed at every sampled step: %s." % "; ".join(
            "%s (%s)" % (label(e), e.get("failure", "")) for e in failed))
    caption = ("Every run takes one step of dt from the same states of a tightly solved implicit "
               "Euler run (every sampled step); its end is compared with that run's next state "
               "(left: the solver error) and with the true motion over the step (right: RK4 at "
               "0.1 / w_max). Markers are the variants of one method (its tolerance, iterations "
               "N, substeps S), joined by cost; dotted: implicit Euler solved by quasi-Newton, and "
               "projective dynamics with Chebyshev acceleration. "
               "The dashed line is implicit Euler's own error against the true motion. Times are "
               "wall times of one step, the integrator set up outside it.")
    return figure_html(saved, "solver error against cost", esc(caption)) + facts_html(facts)
