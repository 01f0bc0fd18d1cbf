"""fluid: the dam break (weakly compressible SPH) under many integrators,
beside Martin and Moyce's (1952) measured surge front; its cost; its energy
budget; and the explicit step limit against the speed of sound. Every
sentence under the figure is computed from the tables."""

import math
import textwrap

import numpy as np

from ..data import Columns
from matplotlib.ticker import FuncFormatter, NullFormatter

from ..figures import esc, facts_html, figure_html, fmt, label_points, names_list, new_figure

KIND = "fluid"
TITLE = "Fluids: the dam break under every integrator"
ABOUT = (
    "Smoothed particle hydrodynamics puts the Navier-Stokes equations on particles, so the state "
    "stays (x, v) with a diagonal mass and every integrator runs a fluid. A weakly compressible "
    "fluid's stiffness is its speed of sound c: the Tait equation of state makes a compression "
    "of 1 % cost a pressure of about ρ₀c²/100, and its fastest (acoustic) mode sets the explicit "
    "step limit, the CFL condition h_t ≤ C h / (c + |v|max) (h the smoothing length), as a "
    "spring's stiffness sets 2/ω. The dam break: a column a wide and 2a high, released at t = 0, "
    "spreads along the floor; Martin and Moyce (1952) measured its front z against time, in "
    "Z = z/a and T = t √(2g/a). No front can outrun Ritter's dry-bed shallow-water wave "
    "2√(gH), H = 2a: in these variables Z ≤ 1 + 2T. Energy: the total energy falls by the "
    "viscous work exactly; what it loses (or gains) beyond that is the integrator's own.")

FIELD_T2 = 2.0


def _pct(x):
    return "%s %%" % fmt(100.0 * x, 2)


def _runs(exp):
    return Columns(exp.table("runs"), numbers=(
        "dt", "diverged_at", "t_final", "steps", "force_evals", "newton_iterations", "wall_seconds",
        "cost_per_second", "Z_T2", "Z_T2_measured", "Z_T2_error", "front_speed_max",
        "ritter_speed", "compression_max", "energy_initial", "viscous_work", "numerical",
        "particles"), texts=("integrator", "status", "failure"))


def _dt_text(dt):
    """A step as a reader says it: "1/60 s" for a frame rate, "1 ms" below."""
    if not math.isfinite(dt) or dt <= 0:
        return "–"
    rate = 1.0 / dt
    if rate < 500 and abs(rate - round(rate)) < 1e-6 * rate:
        return "1/%d s" % round(rate)
    return "%s ms" % fmt(1e3 * dt, 2)


FRAME_STEP = 5e-3  # steps at least this long count as "large" (a game's frame is 16.7 ms)


def _run_label(name, dt):
    return "%s at %s" % (name, _dt_text(dt))


def _gauges(exp):
    table = exp.table("gauges")
    if table is None or not len(table):
        return None, None, None
    series = Columns(table, numbers=("t", "height", "measured"), texts=("gauge",))
    summary = Columns(exp.table("gauge_summary"), numbers=(
        "x", "z", "dt", "t_final", "steps", "cpu_seconds", "particles", "water", "samples",
        "rms_error", "max_error", "bound", "within_bound", "arrival_measured",
        "arrival_simulated"), texts=("gauge", "integrator", "status", "failure"))
    ref_table = exp.table("gauge_reference")
    reference = Columns(ref_table, numbers=("t", "height"), texts=("gauge",)) \
        if ref_table is not None and len(ref_table) else None
    return series, summary, reference


