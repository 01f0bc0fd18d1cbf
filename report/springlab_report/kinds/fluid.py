"""fluid: the dam break (weakly compressible SPH) under many integrators,
beside Martin and Moyce's (1952) measured surge front; its cost; its energy
budget; and the explicit step limit against the speed of sound. Every
sentence under the figure is computed from the tables."""

import math

import numpy as np

from ..data import Columns
from matplotlib.ticker import FuncFormatter, NullFormatter

from ..figures import esc, facts_html, figure_html, fmt, names_list, new_figure

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
        "dt", "diverged_at", "t_final", "steps", "force_evals", "wall_seconds",
        "cost_per_second", "Z_T2", "Z_T2_measured", "Z_T2_error", "front_speed_max",
        "ritter_speed", "compression_max", "energy_initial", "viscous_work", "numerical",
        "particles"), texts=("integrator", "status", "failure"))


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
    series = db.groups("integrator")
    names = integ.sort({k[0] for k in series})

    fig = new_figure(15.0, 8.5)
    axes = fig.subplots(2, 3, squeeze=False)
    ax_z, ax_cost, ax_lim = axes[0]
    ax_e, ax_w, ax_n = axes[1]
    for k, name in enumerate(names):
        idx = series[(name,)]
        T = db["T"][idx]
        style = dict(color=integ.colour(name), ls=integ.linestyle(name),
                     lw=max(1.0, 2.4 - 0.15 * k), marker=integ.marker(name), ms=5, mfc="none",
                     markevery=(k * max(1, len(T) // 50), max(1, len(T) // 6)), label=name)
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
    # One legend for every panel, where the energy panel has room.
    handles, labels = ax_z.get_legend_handles_labels()
    ax_e.legend(handles, labels, loc="lower left", fontsize=8, ncol=2, framealpha=0.9)
    ax_n.axhline(0.0, color="0.5", lw=0.8)

    # Cost per simulated second, completed runs.
    done = [r for r in range(len(runs)) if runs["status"][r] == "completed"]
    order = sorted(done, key=lambda r: runs["cost_per_second"][r])
    if order:
        y = np.arange(len(order))
        ax_cost.barh(y, [runs["cost_per_second"][r] for r in order],
                     color=[integ.colour(runs["integrator"][r]) for r in order])
        ax_cost.set_yticks(y, ["%s (dt %s)" % (runs["integrator"][r], fmt(runs["dt"][r], 2))
                               for r in order], fontsize=9)
        ax_cost.set_xscale("log")
        ax_cost.set_xlabel("CPU seconds per simulated second")
        ax_cost.grid(True, axis="x", which="both", alpha=0.3)
    else:
        ax_cost.text(0.5, 0.5, "no completed run", transform=ax_cost.transAxes, ha="center")
    ax_cost.set_title("cost (one core)", loc="left", fontweight="bold")

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
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = (
        "Top left: the front Z = z/a against T = t √(2g/a) for each integrator, Martin and "
        "Moyce's measured points (circles; %s) and Ritter's bound (dotted). Top middle: CPU "
        "seconds (one core) per simulated second of each completed run. Top right: the largest stable "
        "step found by bisection (markers) against the speed of sound on a coarser dam break, "
        "the acoustic mode's limit (ωh)*/ω_max (lines) and the CFL form with the median "
        "measured C (dashed). Bottom: the total energy's change, the viscous work and their "
        "sum, the integrator's own part, all over M g a (the column's potential energy above "
        "the floor)." % esc(_short_source(exp)))
    facts = sentences(runs, ref, limits, exp)
    return figure_html(saved, "fluid: the dam break", caption) + facts_html(facts)


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
            "%s at dt = %s s %s at t = %s s (T = %s)" % (
                runs["integrator"][r], fmt(runs["dt"][r], 2), runs["status"][r],
                fmt(runs["diverged_at"][r], 3),
                fmt(runs["diverged_at"][r] * dam.get("time_scale", float("nan")), 3))
            for r in stopped))
    with_z = [r for r in done if math.isfinite(runs["Z_T2_error"][r])]
    if with_z:
        measured = runs["Z_T2_measured"][with_z[0]]
        with_z.sort(key=lambda r: abs(runs["Z_T2_error"][r]))
        out.append("At T = 2 Martin and Moyce measured Z = %s; the runs give %s." % (
            fmt(measured, 3), ", ".join("%s %s (%s)" % (runs["integrator"][r],
                                                        fmt(runs["Z_T2"][r], 3),
                                                        _pct(runs["Z_T2_error"][r]))
                                        for r in with_z)))
        within = [runs["integrator"][r] for r in with_z if abs(runs["Z_T2_error"][r]) <= 0.15]
        if within:
            out.append("Within 15 %% of the measured front at T = 2: %s." % names_list(within))
    if done:
        ritter = runs["ritter_speed"][done[0]]
        fastest = max(done, key=lambda r: runs["front_speed_max"][r])
        over = [runs["integrator"][r] for r in done if runs["front_speed_max"][r] > ritter]
        text = ("The fastest front of any completed run is %s's %s m/s, %s Ritter's bound "
                "2√(2ga) = %s m/s" % (runs["integrator"][fastest],
                                      fmt(runs["front_speed_max"][fastest], 3),
                                      "above" if over else "below", fmt(ritter, 3)))
        out.append(text + (" (over it: %s)." % names_list(over) if over else "."))
        cheap = min(done, key=lambda r: runs["cost_per_second"][r])
        dear = max(done, key=lambda r: runs["cost_per_second"][r])
        out.append("Cost per simulated second: cheapest %s at dt = %s s (%s s), dearest %s at "
                   "dt = %s s (%s s), %s times as much." % (
                       runs["integrator"][cheap], fmt(runs["dt"][cheap], 2),
                       fmt(runs["cost_per_second"][cheap], 3), runs["integrator"][dear],
                       fmt(runs["dt"][dear], 2), fmt(runs["cost_per_second"][dear], 3),
                       fmt(runs["cost_per_second"][dear] / runs["cost_per_second"][cheap], 3)))
        comp = max(done, key=lambda r: runs["compression_max"][r])
        out.append("Largest compression ρ/ρ₀ − 1 in any sampled state: %s (%s); the weakly "
                   "compressible model aims at about 1 %%." % (
                       _pct(runs["compression_max"][comp]), runs["integrator"][comp]))
        scale = dam.get("energy_scale") or 1.0
        parts = []
        for r in sorted(done, key=lambda r: runs["numerical"][r]):
            parts.append("%s %s viscous, %s numerical" % (
                runs["integrator"][r], fmt(runs["viscous_work"][r] / scale, 2),
                fmt(runs["numerical"][r] / scale, 2)))
        out.append("Energy at the end, in units of M g a (viscous work, then the integrator's "
                   "own change E − E₀ + W_visc): %s." % "; ".join(parts))
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
