"""solver-error: the ways of solving implicit Euler's step at frame rate,
each from the same states of a tightly solved implicit Euler run (experiments/README.md
"solver-error"): its distance to that step (solver error) and to the true
motion over the step (total error), against its cost per step, next to
implicit Euler's own discretization error. The sentences are computed from
the rows."""

import math

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, label_points, legend_outside, new_figure
from .common import scene_title

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

# The options a run set, one column each (experiments/README.md
# "solver-error"), empty where not set; "variant" is the same as a label.
OPTION_NUMBERS = ("newton_tol", "substeps", "iterations", "chebyshev", "rtol")


def option_columns():
    return tuple("option_" + o for o in OPTION_NUMBERS)


def options(cols, r):
    """The options row r set, e.g. {"newton_tol": 0.01, "solver": "quasi-newton"}."""
    out = {o: float(cols["option_" + o][r]) for o in OPTION_NUMBERS
           if math.isfinite(cols["option_" + o][r])}
    if cols["option_solver"][r]:
        out["solver"] = cols["option_solver"][r]
    return out


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("case", "step", "solver_error", "total_error",
                                       "discretization_error", "wall_seconds", "iterations")
                 + option_columns(),
                 texts=("scene", "integrator", "variant", "option_solver", "status", "failure"))
    integ = ctx.integrators
    html = []
    runs = exp.table("runs")
    runs = None if runs is None else Columns(
        runs, numbers=("case", "energy_lost", "max_strain", "wall_seconds_per_step")
        + option_columns(),
        texts=("scene", "integrator", "variant", "option_solver", "status"))
    cases = sorted({int(c) for c in db["case"]})
    for case in cases:
        rows = [r for r in range(len(db)) if int(db["case"][r]) == case]
        html.append(case_figure(exp, ctx, db, rows, case, integ))
        if runs is not None:
            html.append(small_steps_figure(exp, ctx, db, rows, runs, case, integ))
    return "".join(html)


def substeps_iterations(opts):
    """(S, N) of a run that set both substeps S and iterations N, else None."""
    if "substeps" in opts and "iterations" in opts:
        return int(opts["substeps"]), int(opts["iterations"])
    return None


