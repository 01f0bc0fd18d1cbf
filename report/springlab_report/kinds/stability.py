"""stability: the largest stable step of each fixed-step method against a
swept parameter (spring stiffness, Young's modulus, cell count), measured by
bisection, next to the limit theory gives from w_max; and a map of
final/initial energy over (dt, k)."""

import math
import textwrap

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import patheffects
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..data import Columns, finite
from ..figures import esc, facts_html, figure_html, fmt, log_log, new_figure, swatch

KIND = "stability"
TITLE = "Stability limits"
ABOUT = (
    "For each value of the swept parameter (a spring's stiffness k, a solid's Young's modulus E "
    "or its number of cells), the largest step that does not blow up, found by bisection, next "
    "to the limit theory predicts from the highest frequency w_max of the linearized scene "
    "(2/w_max for symplectic Euler and Verlet, 2√2/w_max for RK4). Theory says the points sit "
    "on their dashed lines and fall like 1/√k or 1/√E (a 100 times stiffer material needs a 10 "
    "times smaller step) and, on solids, like the element size dx (the CFL-like "
    "h ~ dx / √(E/ρ)). A- and L-stable methods have no limit. The map shows the energy on both "
    "sides of the boundary: white kept, red gained, blue lost.")

# The x axis of a swept parameter.
PARAMETER_LABELS = {
    "k": "spring stiffness k [N/m]",
    "young": "Young's modulus E [Pa]",
    "nx": "cells along the length nx (element length L / nx)",
    "n": "cells per side n (element size: side / n)",
}


def swept_parameter(exp, scene):
    """The parameter a scene's case sweeps ("k" when the settings do not say)."""
    for case in exp.setting("cases") or []:
        if not isinstance(case, dict):
            continue
        named = case.get("scene")
        if isinstance(named, dict):  # the scene itself (built with parameters)
            named = named.get("name")
        if named == scene:
            name = case.get("stiffness")
            if isinstance(name, str) and name:
                return name
    return "k"


def limits_table(exp):
    return Columns(exp.table(), numbers=("k", "w_max", "t_end", "max_stable_dt", "bracket_lo",
                                         "bracket_hi", "theory_dt", "ratio"),
                   texts=("scene", "integrator"))


def map_table(exp):
    return Columns(exp.table("map"), numbers=("k", "dt", "w_max", "energy_ratio", "diverged"),
                   texts=("scene", "integrator"))


def log_edges(values):
    """Cell edges on a log axis around sorted positive values."""
    v = np.log10(np.asarray(values, dtype=float))
    if len(v) == 1:
        e = np.array([v[0] - 0.15, v[0] + 0.15])
    else:
        mid = (v[1:] + v[:-1]) / 2
        e = np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])
    return 10.0 ** e


def render(exp, ctx):
    out = []
    if exp.table() is not None:
        out.append("<h3>Largest stable step</h3>\n")
        out.append(stability_figure(exp, ctx.integrators, ctx.figs))
        out.append(facts_html(limit_facts(exp, ctx.integrators)))
        out.append(stability_table(exp, ctx.integrators))
    if exp.table("map") is not None:
        out.append("<h3>Stability map</h3>\n")
        out.append(stability_map_figure(exp, ctx.integrators, ctx.figs))
    return "".join(out)


