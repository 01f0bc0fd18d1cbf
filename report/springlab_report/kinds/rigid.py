"""rigid: the tumbling box, an affine body, under many integrators against the
exact torque-free rigid body (experiments/analysis/rigid_reference.h), and the affine
body's convergence to the rigid one as the rigidity kappa grows. Every
sentence under the figure is computed from the tables."""

import math

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, legend_outside, log_log, new_figure

KIND = "rigid"
TITLE = "Rigid bodies: the tumbling box against the exact rigid body"
ABOUT = (
    "A rigid body is simulated as an affine body: x = p + A X, with a stiff potential "
    "κ V |AᵀA − I|² keeping A a rotation, so every integrator runs it unchanged. Spun about its "
    "middle principal axis, a box is unstable and flips over and back (the Dzhanibekov or "
    "tennis-racket effect) while its energy and angular momentum L stay fixed. The reference is "
    "the exact rigid body: Euler's equations I ω' = (Iω) × ω and the quaternion q' = q (0, ω)/2, "
    "by RK4 at a tiny step. The flip period is the mean time between successive reversals of the "
    "spin axis, i.e. sign changes of the component of L along the middle principal axis. Theory: "
    "symplectic methods keep the energy in a band, implicit Euler drains it, explicit Euler gains "
    "it; the implicit midpoint rule keeps L exactly. As κ grows the affine body tends to the "
    "rigid one (strain and error ∝ 1/κ), but its fastest mode ω_κ = √(8κV / min J_i) grows, so "
    "an explicit method needs h < c / ω_κ ∝ κ^(−1/2).")

FLOOR = 1e-16



# The strain oscillates with the body's spin, many times per second: drawn
# raw, eleven methods make a scribble. Its maximum over each of this many
# equal windows of the run shows what the lesson needs (how far A drifts from
# a rotation, and whether it grows).
STRAIN_WINDOWS = 40


def window_max(t, y, windows):
    """The window centres and the maximum of y within each of `windows` equal
    windows of [t[0], t[-1]] (windows without a sample are left out)."""
    if len(t) == 0:
        return t, y
    edges = np.linspace(t[0], t[-1], windows + 1)
    which = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, windows - 1)
    top = np.full(windows, -np.inf)
    np.maximum.at(top, which, y)
    keep = np.isfinite(top)
    return ((edges[:-1] + edges[1:]) / 2)[keep], top[keep]

def _pct(x):
    return "%s %%" % fmt(100.0 * x, 2)


