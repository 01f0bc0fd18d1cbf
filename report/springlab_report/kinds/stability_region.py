"""stability-region: each fixed-step method's stability region |R(z)| <= 1
in the complex plane with the scene's own eigenvalues scaled by the step,
z = h lambda, at a step below and one above the method's limit; the modes
outside the region are marked, and each panel says whether the run at that
step diverged. All of it read from the tables the C++ side wrote (the grid
of |R|, the eigenvalues, the runs); nothing is recomputed here."""

import numpy as np
from matplotlib.lines import Line2D

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt

KIND = "stability-region"
TITLE = "Stability regions"
ABOUT = (
    "A one-step method advances a linear mode with eigenvalue lambda by the factor R(h lambda) "
    "per step: the run is stable when every scaled eigenvalue z = h lambda lies in the region "
    "|R(z)| <= 1. The eigenvalues are the scene's own, with its damping (the first-order system "
    "[[0, I], [M^-1 K, M^-1 D]]); a larger step stretches them away from 0 along rays, and the "
    "first mode to cross the boundary sets the method's limit. Symplectic Euler and Verlet "
    "treat x and v differently: their step is not a function of h lambda alone, so they have no "
    "region in this plane (for undamped modes they are stable for |z| <= 2 on the imaginary "
    "axis).")

OUTSIDE = "#d00000"


def render(exp, ctx):
    integ = ctx.integrators
    runs = Columns(exp.table(), numbers=("factor", "dt", "limit_dt", "max_abs_R", "modes_outside",
                                         "diverged", "diverged_at"),
                   texts=("scene", "integrator", "limit_from"))
    modes_t = exp.table("modes")
    region_t = exp.table("region")
    modes = Columns(modes_t, numbers=("factor", "z_re", "z_im", "abs_R"),
                    texts=("integrator",)) if modes_t is not None else None
    region = Columns(region_t, numbers=("z_re", "z_im", "abs_R"),
                     texts=("integrator",)) if region_t is not None else None
    names = integ.sort(set(runs["integrator"]))
    factors = sorted(set(float(f) for f in runs["factor"]))
    ncol = columns(len(names))
    blocks = (len(names) + ncol - 1) // ncol
    import matplotlib.pyplot as plt
    # Slots about as tall as the windows (Im z spans more than Re z): the
    # equal-axes panels fill them.
    fig = plt.figure(figsize=(1.95 * ncol + 0.6, 3.0 * blocks * len(factors) + 0.7),
                     layout="constrained")
    # One row of panels per (block of methods, step factor), each a
    # subfigure labelled on its left by its step: h = 0.9 h*, 1.1 h*.
    # (The last, short subfigure holds the legend.)
    nrows = blocks * len(factors)
    rows = fig.subfigures(nrows + 1, 1, squeeze=False,
                          height_ratios=[1.0] * nrows + [0.1])[:, 0]
    axes = []
    for block in range(blocks):
        for k, factor in enumerate(factors):
            sub = rows[block * len(factors) + k]
            sub.supylabel("h = %s h*" % fmt(factor), fontweight="bold", fontsize=11)
            axes.append(sub.subplots(1, ncol, squeeze=False)[0])
    facts = []
    for j, name in enumerate(names):
        block, col = divmod(j, ncol)
        mine = [r for r in range(len(runs)) if runs["integrator"][r] == name]
        grid = _grid(region, name) if region is not None else None
        window = _window(grid, modes, name, runs, mine)
        per_factor = {}
        for r in mine:
            per_factor[float(runs["factor"][r])] = r
        for k, factor in enumerate(factors):
            ax = axes[block * len(factors) + k][col]
            r = per_factor.get(factor)
            if r is None:
                ax.set_visible(False)
                continue
            _panel(ax, integ, name, grid, window, modes, runs, r, factor)
            if col == 0:
                ax.set_ylabel("Im z", fontsize=8, labelpad=1)
        facts.append(_fact(name, runs, mine))
    for j in range(len(names), blocks * ncol):
        block, col = divmod(j, ncol)
        for k in range(len(factors)):
            axes[block * len(factors) + k][col].set_visible(False)
    handles = [Line2D([], [], color="0.3", lw=1.5), Line2D([], [], marker="o", color="0.2",
                                                             ls="none", ms=5),
               Line2D([], [], marker="x", color=OUTSIDE, ls="none", ms=8, mew=2)]
    labels = ["|R(z)| = 1 (inside shaded)", "z = h λ inside the region", "outside: |R(z)| > 1"]
    rows[-1].legend(handles, labels, loc="center", ncol=3, frameon=False, fontsize=9)
    saved = ctx.figs.save(fig, exp.name + ".png")
    scene = runs["scene"][0] if len(runs) else "?"
    caption = ("Stability region |R(z)| <= 1 of each method (shaded; the boundary in its colour) "
               "and the eigenvalues λ of the scene '%s' scaled by the step, z = h λ, at %s times "
               "the method's limit h* (one row each, labelled on its left; a method without a "
               "limit is shown at the step its title gives). A mode outside the region grows by |R(z)| "
               "> 1 every step: red crosses. The title says what the run at that step did. "
               "Methods whose step the data gives no region for in this plane show the "
               "eigenvalues only; for the partitioned ones (their limit comes from bisection on "
               "runs) the thick segment on the imaginary axis is their stable range for undamped "
               "modes."
               % (scene, " and ".join(fmt(f) for f in factors)))
    return figure_html(saved, "stability regions with the scene's eigenvalues", esc(caption)) + \
        facts_html(facts)


