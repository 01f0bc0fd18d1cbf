"""contact: every integrator against the closed forms of contact and friction
over a sweep of steps (docs/physics.md "Contact with planes"). One panel per case: the
relative error of the measured quantity (creep speed, sliding acceleration,
stopping distance, deepest bounce) against the step; then, on the soft and
the stiff bounce, the energy each method keeps and the work it does. The sentences under the
figures are computed from the rows."""

import numpy as np

from ..data import Columns
from ..figures import (esc, facts_html, figure_html, fmt, legend_outside, names_list,
                       new_figure)

KIND = "contact"
TITLE = "Contact and friction"
ABOUT = (
    "A particle on a plane has closed forms: below the friction angle it sticks (the smoothed "
    "friction lets it creep at a known speed below ε_v), above it it slides at g (sin θ − μ cos θ), "
    "launched on level ground it stops after v0² / (2 μ g), and dropped onto a penalty floor it "
    "sinks as deep as energy balance allows. Theory: contact is one more stiff spring "
    "(ω = √(k_c / m)) and friction's stick regime is stiff in the velocity (μ f_n 2 / ε_v per unit "
    "mass), so explicit methods need small steps; implicit Euler stays stable at every step but "
    "its damping absorbs the impact (a shallower bounce); adaptive methods pay with steps for "
    "stiff contact.")

REGIME_TEXT = {
    "stick": ("creep speed", "sticks below the friction angle"),
    "slide": ("acceleration", "slides above the friction angle"),
    "stop": ("stopping distance", "stops on level ground"),
    "bounce": ("deepest penetration", "bounces on a penalty floor"),
}
# The unit of each regime's measured quantity (docs/physics.md "Contact with planes").
REGIME_UNIT = {"stick": "m/s", "slide": "m/s²", "stop": "m", "bounce": "m"}
CEILING = 10.0  # errors drawn up to 1000 %; above, and failed runs, at the top
FLOOR = 1e-8    # and from 1e-8 (round-off of the measurement) up


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("case", "dt", "measured", "theory", "steps",
                                       "newton_iterations", "t_final", "min_gap",
                                       "energy_change"),
                 texts=("scene", "integrator", "regime", "status", "failure"))
    # Methods that refused every run (at t = 0: the fast solvers do not
    # solve contact planes yet) are named, not drawn.
    runs = {}
    for r in range(len(db)):
        runs.setdefault(db["integrator"][r], []).append(r)
    refused = sorted(n for n, idx in runs.items()
                     if all(db["status"][r] == "failed" and db["t_final"][r] == 0.0 for r in idx))
    # One panel per (scene, regime, theory): the cases of one step sweep.
    groups = {}
    for r in range(len(db)):
        if db["regime"][r] and db["integrator"][r] not in refused:
            groups.setdefault(case_label(db, [r]), []).append(r)
    html = []
    if groups:
        html.append(error_figure(exp, ctx, db, groups, refused))
    bounces = {key: rows for key, rows in groups.items() if db["regime"][rows[0]] == "bounce"}
    if bounces:
        html.append(cost_figure(exp, ctx, db, bounces))
    return "".join(html)


def case_label(db, rows):
    r = rows[0]
    regime = db["regime"][r]
    quantity, what = REGIME_TEXT.get(regime, (regime, regime))
    return "%s: %s" % (db["scene"][r], what), quantity, float(db["theory"][r])


def by_integrator(db, rows):
    out = {}
    for r in rows:
        out.setdefault(db["integrator"][r], []).append(r)
    return {name: np.asarray(sorted(idx, key=lambda r: db["dt"][r])) for name, idx in out.items()}


