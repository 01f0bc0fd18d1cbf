"""rotation: linear elasticity under large rotation against the
rotation-invariant models (experiments/README.md "rotation"). One row of panels per
(scenario, integrator): the radius of gyration about the centre of mass
relative to its start (1 for a rigid motion) and the elastic energy, a line
per material model. The sentences under the figure are computed from the
runs table."""

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, names_list, new_figure

KIND = "rotation"
TITLE = "Large rotation: linear elasticity's ghost forces"
ABOUT = (
    "A rigid motion stores no energy and needs no force. Linear elasticity measures strain by "
    "ε = (F + Fᵀ)/2 − I, which is blind to an infinitesimal rotation and wrong for a finite one. "
    "Theory: a spinning linear block feels no force at all, so every particle flies on in a "
    "straight line and the block swells at no energy cost (its radius of gyration grows like "
    "√(1 + (ωt)²) in the plane of the spin); a linear block released turned by θ from its rest "
    "shape holds the ghost energy V 2 (μ + λ)(1 − cos θ)² and its ghost forces blow it up. The "
    "corotated, StVK and neo-Hookean models measure strain through FᵀF or the polar "
    "decomposition, so both rigid motions cost them nothing.")

FLOOR = 1e-12  # J: elastic energies drawn from here up (0 is drawn at the floor)
COLOURS = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf"]
STYLES = ["-", "--", "-.", ":", "-", "--", "-."]


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("scenario", "t", "kinetic", "elastic", "gyration"),
                 texts=("model", "integrator"))
    runs = Columns(exp.table("runs"), numbers=("scenario", "kinetic_initial", "elastic_initial",
                                               "elastic_max", "gyration_max", "gyration_final"),
                   texts=("model", "integrator", "status"))
    scenarios = exp.setting("scenarios") or []
    models = exp.setting("models") or sorted(set(db["model"]))
    panels = {}
    for (s, name, model), idx in db.groups("scenario", "integrator", "model").items():
        panels.setdefault((int(float(s)), name), {})[model] = idx
    order = ctx.integrators.sort(sorted({n for _, n in panels}))
    keys = sorted(panels, key=lambda k: (k[0], order.index(k[1])))
    fig = new_figure(13.5, 3.6 * len(keys) + 0.4)
    axes = fig.subplots(len(keys), 2, squeeze=False)
    for row, (s, name) in enumerate(keys):
        title = scenarios[s]["title"] if s < len(scenarios) else "scenario %d" % s
        for k, model in enumerate(m for m in models if m in panels[(s, name)]):
            idx = panels[(s, name)][model]
            style = dict(color=COLOURS[k % len(COLOURS)], ls=STYLES[k % len(STYLES)],
                         lw=max(1.0, 2.8 - 0.4 * k), label=model)
            axes[row, 0].plot(db["t"][idx], db["gyration"][idx], **style)
            axes[row, 1].plot(db["t"][idx], np.maximum(db["elastic"][idx], FLOOR), **style)
        for col, label in ((0, "radius of gyration / its start"), (1, "elastic energy [J]")):
            ax = axes[row, col]
            ax.set_title("%s — %s" % (title, name), loc="left", fontweight="bold", fontsize=10)
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
            if row == len(keys) - 1:
                ax.set_xlabel("t [s]")
        axes[row, 1].set_yscale("log")
        axes[row, 0].legend(loc="upper left", fontsize=8, framealpha=0.85)
    saved = ctx.figs.save(fig, exp.name + ".png")
    facts = [sentence(runs, scenarios, s, name) for s, name in keys]
    caption = ("Each material model on the same rigid motions. Left: the radius of gyration about "
               "the centre of mass divided by its starting value (a rigid motion keeps 1). Right: "
               "the elastic energy on a log scale (energies below 1e-12 J, round-off, drawn at "
               "1e-12 J).")
    return figure_html(saved, "rotation: gyration and elastic energy", esc(caption)) + \
        facts_html(facts)


def sentence(runs, scenarios, s, name):
    title = scenarios[s]["title"] if s < len(scenarios) else "scenario %d" % s
    rows = [r for r in range(len(runs))
            if int(runs["scenario"][r]) == s and runs["integrator"][r] == name]
    parts = []
    rigid = []
    for r in rows:
        model = runs["model"][r]
        status = runs["status"][r]
        g = runs["gyration_final"][r]
        e0, emax = runs["elastic_initial"][r], runs["elastic_max"][r]
        if status == "completed" and abs(g - 1.0) <= 1e-3 and \
                emax <= 1e-2 * runs["kinetic_initial"][r] + 1e-9:
            rigid.append(model)
            continue
        text = "%s ends at %s times its starting radius of gyration (largest %s), its elastic " \
               "energy %s J at the start and at most %s J" % (
                   model, fmt(g, 4), fmt(runs["gyration_max"][r], 4), fmt(max(e0, 0.0), 4),
                   fmt(max(emax, 0.0), 3))
        if status != "completed":
            text += " (%s)" % status
        parts.append(text)
    if rigid:
        parts.append("%s stay%s rigid: the radius of gyration within 0.1 %% of its start, the "
                     "elastic energy under 1 %% of the starting kinetic energy (or 1e-9 J)" % (
                         names_list(rigid), "" if len(rigid) > 1 else "s"))
    return "%s, %s: %s." % (title, name, "; ".join(parts))