def small_steps_figure(exp, ctx, db, rows, runs, case, integ):
    """Macklin et al. 2019's grid: XPBD's substeps S x iterations N at equal
    cost S N, against S: the largest strain and the energy of the whole run,
    and the one-step distance to the true motion."""
    whole = {(runs["integrator"][r], runs["variant"][r]): r for r in range(len(runs))
             if int(runs["case"][r]) == case and runs["status"][r] == "completed"}
    one_step = {(e["name"], e["variant"]): e for e in summaries(db, rows) if e["completed"]}
    groups = {}
    for (name, variant), r in whole.items():
        sn = substeps_iterations(options(runs, r))
        if sn is not None:
            groups.setdefault((name, sn[0] * sn[1]), []).append((sn[0], sn[1], r, variant))
    groups = {k: sorted(v) for k, v in groups.items() if len(v) >= 3}
    if not groups:
        return ""
    # The tightest Newton run: the reference lines.
    newton = [(options(runs, r)["newton_tol"], r) for (n, v), r in whole.items()
              if n == "implicit-euler" and set(options(runs, r)) == {"newton_tol"}]
    ref = min(newton)[1] if newton else None
    fig = new_figure(13.5, 4.2)
    axes = fig.subplots(1, 3)
    facts = []
    for (name, cost), members in groups.items():
        S = [m[0] for m in members]
        strain = [runs["max_strain"][m[2]] for m in members]
        gained = [-runs["energy_lost"][m[2]] for m in members]
        error = [one_step.get((name, m[3]), {}).get("total_error", np.nan) for m in members]
        style = integ.style(name)
        lab = "%s, S x N = %d" % (name, cost)
        axes[0].plot(S, strain, ms=7, mfc="none", label=lab, **style)
        axes[1].plot(S, gained, ms=7, mfc="none", label=lab, **style)
        axes[2].plot(S, error, ms=7, mfc="none", label=lab, **style)
        first, last = members[0], members[-1]
        errors = ""
        if np.isfinite(error[0]) and np.isfinite(error[-1]):
            errors = "; one step's distance to the true motion %s m against %s m" % (
                fmt(error[0], 2), fmt(error[-1], 2))
        facts.append("%s at equal cost S x N = %d: %d x %d reaches a largest strain of %s %% and "
                     "%s %s J; %d x %d reaches %s %% and %s %s J%s." % (
                         name, cost, first[0], first[1], fmt(strain[0] * 100, 3),
                         "gains" if gained[0] > 0 else "loses", fmt(abs(gained[0]), 3),
                         last[0], last[1], fmt(strain[-1] * 100, 3),
                         "gains" if gained[-1] > 0 else "loses", fmt(abs(gained[-1]), 3),
                         errors))
    if ref is not None:
        axes[0].axhline(runs["max_strain"][ref], color="0.35", ls="--", lw=1.1)
        axes[1].axhline(-runs["energy_lost"][ref], color="0.35", ls="--", lw=1.1)
        facts.append("Dashed: implicit Euler solved by Newton (%s): largest strain %s %%, "
                     "energy %s %s J." % (
                         runs["variant"][ref], fmt(runs["max_strain"][ref] * 100, 3),
                         "gained" if runs["energy_lost"][ref] < 0 else "lost",
                         fmt(abs(runs["energy_lost"][ref]), 3)))
    for ax, ylabel, title in ((axes[0], "largest spring strain |l - L| / L", "stretch"),
                              (axes[1], "energy gained over the run [J]", "energy"),
                              (axes[2], "one step's distance to the true motion [m]", "error")):
        ax.set_xscale("log")
        ax.set_xlabel("substeps S (iterations N = cost / S)")
        ax.set_ylabel(ylabel)
        ax.set_title("%s — %s" % (scene_title(exp, case, db["scene"][rows[0]]), title),
                     loc="left", fontweight="bold", fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
    if any(line.get_ydata().size and np.any(np.asarray(line.get_ydata(), float) > 0)
           for line in axes[2].get_lines()):
        axes[2].set_yscale("log")
    axes[1].axhline(0.0, color="0.6", lw=0.7)
    legend_outside(axes[2])
    saved = ctx.figs.save(fig, "%s-%d-small-steps.png" % (exp.name, case))
    caption = ("XPBD's substeps against its iterations at equal cost (Macklin et al. 2019, "
               "\u201cSmall Steps\u201d): each point splits the same S x N projections of every "
               "spring differently. Left and middle: the whole run from rest (the largest spring "
               "strain at any step, the energy it gained: positive is energy the method made); "
               "right: one step from the same states against the true motion.")
    return figure_html(saved, "small steps at equal cost", esc(caption)) + facts_html(facts)


def summaries(db, rows):
    """Per (integrator, variant): medians over the completed sampled steps."""
    groups = {}
    for r in rows:
        groups.setdefault((db["integrator"][r], db["variant"][r]), []).append(r)
    out = []
    for (name, variant), idx in groups.items():
        ok = [r for r in idx if db["status"][r] == "completed"]
        entry = {"name": name, "variant": variant, "options": options(db, idx[0]),
                 "samples": len(idx), "completed": len(ok)}
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
    if e["options"].get("solver") == "quasi-newton":
        return e["name"] + " quasi-newton"
    if "chebyshev" in e["options"]:
        return e["name"] + " chebyshev"
    return e["name"]


# Labels per panel: the variants on the lower-left front first, then each
# method's cheapest and dearest; any that would overlap are left out (the
# sentences under the figure list every variant).
LABELS = 12


def short_variant(opts):
    """A point's label from its options: "tol 0.01", "QN tol 0.01", "S=10; N=1"."""
    parts = []
    for key, text in (("newton_tol", "tol %s"), ("substeps", "S=%s"), ("iterations", "N=%s"),
                      ("chebyshev", "chebyshev %s"), ("rtol", "rtol %s")):
        if key in opts:
            parts.append(text % fmt(opts[key], 3))
    if opts.get("solver") == "newton":
        parts.append("newton")
    text = "; ".join(parts)
    return "QN " + text if opts.get("solver") == "quasi-newton" else text


def label_order(points):
    """(x, y, text, colour) of the points worth a label, most telling first:
    the front (no other point both cheaper and closer), cheapest first; then
    each method's two ends."""
    front, best = [], float("inf")
    for x, y, text, colour, _ in sorted(points, key=lambda p: (p[0], p[1])):
        if y < best:
            front.append((x, y, text, colour))
            best = y
    ends = []
    for fam in dict.fromkeys(p[4] for p in points):
        mine = sorted((p for p in points if p[4] == fam), key=lambda p: p[0])
        for p in (mine[0], mine[-1]):
            if p[:4] not in front and p[:4] not in ends:
                ends.append(p[:4])
    return front + ends


def cheapest_ranges(done):
    """Which method is cheapest at which solver error (the lower envelope of
    the left panel), computed from the medians: the variants none is both
    cheaper and closer than (the front), cost ascending and so error
    descending; the k-th is the cheapest way to reach any error from its own
    up to the (k-1)-th's. Consecutive variants of one method (family) make
    one range: [{"family", "name", "hi" (None: above every error), "lo",
    "entries"}], from the largest errors to the smallest."""
    front, best = [], float("inf")
    for e in sorted(done, key=lambda e: (e["wall_seconds"], e["solver_error"])):
        if e["solver_error"] < best:
            front.append(e)
            best = e["solver_error"]
    ranges = []
    for k, e in enumerate(front):
        hi = front[k - 1]["solver_error"] if k else None
        if ranges and ranges[-1]["family"] == family(e):
            ranges[-1]["lo"] = e["solver_error"]
            ranges[-1]["entries"].append(e)
        else:
            ranges.append({"family": family(e), "name": e["name"], "hi": hi,
                           "lo": e["solver_error"], "entries": [e]})
    return ranges


def cheapest_sentence(ranges):
    parts = []
    for r in ranges:
        first, last = r["entries"][0], r["entries"][-1]
        where = ("%s m and above" % fmt(r["lo"], 2) if r["hi"] is None
                 else "%s to %s m" % (fmt(r["hi"], 2), fmt(r["lo"], 2)))
        how = "%s, %s ms" % (first["variant"] or "defaults", fmt(first["wall_seconds"] * 1e3, 2))
        if last is not first:
            how += " to %s, %s ms" % (last["variant"] or "defaults",
                                      fmt(last["wall_seconds"] * 1e3, 2))
        parts.append("%s: %s (%s)" % (where, r["family"], how))
    return ("Cheapest for each solver error (the lower envelope of the left panel: its grey "
            "staircase and the bands at its right edge, in the cheapest method's colour): %s; no "
            "run comes closer than %s m." % ("; ".join(parts), fmt(ranges[-1]["lo"], 2)))


# A band at least this many decades tall is labelled with its method.
BAND_LABEL_DECADES = 0.3


def draw_cheapest(ax, ranges, integ, disc):
    """The lower envelope as a grey staircase (cost against error) and, at the
    axes' right edge, a band per range in its method's colour, labelled where
    it is tall enough (and clear of the discretization error's line)."""
    from matplotlib.transforms import blended_transform_factory
    entries = [e for r in ranges for e in r["entries"]]
    xs = [e["wall_seconds"] * 1e3 for e in entries]
    ys = [max(e["solver_error"], FLOOR) for e in entries]
    ax.step(xs, ys, where="post", color="0.55", lw=2.4, alpha=0.35, zorder=0)
    top = ax.get_ylim()[1]
    edge = blended_transform_factory(ax.transAxes, ax.transData)
    for r in ranges:
        hi = top if r["hi"] is None else r["hi"]
        lo = max(r["lo"], FLOOR)
        colour = integ.style(r["name"])["color"]
        ax.axhspan(lo, hi, xmin=0.975, xmax=1.0, color=colour, alpha=0.85, lw=0)
        middle = math.sqrt(lo * hi)
        if (math.log10(hi / lo) >= BAND_LABEL_DECADES and
                abs(math.log10(middle / disc)) > 0.15):
            ax.text(0.965, middle, r["family"], transform=edge, ha="right", va="center",
                    fontsize=8, color=colour, fontweight="bold",
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))


