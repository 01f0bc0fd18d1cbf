"""motion: the runs played side by side. One player per case (scene): a
panel per integrator on one clock, play/pause and a time slider, each
panel's energy change shown as it plays, a diverging run drawn until it
leaves the picture and then marked, a failed run marked with its message,
one fixed camera for every panel. The player (player.js, written for this
page) reads the frames embedded in the page: no network access."""

import base64
import json
from pathlib import Path

import numpy as np

from ..data import DataError
from ..figures import esc, facts_html, fmt, note_html
from .common import runs_table

KIND = "motion"
TITLE = "See it move"
ABOUT = (
    "Each scene is stepped at a game's frame time by every method, played on one clock with the "
    "same camera in every panel. Theory: the explicit methods blow up within a few frames at this "
    "step (the panel shows the explosion leaving the picture, then marks the run); implicit Euler "
    "stays calm because it damps the fast motion; implicit midpoint and the discrete gradient "
    "method keep the motion going; the fast solvers approximate implicit Euler's step on "
    "springs. Under each panel: the energy change (E - E(0)) / E_s over time, and its value now.")

PLAYER_JS = Path(__file__).resolve().parent.parent / "player.js"


# Positions are embedded as 16-bit integers, each frame on its own grid
# from its smallest to its largest coordinate per axis (1/65534 of the
# frame's extent: far below a pixel; a frame past the blow-up bound keeps
# its own huge extent). A non-finite coordinate is NO_VALUE.
NO_VALUE = -32768
LEVELS = 65534
# The position data of one player (base64 text) is kept under this many
# characters: a longer case keeps every k-th output frame (and every frame
# past the blow-up bound, and the last good one), and its caption says so.
PLAYER_BUDGET_CHARS = 500_000
# A run that completes with its energy above E(0) by more than this many
# E_s at some frame is flagged: springs, gravity and contact do not make
# energy, so a gain of the whole energy scale is the method's.
GAIN_FLAG_ES = 1.0


def encode_frames(xyz):
    """(frames, particles, 3) positions as base64 little-endian int16 and,
    per frame, its grid: [lo_x, lo_y, lo_z, step_x, step_y, step_z]; a
    position is lo + (value + 32767) step."""
    out = np.full(xyz.shape, NO_VALUE, dtype="<i2")
    grids = []
    for f, frame in enumerate(xyz):
        ok = np.isfinite(frame)
        lo = np.array([float(frame[ok[:, a], a].min()) if ok[:, a].any() else 0.0
                       for a in range(3)])
        hi = np.array([float(frame[ok[:, a], a].max()) if ok[:, a].any() else 0.0
                       for a in range(3)])
        step = np.where(hi > lo, (hi - lo) / LEVELS, 1.0)
        q = np.rint((np.where(ok, frame, lo) - lo) / step) - 32767
        out[f] = np.where(ok, q, NO_VALUE).astype("<i2")
        grids.extend(float(v) for v in np.concatenate([lo, step]))
    return base64.b64encode(out.tobytes()).decode("ascii"), grids


def decode_frames(text, grids, particles):
    """encode_frames' inverse (for the tests): (frames, particles, 3)."""
    q = np.frombuffer(base64.b64decode(text), dtype="<i2").reshape(-1, particles, 3)
    g = np.asarray(grids, dtype=float).reshape(-1, 6)
    x = g[:, None, :3] + (q.astype(float) + 32767) * g[:, None, 3:]
    return np.where(q == NO_VALUE, np.nan, x)


def thinned(frame_t, frame_past, every):
    """Indices of the frames kept when only every `every`-th good frame is:
    those, the last good frame and every frame past the blow-up bound."""
    good = np.flatnonzero(~frame_past)
    keep = set(good[::every].tolist()) | set(np.flatnonzero(frame_past).tolist())
    if len(good):
        keep.add(int(good[-1]))
    return np.array(sorted(keep), dtype=int)