def _slope(x, y):
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if ok.sum() < 2:
        return None
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("t", "energy", "momentum_drift", "strain", "axis",
                                       "axis_reference", "orientation_error"),
                 texts=("integrator",))
    runs = Columns(exp.table("runs"), numbers=(
        "energy_final", "energy_drift_max", "momentum_drift_max", "strain_max",
        "orientation_error_max", "reversals", "first_reversal", "flip_period",
        "reference_first_reversal", "reference_flip_period", "period_error", "diverged_at"),
        texts=("integrator", "status"))
    kap = exp.table("kappa")
    lim = exp.table("limits")
    kappa = Columns(kap, numbers=("kappa", "strain_max", "orientation_error_max",
                                  "period_error"), texts=("integrator", "status")) \
        if kap is not None and len(kap) else None
    limits = Columns(lim, numbers=("kappa", "w_formula", "w_max", "dt_theory", "dt_max_stable",
                                   "ratio"), texts=("integrator", "outcome")) \
        if lim is not None and len(lim) else None
    integ = ctx.integrators
    names = integ.sort(set(db["integrator"]))
    series = db.groups("integrator")

    fig = new_figure(15.0, 9.0)
    axes = fig.subplots(2, 3, squeeze=False)
    ax_e, ax_l, ax_c = axes[0]
    ax_s, ax_k, ax_h = axes[1]
    for k, name in enumerate(names):
        idx = series[(name,)]
        t = db["t"][idx]
        style = dict(color=integ.colour(name), ls=integ.linestyle(name),
                     lw=max(1.0, 2.6 - 0.15 * k), marker=integ.marker(name), ms=5, mfc="none",
                     markevery=(k * max(1, len(t) // 60), max(1, len(t) // 6)), label=name)
        later = t > 0  # the drifts and the strain are 0 at t = 0: not on a log scale
        ax_e.plot(t[later], np.maximum(np.abs(db["energy"][idx][later] - 1.0), FLOOR), **style)
        ax_l.plot(t[later], np.maximum(db["momentum_drift"][idx][later], FLOOR), **style)
        ax_c.plot(t, db["axis"][idx], **style)
        tw, sw = window_max(t[later], db["strain"][idx][later], STRAIN_WINDOWS)
        ax_s.plot(tw, np.maximum(sw, FLOOR), **dict(style, markevery=max(1, k % 5)))
    if names:
        idx = series[(names[0],)]
        ax_c.plot(db["t"][idx], db["axis_reference"][idx], color="0.6", lw=7, alpha=0.6,
                  solid_capstyle="butt", label="exact rigid body", zorder=1)
    for ax, title, label in (
            (ax_e, "energy drift", "|E / E₀ − 1|"),
            (ax_l, "angular momentum drift", "|L − L₀| / |L₀|"),
            (ax_c, "the flip: spin axis along L", "cos(a_middle, L)"),
            (ax_s, "distance of A from a rotation", "max of |AᵀA − I|_F per 1/%d of the run"
             % STRAIN_WINDOWS)):
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_ylabel(label)
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
        if ax is not ax_c:
            ax.set_yscale("log")
    ax_c.set_ylim(-1.1, 1.1)
    legend_outside(ax_c, fontsize=9)

    if kappa is not None:
        order = np.argsort(kappa["kappa"])
        x = kappa["kappa"][order]
        ax_k.plot(x, kappa["orientation_error_max"][order], "o-", color="#1f77b4", lw=2,
                  label="max |A − R_exact|_F")
        ax_k.plot(x, kappa["strain_max"][order], "s--", color="#d62728", lw=2,
                  label="max |AᵀA − I|_F")
        ax_k.plot(x, np.abs(kappa["period_error"][order]), "^-.", color="#2ca02c", lw=2,
                  label="|flip period error|")
        if log_log(ax_k):
            ax_k.legend(loc="lower left", fontsize=9)
        ax_k.set_title("error against κ (%s)" % kappa["integrator"][0], loc="left",
                       fontweight="bold")
        ax_k.set_xlabel("κ [Pa]")
        ax_k.grid(True, which="both", alpha=0.3)
    else:
        log_log(ax_k, "no κ sweep in this run")
    if limits is not None:
        for name, idx in limits.groups("integrator").items():
            idx = idx[np.argsort(limits["kappa"][idx])]
            ax_h.plot(limits["kappa"][idx], limits["dt_max_stable"][idx], ls="none",
                      ms=9, mew=1.8, mfc="none", **{k: v for k, v in integ.style(name[0]).items()
                                                    if k != "ls"}, label=name[0] + " (measured)")
            theory = limits["dt_theory"][idx]
            if np.isfinite(theory).any():
                ax_h.plot(limits["kappa"][idx], theory, color=integ.colour(name[0]), lw=1.2,
                          label="%s: c / ω_κ" % name[0])
        if log_log(ax_h):
            ax_h.legend(loc="upper right", fontsize=8)
        ax_h.set_title("explicit step limit against κ", loc="left", fontweight="bold")
        ax_h.set_xlabel("κ [Pa]")
        ax_h.set_ylabel("largest stable dt [s]")
        ax_h.grid(True, which="both", alpha=0.3)
    else:
        log_log(ax_h, "no step-limit search in this run")
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = (
        "Top: energy drift, angular-momentum drift (about the centre of mass) and the cosine "
        "between the body's middle principal axis and L (the flip; the exact rigid body as the "
        "wide grey band) for each integrator at the same step. Bottom left: |AᵀA − I|_F, how far A is "
        "from a rotation, as its largest value in each 1/%d of the run (it oscillates with the "
        "spin many times per window). Bottom middle: the affine body against the rigid one as κ grows. Bottom "
        "right: the largest stable step found by bisection (markers) and theory's c / ω_max "
        "(lines). Drifts and strain from the first output after t = 0; below 1e-16 drawn at 1e-16." % STRAIN_WINDOWS)
    facts = sentences(runs, kappa, limits, exp)
    html = figure_html(saved, "rigid: the tumbling box", esc(caption)) + facts_html(facts)
    return html + render_pile(exp, ctx)


def render_pile(exp, ctx):
    """The pile: the top box's height and the energy against time for each
    (integrator, dt), and what each run did."""
    rows, runs = exp.table("pile"), exp.table("pile_runs")
    if rows is None or runs is None or not len(runs):
        return ""
    db = Columns(rows, numbers=("dt", "t", "top_height", "energy", "kinetic", "smallest_gap"),
                 texts=("integrator",))
    runs = Columns(runs, numbers=("dt", "diverged_at", "steps", "newton_per_step",
                                  "top_height_final", "energy_initial", "energy_final",
                                  "smallest_gap", "wall_seconds"),
                   texts=("integrator", "status", "failure"))
    integ = ctx.integrators
    fig = new_figure(15.0, 4.8)
    ax_h, ax_e = fig.subplots(1, 2, squeeze=False)[0]
    groups = db.groups("integrator", "dt")
    order = integ.sort(set(db["integrator"]))
    keys = sorted(groups, key=lambda k: (order.index(k[0]), -float(k[1])))
    stopped_at = pile_stops(runs)
    # The energy axis spans what the runs that completed reached (with a
    # margin); a run that leaves it is named in the caption, with its peak.
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    top = max((float(np.nanmax(db["energy"][groups[k]])) for k in keys
               if pile_stop(stopped_at, k) is None), default=None)
    left_axis = []
    for k, key in enumerate(keys):
        idx = groups[key]
        name, dt = key[0], float(key[1])
        stop = pile_stop(stopped_at, key)
        label = "%s, dt = %s s" % (name, fmt(dt, 3))
        if stop is not None:
            label += ", %s at t = %s s" % (stop[0], fmt(stop[1], 3))
        style = dict(color=integ.colour(name), ls="-" if dt < 0.005 else "--",
                     lw=max(1.0, 2.4 - 0.15 * k), label=label)
        t, h, e = db["t"][idx], db["top_height"][idx], db["energy"][idx]
        ax_h.plot(t, h, **style)
        ax_e.plot(t, e, **style)
        if stop is not None and len(t):  # where the run ended: a cross
            for ax, y in ((ax_h, h), (ax_e, e)):
                ax.plot([t[-1]], [y[-1]], "x", color=style["color"], ms=9, mew=2.2)
        if top is not None and done and np.nanmax(e) > 1.25 * top:
            peak = int(np.nanargmax(e))
            left_axis.append("%s at %s s (%s J at t = %s s)" % (
                name, fmt(dt, 3), fmt(e[peak], 3), fmt(t[peak], 3)))
    if top is not None and done:
        ax_e.set_ylim(0.0, 1.25 * top)
    for ax, title, label in ((ax_h, "height of the top box", "y of its centre [m]"),
                             (ax_e, "energy", "E [J]")):
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_ylabel(label)
        ax.set_xlabel("t [s]")
        ax.grid(True, alpha=0.3)
    legend_outside(ax_e, fontsize=9)
    saved = ctx.figs.save(fig, exp.name + "-pile.png")
    pile = exp.setting("pile") or {}
    damping = pile_damping(pile)
    caption = ("The box pile (%s bodies meeting each other and the ground under the barrier%s) "
               "under each implicit method: the top box's height and the total energy against "
               "time. A pile that stands keeps its top box up; a run that stops ends its lines "
               "with a cross (the legend says when, the sentences below why)." %
               (fmt(pile.get("bodies"), 3), ", " + damping if damping else ""))
    if left_axis:
        caption += (" The energy axis ends at 1.25 times the highest energy of the runs that "
                    "completed; above it: %s." % "; ".join(left_axis))
    return (figure_html(saved, "rigid: the box pile", esc(caption)) +
            facts_html(pile_sentences(runs), heading="What the pile shows"))


def pile_damping(pile):
    """How the pile's collisions dissipate, from its scene's bodies (the
    setting's scene as the experiment wrote it); "" when it does not say."""
    scene = pile.get("scene")
    bodies = scene.get("bodies") if isinstance(scene, dict) else None
    if not bodies:
        return ""
    alphas = sorted({float(b.get("contact_damping", 0.0)) for b in bodies})
    if alphas == [0.0]:
        return "elastic contact: no contact damping"
    if len(alphas) == 1:
        return "every box with contact damping alpha = %s s/m" % fmt(alphas[0], 3)
    return "the boxes' contact damping alpha from %s to %s s/m" % (fmt(alphas[0], 3),
                                                                   fmt(alphas[-1], 3))


def pile_stops(runs):
    """(integrator, dt) -> (status, time) of each run that did not complete."""
    return {(runs["integrator"][r], float(runs["dt"][r])): (runs["status"][r],
                                                           float(runs["diverged_at"][r]))
            for r in range(len(runs)) if runs["status"][r] != "completed"}


def pile_stop(stops, key):
    """The stop of the run drawn as `key` (integrator, dt text), or None."""
    for (name, dt), stop in stops.items():
        if name == key[0] and math.isclose(dt, float(key[1]), rel_tol=1e-9):
            return stop
    return None


def pile_sentences(runs):
    out = []
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    stopped = [r for r in range(len(runs)) if runs["status"][r] != "completed"]

    def label(r):
        return "%s at %s s" % (runs["integrator"][r], fmt(runs["dt"][r], 3))
    if done:
        heights = [runs["top_height_final"][r] for r in done]
        reference = max(heights)
        standing = [r for r in done if runs["top_height_final"][r] >= reference - 0.01]
        fallen = [r for r in done if runs["top_height_final"][r] < reference - 0.01]
        if standing:
            out.append("Completed with the top box within 1 cm of the highest final height "
                       "(%s m): %s." % (fmt(reference, 4), ", ".join(
                           "%s (%s Newton iterations per step)" % (
                               label(r), fmt(runs["newton_per_step"][r], 3)) for r in standing)))
        if fallen:
            out.append("Completed with the top box lower (boxes slid or bounced off): %s." %
                       ", ".join("%s (%s m)" % (label(r), fmt(runs["top_height_final"][r], 3))
                                 for r in fallen))
        gaps = [runs["smallest_gap"][r] for r in done if math.isfinite(runs["smallest_gap"][r])]
        if gaps:
            out.append("The smallest gap between two boxes' surfaces over every completed run "
                       "is %s m: no accepted state has them touching." % fmt(min(gaps), 3))
        losses = ["%s %s" % (label(r), _pct(runs["energy_final"][r] / runs["energy_initial"][r]
                                            - 1.0)) for r in done]
        out.append("Energy change over the run: %s." % ", ".join(losses))
    if stopped:
        out.append("Stopped: %s." % "; ".join(
            "%s %s at t = %s s (%s)" % (label(r), runs["status"][r], fmt(runs["diverged_at"][r], 4),
                                      runs["failure"][r]) for r in stopped))
    return out


def sentences(runs, kappa, limits, exp):
    out = []
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    ref_period = next((runs["reference_flip_period"][r] for r in range(len(runs))
                       if math.isfinite(runs["reference_flip_period"][r])), None)
    ref_first = next((runs["reference_first_reversal"][r] for r in range(len(runs))
                      if math.isfinite(runs["reference_first_reversal"][r])), None)
    t_end = exp.setting("t_end")
    if ref_period is not None:
        out.append("The exact rigid body reverses its spin axis first at t = %s s and then every "
                   "%s s (the flip period)." % (fmt(ref_first, 4), fmt(ref_period, 4)))
    elif ref_first is not None:
        out.append("The exact rigid body reverses its spin axis once, at t = %s s; the run is too "
                   "short for a period." % fmt(ref_first, 4))
    stopped = [r for r in range(len(runs)) if runs["status"][r] != "completed"]
    if stopped:
        out.append("%s at the same step: %s." % (
            "Stopped" if len(stopped) > 1 else "Stopped",
            "; ".join("%s %s at t = %s s" % (runs["integrator"][r], runs["status"][r],
                                              fmt(runs["diverged_at"][r], 3)) for r in stopped)))
    with_period = [r for r in done if math.isfinite(runs["period_error"][r])]
    if with_period:
        with_period.sort(key=lambda r: abs(runs["period_error"][r]))
        close = [r for r in with_period if abs(runs["period_error"][r]) <= 0.01]
        far = [r for r in with_period if abs(runs["period_error"][r]) > 0.01]
        if close:
            out.append("Flip period within 1 %% of the exact one: %s." % ", ".join(
                "%s (%s)" % (runs["integrator"][r], _pct(runs["period_error"][r]))
                for r in close))
        if far:
            out.append("Flip period off by more than 1 %%: %s." % ", ".join(
                "%s (%s)" % (runs["integrator"][r], _pct(runs["period_error"][r])) for r in far))
    no_flip = [r for r in done if runs["reversals"][r] < 2]
    if no_flip:
        out.append("Fewer than two reversals by t = %s s (no period measured): %s." % (
            fmt(t_end, 4), ", ".join("%s (%d)" % (runs["integrator"][r], runs["reversals"][r])
                                     for r in no_flip)))
    if done:
        by_energy = sorted(done, key=lambda r: runs["energy_final"][r])
        out.append("Energy at the end, E / E₀: %s." % ", ".join(
            "%s %s" % (runs["integrator"][r], fmt(runs["energy_final"][r], 6)) for r in by_energy))
        best = min(done, key=lambda r: runs["momentum_drift_max"][r])
        worst = max(done, key=lambda r: runs["momentum_drift_max"][r])
        out.append("Angular momentum: the smallest largest drift |L − L₀| / |L₀| is %s's %s, the "
                   "largest %s's %s." % (runs["integrator"][best],
                                         fmt(runs["momentum_drift_max"][best], 2),
                                         runs["integrator"][worst],
                                         fmt(runs["momentum_drift_max"][worst], 2)))
        strain = max(done, key=lambda r: runs["strain_max"][r])
        out.append("A stays within |AᵀA − I|_F ≤ %s of a rotation in every completed run (largest: "
                   "%s) at κ = %s Pa." % (fmt(runs["strain_max"][strain], 2),
                                          runs["integrator"][strain],
                                          fmt((exp.setting("body") or {}).get("rigidity"), 3)))
    if kappa is not None:
        order = np.argsort(kappa["kappa"])
        x = kappa["kappa"][order]
        err = kappa["orientation_error_max"][order]
        strain = kappa["strain_max"][order]
        perr = np.abs(kappa["period_error"][order])
        s_err, s_strain = _slope(x, err), _slope(x, strain)
        text = ("As κ grows from %s to %s Pa (%s at dt = %s s), the largest |A − R_exact|_F falls "
                "from %s to %s%s and the largest strain from %s to %s%s" % (
                    fmt(x[0], 3), fmt(x[-1], 3), kappa["integrator"][0],
                    fmt(exp.setting("kappa_dt"), 3), fmt(err[0], 3), fmt(err[-1], 3),
                    " (fitted slope %s)" % fmt(s_err, 2) if s_err is not None else "",
                    fmt(strain[0], 3), fmt(strain[-1], 3),
                    " (slope %s)" % fmt(s_strain, 2) if s_strain is not None else ""))
        if np.isfinite(perr).any():
            text += "; the flip period's error from %s to %s" % (_pct(perr[0]), _pct(perr[-1]))
        out.append(text + ".")
    if limits is not None:
        parts = []
        for name, idx in limits.groups("integrator").items():
            idx = idx[np.argsort(limits["kappa"][idx])]
            ratio = limits["ratio"][idx]
            s = _slope(limits["kappa"][idx], limits["dt_max_stable"][idx])
            part = "%s from %s s to %s s" % (name[0], fmt(limits["dt_max_stable"][idx][0], 3),
                                             fmt(limits["dt_max_stable"][idx][-1], 3))
            if s is not None:
                part += " (slope %s)" % fmt(s, 3)
            if np.isfinite(ratio).any():
                part += ", %s to %s times theory's" % (fmt(np.nanmin(ratio), 3),
                                                       fmt(np.nanmax(ratio), 3))
            parts.append(part)
        w_rel = np.nanmax(np.abs(limits["w_max"] / limits["w_formula"] - 1.0))
        out.append("Largest stable step as κ grows: %s. The fastest mode found numerically "
                   "matches ω_κ = √(8κV / min J_i) to %s (relative)." % (
                       "; ".join(parts), fmt(w_rel, 2)))
    return out
