"""convergence: final-position error over a step sweep (fixed-step methods)
and a tolerance sweep (adaptive ones). Fixed-step: error against dt with
slope triangles of the theoretical orders. Adaptive: error against the work
it took (force evaluations), a measure that compares with the fixed-step
ones, instead of against the tolerance."""

import math

import numpy as np

from ..data import Columns, finite
from ..figures import (count, esc, facts_html, figure_html, finite_positive, fmt, log_log,
                       names_list, new_figure, slope_triangle, swatch)

KIND = "convergence"
TITLE = "Convergence order"
ABOUT = (
    "A fixed-step method of order p has a global error proportional to h^p: on log-log axes a "
    "line of slope p (the triangles show slopes 1, 2 and 4), so halving dt divides the error by "
    "2 for the Euler methods, 4 for Verlet and implicit midpoint, 16 for RK4. An adaptive "
    "method controls each step's local error to the tolerance; its global error need not be "
    "proportional to the tolerance, so it is drawn against the work it took instead (force "
    "evaluations): for a method of order p with a fixed cost per step the error falls like "
    "work^-p. A flat floor is round-off or the reference's own accuracy.")

ERROR_LABEL = "max |x − x_ref| at t_end [m]"
SAME = 0.05  # errors within 5% at every point: the lines are said to coincide


def _cheapest(scene, drawn):
    """The work each adaptive method needed to reach an error of at most the
    target (the largest error every method reached), cheapest first."""
    reached = [float(np.min(err)) for x, err in drawn.values() if len(err)]
    if len(reached) < 2:
        return []
    target = 10.0 ** math.floor(math.log10(max(reached)))
    work = []
    for name, (x, err) in drawn.items():
        ok = err <= target
        if ok.any():
            work.append((float(np.min(x[ok])), name))
    work.sort()
    return ["On %s, the least work for an error of at most %s m: %s." % (
        scene, fmt(target), ", ".join("%s %s force evaluations" % (n, count(w))
                                      for w, n in work))]


def render(exp, ctx):
    integ = ctx.integrators
    cv = Columns(exp.table(), numbers=("adaptive", "value", "error", "force_evals"),
                 texts=("scene", "integrator", "parameter", "status"))
    orders = {}
    o_table = exp.table("orders")
    if o_table is not None:
        o = Columns(o_table, numbers=("adaptive", "theoretical_order", "fitted_order", "points"),
                    texts=("scene", "integrator"))
        for r in range(len(o)):
            orders[(o["scene"][r], o["integrator"][r])] = (o["fitted_order"][r],
                                                          o["theoretical_order"][r])
    scenes = cv.groups("scene")
    kinds = [a for a in (False, True) if np.any((cv["adaptive"] == 1) == a)]
    fig = new_figure(6.4 * len(kinds) + 0.4, 5.6 * len(scenes))
    axes = fig.subplots(len(scenes), len(kinds), squeeze=False)
    facts, skipped = [], 0
    for row, ((scene,), sidx) in enumerate(scenes.items()):
        for col, adaptive in enumerate(kinds):
            ax = axes[row, col]
            series = {}
            for r in sidx:
                if (cv["adaptive"][r] == 1) == adaptive:
                    series.setdefault(cv["integrator"][r], []).append(r)
            drawn = {}
            for name in integ.sort(series):
                rows = np.asarray(series[name])
                rows = rows[np.argsort(cv["value"][rows], kind="stable")]
                x = cv["force_evals"][rows] if adaptive else cv["value"][rows]
                err = cv["error"][rows]
                ok = np.array([cv["status"][r] == "completed" for r in rows]) & \
                    finite_positive(x, err)
                skipped += int((~ok).sum())
                drawn[name] = (x[ok], err[ok])
            groups = _coinciding(drawn)
            for name in integ.sort(drawn):
                x, err = drawn[name]
                group = next((g for g in groups if name in g), [name])
                k = group.index(name)
                if adaptive:
                    label = name
                else:
                    fitted, theory = orders.get((scene, name), (math.nan, integ.order(name)))
                    label = "%s: fitted order %s (theory %s)" % (
                        name, "%.2f" % fitted if finite(fitted) else "–",
                        fmt(theory) if finite(theory) else "–")
                # Coinciding lines: concentric markers of falling size, line
                # widths falling too, so every one of them shows.
                ax.plot(x, err, lw=max(0.9, 3.2 - 1.1 * k), ms=14 - 4 * k, mfc="none",
                        mew=1.6, label=label, zorder=3 + k, **integ.style(name))
            has = log_log(ax)
            if has and not adaptive:
                _triangles(ax, drawn, integ)
            if has and adaptive:
                facts.extend(_cheapest(scene, drawn))
            for g in groups:
                facts.append("On %s, %s have errors within %d%% of each other at every %s, so "
                             "their lines coincide (drawn with concentric markers)." % (
                                 scene, names_list(g), round(100 * SAME),
                                 "tolerance" if adaptive else "step"))
            if adaptive:
                ax.set_xlabel("work: force evaluations")
                ax.set_title("%s — adaptive: error against work" % scene, loc="left",
                             fontweight="bold")
            else:
                ax.set_xlabel("step dt [s]")
                ax.set_title("%s — fixed step: error against step" % scene, loc="left",
                             fontweight="bold")
            ax.set_ylabel(ERROR_LABEL)
            ax.grid(True, which="major", alpha=0.3)
            ax.grid(True, which="minor", alpha=0.1)
            if drawn:
                ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8,
                          frameon=False, handlelength=2.6)
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = ("Error of the final positions against the exact solution (oscillator) or a tight "
               "reference run, log-log. Left: fixed-step methods against the step, with "
               "triangles of slope 1, 2 and 4; the legend gives the order fitted to the points "
               "(convergence-orders.csv) beside the theoretical one. Right: adaptive methods "
               "over their tolerance sweep, against the force evaluations the run took (lower "
               "left is better).")
    if skipped:
        caption += (" %d point%s not drawn (diverged or failed run, or an error that is not a "
                    "positive finite number)." % (skipped, "" if skipped == 1 else "s"))
    out = [figure_html(saved, "convergence", esc(caption)), facts_html(facts + order_facts(
        exp, integ))]
    if o_table is not None:
        out.append(orders_table(exp, integ))
    return "".join(out)


