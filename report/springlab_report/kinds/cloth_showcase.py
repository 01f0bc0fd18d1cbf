"""cloth-showcase: the cloth at a few instants for a few integrators at a
game's frame step. A run that diverged is shown by its last good frames and
the first states past the blow-up bound (the explosion itself); every good
frame shares one scale, tight around the cloth."""

import math

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Line3DCollection

from ..data import Columns
from ..figures import count, esc, facts_html, figure_html, fmt, note_html
from ..page import find_scenes
from .common import runs_table

KIND = "cloth-showcase"
TITLE = "Cloth showcase"
ABOUT = (
    "The same cloth at the same step, a few integrators, seen at a few instants. At a game's "
    "frame step (1/60 s) the step is far beyond 2/w_max of the cloth's stiff springs: theory "
    "says the explicit methods blow up within a few steps, while the implicit ones stay stable "
    "— implicit Euler by damping the fast motion, implicit midpoint without damping it. A run "
    "that blew up is shown by its last good frames and its first frames past the blow-up bound, "
    "each on its own scale.")

COLUMNS = 5


def render(exp, ctx):
    integ = ctx.integrators
    cl = Columns(exp.table(), numbers=("t", "i", "x", "y", "z"),
                 texts=("scene", "integrator", "past_blowup") if exp.table().has("past_blowup")
                 else ("scene", "integrator"))
    runs = exp.table("runs")
    run_by = {}
    if runs is not None:
        runs.require("integrator", "status", "diverged_at", "steps")
        status = runs.status()
        for r in range(len(runs)):
            run_by[runs.text("integrator")[r]] = {
                "status": status[r], "diverged_at": runs.num("diverged_at")[r],
                "steps": runs.num("steps")[r]}
    settings = exp.settings
    n = settings.get("n")
    fixed, vertical = set(), 1
    scenes = find_scenes(settings)
    if scenes:
        scene = scenes[0][1]
        fixed = {j for j, p in enumerate(scene.get("particles", []))
                 if isinstance(p, dict) and p.get("fixed") is True}
        g = scene.get("gravity")
        if isinstance(g, list) and any(isinstance(v, (int, float)) and v for v in g):
            vertical = int(np.argmax(np.abs(g)))
    frames = {}  # integrator -> [(t, past_blowup, ids, points)]
    past = cl["past_blowup"] if cl.table.has("past_blowup") else ["0"] * len(cl)
    for (name, t_text), idx in cl.table.groups("integrator", "t").items():
        idx = idx[np.argsort(cl["i"][idx], kind="stable")]
        pts = np.stack([cl["x"][idx], cl["y"][idx], cl["z"][idx]], axis=1)
        frames.setdefault(name, []).append((float(t_text), past[idx[0]] == "1",
                                            cl["i"][idx].astype(int), pts))
    for v in frames.values():
        v.sort(key=lambda f: (f[1], f[0]))
    # Runs that blew up first (the lesson), then the others, each by family.
    names = sorted(integ.sort(frames), key=lambda n: run_by.get(n, {}).get("status",
                                                                          "completed") == "completed")
    npart = max(len(f[2]) for v in frames.values() for f in v)
    nn = n if isinstance(n, int) and n * n == npart else None
    if nn is None:
        root = int(round(math.sqrt(npart)))
        nn = root if root * root == npart else None
    horiz = [a for a in range(3) if a != vertical]
    axes_order = [horiz[0], horiz[1], vertical]
    good_pts = np.concatenate([f[3] for v in frames.values() for f in v if not f[1]])
    lims = _limits(good_pts)
    fig = plt.figure(figsize=(2.9 * COLUMNS + 1.2, 2.7 * len(names) + 0.3))
    gs = fig.add_gridspec(len(names), COLUMNS + 1, width_ratios=[0.42] + [1] * COLUMNS,
                          left=0.0, right=1.0, bottom=0.0, top=1.0, wspace=0.02, hspace=0.12)
    facts = []
    for row, name in enumerate(names):
        run = run_by.get(name, {})
        chosen = _choose(frames[name], settings.get("frames"))
        label = fig.add_subplot(gs[row, 0])
        label.set_axis_off()
        status = run.get("status", "completed")
        line2 = ("completed" if status == "completed" else "%s at\nt = %s s" % (
            status, fmt(run.get("diverged_at"), 4)))
        label.text(0.5, 0.5, "%s\n%s" % (name, line2), ha="center", va="center", fontsize=10,
                   fontweight="bold", color=integ.colour(name), rotation=90)
        for col, (t, is_past, ids, pts) in enumerate(chosen):
            ax = fig.add_subplot(gs[row, col + 1], projection="3d")
            own = is_past or not _inside(pts, lims)
            lim = _limits(pts) if own else lims
            P = pts[:, axes_order]
            colour = "#b00000" if is_past else integ.colour(name)
            if nn and len(ids) == nn * nn and np.all(ids == np.arange(nn * nn)):
                segs = _grid_pairs(nn)
                ax.add_collection3d(Line3DCollection(np.stack([P[segs[:, 0]], P[segs[:, 1]]],
                                                              axis=1), colors=colour,
                                                     linewidths=0.9))
            else:
                ax.scatter(P[:, 0], P[:, 1], P[:, 2], s=3, color=colour, depthshade=False)
            fx = [k for k, pid in enumerate(ids) if int(pid) in fixed]
            if fx:
                ax.scatter(P[fx, 0], P[fx, 1], P[fx, 2], s=18, color="black", depthshade=False)
            _style(ax, lim, axes_order)
            title = "t = %s s" % fmt(t, 4)
            if is_past:
                grow = _size(_limits(pts)) / _size(lims)
                title += "\npast the blow-up bound\n(own scale, %s× larger)" % _times(grow)
            elif own:
                title += "\n(own scale)"
            ax.set_title(title, fontsize=9, color="#b00000" if is_past else "black", pad=-4)
        for col in range(len(chosen), COLUMNS):
            ax = fig.add_subplot(gs[row, col + 1])
            ax.set_axis_off()
        facts.append(_fact(name, run, frames[name], vertical))
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = ("Cloth %s (%s) at the step of the runs table, one row per integrator, drawn as "
               "its structural grid (black dots: fixed corners). Completed runs at t = 0 and the "
               "frame times; diverged runs at t = 0, their last two good states and their first "
               "two states past the blow-up bound (red, each on its own scale). All other "
               "panels share one scale, tight around the cloth." % (
                   esc(settings.get("scene", {}).get("name", "")) if isinstance(
                       settings.get("scene"), dict) else "",
                   "%d x %d particles" % (nn, nn) if nn else "%d particles" % npart))
    out = [figure_html(saved, "cloth showcase", esc(caption)), facts_html(facts)]
    if not cl.table.has("past_blowup"):
        out.append(note_html("This data has no past_blowup column (an older springlab): diverged "
                             "runs show only their last good state."))
    if runs is not None:
        out.append(runs_table(runs, integ, "Runs", [
            ("status", "status", None), ("diverged_at", "diverged at [s]", 4),
            ("steps", "steps", 10), ("wall_seconds", "wall [s]", 3)]))
    return "".join(out)


