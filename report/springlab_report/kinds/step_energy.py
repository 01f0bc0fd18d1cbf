"""step-energy: the energy change of every step next to the number of
compressed springs, for integrator variants run side by side (each run an
integrator and its options: linear-implicit Euler's stiffness). Left: the
total energy over time, one line per run; right: each step's energy change
against the compressed springs at its end."""

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, legend_outside, new_figure
from .common import case_index, scene_title

KIND = "step-energy"
TITLE = "Energy per step and compressed springs"
ABOUT = (
    "A linearized step (linear-implicit Euler) replaces each spring's force by its tangent at the "
    "start of the step. A compressed spring's sideways stiffness k (1 − L/l) is negative; where "
    "such springs outweigh the mass over the step (h² k (L/l − 1) > m, counted as indefinite "
    "springs), the step's matrix M − h² K is indefinite and the linear step can amplify a motion "
    "from step to step instead of damping it. Dropping the negative stiffness (the definite "
    "variant, Choi and Ko 2002) keeps the matrix at least M. Implicit Euler solved to "
    "convergence is shown beside them.")


def label(name, stiffness):
    return name if name != "linear-implicit-euler" else "%s (%s)" % (name, stiffness)


def render(exp, ctx):
    integ = ctx.integrators
    steps = Columns(exp.table(), numbers=("t", "total", "change", "compressed",
                                          "indefinite_springs"),
                    texts=("task", "scene", "integrator", "stiffness", "dt"))
    runs = Columns(exp.table("runs"), numbers=("springs", "gaining_steps"),
                   texts=("task", "scene", "integrator", "stiffness", "status", "diverged_at"))
    cases = steps.groups("scene", "dt")
    fig = new_figure(13.5, 4.8 * len(cases))
    axes = fig.subplots(len(cases), 2, squeeze=False)
    facts = []
    for row, ((scene, dt), cidx) in enumerate(cases.items()):
        by_run = {}
        for r in cidx:
            by_run.setdefault((steps["task"][r], steps["integrator"][r], steps["stiffness"][r]),
                              []).append(r)
        styles = integ.variant_styles([(name, stiffness) for _, name, stiffness in by_run])
        for k, ((task, name, stiffness), idx) in enumerate(by_run.items()):
            idx = np.asarray(idx)
            # Every run its own colour and marker (integrators.variant_styles);
            # the definite variant also dotted with filled markers.
            style = styles[(name, stiffness)]
            fill = "none"
            if stiffness == "definite":
                style = dict(style, ls=":")
                fill = style["color"]
            text = label(name, stiffness)
            axes[row, 0].plot(steps["t"][idx], steps["total"][idx], lw=1.6, ms=5, mfc=fill,
                              markevery=max(1, len(idx) // 10), label=text, **style)
            change, compressed = steps["change"][idx], steps["compressed"][idx]
            ok = np.isfinite(change)
            axes[row, 1].plot(compressed[ok], change[ok], ls="none", marker=style["marker"],
                              ms=5, mfc=fill, color=style["color"], label=text)
            facts.append(run_sentence(scene, text, runs, task, change[ok], compressed[ok],
                                      steps["indefinite_springs"][idx][ok]))
        axes[row, 0].set_xlabel("t [s]")
        axes[row, 0].set_ylabel("total energy [J]")
        axes[row, 0].set_yscale("symlog", linthresh=1.0)
        k = case_index(exp, scene, dt)
        axes[row, 0].set_title("%s, dt = %s s" % (scene if k is None else scene_title(exp, k, scene),
                                                 fmt(float(dt), 6)), loc="left",
                               fontweight="bold")
        axes[row, 1].set_xlabel("compressed springs at the end of the step")
        axes[row, 1].set_ylabel("energy change of the step [J]")
        axes[row, 1].set_yscale("symlog", linthresh=1e-3)
        axes[row, 1].axhline(0.0, color="0.5", lw=0.7)
        for ax in axes[row]:
            ax.grid(True, alpha=0.3)
        legend_outside(axes[row, 1])
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = ("Left: the total mechanical energy of each run over time (symmetric log scale, "
               "linear within ±1 J; dotted with filled markers: the definite stiffness). Right: the energy change of every step against the number of "
               "compressed springs at its end (symmetric log scale, linear within ±1e-3 J).")
    return figure_html(saved, "step energy", esc(caption)) + facts_html(facts)


def run_sentence(scene, text, runs, task, change, compressed, indefinite):
    r = [i for i in range(len(runs)) if runs["task"][i] == task]
    status = runs["status"][r[0]] if r else "completed"
    out = "%s on %s: " % (text, scene)
    if status == "completed":
        out += "completed"
    else:
        out += "%s at t = %s s" % (status, fmt(float(runs["diverged_at"][r[0]]), 4))
    gaining = change > 0
    out += "; %d of %d steps gained energy" % (int(gaining.sum()), len(change))
    if gaining.any():
        out += (" (the largest gain %s J, at %d compressed springs; steps that lost energy had "
                "%s compressed springs on average, steps that gained %s)"
                % (fmt(float(change.max()), 3), int(compressed[np.argmax(change)]),
                   fmt(float(compressed[~gaining].mean()), 3) if (~gaining).any() else "–",
                   fmt(float(compressed[gaining].mean()), 3)))
    if len(indefinite):
        out += ("; %s compressed springs on average made the exact step matrix M − h² K "
                "indefinite on their own" % fmt(float(indefinite.mean()), 3))
    return out + "."