def _coinciding(drawn):
    """Groups of methods whose points share x and agree within SAME."""
    names = sorted(drawn)
    groups = []
    for a in names:
        if any(a in g for g in groups):
            continue
        g = [a]
        xa, ya = drawn[a]
        for b in names:
            if b == a or any(b in h for h in groups):
                continue
            xb, yb = drawn[b]
            if len(xa) and len(xa) == len(xb) and np.array_equal(xa, xb) and \
                    np.all(np.abs(ya - yb) <= SAME * np.maximum(ya, yb)):
                g.append(b)
        if len(g) > 1:
            groups.append(g)
    return groups


def _triangles(ax, drawn, integ):
    """A slope triangle per theoretical order, below the lowest line of that order."""
    by_order = {}
    for name, (x, err) in drawn.items():
        p = integ.order(name)
        if isinstance(p, (int, float)) and len(x) >= 2:
            by_order.setdefault(p, []).append((x, err))
    for p, lines in sorted(by_order.items()):
        x_lo = max(float(np.min(x)) for x, _ in lines)
        x_hi = min(float(np.max(x)) for x, _ in lines)
        if not x_hi > x_lo:
            continue
        decades = min(0.5, math.log10(x_hi / x_lo) * 0.6)
        x0 = x_lo * 10 ** (0.2 * math.log10(x_hi / x_lo))
        y_at = min(float(np.interp(math.log10(x0), np.log10(x), np.log10(err)))
                   for x, err in lines)
        slope_triangle(ax, x0, 10 ** y_at / 4.0, p, width_decades=decades,
                       label="order %g" % p)


def order_facts(exp, integ):
    t = exp.table("orders")
    if t is None:
        return []
    o = Columns(t, numbers=("adaptive", "theoretical_order", "fitted_order"),
                texts=("scene", "integrator"))
    fixed = [(o["fitted_order"][r] - o["theoretical_order"][r], o["integrator"][r],
              o["scene"][r]) for r in range(len(o)) if o["adaptive"][r] == 0
             and finite(o["fitted_order"][r])]
    adaptive = [(o["fitted_order"][r], o["integrator"][r], o["scene"][r]) for r in range(len(o))
                if o["adaptive"][r] == 1 and finite(o["fitted_order"][r])]
    out = []
    if fixed:
        worst = max(fixed, key=lambda f: abs(f[0]))
        out.append("Fixed-step methods: every fitted order is within %s of the theoretical one "
                   "(largest difference: %s on %s)." % (fmt(abs(worst[0]), 2), worst[1],
                                                        worst[2]))
    if adaptive:
        lo, hi = min(adaptive), max(adaptive)
        out.append("Adaptive methods: the slope of log error against log rtol lies between %s "
                   "(%s on %s) and %s (%s on %s); 1 would be an error proportional to the "
                   "tolerance." % (fmt(lo[0], 2), lo[1], lo[2], fmt(hi[0], 2), hi[1], hi[2]))
    return out


def orders_table(exp, integ):
    o = Columns(exp.table("orders"), numbers=("adaptive", "theoretical_order", "fitted_order",
                                              "points"), texts=("scene", "integrator"))
    out = ["<details><summary>Fitted orders (convergence-orders.csv)</summary>\n<p>Fixed-step "
           "methods: slope of log error against log dt, beside the method's order (highlighted "
           "when more than 0.2 apart). Adaptive methods: slope against log rtol, beside 1 (error "
           "proportional to the tolerance; not a property SUNDIALS promises).</p>\n"
           "<table><tr><th>scene</th><th>integrator</th><th>against</th><th>theoretical</th>"
           "<th>fitted</th><th>points</th></tr>\n"]
    for r in sorted(range(len(o)), key=lambda r: (o["scene"][r], o["adaptive"][r],
                                                  integ.sort(set(o["integrator"])).index(
                                                      o["integrator"][r]))):
        th, fi = o["theoretical_order"][r], o["fitted_order"][r]
        bad = o["adaptive"][r] == 0 and finite(th) and finite(fi) and abs(fi - th) > 0.2
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>'
                   '</tr>\n' % (' class="off"' if bad else "", esc(o["scene"][r]),
                                swatch(integ, o["integrator"][r]),
                                "rtol" if o["adaptive"][r] == 1 else "dt", fmt(th),
                                "%.3f" % fi if finite(fi) else "–", fmt(o["points"][r])))
    out.append("</table></details>\n")
    return "".join(out)