def case_data(exp, ctx, case_index, case, positions, frames, runs):
    """The JSON one player reads: frames per integrator, cells, camera bounds."""
    scene = case.get("scene") or {}
    name = scene.get("name")
    dt = case.get("dt")
    particles = scene.get("particles") or []
    # A frame's points: the particles, then the bodies' surface vertices
    # ("points" in the settings when the scene has bodies), whose triangles
    # are the case's "faces".
    n = case.get("points") if isinstance(case.get("points"), int) else len(particles)
    cells = case.get("cells") or []
    faces = case.get("faces") or []
    fixed = [j for j, p in enumerate(particles) if isinstance(p, dict) and p.get("fixed") is True]
    g = scene.get("gravity")
    up = 1
    if isinstance(g, list) and any(isinstance(v, (int, float)) and v for v in g):
        up = int(np.argmax(np.abs(g)))
    panels, good = [], []
    names = [k[1] for k in positions if k[0] == case_index]
    for integ in ctx.integrators.sort(names):
        idx = positions[(case_index, integ)]
        t = positions.table.num("t")[idx]
        past = np.array(positions.table.text("past_blowup"))[idx] == "1"
        order = np.lexsort((positions.table.num("i")[idx], past, t))
        idx, t, past = idx[order], t[order], past[order]
        if len(idx) % n:
            raise DataError(positions.table.path, None, "%s/%s: %d position rows is not a whole "
                            "number of %d-particle frames" % (name, integ, len(idx), n))
        xyz = np.stack([positions.table.num(c)[idx] for c in ("x", "y", "z")], axis=1)
        frame_t, frame_past = t[::n], past[::n]
        xyz = xyz.reshape(len(frame_t), n, 3)
        good.append(xyz[~frame_past].reshape(-1, 3))
        fidx = frames.get((case_index, integ))
        energy = np.full(len(frame_t), np.nan)
        if fidx is not None:
            ft = frames.table.num("t")[fidx]
            fpast = np.array(frames.table.text("past_blowup"))[fidx] == "1"
            fe = frames.table.num("energy")[fidx]
            lookup = {(float(a), bool(b)): e for a, b, e in zip(ft, fpast, fe)}
            energy = np.array([lookup.get((float(a), bool(b)), np.nan)
                               for a, b in zip(frame_t, frame_past)])
        run = runs.get((case_index, integ), {})
        escape = escaped(xyz, frame_t, frame_past, fixed, fluid_particles(scene, n))
        panels.append({
            "name": integ, "colour": ctx.integrators.colour(integ),
            "status": run.get("status", "completed"),
            "stopped_at": run.get("diverged_at"), "failure": run.get("failure") or "",
            "E0": run.get("energy_initial"), "Es": run.get("energy_scale"),
            "gain": energy_gain(energy[~frame_past], run), "escape": escape,
            "t": frame_t, "past": frame_past, "energy": energy, "x": xyz})
    fluid = fluid_particles(scene, n)
    # Every k-th frame, k as small as keeps the positions within the budget
    # (base64: 4 characters per 3 bytes, 2 bytes a coordinate).
    chars = sum(len(p["t"]) for p in panels) * n * 3 * 2 * 4 / 3
    every = max(1, int(np.ceil(chars / PLAYER_BUDGET_CHARS)))
    for p in panels:
        keep = thinned(p["t"], p["past"], every)
        if fluid:
            p["speed"] = frame_speeds(p["x"][keep], p["t"][keep], fluid)
        p["x"], p["q"] = encode_frames(p["x"][keep])
        p["t"] = [float(v) for v in p["t"][keep]]
        p["energy"] = [None if not np.isfinite(e) else float(e) for e in p["energy"][keep]]
        p["past"] = [int(v) for v in p["past"][keep]]
    speed_max = encode_speeds(panels) if fluid else None
    pts = np.concatenate(good) if good else np.zeros((1, 3))
    if fluid and good:
        # A fluid is seen in its box: the first frame (the walls and the
        # water at rest), not the spray of a run that scattered it.
        pts = good[0][:n]
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        pts = np.zeros((1, 3))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    flat = bool(np.all(np.abs(pts[:, 2]) == 0.0)) if len(pts) else True
    # Planes (the ground) whose normal is a coordinate axis: drawn as a
    # rectangle over the bounds (others are not drawn).
    planes = []
    for plane in scene.get("planes") or []:
        if not isinstance(plane, dict):
            continue
        normal, point = plane.get("normal"), plane.get("point")
        if not (isinstance(normal, list) and isinstance(point, list)) or len(normal) != len(point):
            continue
        axes = [a for a, v in enumerate(normal) if v]
        if len(axes) == 1 and len(point) >= 2:
            planes.append({"axis": axes[0], "at": float(point[axes[0]])})
    return {"id": "player-%s-%d" % (exp.name, case_index), "scene": name, "dt": dt, "planes": planes,
            "every": case.get("every", 1), "thinned": every, "particles": n, "cells": cells,
            "faces": faces, "fixed": fixed, "fluid": fluid, "speed_max": speed_max,
            "up": up, "planar": flat, "bounds": [[float(a) for a in lo], [float(b) for b in hi]],
            "t_end": case.get("t_end"), "panels": panels}