def limit_facts(exp, integrators):
    """Per method and scene: the range of measured / theory over the stiffnesses."""
    st = limits_table(exp)
    nolimit = no_limit_rows(st, stability_dt_max(exp))
    out = []
    for (scene, name), idx in st.groups("scene", "integrator").items():
        ratio = st["max_stable_dt"][idx] / st["theory_dt"][idx]
        ok = np.isfinite(ratio)
        if ok.any():
            parameter = swept_parameter(exp, scene)
            lo, hi = fmt(float(np.min(ratio[ok])), 4), fmt(float(np.max(ratio[ok])), 4)
            text = "%s on %s: measured / theory %s over %d %s" % (
                name, scene, lo if lo == hi else "between %s and %s" % (lo, hi), int(ok.sum()),
                "stiffnesses" if parameter == "k" else "values of %s" % parameter)
            k, m = st["k"][idx][ok], st["max_stable_dt"][idx][ok]
            if len(set(k.tolist())) >= 2 and np.all(k > 0) and np.all(m > 0):
                slope = np.polyfit(np.log(k), np.log(m), 1)[0]
                text += "; the limit goes like %s^%s" % (parameter, fmt(float(slope), 3))
            limit_wh = integrators.stability(name).get("limit_wh")
            if limit_wh == 0:
                text += " (its theory, the time to grow by the blow-up factor, is exact for " \
                        "one mode, an estimate for several)"
            elif limit_wh and float(np.min(ratio[ok])) > 1.03:
                text += " (above its stated limit, the first step at which a mode grows: runs " \
                        "past it are stable again, so its stable steps are not one interval, " \
                        "and the bisection, which assumes one, ends on the edge of a later one)"
            out.append(text + ".")
        elif nolimit[idx].all():
            out.append("%s on %s: no run diverged up to the largest step searched, at any "
                       "stiffness." % (name, scene))
    return out


def stability_dt_max(exp):
    v = exp.setting("dt_max")
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def searched_to_max(st, dt_max):
    """Rows where no tested step diverged: max_stable_dt is the searched dt_max
    (the bracket collapsed onto it, or it reaches the dt_max of the settings)."""
    out = np.zeros(len(st), dtype=bool)
    for r in range(len(st)):
        m, lo, hi = st["max_stable_dt"][r], st["bracket_lo"][r], st["bracket_hi"][r]
        if not finite(m):
            continue
        collapsed = finite(lo) and finite(hi) and lo == hi == m
        out[r] = collapsed or (finite(m) and not finite(hi)) or \
            (dt_max is not None and m >= dt_max * (1 - 1e-9))
    return out


def no_limit_rows(st, dt_max):
    """Rows of methods without a limit: no theory, and nothing diverged."""
    return searched_to_max(st, dt_max) & np.isnan(st["theory_dt"])


# Methods whose measured limits differ by less than this fraction at every
# swept value are drawn as one series (on a slide, nine markers on one point
# read as a smudge; the table keeps each method's own numbers).
SAME_LIMIT = 0.02


def limit_series(st, nolimit, integrators):
    """The methods with a measured limit, grouped: each group's methods were
    measured at the same values of the swept parameter on every scene, with
    limits within SAME_LIMIT of each other. Returns [[name, ...], ...] in the
    registry's order."""
    points = {}
    for (scene, name), idx in st.groups("scene", "integrator").items():
        lim = idx[~nolimit[idx]]
        if len(lim):
            points.setdefault(name, {})[scene] = dict(zip(st["k"][lim].tolist(),
                                                          st["max_stable_dt"][lim].tolist()))

    def same(a, b):
        if points[a].keys() != points[b].keys():
            return False
        for scene, pa in points[a].items():
            pb = points[b][scene]
            if pa.keys() != pb.keys():
                return False
            for k, m in pa.items():
                n = pb[k]
                if not (finite(m) and finite(n) and m > 0 and n > 0) or \
                        abs(m / n - 1) > SAME_LIMIT:
                    return False
        return True

    groups = []
    for name in integrators.sort(points):
        for g in groups:
            if all(same(name, other) for other in g):
                g.append(name)
                break
        else:
            groups.append([name])
    return groups