def columns(n):
    """Panels per row: 4 to 6, the one that leaves the fewest empty places
    in the last row (5 on a tie)."""
    return min((5, 4, 6), key=lambda c: (-n % c, abs(c - 5)))


def _grid(region, name):
    """(re values, im values, |R| as [im, re]) for the method, or None."""
    idx = [r for r in range(len(region)) if region["integrator"][r] == name]
    if not idx:
        return None
    idx = np.asarray(idx)
    re, im, a = region["z_re"][idx], region["z_im"][idx], region["abs_R"][idx]
    xs, ys = np.unique(re), np.unique(im)
    z = np.full((len(ys), len(xs)), np.nan)
    z[np.searchsorted(ys, im), np.searchsorted(xs, re)] = a
    return xs, ys, z


def _mode_rows(modes, name, factor):
    return [m for m in range(len(modes)) if modes["integrator"][m] == name
            and float(modes["factor"][m]) == factor]


def _window(grid, modes, name, runs, mine):
    if grid is not None:
        xs, ys, _ = grid
        return xs[0], xs[-1], ys[0], ys[-1]
    zs = [complex(modes["z_re"][m], modes["z_im"][m]) for m in range(len(modes))
          if modes["integrator"][m] == name] if modes is not None else []
    lim = max([abs(z.imag) for z in zs] + [abs(z.real) for z in zs] + [2.0]) * 1.15
    return -lim, 0.35 * lim, -lim, lim


def _panel(ax, integ, name, grid, window, modes, runs, r, factor):
    colour = integ.colour(name)
    if grid is not None:
        xs, ys, z = grid
        ax.contourf(xs, ys, z, levels=[0.0, 1.0], colors=[colour], alpha=0.16)
        if np.nanmin(z) < 1.0 < np.nanmax(z):  # the boundary crosses the window
            ax.contour(xs, ys, z, levels=[1.0], colors=[colour], linewidths=1.6)
    else:
        limit = integ.stability(name).get("limit_wh")
        if isinstance(limit, (int, float)) and limit > 0:
            ax.plot([0, 0], [-limit, limit], color=colour, lw=5, alpha=0.5, solid_capstyle="butt")
    ax.axhline(0, color="0.6", lw=0.6, zorder=0)
    ax.axvline(0, color="0.6", lw=0.6, zorder=0)
    outside = 0
    total = 0
    if modes is not None:
        rows = _mode_rows(modes, name, factor)
        zr = np.array([modes["z_re"][m] for m in rows])
        zi = np.array([modes["z_im"][m] for m in rows])
        a = np.array([modes["abs_R"][m] for m in rows])
        out = np.isfinite(a) & (a > 1.0 + 1e-12)
        total, outside = len(rows), int(out.sum())
        ax.plot(zr[~out], zi[~out], "o", ms=4.5, color="0.15", zorder=4)
        ax.plot(zr[out], zi[out], "x", ms=8, mew=2.0, color=OUTSIDE, zorder=5)
    ax.set_xlim(window[0], window[1])
    ax.set_ylim(window[2], window[3])
    ax.set_aspect("equal", adjustable="box")
    ax.tick_params(labelsize=7)
    ax.set_xlabel("Re z", fontsize=8, labelpad=1)
    dt = runs["dt"][r]
    if runs["diverged"][r] == 1:
        at = runs["diverged_at"][r]
        outcome = "run diverged at %s s" % fmt(at, 3)
    else:
        outcome = "run stable"
    where = ("%d of %d modes outside" % (outside, total)) if grid is not None \
        else "no region in the z-plane"
    limit_from = runs["limit_from"][r]
    step = ("h = %s s" % fmt(dt, 3) if limit_from in ("R", "runs")
            else "h = %s s (%s)" % (fmt(dt, 3), "no limit" if limit_from == "none" else limit_from))
    ax.set_title("\n".join([name, step, where, outcome]),
                 fontsize=8, loc="left", color="black")
    ax.title.set_color(colour if runs["diverged"][r] != 1 else OUTSIDE)


def _fact(name, runs, mine):
    rows = sorted(mine, key=lambda r: runs["factor"][r])
    first = rows[0]
    source = runs["limit_from"][first]
    limit = runs["limit_dt"][first]
    parts = []
    for r in rows:
        outside = runs["modes_outside"][r]
        has_r = np.isfinite(runs["max_abs_R"][r])
        outcome = ("diverged at t = %s s" % fmt(runs["diverged_at"][r], 3)
                   if runs["diverged"][r] == 1 else "stayed stable")
        if has_r:
            predicted = "%d mode%s outside (max |R| = %s)" % (
                int(outside), "" if outside == 1 else "s", fmt(runs["max_abs_R"][r], 4)) \
                if outside > 0 else "every mode inside"
            agree = (outside > 0) == (runs["diverged"][r] == 1)
            parts.append("at %s h*: %s, the run %s%s" % (
                fmt(runs["factor"][r]), predicted, outcome,
                "" if agree else " (prediction and run disagree)"))
        else:
            parts.append("at %s h*: the run %s" % (fmt(runs["factor"][r]), outcome))
    if source == "R":
        head = "%s: limit h* = %s s, where the first mode leaves the region" % (name, fmt(limit, 4))
    elif source == "runs":
        head = "%s: limit h* = %s s, found by bisection on runs (no scalar region)" % (
            name, fmt(limit, 4))
    elif source == "none":
        head = "%s: no mode leaves the region up to h = %s s (shown there)" % (name, fmt(limit, 4))
    else:
        head = "%s: %s" % (name, source)
    return "%s; %s." % (head, "; ".join(parts))