def case_figure(exp, ctx, db, rows, case, integ):
    disc = float(np.median([db["discretization_error"][r] for r in rows
                            if np.isfinite(db["discretization_error"][r])]))
    scene = db["scene"][rows[0]]
    titled = scene_title(exp, case, scene)
    entries = summaries(db, rows)
    fig = new_figure(13.5, 5.0)
    axes = fig.subplots(1, 2)
    families = {}
    for e in entries:
        if e["completed"]:
            families.setdefault(family(e), []).append(e)
    labelled = []
    # Adaptive methods solve the ODE, not the implicit Euler step: their
    # distance to that step is its own error, not a solver error.
    cheapest = cheapest_ranges([e for e in entries if e["completed"] and
                                not integ.adaptive(e["name"])])
    for ax, col, title in ((axes[0], "solver_error", "distance to the implicit Euler step"),
                           (axes[1], "total_error", "distance to the true motion")):
        points = []
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
                if e["variant"]:
                    points.append((x, y, short_variant(e["options"]), style["color"], fam))
        ax.axhline(disc, color="0.35", lw=1.2, ls="--")
        ax.text(0.99, disc, "implicit Euler's discretization error per step ", va="top",
                ha="right", fontsize=7.5, color="0.3", transform=ax.get_yaxis_transform())
        ax.set_xscale("log")
        ax.set_yscale("log")
        if col == "solver_error" and cheapest:
            draw_cheapest(ax, cheapest, integ, disc)
        ax.set_xlabel("wall time per step [ms] (median)")
        ax.set_ylabel("max position error after one step [m] (median)")
        ax.set_title("%s — %s" % (titled, title), loc="left", fontweight="bold", fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
        labelled.append((ax, points))
    legend_outside(axes[1])
    for ax, points in labelled:
        label_points(ax, label_order(points), fontsize=6.5, most=LABELS,
                     avoid=[(p[0], p[1]) for p in points])
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
    def costs(chosen, column):
        """"name (variant) T ms (E m); ..." of entries, in the given order."""
        return "; ".join("%s %s ms (%s m)" % (label(e), fmt(e["wall_seconds"] * 1e3, 3),
                                              fmt(e[column], 2)) for e in chosen)

    if cheapest:
        facts.append(cheapest_sentence(cheapest))
    if below:
        facts.append("Solver error below it (as good as solving the step exactly), cheapest "
                     "first: %s." % costs(below, "solver_error"))
    if above:
        facts.append("Solver error above it: %s." % costs(above, "solver_error"))
    closer = sorted((e for e in done if e["total_error"] < 0.5 * disc),
                    key=lambda e: e["wall_seconds"])
    if closer:
        facts.append("Closer to the true motion than the exact implicit Euler step (less than "
                     "half its error), cheapest first: %s." % costs(closer, "total_error"))
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
               "N, substeps S), joined by cost; the labelled ones are the cheapest for their "
               "error and each method's ends (the sentences below list all); dotted: implicit Euler solved by quasi-Newton, and "
               "projective dynamics with Chebyshev acceleration. "
               "The dashed line is implicit Euler's own error against the true motion. Times are "
               "wall times of one step, the integrator set up outside it.")
    return figure_html(saved, "solver error against cost", esc(caption)) + facts_html(facts)