def stability_figure(exp, integrators, figs):
    st = limits_table(exp)
    dt_max = stability_dt_max(exp)
    nolimit = no_limit_rows(st, dt_max)
    scenes = st.groups("scene")
    groups = limit_series(st, nolimit, integrators)
    group_of = {name: g for g in groups for name in g}
    fig = new_figure(5.2 * len(scenes) + 3.2, 4.6)
    axes = fig.subplots(1, len(scenes) + 1, squeeze=False,
                        gridspec_kw={"width_ratios": [5.2] * len(scenes) + [3.2]})[0]
    side = axes[-1]
    handles = {}
    free_by_scene = {}
    for ax, ((scene,), idx) in zip(axes, scenes.items()):
        by_int = {}
        for r in idx:
            by_int.setdefault(st["integrator"][r], []).append(r)
        free = []
        for integ in integrators.sort(by_int):
            rows = np.asarray(by_int[integ])
            lim = rows[~nolimit[rows]]
            if len(lim) == 0:
                free.append(integ)
                continue
            if (~nolimit[rows]).sum() < len(rows):
                ks = ", ".join(fmt(x) for x in st["k"][rows[nolimit[rows]]])
                free.append("%s (only at %s = %s)" % (integ, swept_parameter(exp, scene), ks))
            group = group_of[integ]
            if group[0] != integ:
                continue  # drawn once, as its group's first method
            lim = lim[np.argsort(st["k"][lim], kind="stable")]
            k, m, th = st["k"][lim], st["max_stable_dt"][lim], st["theory_dt"][lim]
            c = integrators.colour(integ)
            ok = np.isfinite(m) & (m > 0)
            okt = np.isfinite(th) & (th > 0)
            label = " = ".join(group) + ("" if okt.any() else "  (no theory)")
            line, = ax.plot(k[ok], m[ok], marker=integrators.marker(integ), ms=9, mfc="none",
                            mew=1.8, color=c, ls="none", zorder=3)
            handles.setdefault(label, line)
            if okt.any():
                ax.plot(k[okt], th[okt], color=c, ls="--", lw=1.4, alpha=0.9, zorder=2,
                        marker="_" if okt.sum() == 1 else None, ms=16, mew=1.5)
        free_by_scene[scene] = free
        log_log(ax, "no integrator with a step limit on this scene")
        parameter = swept_parameter(exp, scene)
        ax.set_xlabel(PARAMETER_LABELS.get(parameter, parameter))
        ax.set_ylabel("largest stable step dt [s]")
        ax.set_title(scene, loc="left", fontweight="bold")
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", alpha=0.1)
    # The side column: one legend for every panel (a method keeps its colour
    # and marker across panels), then the methods that never diverged.
    side.axis("off")
    labels = list(handles)
    lines = [handles[x] for x in labels]
    lines += [Line2D([], [], color="0.2", marker="o", mfc="none", ls="none"),
              Line2D([], [], color="0.2", ls="--")]
    labels += ["measured (bisection)", "theory from w_max"]
    side.legend(lines, labels, loc="upper left", fontsize=8, frameon=False, handlelength=2.6,
                borderaxespad=0)
    text = free_text(free_by_scene, dt_max)
    if text:
        side.text(0, 0, text, transform=side.transAxes, fontsize=8, va="bottom", ha="left")
    saved = figs.save(fig, exp.name + ".png")
    return figure_html(saved, "stability limit against stiffness", esc(
        "Largest stable step found by bisection (hollow markers) against the theoretical limit "
        "from the largest eigenfrequency w_max of the initial state (dashed, same colour). "
        "Methods whose measured limits agree within %d %% at every point share one marker "
        "(their names joined by '='); the table below has each one's numbers. Methods that "
        "never diverged up to the largest step searched are listed beside the panels instead "
        "of being drawn." % round(100 * SAME_LIMIT)))


def free_text(free_by_scene, dt_max, width=44):
    """The methods without a limit, wrapped for the side column: those that
    never diverged on any panel, then the panels' own extra ones."""
    if not any(free_by_scene.values()):
        return ""
    top = ("dt_max = %s s" % fmt(dt_max)) if dt_max else "the largest step searched"
    having = [scene for scene, free in free_by_scene.items() if free]
    lists = [free_by_scene[scene] for scene in having]
    common = [f for f in lists[0] if all(f in other for other in lists[1:])]
    where = "" if len(free_by_scene) == 1 else " on %s" % " and ".join(
        [", ".join(having[:-1]), having[-1]] if len(having) > 1 else having)
    out = []
    if common:
        out.append("No divergence up to %s%s: %s." % (top, where, ", ".join(common)))
    for scene, free in free_by_scene.items():
        extra = [f for f in free if f not in common]
        if extra:
            out.append("%s on %s: %s." % ("Also" if common else
                                          "No divergence up to %s" % top, scene, ", ".join(extra)))
    return "\n\n".join(textwrap.fill(x, width, break_on_hyphens=False) for x in out)