def render(exp, ctx):
    db = Columns(exp.table(), numbers=("dt", "t", "T", "Z", "total", "viscous_work", "numerical",
                                       "compression"), texts=("integrator",))
    runs = _runs(exp)
    ref_table = exp.table("reference")
    ref = Columns(ref_table, numbers=("T", "Z")) if ref_table is not None and len(ref_table) \
        else None
    lim_table = exp.table("limits")
    limits = Columns(lim_table, numbers=(
        "sound", "c", "h", "hydrostatic", "w_max", "dt_theory", "C_theory", "dt_max_stable",
        "v_max",
        "C_measured", "ratio"), texts=("integrator", "outcome")) \
        if lim_table is not None and len(lim_table) else None
    dam = exp.setting("dam_break") or {}
    scale = dam.get("energy_scale") or 1.0
    integ = ctx.integrators
    # One series per run: (integrator, dt) (an integrator may run at a small
    # and at a frame step).
    series = db.groups("integrator", "dt")
    order = integ.sort({k[0] for k in series})
    keys = sorted(series, key=lambda k: (order.index(k[0]), float(k[1])))

    fig = new_figure(15.0, 13.2)
    axes = fig.subplots(3, 3, squeeze=False)
    ax_z, ax_cz, ax_lim = axes[0]
    ax_e, ax_w, ax_n = axes[1]
    ax_ce, ax_cd, ax_g = axes[2]
    for k, key in enumerate(keys):
        name, dt = key[0], float(key[1])
        idx = series[key]
        T = db["T"][idx]
        large = dt >= FRAME_STEP
        style = dict(color=integ.colour(name), ls="--" if large else integ.linestyle(name),
                     lw=max(1.0, 2.4 - 0.12 * k), marker=integ.marker(name), ms=5,
                     mfc=integ.colour(name) if large else "none",
                     markevery=(k * max(1, len(T) // 50), max(1, len(T) // 6)),
                     label=_run_label(name, dt))
        ax_z.plot(T, db["Z"][idx], **style)
        e0 = db["total"][idx][0] if len(idx) else 0.0
        ax_e.plot(T, (db["total"][idx] - e0) / scale, **style)
        ax_w.plot(T, db["viscous_work"][idx] / scale, **style)
        ax_n.plot(T, db["numerical"][idx] / scale, **style)
    T_top = float(np.nanmax(db["T"])) if len(db) else 3.0
    ritter = np.array([0.0, T_top])
    ax_z.plot(ritter, 1.0 + 2.0 * ritter, color="0.45", ls=":", lw=1.5,
              label="Ritter's bound Z = 1 + 2T")
    if ref is not None:
        ax_z.plot(ref["T"], ref["Z"], ls="none", marker="o", ms=8, color="black", mfc="0.85",
                  label="Martin and Moyce 1952", zorder=5)
    ax_z.set_ylim(0.9, max(4.5, float(np.nanmax(ref["Z"])) + 0.3 if ref is not None else 4.5))
    ax_z.set_xlim(0.0, T_top)
    for ax, title, ylabel in (
            (ax_z, "surge front", "Z = z / a"),
            (ax_e, "total energy change", "(E − E₀) / (M g a)"),
            (ax_w, "viscous work", "W_visc / (M g a)"),
            (ax_n, "numerical: E − E₀ + W_visc", "(E − E₀ + W_visc) / (M g a)")):
        ax.set_title(title, loc="left", fontweight="bold")
        ax.set_xlabel("T = t √(2g/a)")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    # One legend for every panel of runs, under the figure (there are many runs).
    handles, labels = ax_z.get_legend_handles_labels()
    ax_n.axhline(0.0, color="0.5", lw=0.8)

    # Cost against accuracy, completed runs: the front at T = 2 against Martin
    # and Moyce, the energy budget's closure, the density error.
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    accuracy = (
        (ax_cz, "cost against the front's error", "|Z(T=2) / measured − 1|",
         lambda r: abs(runs["Z_T2_error"][r])),
        (ax_ce, "cost against the energy budget", "|E − E₀ + W_visc| / (M g a) at the end",
         lambda r: abs(runs["numerical"][r]) / scale),
        (ax_cd, "cost against the density error", "largest compression ρ/ρ₀ − 1",
         lambda r: runs["compression_max"][r]))
    for ax, title, ylabel, value in accuracy:
        candidates, avoid = [], []
        for r in done:
            x, y = runs["cost_per_second"][r], value(r)
            if not (math.isfinite(x) and math.isfinite(y) and x > 0 and y > 0):
                continue
            name, dt = runs["integrator"][r], runs["dt"][r]
            large = dt >= FRAME_STEP
            ax.plot([x], [y], ls="none", marker=integ.marker(name), ms=8, mew=1.6,
                    color=integ.colour(name), mfc=integ.colour(name) if large else "none")
            candidates.append((x, y, _run_label(name, dt), integ.colour(name)))
            avoid.append((x, y))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU seconds per simulated second (one core)")
        ax.set_ylabel(ylabel)
        ax.set_title(title, loc="left", fontweight="bold")
        ax.grid(True, which="both", alpha=0.3)
        if candidates:
            label_points(ax, candidates, fontsize=7.5, avoid=avoid)
        else:
            ax.text(0.5, 0.5, "no completed run", transform=ax.transAxes, ha="center")

    if limits is not None:
        for name, idx in limits.groups("integrator").items():
            idx = idx[np.argsort(limits["c"][idx])]
            kw = {k: v for k, v in integ.style(name[0]).items() if k != "ls"}
            ax_lim.plot(limits["c"][idx], limits["dt_max_stable"][idx], ls="none", ms=9, mew=1.8,
                        mfc="none", label=name[0] + " (measured)", **kw)
            theory = limits["dt_theory"][idx]
            if np.isfinite(theory).any():
                ax_lim.plot(limits["c"][idx], theory, color=integ.colour(name[0]), lw=1.2,
                            label="%s: (ωh)* / ω_max" % name[0])
        c = np.sort(limits["c"])
        h = float(np.nanmax(limits["h"]))
        C = _median(limits["C_measured"])
        if C is not None:
            vmax = np.interp(c, np.sort(limits["c"]), limits["v_max"][np.argsort(limits["c"])])
            ax_lim.plot(c, C * h / (c + vmax), color="0.3", ls="--", lw=1.2,
                        label="C h / (c + |v|max), C = %s" % fmt(C, 2))
        ax_lim.set_xscale("log")
        ax_lim.set_yscale("log")
        ax_lim.xaxis.set_major_formatter(FuncFormatter(lambda v, _: "%.3g" % v))
        ax_lim.xaxis.set_minor_formatter(NullFormatter())
        ax_lim.set_xticks(sorted(set(float(c) for c in limits["c"])))
        ax_lim.legend(loc="lower left", fontsize=8)
        ax_lim.set_xlabel("speed of sound c [m/s]")
        ax_lim.set_ylabel("largest stable dt [s]")
        ax_lim.grid(True, which="both", alpha=0.3)
    else:
        ax_lim.text(0.5, 0.5, "no step-limit search in this run", transform=ax_lim.transAxes,
                    ha="center")
    ax_lim.set_title("explicit step limit against c", loc="left", fontweight="bold")

    gauges, gauge_summary, gauge_ref = _gauges(exp)
    gauge_colours = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd")
    if gauges is not None:
        for k, (name, idx) in enumerate(gauges.groups("gauge").items()):
            colour = gauge_colours[k % len(gauge_colours)]
            ax_g.plot(gauges["t"][idx], gauges["height"][idx], color=colour, lw=2.0,
                      label="%s simulated" % name[0])
            if gauge_ref is not None:
                ridx = gauge_ref.groups("gauge").get(name)
                if ridx is not None:
                    step = max(1, len(ridx) // 40)
                    ax_g.plot(gauge_ref["t"][ridx][::step], gauge_ref["height"][ridx][::step],
                              ls="none", marker="o", ms=5, color=colour, mfc="white",
                              label="%s measured" % name[0])
        g = exp.setting("gauges") or {}
        ax_g.set_title("3-D: MARIN dam break (%s, %s)" % (
            g.get("integrator", ""), _dt_text(g.get("dt", float("nan")))),
            loc="left", fontweight="bold", fontsize=10)
        ax_g.set_xlabel("t [s]")
        ax_g.set_ylabel("water height at the gauge [m]")
        ax_g.grid(True, alpha=0.3)
        ax_g.legend(loc="upper right", fontsize=8)
    else:
        ax_g.text(0.5, 0.5, "no 3-D gauges in this run", transform=ax_g.transAxes, ha="center")
        ax_g.set_title("3-D: water height", loc="left", fontweight="bold")
    rows = (len(labels) + 5) // 6
    fig.tight_layout(rect=(0.0, 0.0125 * rows + 0.008, 1.0, 1.0))
    # The legend right under the bottom row's labels.
    renderer = fig.canvas.get_renderer()
    bottom = min(ax.get_tightbbox(renderer).y0 for ax in axes[2]) / fig.bbox.height
    fig.legend(handles, labels, loc="upper center", ncol=6, fontsize=8.5, frameon=False,
               bbox_to_anchor=(0.5, bottom))
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = (
        "Top left: the front Z = z/a against T = t √(2g/a) for each run (integrator and step; "
        "dashed, filled markers: steps of 5 ms or more), Martin and Moyce's measured points "
        "(circles; %s) and Ritter's bound (dotted). Top middle and bottom left and middle: each "
        "completed run's CPU seconds (one core) per simulated second against its error: the "
        "front at T = 2 against the measurement, the energy the integrator itself added or "
        "removed by the end, and the largest compression (a weakly compressible fluid aims at "
        "about 1 %%); filled markers: the large steps. Top right: the largest stable step found "
        "by bisection (markers) against the speed of sound on a coarser dam break, the acoustic "
        "mode's limit (ωh)*/ω_max (lines) and the CFL form with the median measured C (dashed). "
        "Middle row: the total energy's change, the viscous work and their sum, the "
        "integrator's own part, all over M g a (the column's potential energy above the floor). "
        "Bottom right: the 3-D dam break onto a box (MARIN, SPHERIC test 2) at its water-height "
        "gauges, simulated (lines) and measured (circles; %s)." % (
            esc(_short_source(exp)), esc(_gauge_source(exp))))
    facts = sentences(runs, ref, limits, exp) + gauge_sentences(gauge_summary, exp)
    return figure_html(saved, "fluid: the dam break", caption) + facts_html(facts)


def _gauge_source(exp):
    g = exp.setting("gauges") or {}
    source = (g.get("reference") or {}).get("source") or ""
    # The citation's start, shortened at a word's end (the data file's own
    # '#' lines say the rest).
    return textwrap.shorten(source, width=200, placeholder=" …") or "no reference"


def gauge_sentences(summary, exp):
    if summary is None or not len(summary):
        return []
    g = exp.setting("gauges") or {}
    out = []
    r0 = 0
    status = summary["status"][r0]
    head = ("3-D (MARIN's dam break onto a box, SPHERIC test 2): %s at dt = %s, %d particles "
            "(%d of them water, spacing %s m), %s t = %s s in %s CPU seconds." % (
                summary["integrator"][r0], _dt_text(summary["dt"][r0]),
                int(summary["particles"][r0]), int(summary["water"][r0]),
                fmt(g.get("spacing", float("nan")), 3),
                "completed to" if status == "completed" else "%s at" % status,
                fmt(summary["t_final"][r0], 3), fmt(summary["cpu_seconds"][r0], 3)))
    out.append(head)
    parts, within, over = [], [], []
    for r in range(len(summary)):
        name = summary["gauge"][r]
        rms = summary["rms_error"][r]
        if not math.isfinite(rms):
            continue
        part = "%s %s m rms (largest %s m)" % (name, fmt(rms, 2), fmt(summary["max_error"][r], 2))
        am, asim = summary["arrival_measured"][r], summary["arrival_simulated"][r]
        if math.isfinite(am):
            part += ", water arriving at t = %s s (measured %s s)" % (
                fmt(asim, 3) if math.isfinite(asim) else "– (never)", fmt(am, 3))
        parts.append(part)
        (within if summary["within_bound"][r] == 1 else over).append(name)
    if parts:
        bound = summary["bound"][r0]
        text = "Against the measured heights: %s; the bound is %s m rms" % (
            "; ".join(parts), fmt(bound, 2))
        if over:
            text += ", which %s %s." % (names_list(over), "passes" if len(over) == 1 else "pass")
        else:
            text += ", which every gauge keeps."
        out.append(text)
    return out


def _short_source(exp):
    ref = exp.setting("reference") or {}
    source = ref.get("source") or ""
    cut = source.find(": the surge front")
    return (source[:cut] if cut > 0 else source[:200]) or ref.get("file", "reference")


def _median(x):
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(np.median(x)) if len(x) else None


def sentences(runs, ref, limits, exp):
    out = []
    dam = exp.setting("dam_break") or {}
    if dam:
        out.append("The column: a = %s m, %d water particles and %d in all (spacing %s m), "
                   "c = %s m/s; T = 1 is t = %s s." % (
                       fmt(dam.get("a"), 3), dam.get("water_particles", 0),
                       dam.get("particles", 0), fmt(dam.get("spacing"), 3),
                       fmt(dam.get("speed_of_sound"), 3),
                       fmt(1.0 / dam["time_scale"], 3) if dam.get("time_scale") else "–"))
    refused = [r for r in range(len(runs)) if runs["status"][r] == "failed"
               and runs["diverged_at"][r] == 0.0]
    stopped = [r for r in range(len(runs)) if runs["status"][r] != "completed"
               and r not in refused]
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    if refused:
        out.append("Refused at the start: %s." % "; ".join(
            runs["failure"][r] for r in refused))
    if stopped:
        out.append("Stopped: %s." % "; ".join(
            "%s %s at t = %s s (T = %s)" % (
                _run_label(runs["integrator"][r], runs["dt"][r]), runs["status"][r],
                fmt(runs["diverged_at"][r], 3),
                fmt(runs["diverged_at"][r] * dam.get("time_scale", float("nan")), 3))
            for r in stopped))
    with_z = [r for r in done if math.isfinite(runs["Z_T2_error"][r])]
    if with_z:
        measured = runs["Z_T2_measured"][with_z[0]]
        with_z.sort(key=lambda r: abs(runs["Z_T2_error"][r]))
        out.append("At T = 2 Martin and Moyce measured Z = %s; the runs give %s." % (
            fmt(measured, 3), ", ".join("%s %s (%s)" % (_run_label(runs["integrator"][r], runs["dt"][r]),
                                                        fmt(runs["Z_T2"][r], 3),
                                                        _pct(runs["Z_T2_error"][r]))
                                        for r in with_z)))
        within = [_run_label(runs["integrator"][r], runs["dt"][r]) for r in with_z
                  if abs(runs["Z_T2_error"][r]) <= 0.15]
        if within:
            out.append("Within 15 %% of the measured front at T = 2: %s." % names_list(within))
    if done:
        ritter = runs["ritter_speed"][done[0]]
        fastest = max(done, key=lambda r: runs["front_speed_max"][r])
        over = [_run_label(runs["integrator"][r], runs["dt"][r]) for r in done
                if runs["front_speed_max"][r] > ritter]
        text = ("The fastest front of any completed run, %s m/s (%s), is %s Ritter's bound "
                "2√(2ga) = %s m/s" % (fmt(runs["front_speed_max"][fastest], 3),
                                      _run_label(runs["integrator"][fastest], runs["dt"][fastest]),
                                      "above" if over else "below", fmt(ritter, 3)))
        out.append(text + (" (over it: %s)." % names_list(over) if over else "."))
        large = [r for r in done if runs["dt"][r] >= FRAME_STEP and runs["steps"][r] > 0
                 and runs["newton_iterations"][r] > 0 and runs["integrator"][r] != "xpbd"]
        if large:
            out.append("At the large steps the implicit methods' Newton takes, per step: %s "
                       "iterations (at 1 ms: %s)." % (
                           ", ".join("%s %s" % (_run_label(runs["integrator"][r], runs["dt"][r]),
                                                fmt(runs["newton_iterations"][r] / runs["steps"][r], 3))
                                     for r in large),
                           ", ".join("%s %s" % (runs["integrator"][r],
                                                fmt(runs["newton_iterations"][r] / runs["steps"][r], 3))
                                     for r in done if runs["dt"][r] < FRAME_STEP
                                     and runs["newton_iterations"][r] > 0 and runs["steps"][r] > 0
                                     and runs["integrator"][r] != "xpbd") or "none"))
        cheap = min(done, key=lambda r: runs["cost_per_second"][r])
        dear = max(done, key=lambda r: runs["cost_per_second"][r])
        out.append("Cost per simulated second: cheapest %s (%s s), dearest %s (%s s), %s times "
                   "as much." % (
                       _run_label(runs["integrator"][cheap], runs["dt"][cheap]),
                       fmt(runs["cost_per_second"][cheap], 3),
                       _run_label(runs["integrator"][dear], runs["dt"][dear]),
                       fmt(runs["cost_per_second"][dear], 3),
                       fmt(runs["cost_per_second"][dear] / runs["cost_per_second"][cheap], 3)))
        comp = max(done, key=lambda r: runs["compression_max"][r])
        out.append("Largest compression ρ/ρ₀ − 1 in any sampled state: %s (%s); the weakly "
                   "compressible model aims at about 1 %%." % (
                       _pct(runs["compression_max"][comp]),
                       _run_label(runs["integrator"][comp], runs["dt"][comp])))
        scale = dam.get("energy_scale") or 1.0
        parts = []
        for r in sorted(done, key=lambda r: runs["numerical"][r]):
            parts.append("%s %s viscous, %s numerical" % (
                _run_label(runs["integrator"][r], runs["dt"][r]),
                fmt(runs["viscous_work"][r] / scale, 2),
                fmt(runs["numerical"][r] / scale, 2)))
        out.append("Energy at the end, in units of M g a (viscous work, then the integrator's "
                   "own change E − E₀ + W_visc): %s." % "; ".join(parts))
        gained = [r for r in done if runs["numerical"][r] > 0.01 * scale]
        if gained:
            out.append("Energy the integrator added of its own, more than 1 %% of M g a by the "
                       "end: %s." %
                       "; ".join("%s +%s M g a" % (_run_label(runs["integrator"][r], runs["dt"][r]),
                                                    fmt(runs["numerical"][r] / scale, 2))
                                 for r in gained))
    if limits is not None:
        parts = []
        for name, idx in limits.groups("integrator").items():
            idx = idx[np.argsort(limits["c"][idx])]
            ratio = limits["ratio"][idx]
            Cm = limits["C_measured"][idx]
            part = "%s from %s s at c = %s m/s to %s s at c = %s m/s" % (
                name[0], fmt(limits["dt_max_stable"][idx][0], 3), fmt(limits["c"][idx][0], 3),
                fmt(limits["dt_max_stable"][idx][-1], 3), fmt(limits["c"][idx][-1], 3))
            if np.isfinite(ratio).any():
                part += ", %s to %s times the acoustic mode's (ωh)*/ω_max" % (
                    fmt(np.nanmin(ratio), 3), fmt(np.nanmax(ratio), 3))
            if np.isfinite(Cm).any():
                part += ", C = dt (c + |v|max)/h from %s to %s" % (fmt(np.nanmin(Cm), 3),
                                                                    fmt(np.nanmax(Cm), 3))
            parts.append(part)
        out.append("Largest stable step as the speed of sound grows: %s." % "; ".join(parts))
        order = np.argsort(limits["c"])
        hyd = limits["hydrostatic"][order]
        if np.isfinite(hyd).all() and len(hyd) > 1:
            out.append("Meanwhile the compression at the column's foot at rest, g 2a / c², falls "
                       "from %s to %s: the Tait law is stiff only in compression, and the "
                       "linearization at rest takes the stiff side everywhere." % (
                           _pct(hyd[0]), _pct(hyd[-1])))
    return out