def fluid_particles(scene, n):
    """The free particles of the scene's fluids (their "particles" ranges),
    which the player draws as dots coloured by speed; [] without fluids."""
    particles = scene.get("particles") or []
    out = []
    for f in scene.get("fluids") or []:
        r = f.get("particles") if isinstance(f, dict) else None
        if not (isinstance(r, list) and len(r) == 2):
            continue
        for i in range(int(r[0]), min(int(r[0]) + int(r[1]), n)):
            p = particles[i] if i < len(particles) else {}
            if not (isinstance(p, dict) and p.get("fixed") is True):
                out.append(i)
    return out


def frame_speeds(xyz, t, fluid):
    """Each fluid particle's speed in each frame, |x_k - x_(k-1)| / (t_k -
    t_(k-1)) (the first frame: 0), as (frames, len(fluid)) floats; NaN
    where a position is not finite."""
    x = xyz[:, fluid, :]
    out = np.zeros((len(t), len(fluid)))
    if len(t) > 1:
        dt = np.diff(np.asarray(t, dtype=float))
        with np.errstate(invalid="ignore", divide="ignore"):
            out[1:] = np.linalg.norm(np.diff(x, axis=0), axis=2) / dt[:, None]
    return out


def encode_speeds(panels):
    """Every panel's speeds as base64 bytes, 0..255 of one scale for all
    panels: the largest finite speed of a frame within the blow-up bound of
    a panel whose energy gain is not flagged (GAIN_FLAG_ES: a scattered
    fluid's spray would make every other panel blue); faster ones drawn at
    255. Returns that largest speed."""
    top = 0.0
    for p in panels:
        if p.get("gain") is not None and p["gain"] > GAIN_FLAG_ES:
            continue
        good = p["speed"][~np.array(p["past"], dtype=bool)] if len(p["speed"]) else p["speed"]
        finite = good[np.isfinite(good)]
        if len(finite):
            top = max(top, float(finite.max()))
    for p in panels:
        level = np.clip(np.nan_to_num(p["speed"], nan=0.0) / max(top, 1e-300) * 255.0, 0, 255)
        p["speed"] = base64.b64encode(np.rint(level).astype(np.uint8).tobytes()).decode("ascii")
    return top


# The sides of the walls' box a water particle can leave by, per axis.
SIDES = (("x", "the wall at the lower x", "the wall at the upper x"),
         ("y", "the floor", "the top of the walls"),
         ("z", "the wall at the lower z", "the wall at the upper z"))


def escaped(xyz, t, past, fixed, fluid):
    """Where a fluid's water first left its walls' box (the bounding box of
    the fixed particles at the first frame): {"t", "side"} of the first
    good frame with a water particle outside it, or None (no fluid, no
    walls, or the water stayed in)."""
    if not fluid or not fixed or not len(xyz):
        return None
    walls = xyz[0][fixed]
    lo, hi = walls.min(axis=0), walls.max(axis=0)
    for f in range(len(t)):
        if past[f]:
            continue
        water = xyz[f][fluid]
        with np.errstate(invalid="ignore"):
            below, above = water < lo, water > hi
        for axis in range(3):
            for outside, side in ((below, 1), (above, 2)):
                if outside[:, axis].any():
                    return {"t": float(t[f]), "side": SIDES[axis][side],
                            "count": int(np.any(below | above, axis=1).sum())}
    return None


def escape_flag(panel):
    """The warning for a completed run whose water left the walls' box, or ""."""
    e = panel.get("escape")
    if panel["status"] != "completed" or not e:
        return ""
    return ("water left the box through %s at t = %s s (%d particle%s): the walls no longer "
            "hold it" % (e["side"], fmt(e["t"], 3), e["count"], "" if e["count"] == 1 else "s"))