def stability_table(exp, integrators):
    st = limits_table(exp)
    reached = searched_to_max(st, stability_dt_max(exp))
    out = ['<table><tr><th>scene</th><th>integrator</th><th>k [N/m]</th><th>w_max [rad/s]</th>'
           '<th>max stable dt [s]</th><th>theory dt [s]</th><th>ratio</th></tr>\n']
    scene_pos = {key[0]: j for j, key in enumerate(st.groups("scene"))}
    integ_pos = {n: j for j, n in enumerate(integrators.sort(set(st["integrator"])))}
    order = sorted(range(len(st)), key=lambda r: (
        scene_pos[st["scene"][r]], integ_pos[st["integrator"][r]], st["k"][r]))
    nbad = 0
    for r in order:
        row = st.row(r)
        ratio = row["ratio"]
        if not finite(ratio) and finite(row["theory_dt"]) and finite(row["max_stable_dt"]) \
                and row["theory_dt"] > 0:
            ratio = row["max_stable_dt"] / row["theory_dt"]
        bad = finite(row["theory_dt"]) and (not finite(ratio) or not 0.97 <= ratio <= 1.03)
        nbad += bad
        msd = fmt(row["max_stable_dt"], 4)
        if reached[r]:
            msd = "≥ %s (none diverged)" % msd
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>'
                   '<td>%s</td></tr>\n' % (
                       ' class="off"' if bad else "", esc(row["scene"]),
                       swatch(integrators, row["integrator"]), fmt(row["k"], 6), fmt(row["w_max"], 4),
                       msd, fmt(row["theory_dt"], 4) if finite(row["theory_dt"]) else "– (none)",
                       fmt(ratio, 4) if finite(row["theory_dt"]) else "–"))
    out.append("</table>\n")
    head = ("<details><summary>Every limit (%d rows)</summary><p>Measured against theoretical "
            "stability limit. Highlighted: a theoretical limit exists and the ratio measured / "
            "theory lies outside [0.97, 1.03] (%d row%s).</p>\n" % (len(st), nbad,
                                                                   "" if nbad == 1 else "s"))
    return head + "".join(out) + "</details>\n"


DIVERGED_COLOR, DIVERGED_HATCH, NONPOS_COLOR = "#2b2b2b", "#9a9a9a", "#c8c8c8"