def _choose(frames, requested):
    """Up to COLUMNS frames: t = 0 and the requested frame times for a run
    that reached them all; else t = 0, its last good frames and the frames
    past the blow-up bound."""
    good = [f for f in frames if not f[1]]
    past = [f for f in frames if f[1]]
    if not past:
        return good[:COLUMNS]
    tail = past[:2]
    head = good[:1]
    rest = good[1:][-(COLUMNS - len(head) - len(tail)):] if len(good) > 1 else []
    return head + rest + tail


def _limits(pts):
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        return np.array([[-1.0] * 3, [1.0] * 3])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.04 * max(float(np.max(hi - lo)), 1e-9)
    return np.array([lo - pad, hi + pad])


def _size(lim):
    return float(np.max(lim[1] - lim[0]))


def _inside(pts, lim):
    span = lim[1] - lim[0]
    return bool(np.all(pts >= lim[0] - 0.05 * span) and np.all(pts <= lim[1] + 0.05 * span))


def _style(ax, lim, order):
    lo, hi = lim[0][order], lim[1][order]
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    span = np.maximum(hi - lo, 0.08 * float(np.max(hi - lo)))
    ax.set_box_aspect(tuple(span), zoom=1.4)
    ax.view_init(elev=16, azim=-58)
    ax.set_axis_off()


def _times(x):
    return "%.0f" % x if x >= 100 else fmt(x, 2)


def _grid_pairs(n):
    pairs = []
    for r in range(n):
        for c in range(n):
            i = r * n + c
            if c + 1 < n:
                pairs.append((i, i + 1))
            if r + 1 < n:
                pairs.append((i, i + n))
    return np.asarray(pairs, dtype=int).reshape(-1, 2)


def _fact(name, run, frames, vertical):
    status = run.get("status", "completed")
    steps = run.get("steps")
    if status != "completed":
        past = [f for f in frames if f[1]]
        good = [f for f in frames if not f[1]]
        text = "%s %s at t = %s s after %s steps" % (name, status, fmt(run.get("diverged_at"), 4),
                                                      count(steps))
        if past and good:
            grow = _size(_limits(past[-1][3])) / _size(_limits(good[0][3]))
            text += ("; one step past the bound the cloth spans %s times its initial size"
                     % _times(grow))
        return text + "."
    last = max((f for f in frames if not f[1]), key=lambda f: f[0])
    low = float(np.min(last[3][:, vertical]))
    return "%s completed (%s steps); at t = %s s its lowest particle is at %s = %s m." % (
        name, count(steps), fmt(last[0], 4), "xyz"[vertical], fmt(low, 3))