def energy_gain(energy, run):
    """The largest (E - E(0)) / E_s over the good frames, or None."""
    e0, es = run.get("energy_initial"), run.get("energy_scale")
    finite = energy[np.isfinite(energy)]
    if not es or e0 is None or not len(finite):
        return None
    return float((finite.max() - e0) / es)


def gain_flag(panel):
    """The warning for a completed run that gained more than GAIN_FLAG_ES, or ""."""
    gain = panel.get("gain")
    if panel["status"] != "completed" or gain is None or gain <= GAIN_FLAG_ES:
        return ""
    return "energy gain up to +%s E_s: not a physical motion" % fmt(gain, 3)


def case_of(task, integrators):
    """The case a task ran: tasks go case by case, one per integrator (two
    cases may share a scene's name and step, like the cloth with and
    without the ground)."""
    return int(task) // max(1, integrators)


class Grouped:
    """Row indices of a table grouped by (case, integrator)."""

    def __init__(self, table, integrators):
        self.table = table
        task, integ = table.num("task"), table.text("integrator")
        groups = {}
        for r in range(len(table)):
            groups.setdefault((case_of(task[r], integrators), integ[r]), []).append(r)
        self.groups = {k: np.array(v) for k, v in groups.items()}

    def __getitem__(self, key):
        return self.groups[key]

    def get(self, key):
        return self.groups.get(key)

    def __iter__(self):
        return iter(self.groups)


def render(exp, ctx):
    positions = exp.table().require("scene", "integrator", "dt", "t", "past_blowup", "i", "x",
                                    "y", "z")
    frames_t = exp.table("frames")
    runs_t = exp.table("runs")
    listed = exp.setting("integrators")
    integrators = len(listed) if isinstance(listed, list) else 1
    frames = Grouped(frames_t.require("task", "scene", "integrator", "dt", "t", "past_blowup",
                                      "energy"), integrators) if frames_t is not None else {}
    runs = {}
    if runs_t is not None:
        runs_t.require("task", "scene", "integrator", "dt", "status", "diverged_at", "energy_initial",
                       "energy_scale")
        status = runs_t.status()
        failure = runs_t.text("failure") if runs_t.has("failure") else [""] * len(runs_t)
        for r in range(len(runs_t)):
            d = runs_t.num("diverged_at")[r]
            runs[(case_of(runs_t.num("task")[r], integrators), runs_t.text("integrator")[r])] = {
                "status": status[r], "diverged_at": None if np.isnan(d) else float(d),
                "energy_initial": float(runs_t.num("energy_initial")[r]),
                "energy_scale": float(runs_t.num("energy_scale")[r]), "failure": failure[r]}
    grouped = Grouped(positions.require("task"), integrators)
    cases = exp.setting("cases")
    if not isinstance(cases, list) or not cases:
        return note_html("No cases in %s: nothing to play." % esc(exp.settings_path.name))
    out = ['<script>%s</script>\n' % PLAYER_JS.read_text(encoding="utf-8")]
    for k, case in enumerate(cases):
        data = case_data(exp, ctx, k, case, grouped, frames, runs)
        if not data["panels"]:
            out.append(note_html("%s: no frames in the data." % esc(str(data["scene"]))))
            continue
        out.append(player_html(data))
        out.append(facts_html(case_facts(data)))
    if runs_t is not None:
        out.append(runs_table(runs_t, ctx.integrators, "Runs", [
            ("status", "status", None), ("diverged_at", "stopped at t [s]", 4),
            ("steps", "steps", 6), ("wall_seconds", "wall [s]", 3), ("failure", "message", None)]))
    return "".join(out)


def case_facts(data):
    """Sentences under a player, computed from its frames."""
    facts = []
    for p in data["panels"]:
        e = [v for v, past in zip(p["energy"], p["past"]) if v is not None and not past]
        es = p["Es"] if p["Es"] else None
        change = "" if not e or not es else " energy change at its last good frame %s E_s" % fmt(
            (e[-1] - e[0]) / es, 2)
        # Plain text: facts_html escapes it.
        if p["status"] == "diverged":
            facts.append("%s diverged at t = %s s;%s" % (p["name"], fmt(p["stopped_at"]), change))
        elif p["status"] == "failed":
            facts.append("%s failed at t = %s s: %s" % (p["name"], fmt(p["stopped_at"]),
                                                        p["failure"]))
        else:
            flag = gain_flag(p)
            text = "%s ran to t = %s s;%s%s" % (
                p["name"], fmt(p["t"][-1]), change,
                "" if not flag else " \u2014 but it completed with an energy gain of up to %s "
                "E_s (more than %s E_s): springs, gravity and contact make no energy, so this "
                "motion is the method's, not the scene's" % (fmt(p["gain"], 3),
                                                               fmt(GAIN_FLAG_ES)))
            if escape_flag(p):
                text += " \u2014 but its %s" % escape_flag(p)
            facts.append(text)
    contrast = damping_contrast(data["panels"])
    if contrast:
        facts.append(contrast)
    return facts