def error_figure(exp, ctx, db, groups, refused):
    integ = ctx.integrators
    cols = 2
    nrows = (len(groups) + cols - 1) // cols
    fig = new_figure(13.5, 4.3 * nrows)
    axes = np.atleast_2d(fig.subplots(nrows, cols, squeeze=False))
    facts = []
    for j, ((title, quantity, theory), rows) in enumerate(groups.items()):
        ax = axes[j // cols, j % cols]
        series = by_integrator(db, rows)
        dts = sorted({float(db["dt"][r]) for r in rows})
        within, exact = {}, []
        regime = db["regime"][rows[0]]
        for name in integ.sort(series):
            idx = series[name]
            dt = db["dt"][idx]
            err = np.abs(db["measured"][idx] / theory - 1.0)
            ok = np.array([db["status"][r] == "completed" for r in idx]) & np.isfinite(err)
            shown = np.where(ok, np.minimum(np.maximum(err, FLOOR), CEILING), CEILING)
            ax.plot(dt, shown, ms=6, mfc="none", mew=1.3, lw=1.3, label=name, **integ.style(name))
            bad = ~ok
            if bad.any():
                ax.plot(dt[bad], np.full(bad.sum(), CEILING), ls="none", marker="x", ms=8,
                        color=integ.colour(name))
            # The largest step up to which every step of the sweep is within 1 %.
            good = ok & (err <= 0.01)
            first_bad = int(np.argmin(good)) if not good.all() else len(good)
            within[name] = float(dt[first_bad - 1]) if first_bad > 0 else None
            # Sticking without any creep (Coulomb's friction without the
            # smoothing: the fast solvers) is not an error of the creep speed.
            if regime == "stick" and ok.all() and \
                    np.all(np.abs(db["measured"][idx]) <= 1e-6 * abs(theory)):
                exact.append(name)
                within.pop(name)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axhline(0.01, color="0.5", lw=0.8, ls=":")
        ax.set_xlabel("step dt [s] (adaptive methods: output interval)")
        ax.set_ylabel("|measured / theory − 1|")
        unit = REGIME_UNIT.get(regime)
        ax.set_title("%s\n%s: theory %s%s" % (title, quantity, fmt(theory, 4),
                                              " " + unit if unit else ""), loc="left",
                     fontweight="bold", fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
        sentence = within_sentence(title, quantity, within, dts)
        if exact:
            sentence = sentence[:-1] + "; stick without creeping at every step (their friction " \
                "has no smoothing): %s." % names_list(exact)
        facts.append(sentence)
    for j in range(len(groups), nrows * cols):
        axes[j // cols, j % cols].set_visible(False)
    if refused:
        first = next(r for r in range(len(db)) if db["integrator"][r] == refused[0])
        facts.append("Not drawn: %s refuse%s every case at t = 0 (\u201c%s\u201d)." % (
            names_list(refused), "" if len(refused) > 1 else "s", db["failure"][first]))
    legend_outside(axes[0, cols - 1])
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = ("The relative error of the measured quantity against its closed form, for every "
               "method over the step sweep; the dotted line is 1 %. A run that failed or diverged "
               "(✕), or whose error is above 1000 %, is drawn at the top; errors below 1e-8 at the "
               "bottom. Adaptive methods choose "
               "their own steps: for them dt is the output interval, at which the bounce's depth is "
               "sampled.")
    return figure_html(saved, "contact: error against the step", esc(caption)) + facts_html(facts)


def within_sentence(title, quantity, within, dts):
    reach = sorted(((v, n) for n, v in within.items() if v is not None), key=lambda p: (-p[0], p[1]))
    never = sorted(n for n, v in within.items() if v is None)
    parts = []
    largest = max(dts)
    at_all = [n for v, n in reach if v == largest]
    if at_all:
        parts.append("within 1 %% at every step of the sweep (up to %s s): %s" % (fmt(largest, 3),
                                                                         names_list(at_all)))
    rest = [(v, n) for v, n in reach if v != largest]
    if rest:
        parts.append("within 1 %% at every step up to: %s" % ", ".join("%s (%s s)" % (n, fmt(v, 3))
                                                            for v, n in rest))
    if never:
        parts.append("not within 1 %% even at the smallest step (%s s): %s"
                     % (fmt(min(dts), 3), names_list(never)))
    return "%s (%s) — %s." % (title, quantity, "; ".join(parts))


def drop_energy(exp, case):
    """m |g| h of a bounce case's falling particle, from its scene in the
    settings file (None when the scene does not say)."""
    cases = exp.setting("cases")
    try:
        scene = cases[case]["scene"]
        g = np.asarray(scene["gravity"], dtype=float)
        plane = scene["planes"][0]
        n = np.asarray(plane["normal"], dtype=float)
        n = n / np.linalg.norm(n)
        point = np.asarray(plane["point"], dtype=float)
        for p in scene["particles"]:
            if not p.get("fixed"):
                gap = float(n.dot(np.asarray(p["x"], dtype=float) - point))
                return float(p.get("mass", 1.0)) * float(np.linalg.norm(g)) * gap
    except (KeyError, IndexError, TypeError, ValueError):
        return None
    return None


def cost_figure(exp, ctx, db, bounces):
    """The bounces: the energy each run lost or gained (a fraction of the
    drop's m g h), and the work it took."""
    integ = ctx.integrators
    fig = new_figure(13.5, 8.4)
    axes = fig.subplots(2, len(bounces), squeeze=False)
    facts = []
    costs = {}
    titles = []
    for col, ((title, _, _), rows) in enumerate(bounces.items()):
        titles.append(title)
        series = by_integrator(db, rows)
        e_drop = drop_energy(exp, int(db["case"][rows[0]]))
        kept = []
        for name in integ.sort(series):
            idx = series[name]
            ok = np.array([db["status"][r] == "completed" for r in idx])
            idx = idx[ok]
            work = (db["steps"][idx] + db["newton_iterations"][idx]) / db["t_final"][idx]
            axes[1, col].plot(db["dt"][idx], work, ms=6, mfc="none", mew=1.3, lw=1.3, label=name,
                              **integ.style(name))
            costs.setdefault(name, {})[title] = dict(zip(db["dt"][idx], work))
            if e_drop:
                change = np.abs(db["energy_change"][idx]) / e_drop
                axes[0, col].plot(db["dt"][idx], np.maximum(change, FLOOR), ms=6, mfc="none",
                                  mew=1.3, lw=1.3, label=name, **integ.style(name))
                good = idx[np.abs(db["energy_change"][idx]) <= 0.01 * e_drop]
                if len(idx) and len(good) == len(idx):
                    kept.append(name)
        for row, label in ((0, "|E(T) − E(0)| / (m g h)"),
                           (1, "(steps + Newton iterations) per simulated second")):
            ax = axes[row, col]
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("step dt [s] (adaptive methods: output interval)")
            ax.set_ylabel(label)
            ax.set_title(title + (" — energy kept" if row == 0 else " — work"), loc="left",
                         fontweight="bold", fontsize=10)
            ax.grid(True, which="major", alpha=0.3)
        if e_drop:
            axes[0, col].axhline(0.01, color="0.5", lw=0.8, ls=":")
            facts.append("%s: the drop's energy m g h is %s J; the runs that keep the energy "
                         "within 1 %% of it at every step they completed: %s." % (
                             title, fmt(e_drop, 3), names_list(kept) if kept else "none"))
    legend_outside(axes[0, -1])
    saved = ctx.figs.save(fig, exp.name + "-bounce.png")
    if len(titles) == 2:
        soft, stiff = titles
        ratios = []
        for name, by_case in costs.items():
            a, b = by_case.get(soft, {}), by_case.get(stiff, {})
            common = sorted(set(a) & set(b))
            if common:
                dt = common[-1]
                ratios.append((b[dt] / a[dt], name, dt))
        if ratios:
            ratios.sort(key=lambda p: (-p[0], p[1]))
            facts.append("Work on the stiff floor relative to the soft one, at the largest step "
                         "(or output interval) both runs completed: %s." % ", ".join(
                             "%s %s x (dt = %s s)" % (n, fmt(q, 3), fmt(dt, 3))
                             for q, n, dt in ratios))
    caption = ("The bounces without friction, where the physics keeps the energy: above, how much "
               "each run lost or gained by its end, as a fraction of the drop's m g h (dotted: "
               "1 %); below, the work per simulated second (steps plus Newton iterations): "
               "fixed-step methods pay 1/dt steps plus their Newton iterations, adaptive ones "
               "choose their steps from the stiffness. Runs that failed or diverged are not "
               "drawn.")
    return figure_html(saved, "contact: bounce energy and cost", esc(caption)) + \
        facts_html(facts)