def _cells(xe, ye, mask, **kw):
    """Rectangles of the grid cells where mask is set (rows: y, columns: x)."""
    from matplotlib.collections import PolyCollection
    verts = []
    for a, b in zip(*np.nonzero(mask)):
        x0, x1, y0, y1 = xe[b], xe[b + 1], ye[a], ye[a + 1]
        verts.append([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
    return PolyCollection(verts, linewidths=0.0, zorder=1.5, **kw)


def stability_map_figure(exp, integrators, figs):
    sm = map_table(exp)
    panels = []
    for (scene,), sidx in sm.groups("scene").items():
        by_int = {}
        for r in sidx:
            by_int.setdefault(sm["integrator"][r], []).append(r)
        for integ in integrators.sort(by_int):
            panels.append((scene, integ, np.asarray(by_int[integ])))
    nscenes = len(sm.groups("scene"))
    finite_logs = []
    for _, _, rows in panels:
        er = sm["energy_ratio"][rows]
        ok = (sm["diverged"][rows] == 0) & np.isfinite(er) & (er > 0)
        finite_logs.append(np.log10(er[ok]))
    allv = np.concatenate(finite_logs) if finite_logs else np.array([])
    span = float(np.max(np.abs(allv))) if len(allv) else 1.0
    lim = min(6.0, max(1.0, math.ceil(span)))
    clipped = span > lim
    ncol = min(4, len(panels))
    nrow = (len(panels) + ncol - 1) // ncol
    fig = new_figure(3.6 * ncol + 1.2, 3.3 * nrow + 0.9)
    axes = fig.subplots(nrow, ncol, squeeze=False)
    cmap = plt.get_cmap("RdBu_r").copy()
    cmap.set_bad("white")
    mesh = None
    any_div = any_nonpos = any_missing = False
    for j, (scene, integ, rows) in enumerate(panels):
        ax = axes[j // ncol, j % ncol]
        ks = np.unique(sm["k"][rows])
        dts = np.unique(sm["dt"][rows])
        z = np.full((len(ks), len(dts)), np.nan)
        div = np.zeros_like(z, dtype=bool)
        nonpos = np.zeros_like(z, dtype=bool)
        wmax = {}
        for r in rows:
            a = np.searchsorted(ks, sm["k"][r])
            b = np.searchsorted(dts, sm["dt"][r])
            er = sm["energy_ratio"][r]
            if finite(sm["w_max"][r]):
                wmax[float(sm["k"][r])] = float(sm["w_max"][r])
            if sm["diverged"][r]:
                div[a, b] = True
            elif finite(er) and er > 0:
                z[a, b] = math.log10(er)
            else:
                nonpos[a, b] = True
        xe, ye = log_edges(dts), log_edges(ks)
        mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(np.clip(z, -lim, lim)), cmap=cmap,
                             vmin=-lim, vmax=lim, shading="flat")
        if div.any():
            any_div = True
            ax.add_collection(_cells(xe, ye, div, facecolor=DIVERGED_COLOR, hatch="///",
                                     edgecolor=DIVERGED_HATCH))
        if nonpos.any():
            any_nonpos = True
            ax.add_collection(_cells(xe, ye, nonpos, facecolor=NONPOS_COLOR))
        missing = np.isnan(z) & ~div & ~nonpos
        if missing.any():
            any_missing = True
            ax.add_collection(_cells(xe, ye, missing, facecolor="white", hatch="..",
                                     edgecolor="#b0b0b0"))
        if wmax:
            kk = np.array(sorted(wmax))
            ww = np.array([wmax[k] for k in kk])
            halo = [patheffects.withStroke(linewidth=3.2, foreground="white")]
            ax.plot(2.0 / ww, kk, color="black", ls="--", lw=1.5, path_effects=halo)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
        ax.set_xlabel("dt [s]")
        ax.set_ylabel("k [N/m]")
        ax.set_title(integ if nscenes == 1 else "%s — %s" % (integ, scene), color=integrators.colour(integ),
                     fontweight="bold", fontsize=11)
    for j in range(len(panels), nrow * ncol):
        axes[j // ncol, j % ncol].set_visible(False)
    if mesh is not None:
        cb = fig.colorbar(mesh, ax=axes, shrink=0.9, extend="both" if clipped else "neither",
                          aspect=30)
        cb.set_label("log10 E(T)/E(0)")
    handles = [Line2D([], [], color="black", ls="--", lw=1.5), ]
    labels = ["dt = 2 / w_max (reference)"]
    if any_div:
        handles.append(Patch(facecolor=DIVERGED_COLOR, hatch="///", edgecolor=DIVERGED_HATCH))
        labels.append("diverged")
    if any_nonpos:
        handles.append(Patch(facecolor=NONPOS_COLOR))
        labels.append("E(T)/E(0) ≤ 0 (no log)")
    if any_missing:
        handles.append(Patch(facecolor="white", hatch="..", edgecolor="#b0b0b0"))
        labels.append("not run")
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=len(handles), fontsize=9, frameon=False)
    saved = figs.save(fig, exp.name + "-map.png")
    caption = ("Final over initial mechanical energy for every step dt (x) and stiffness k (y): "
               "white = kept, red = gained, blue = lost, dark hatched = diverged. The dashed line "
               "is dt = 2/w_max, w_max the largest eigenfrequency at the initial state.")
    if clipped:
        caption += " Colours are clipped at ±%g decades (arrows on the colour bar)." % lim
    return figure_html(saved, "stability map", esc(caption))


# --------------------------------------------------------------------------
# 3. convergence

