"""mode: what each integrator does to one vibration mode (experiments/README.md "mode"):
the period error and the amplitude kept per period of the beam's first
bending mode, against the steps per period, measured on the beam and
predicted from the method's step map on one oscillator of the mode's
frequency; and the mode's motion at the coarsest step each method survived.
The sentences under the figure are computed from the rows."""

import numpy as np

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, legend_outside, names_list, new_figure

KIND = "mode"
TITLE = "One vibration mode: period error and numerical damping"
ABOUT = (
    "Released in its first bending mode, a linear beam should swing at the mode's frequency w1 "
    "with constant amplitude forever. Theory: a one-step method treats each mode of a linear "
    "model like one oscillator of that frequency, so its period error and damping follow from "
    "one step of the method on x'' = −w1² x: implicit Euler lengthens the period by about "
    "(w1 h)²/3 and loses amplitude (it multiplies by 1/√(1 + w1² h²) per step); the midpoint rule "
    "keeps the amplitude and lengthens the period by about (w1 h)²/12; symplectic Euler and "
    "Verlet keep it and shorten the period by about (w1 h)²/24; RK4 damps a little. The explicit methods cannot take these steps at all: the beam's "
    "fastest mode w_max, not the first, sets their limit (w_max h ≤ 2).")

CEILING = 10.0  # period errors drawn up to 1000 %; diverged runs at the top
FLOOR = 1e-12


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("steps_per_period", "dt", "w", "period_exact", "period",
                                       "period_predicted", "amplitude_per_period",
                                       "amplitude_per_period_predicted", "steps"),
                 texts=("integrator", "status"))
    series = exp.table("series")
    integ = ctx.integrators
    by_name = {}
    for r in range(len(db)):
        by_name.setdefault(db["integrator"][r], []).append(r)
    names = integ.sort(by_name)
    w = float(exp.setting("w", db["w"][0]))
    w_max = exp.setting("w_max")
    period = 2 * np.pi / w

    fig = new_figure(16.5, 4.6)
    ax_err, ax_amp, ax_q = fig.subplots(1, 3)
    facts = []
    diverged = {}
    coarsest = {}
    mismatch_period, mismatch_amplitude = 0.0, 0.0
    for name in names:
        idx = np.asarray(sorted(by_name[name], key=lambda r: db["steps_per_period"][r]))
        s = db["steps_per_period"][idx]
        ok = np.array([db["status"][r] == "completed" for r in idx])
        err = np.abs(db["period"][idx] / period - 1.0)
        style = integ.style(name)
        shown = np.where(ok & np.isfinite(err), np.clip(err, FLOOR, CEILING), np.nan)
        ax_err.plot(s, shown, ls="none", marker=style.get("marker", "o"), ms=7, mfc="none",
                    mew=1.4, color=style.get("color"), label=name)
        predicted = np.abs(db["period_predicted"][idx] / period - 1.0)
        if np.isfinite(predicted).any():
            ax_err.plot(s, np.clip(predicted, FLOOR, CEILING), lw=1.0,
                        ls=style.get("ls", "-"), color=style.get("color"))
        if (~ok).any():
            # Stacked one above the other: several methods diverge at once.
            ax_err.plot(s[~ok], np.full((~ok).sum(), CEILING * 2.5 ** len(diverged)), ls="none",
                        marker="x", ms=9, mew=2, color=style.get("color"))
            diverged[name] = (float(s[~ok].max()), float(s[ok].min()) if ok.any() else None)
        amp = db["amplitude_per_period"][idx]
        ax_amp.plot(s[ok], amp[ok], ls="none", marker=style.get("marker", "o"), ms=7, mfc="none",
                    mew=1.4, color=style.get("color"), label=name)
        amp_predicted = db["amplitude_per_period_predicted"][idx]
        if np.isfinite(amp_predicted).any():
            ax_amp.plot(s, amp_predicted, lw=1.0, ls=style.get("ls", "-"),
                        color=style.get("color"))
        for r in idx[ok]:
            p, pp = db["period"][r], db["period_predicted"][r]
            a, ap = db["amplitude_per_period"][r], db["amplitude_per_period_predicted"][r]
            if np.isfinite(pp) and np.isfinite(p):
                mismatch_period = max(mismatch_period, abs(p / pp - 1.0))
            if np.isfinite(ap) and np.isfinite(a):
                mismatch_amplitude = max(mismatch_amplitude, abs(a - ap))
        if ok.any():
            coarsest[name] = int(idx[ok][0])

    for ax in (ax_err, ax_amp):
        ax.set_xscale("log")
        ax.set_xlabel("steps per period of the mode (adaptive methods: outputs)")
        ax.grid(True, which="major", alpha=0.3)
    ax_err.set_yscale("log")
    ax_err.set_ylabel("|period / (2π / w1) − 1|")
    ax_err.set_title("period error", loc="left", fontweight="bold", fontsize=10)
    ax_amp.set_yscale("log")
    ax_amp.set_yticks([0.1, 0.2, 0.5, 1, 2, 5, 10])
    ax_amp.set_yticklabels(["0.1", "0.2", "0.5", "1", "2", "5", "10"])
    ax_amp.minorticks_off()
    ax_amp.set_ylabel("amplitude kept per period")
    ax_amp.set_title("numerical damping", loc="left", fontweight="bold", fontsize=10)
    ax_amp.axhline(1.0, color="0.5", lw=0.8, ls=":")

    if series is not None and coarsest:
        q = Columns(series, numbers=("steps_per_period", "t", "q"), texts=("integrator",))
        groups = {(n, float(s)): rows
                  for (n, s), rows in q.groups("integrator", "steps_per_period").items()}
        for name, r in coarsest.items():
            rows = groups.get((name, float(db["steps_per_period"][r])))
            if rows is None:
                continue
            style = integ.style(name)
            ax_q.plot(q["t"][rows] / period, q["q"][rows], lw=1.1, ls=style.get("ls", "-"),
                      color=style.get("color"),
                      label="%s (%s steps/period)" % (name, fmt(db["steps_per_period"][r], 4)))
        ax_q.set_xlabel("t / (2π / w1)")
        ax_q.set_ylabel("modal coordinate q / q(0)")
        ax_q.set_title("the mode at each method's coarsest completed step", loc="left",
                       fontweight="bold", fontsize=10)
        ax_q.grid(True, alpha=0.3)
        ax_q.legend(loc="lower left", fontsize=6.5, framealpha=0.85)
    else:
        ax_q.set_visible(False)
    legend_outside(ax_amp)
    saved = ctx.figs.save(fig, exp.name + ".png")

    facts.append("The first mode: w1 = %s rad/s (period %s s)%s." % (
        fmt(w, 4), fmt(period, 4),
        "; the fastest mode of the same beam: w_max = %s rad/s, %s times faster" % (
            fmt(float(w_max), 4), fmt(float(w_max) / w, 3)) if w_max else ""))
    if diverged:
        parts = []
        for name in integ.sort(diverged):
            worst, first_ok = diverged[name]
            parts.append("%s up to %s steps per period%s" % (
                name, fmt(worst, 5), "" if first_ok is None else
                " (completed from %s)" % fmt(first_ok, 5)))
        limit = ""
        if w_max:
            ratio = float(w_max) / w
            limit = (" Symplectic Euler and Verlet are stable for w_max h ≤ 2, which is "
                     "π w_max / w1 = %s steps per period of the first mode; RK4 for "
                     "w_max h ≤ 2.83, %s steps per period." % (fmt(np.pi * ratio, 4),
                                                              fmt(2 * np.pi * ratio / 2.828, 4)))
        facts.append("Diverged: %s.%s" % ("; ".join(parts), limit))
    if mismatch_period or mismatch_amplitude:
        facts.append("Measured on the beam against predicted from the step map on one "
                     "oscillator (every completed fixed-step run): the period differs by at most "
                     "%s (relative), the amplitude per period by at most %s." % (
                         fmt(mismatch_period, 2), fmt(mismatch_amplitude, 2)))
    at_coarsest = []
    for name in integ.sort(coarsest):
        r = coarsest[name]
        at_coarsest.append("%s at %s steps per period: period %s%% %s, keeps %s%% per period" % (
            name, fmt(db["steps_per_period"][r], 4),
            fmt(abs(db["period"][r] / period - 1.0) * 100, 2),
            "long" if db["period"][r] >= period else "short",
            fmt(db["amplitude_per_period"][r] * 100, 4)))
    if at_coarsest:
        facts.append("At the coarsest step each method completed: %s." % "; ".join(at_coarsest))
    caption = ("Left: the period error of the first mode against the steps per period, measured "
               "from the zero crossings of the modal coordinate (markers) and predicted from one "
               "step of the same method on the oscillator x'' = −w1² x (lines); ✕ at the top, "
               "one row per method: the run diverged. Middle: the amplitude kept per period, from the slope of the "
               "logarithm of the mode's phase-space radius; above 1 the method adds energy. "
               "Right: the modal coordinate over time at the coarsest step each method "
               "completed.")
    return figure_html(saved, "mode: period error and damping", esc(caption)) + facts_html(facts)