# A completed run keeps the energy when its change stays within KEEP_ES of
# E_s, and damps it when it loses more than LOSE_ES of E_s.
KEEP_ES = 0.01
LOSE_ES = 0.1


def damping_contrast(panels):
    """A sentence when, at one step, some completed runs keep the energy and
    others lose a good part of it: their panels then differ at one moment
    (one body still bouncing or swinging, another at rest) for a numerical
    reason, which the reader should be told. None otherwise."""
    keep, lose = [], []
    for p in panels:
        e = [v for v, past in zip(p["energy"], p["past"]) if v is not None and not past]
        if p["status"] != "completed" or len(e) < 2 or not p["Es"]:
            continue
        change = (e[-1] - e[0]) / p["Es"]
        if abs(change) <= KEEP_ES:
            keep.append(p["name"])
        elif change < -LOSE_ES:
            lose.append((p["name"], -change))
    if not keep or not lose:
        return None
    lo, hi = min(c for _, c in lose), max(c for _, c in lose)
    amount = fmt(lo, 2) if fmt(lo, 2) == fmt(hi, 2) else "%s to %s" % (fmt(lo, 2), fmt(hi, 2))
    return ("At this step %s %s the energy within %s E_s while %s %s %s E_s: where their panels "
            "differ at one moment (one still moving, another at rest), that is the methods' "
            "numerical damping, not the scene" % (
                ", ".join(keep), "keeps" if len(keep) == 1 else "keep", fmt(KEEP_ES),
                ", ".join(n for n, _ in lose), "loses" if len(lose) == 1 else "lose", amount))


def player_html(data):
    panels = "".join(
        '<div class="player-panel"><canvas class="player-view" width="300" height="250"></canvas>'
        '<canvas class="player-energy" width="300" height="46"></canvas>'
        '<div class="player-label"><span class="sw" style="background:%s"></span>%s '
        '<span class="player-value"></span>%s</div></div>' % (
            esc(p["colour"]), esc(p["name"]),
            "".join('<br><span class="player-flag">%s</span>' % esc(f)
                    for f in (gain_flag(p), escape_flag(p)) if f))
        for p in data["panels"])
    shown = data["every"] * data["thinned"]
    thinned = ("" if data["thinned"] == 1 else
               " (the run wrote a frame every %s; one in %d of those is embedded to keep the "
               "page light, plus the last good one and those past the blow-up bound)"
               % (esc(str(data["every"])), data["thinned"]))
    return ('<figure class="player" id="%s" data-frames-drawn="0">\n'
            '<div class="player-controls"><button type="button" class="player-play">Pause</button> '
            '<input type="range" class="player-slider" min="0" max="1000" value="0"> '
            '<span class="player-time">t = 0 s</span></div>\n'
            '<div class="player-panels">%s</div>\n'
            '<figcaption>%s, dt = %s s: every %s step%s shown%s, %s panels on one clock and one '
            'camera. Under each panel, (E - E(0)) / E_s over time; the dot is now.%s</figcaption>\n'
            '<script type="application/json" class="player-data">%s</script>\n</figure>\n'
            % (esc(data["id"]), panels, esc(str(data["scene"])), fmt(data["dt"], 4),
               esc(str(shown)), "" if shown == 1 else "s", thinned,
               len(data["panels"]),
               "" if not data.get("fluid") else
               " Fluid particles coloured by speed, the distance between two shown frames over "
               "their time, from 0 (blue) to %s m/s (red), the fastest of the frames within "
               "the blow-up bound of any panel whose energy gain is not flagged." % fmt(
                   data.get("speed_max"), 3),
               json.dumps(data, separators=(",", ":")).replace("</", "<\\/")))
