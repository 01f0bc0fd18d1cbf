"""Unit tests of the report package (report/springlab_report): what it says
about the data follows the data. Run by ctest (report_package):

    python3 -m unittest discover -s tests/report -p "test_*.py"

with report/ on PYTHONPATH. Each test builds a small data directory by hand,
with known answers, and reads back the figures' labels or the page's
sentences."""

import base64
import html
import json
import math
import re
import shutil
import sys
import tempfile
import unittest
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "report"))

from springlab_report import main as report_main  # noqa: E402
from springlab_report.data import DataError, read_table  # noqa: E402
from springlab_report.integrators import Integrators  # noqa: E402
from springlab_report.kinds import KINDS  # noqa: E402
from springlab_report.kinds.convergence import _coinciding  # noqa: E402
from springlab_report.kinds.energy import classify  # noqa: E402
from springlab_report.kinds import motion, rigid, spectral, stability  # noqa: E402
from springlab_report.page import marker_text  # noqa: E402

INTEGRATORS = {"integrators": [
    {"name": "symplectic-euler", "family": "symplectic", "order": 1, "adaptive": False,
     "stability": {"kind": "conditional", "text": "conditionally stable: w h <= 2 undamped",
                   "limit_wh": 2.0}, "colour": "#2ca02c", "marker": "^"},
    {"name": "implicit-euler", "family": "implicit", "order": 1, "adaptive": False,
     "stability": {"kind": "L", "text": "L-stable"}, "colour": "#9467bd", "marker": "P"},
    {"name": "explicit-euler", "family": "explicit", "order": 1, "adaptive": False,
     "stability": {"kind": "conditional", "text": "conditionally stable", "limit_wh": 0.0},
     "colour": "#d62728", "marker": "o"},
]}


class Scratch:
    def __init__(self):
        self.dir = Path(tempfile.mkdtemp(prefix="springlab-report-test-"))

    def write(self, name, text):
        (self.dir / name).write_text(text, encoding="utf-8")

    def json(self, name, obj):
        self.write(name, json.dumps(obj))

    def close(self):
        shutil.rmtree(self.dir, ignore_errors=True)


def energy_data(scratch, series, statuses=None):
    """An energy experiment: one oscillator case, E(t) for each method,
    E(0) = 1, E_s = 1."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "scene", "integrator", "dt", "t", "kinetic", "spring", "gravity", "total"]
    runs_cols = ["task", "scene", "integrator", "dt", "status", "diverged_at", "steps",
                 "force_evals", "wall_seconds", "energy_initial", "energy_final", "energy_scale"]
    scratch.json("energy.json", {"name": "energy", "experiment": "energy", "title": "Energy",
                                 "tables": [{"file": "energy.csv", "suffix": "", "columns": cols},
                                            {"file": "energy-runs.csv", "suffix": "runs",
                                             "columns": runs_cols}]})
    rows, runs = [",".join(cols)], [",".join(runs_cols)]
    for task, (name, (t, e)) in enumerate(series.items()):
        for tk, ek in zip(t, e):
            rows.append("%d,oscillator,%s,0.1,%r,%r,0,0,%r" % (task, name, tk, ek, ek))
        status = (statuses or {}).get(name, "completed")
        runs.append("%d,oscillator,%s,0.1,%s,%s,%d,%d,0.001,1,%r,1" % (
            task, name, status, repr(t[-1] + 0.1) if status != "completed" else "", len(t),
            len(t), e[-1]))
    scratch.write("energy.csv", "\n".join(rows) + "\n")
    scratch.write("energy-runs.csv", "\n".join(runs) + "\n")


def render(scratch):
    out = scratch.dir / "out"
    status = report_main.main(["--data", str(scratch.dir), "--out", str(out)])
    page = (out / "index.html").read_text(encoding="utf-8")
    return status, page


class LabLink(unittest.TestCase):
    """--lab: the lab page copied next to index.html and linked, only when it exists."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_linked_when_built_noted_when_not(self):
        t = [0.1 * k for k in range(20)]
        energy_data(self.s, {"symplectic-euler": (t, [1.0] * len(t))})
        out = self.s.dir / "out"
        lab = self.s.dir / "built-lab.html"
        lab.write_text("<!DOCTYPE html><title>lab</title>", encoding="utf-8")
        self.assertEqual(report_main.main(["--data", str(self.s.dir), "--out", str(out),
                                           "--lab", str(lab)]), 0)
        page = (out / "index.html").read_text(encoding="utf-8")
        self.assertIn('<a href="lab.html">', page)
        self.assertEqual((out / "lab.html").read_bytes(), lab.read_bytes())
        lab.unlink()
        self.assertEqual(report_main.main(["--data", str(self.s.dir), "--out", str(out),
                                           "--lab", str(lab)]), 0)
        page = (out / "index.html").read_text(encoding="utf-8")
        self.assertNotIn('href="lab.html"', page)
        self.assertIn("The lab page (%s) is not built" % lab, page)
        self.assertFalse((out / "lab.html").exists())


class MarkerText(unittest.TestCase):
    """The integrators table shows a mathtext marker as the figures draw it."""

    def test_mathtext_markers_are_shown_as_their_text(self):
        self.assertEqual(marker_text("$4$"), "4")
        self.assertEqual(marker_text("$\\alpha$"), "\u03b1")
        self.assertEqual(marker_text("o"), "o")
        self.assertEqual(marker_text("$"), "$")


class Classification(unittest.TestCase):
    t = np.linspace(0.0, 10.0, 401)

    def test_bounded_oscillation_without_drift(self):
        self.assertEqual(classify(self.t, 0.1 * np.sin(5 * self.t))[0], "oscillates")
        # One-signed, as Verlet's energy on an oscillator: still back to E(0) each period.
        e = -0.03 * (1 - np.cos(5 * self.t))
        self.assertEqual(classify(self.t, e), ("oscillates", float(np.max(np.abs(e)))))

    def test_drift_and_decay(self):
        self.assertEqual(classify(self.t, -0.01 * self.t)[0], "loses")
        self.assertEqual(classify(self.t, 0.02 * self.t + 0.001 * np.sin(9 * self.t))[0], "gains")
        # Decays early and stays down (implicit Euler on an oscillator): not an oscillation.
        kind, value = classify(self.t, np.exp(-self.t) - 1.0)
        self.assertEqual(kind, "loses")
        self.assertAlmostEqual(value, math.exp(-10.0) - 1.0)

    def test_flat(self):
        self.assertEqual(classify(self.t, 1e-9 * np.sin(self.t))[0], "flat")


class EnergySentences(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_the_page_says_what_the_data_shows(self):
        t = [0.1 * k for k in range(101)]
        energy_data(self.s, {
            "symplectic-euler": (t, [1 + 0.2 * math.sin(3 * x) for x in t]),
            "implicit-euler": (t, [math.exp(-0.5 * x) for x in t]),
            "explicit-euler": (t[:30], [1.3 ** k for k in range(30)]),
        }, statuses={"explicit-euler": "diverged"})
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertIn("oscillate without drift: symplectic-euler (±20% E_s)", page)
        self.assertIn("lose energy: implicit-euler (−99% E_s by t = 10 s)", page)
        self.assertIn("diverged: explicit-euler (t = 3 s)", page)
        # Change the data, and the sentence changes with it.
        energy_data(self.s, {"symplectic-euler": (t, [1 + 0.05 * x for x in t])})
        _, page = render(self.s)
        self.assertIn("gain energy: symplectic-euler (+50% E_s by t = 10 s)", page)
        self.assertNotIn("oscillate without drift", page)

    def test_a_second_section_of_one_kind_links_to_the_first(self):
        t = [0.1 * k for k in range(11)]
        energy_data(self.s, {"symplectic-euler": (t, [1.0] * len(t))})
        second = json.loads((self.s.dir / "energy.json").read_text())
        second["name"] = "energy-again"
        self.s.json("energy-again.json", second)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        about = html.escape(KINDS["energy"].ABOUT, quote=True)
        self.assertEqual(page.count(about), 1)
        self.assertIn('The same as in <a href="#energy">', page)

    def test_coinciding_runs_are_said_to_coincide(self):
        t = [0.1 * k for k in range(50)]
        e = [math.exp(-x) for x in t]
        energy_data(self.s, {"implicit-euler": (t, e), "symplectic-euler": (t, list(e))})
        _, page = render(self.s)
        self.assertIn("implicit-euler and symplectic-euler have the same energy at every output",
                      page)

    def test_same_data_same_bytes(self):
        t = [0.1 * k for k in range(60)]
        energy_data(self.s, {"symplectic-euler": (t, [1 + 0.1 * math.sin(x) for x in t])})
        render(self.s)
        out = self.s.dir / "out"
        first = {str(p.relative_to(out)): p.read_bytes() for p in out.rglob("*") if p.is_file()}
        self.assertIn("data/energy.csv", first)
        shutil.rmtree(out)
        render(self.s)
        second = {str(p.relative_to(out)): p.read_bytes() for p in out.rglob("*") if p.is_file()}
        self.assertEqual(first, second)


class SectionsOnTwoCpus(unittest.TestCase):
    """make_report.py draws the sections in two forked workers: the page, its
    figures and data files are the same bytes as drawn one by one."""

    def setUp(self):
        self.s = Scratch()
        self.affinity = report_main.os.sched_getaffinity
        self.get_context = report_main.multiprocessing.get_context
        self.pools = []

        def counted(method):
            self.pools.append(method)
            return self.get_context(method)
        report_main.multiprocessing.get_context = counted

    def tearDown(self):
        report_main.os.sched_getaffinity = self.affinity
        report_main.multiprocessing.get_context = self.get_context
        self.s.close()

    def files(self, cpus):
        report_main.os.sched_getaffinity = lambda _pid: set(range(cpus))
        out = self.s.dir / "out"
        shutil.rmtree(out, ignore_errors=True)
        status, _ = render(self.s)
        self.assertEqual(status, 0)
        return {str(p.relative_to(out)): p.read_bytes() for p in out.rglob("*") if p.is_file()}

    def test_two_workers_draw_what_one_draws(self):
        t = [0.1 * k for k in range(60)]
        energy_data(self.s, {"symplectic-euler": (t, [1 + 0.1 * math.sin(x) for x in t]),
                             "implicit-euler": (t, [math.exp(-0.3 * x) for x in t])})
        second = json.loads((self.s.dir / "energy.json").read_text())
        second["name"] = "energy-again"
        self.s.json("energy-again.json", second)
        one = self.files(1)
        self.assertEqual(self.pools, [])  # one CPU: drawn in this process
        two = self.files(2)
        self.assertEqual(self.pools, ["fork"])
        self.assertEqual(sum(name.endswith(".png") for name in two), 2)
        self.assertEqual(one, two)


class OwnMethods(unittest.TestCase):
    """A method an experiment brought (a plug-in's, a Python class's) is
    listed in its settings' "own_integrators": drawn in its family beside
    the built-ins, in a colour and marker no built-in has."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_learned_from_the_settings(self):
        t = [0.1 * k for k in range(101)]
        swing = [1 + 0.2 * math.sin(3 * x) for x in t]
        energy_data(self.s, {"symplectic-euler": (t, swing), "my-euler": (t, list(swing))})
        _, page = render(self.s)
        self.assertIn("does not list my-euler", page)  # no facts: a palette colour, a note
        settings = json.loads((self.s.dir / "energy.json").read_text())
        settings["own_integrators"] = [{"name": "my-euler", "family": "symplectic", "order": 1,
                                        "adaptive": False, "symplectic": True,
                                        "stability": {"kind": "conditional", "limit_wh": 2.0}}]
        self.s.json("energy.json", settings)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertNotIn("does not list my-euler", page)
        integrators = Integrators.load(self.s.dir / "integrators.json")
        experiments, _ = report_main.load_experiments(self.s.dir, KINDS)
        report_main.collect_names(experiments, integrators)
        self.assertEqual(integrators.family("my-euler"), "symplectic")
        self.assertEqual(integrators.sort(["my-euler", "implicit-euler", "explicit-euler"]),
                         ["explicit-euler", "my-euler", "implicit-euler"])
        builtin = {e["colour"] for e in INTEGRATORS["integrators"]}
        self.assertNotIn(integrators.colour("my-euler"), builtin)
        self.assertNotIn(integrators.marker("my-euler"),
                         {e["marker"] for e in INTEGRATORS["integrators"]})


def motion_data(scratch):
    """A motion experiment: two particles joined by a spring; implicit Euler
    runs 3 frames, explicit Euler diverges after 1 good frame and records one
    frame past the blow-up bound far away."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "scene", "integrator", "dt", "t", "past_blowup", "i", "x", "y", "z"]
    fcols = ["task", "scene", "integrator", "dt", "t", "past_blowup", "energy"]
    rcols = ["task", "scene", "integrator", "dt", "status", "diverged_at", "steps", "wall_seconds",
             "energy_initial", "energy_scale", "failure"]
    scene = {"name": "pair", "dimension": 2, "gravity": [0, -9.81],
             "particles": [{"x": [0, 0], "fixed": True}, {"x": [1, 0]}],
             "springs": [{"i": 0, "j": 1, "k": 10}]}
    scratch.json("motion.json", {
        "name": "motion", "experiment": "motion", "title": "Motion",
        "integrators": ["implicit-euler", "explicit-euler"],
        "cases": [{"scene": scene, "dt": 0.1, "t_end": 0.2, "every": 1, "cells": [[0, 1]]}],
        "tables": [{"file": "motion.csv", "suffix": "", "columns": cols},
                   {"file": "motion-frames.csv", "suffix": "frames", "columns": fcols},
                   {"file": "motion-runs.csv", "suffix": "runs", "columns": rcols}]})
    rows, frames = [",".join(cols)], [",".join(fcols)]
    for t, y in ((0, 0.0), (0.1, -0.5), (0.2, -1.0)):
        for i, x in ((0, 0.0), (1, 1.0)):
            rows.append("0,pair,implicit-euler,0.1,%r,0,%d,%r,%r,0" % (t, i, x, y if i else 0.0))
        frames.append("0,pair,implicit-euler,0.1,%r,0,%r" % (t, -2.0 * t))
    rows += ["1,pair,explicit-euler,0.1,0,0,0,0,0,0", "1,pair,explicit-euler,0.1,0,0,1,1,0,0",
             "1,pair,explicit-euler,0.1,0.1,1,0,0,0,0", "1,pair,explicit-euler,0.1,0.1,1,1,1000,0,0"]
    frames += ["1,pair,explicit-euler,0.1,0,0,0", "1,pair,explicit-euler,0.1,0.1,1,1e9"]
    scratch.write("motion.csv", "\n".join(rows) + "\n")
    scratch.write("motion-frames.csv", "\n".join(frames) + "\n")
    scratch.write("motion-runs.csv", "\n".join([
        ",".join(rcols),
        "0,pair,implicit-euler,0.1,completed,,2,0.001,0,2,",
        "1,pair,explicit-euler,0.1,diverged,0.1,1,0.001,0,2,"]) + "\n")


class Motion(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def player(self, page):
        found = re.search(r'<script type="application/json" class="player-data">(.*?)</script>',
                          page, re.S)
        self.assertIsNotNone(found)
        return json.loads(found.group(1))

    def test_frames_bounds_and_sentences_follow_the_data(self):
        motion_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        data = self.player(page)
        by_name = {p["name"]: p for p in data["panels"]}
        ie, ee = by_name["implicit-euler"], by_name["explicit-euler"]
        self.assertEqual(ie["t"], [0, 0.1, 0.2])
        x = motion.decode_frames(ie["x"], ie["q"], 2)
        self.assertEqual(x.shape, (3, 2, 3))
        np.testing.assert_allclose(x[:, 1, 1], [0.0, -0.5, -1.0], rtol=0, atol=1e-12)
        # Past the blow-up bound a frame keeps its own grid: x = 1000 comes back.
        self.assertAlmostEqual(float(motion.decode_frames(ee["x"], ee["q"], 2)[1, 1, 0]), 1000.0,
                               places=9)
        self.assertEqual(ee["past"], [0, 1])
        # The camera frames the good frames only: the explosion (x = 1000) leaves the picture.
        self.assertEqual(data["bounds"], [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
        self.assertTrue(data["planar"])
        self.assertEqual(data["fixed"], [0])
        self.assertIn("explicit-euler diverged at t = 0.1 s", page)
        self.assertIn("implicit-euler ran to t = 0.2 s; energy change at its last good frame "
                      "-0.2 E_s", page)


class MotionDampingContrast(unittest.TestCase):
    """Runs that keep the energy beside runs that damp it are told apart in
    one sentence; none when all agree."""

    def panel(self, name, change, status="completed"):
        """A run whose energy changes by `change` E_s (E_s = 2 J)."""
        return {"name": name, "status": status, "Es": 2.0, "energy": [1.0, 1.0 + 2.0 * change],
                "past": [0, 0]}

    def test_sentence_follows_the_energies(self):
        panels = [self.panel("cvode-bdf", 0.001), self.panel("implicit-euler", -0.66),
                  self.panel("xpbd", -0.58), self.panel("explicit-euler", 9, "diverged")]
        text = motion.damping_contrast(panels)
        self.assertEqual(text, "At this step cvode-bdf keeps the energy within 0.01 E_s while "
                               "implicit-euler, xpbd lose 0.58 to 0.66 E_s: where their panels "
                               "differ at one moment (one still moving, another at rest), that is "
                               "the methods' numerical damping, not the scene")
        # All damp (or all keep): nothing to contrast.
        self.assertIsNone(motion.damping_contrast(panels[1:]))
        self.assertIsNone(motion.damping_contrast(panels[:1]))


class MotionBodies(unittest.TestCase):
    """A case with rigid bodies: its settings give the points per frame
    (particles, then the bodies' surface vertices) and the surface
    triangles, which reach the player as data["particles"] and data["faces"]."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def settings(self, points, faces):
        d = json.loads((self.s.dir / "motion.json").read_text(encoding="utf-8"))
        d["cases"][0]["points"] = points
        d["cases"][0]["faces"] = faces
        self.s.json("motion.json", d)

    def test_points_and_faces_reach_the_player(self):
        motion_data(self.s)
        self.settings(2, [[0, 1, 1]])
        status, page = render(self.s)
        self.assertEqual(status, 0)
        found = re.search(r'<script type="application/json" class="player-data">(.*?)</script>',
                          page, re.S)
        data = json.loads(found.group(1))
        self.assertEqual(data["particles"], 2)
        self.assertEqual(data["faces"], [[0, 1, 1]])

    def test_points_set_the_frame_size(self):
        motion_data(self.s)  # 2 rows a frame
        self.settings(3, [])
        status, _ = render(self.s)
        self.assertNotEqual(status, 0)


def contact_data(scratch):
    """A contact experiment: the slide case (theory a = 2) over three steps,
    implicit Euler within 1 % at every step, symplectic Euler only at the
    smallest, explicit Euler failing at the largest; a soft and a stiff
    bounce for the cost sentence."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "case", "scene", "integrator", "dt", "status", "t_final", "regime", "measured",
            "theory", "min_gap", "energy_change", "steps", "newton_iterations", "wall_seconds",
            "failure"]
    drop = {"gravity": [0, -10], "planes": [{"point": [0, 0], "normal": [0, 2]}],
            "particles": [{"x": [0, 0.1], "mass": 2}, {"x": [0, 0], "fixed": True}]}
    scratch.json("contact.json", {"name": "contact", "experiment": "contact", "title": "Contact",
                                  "cases": [{}, {}, {}, {"scene": drop}, {"scene": drop}],
                                  "tables": [{"file": "contact.csv", "suffix": "",
                                              "columns": cols}]})
    rows = [",".join(cols)]
    measured = {"implicit-euler": (2.0, 2.001, 1.99), "symplectic-euler": (2.01, 2.5, 3.0),
                "explicit-euler": (2.01, 2.2, None)}
    task = 0
    for k, dt in enumerate((0.001, 0.01, 0.1)):
        for name, values in measured.items():
            value = values[k]
            status = "completed" if value is not None else "failed"
            rows.append("%d,%d,slope,%s,%r,%s,%s,slide,%s,2,-1e-4,-1,%d,%d,0.01,%s" % (
                task, k, name, dt, status, "1" if value is not None else "0.5",
                repr(value) if value is not None else "nan", round(1 / dt), 0,
                "" if value is not None else "no convergence"))
            task += 1
    for k, (scene, work) in enumerate((("bounce-soft", 100), ("bounce-stiff", 300))):
        for name in measured:
            change = -0.5 if name == "explicit-euler" else 0.01  # of m g h = 2 J
            rows.append("%d,%d,%s,%s,0.01,completed,1,bounce,0.0015,0.0015,-0.0015,%r,%d,0,0.01,"
                        % (task, 3 + k, scene, name, change, work))
            task += 1
    scratch.write("contact.csv", "\n".join(rows) + "\n")


class Contact(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentences_follow_the_sweep(self):
        contact_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("slope: slides above the friction angle (acceleration) — within 1 % at "
                      "every step of the sweep (up to 0.1 s): implicit-euler; within 1 % at every "
                      "step up to: explicit-euler (0.001 s), symplectic-euler (0.001 s).", facts)
        self.assertIn("Work on the stiff floor relative to the soft one, at the largest step (or "
                      "output interval) both runs completed: explicit-euler 3 x (dt = 0.01 s), "
                      "implicit-euler 3 x (dt = 0.01 s), symplectic-euler 3 x (dt = 0.01 s).",
                      facts)
        self.assertIn("bounce-soft: bounces on a penalty floor: the drop's energy m g h is 2 J; "
                      "the runs that keep the energy within 1 % of it at every step they "
                      "completed: symplectic-euler and implicit-euler.", facts)
        self.assertTrue((self.s.dir / "out" / "contact.png").is_file())
        self.assertTrue((self.s.dir / "out" / "contact-bounce.png").is_file())


def mode_data(scratch):
    """A mode experiment: w1 = 2 pi (period 1 s), w_max = 100 w1; implicit
    Euler completes at 10 and 100 steps per period (measured within 1e-4 of
    the prediction), symplectic Euler diverges at 10 and completes at 100."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "scene", "integrator", "steps_per_period", "dt", "status", "diverged_at", "w",
            "period_exact", "period", "period_predicted", "amplitude_per_period",
            "amplitude_per_period_predicted", "steps", "force_evals", "wall_seconds", "failure"]
    series = ["task", "scene", "integrator", "steps_per_period", "dt", "t", "q", "dq_over_w"]
    w = 2 * math.pi
    scratch.json("mode.json", {"name": "mode", "experiment": "mode", "title": "Mode",
                               "w": w, "w_max": 100 * w, "period_exact": 1.0,
                               "tables": [{"file": "mode.csv", "suffix": "", "columns": cols},
                                          {"file": "mode-series.csv", "suffix": "series",
                                           "columns": series}]})
    rows, q = [",".join(cols)], [",".join(series)]
    runs = [("implicit-euler", 10, "completed", 1.12, 1.1201, 0.155, 0.1551),
            ("symplectic-euler", 10, "diverged", None, 0.97, None, 1.0),
            ("implicit-euler", 100, "completed", 1.0013, 1.0013, 0.82, 0.82),
            ("symplectic-euler", 100, "completed", 0.9998, 0.9998, 1.0, 1.0)]
    for task, (name, s, status, period, predicted, amp, amp_predicted) in enumerate(runs):
        f = lambda x: "" if x is None else repr(x)  # noqa: E731
        rows.append("%d,beam,%s,%d,%r,%s,%s,%r,1,%s,%r,%s,%r,%d,%d,0.01," % (
            task, name, s, 1.0 / s, status, "" if period else "0.1", w, f(period), predicted,
            f(amp), amp_predicted, s, s))
        if period:
            for k in range(s + 1):
                q.append("%d,beam,%s,%d,%r,%r,%r,0" % (task, name, s, 1.0 / s, k / s,
                                                       math.cos(2 * math.pi * k / s)))
    scratch.write("mode.csv", "\n".join(rows) + "\n")
    scratch.write("mode-series.csv", "\n".join(q) + "\n")


class ModeKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentences_follow_the_rows(self):
        mode_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("The first mode: w1 = 6.283 rad/s (period 1 s); the fastest mode of the "
                      "same beam: w_max = 628.3 rad/s, 100 times faster.", facts)
        self.assertIn("Diverged: symplectic-euler up to 10 steps per period (completed from 100)."
                      " Symplectic Euler and Verlet are stable for w_max h ≤ 2, which is "
                      "π w_max / w1 = 314.2 steps per period of the first mode; RK4 for "
                      "w_max h ≤ 2.83, 222.2 steps per period.", facts)
        self.assertIn("Measured on the beam against predicted from the step map on one oscillator "
                      "(every completed fixed-step run): the period differs by at most 8.9e-05 "
                      "(relative), the amplitude per period by at most 0.0001.", facts)
        self.assertTrue((self.s.dir / "out" / "mode.png").is_file())


def rotation_data(scratch):
    """A rotation experiment: one scenario, verlet; linear swells to 5 x its
    radius of gyration at no energy, corotated stays rigid."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "scenario", "scene", "model", "integrator", "dt", "t", "kinetic", "elastic",
            "gyration"]
    runs = ["task", "scenario", "scene", "model", "integrator", "dt", "status", "diverged_at",
            "kinetic_initial", "elastic_initial", "elastic_max", "gyration_max",
            "gyration_final", "steps", "wall_seconds", "failure"]
    scratch.json("rotation.json", {"name": "rotation", "experiment": "rotation",
                                   "title": "Rotation", "models": ["linear", "corotated"],
                                   "scenarios": [{"title": "spinning", "scenes": []}],
                                   "tables": [{"file": "rotation.csv", "suffix": "",
                                               "columns": cols},
                                              {"file": "rotation-runs.csv", "suffix": "runs",
                                               "columns": runs}]})
    rows, run_rows = [",".join(cols)], [",".join(runs)]
    for task, (model, g_end, elastic) in enumerate((("linear", 5.0, 0.0),
                                                   ("corotated", 1.0001, 2e-4))):
        for k in range(11):
            t = k / 10
            g = 1 + (g_end - 1) * t
            rows.append("%d,0,block,%s,verlet,0.01,%r,0.3,%r,%r" % (task, model, t, elastic, g))
        run_rows.append("%d,0,block,%s,verlet,0.01,completed,,0.3,0,%r,%r,%r,100,0.1," % (
            task, model, elastic, g_end, g_end))
    scratch.write("rotation.csv", "\n".join(rows) + "\n")
    scratch.write("rotation-runs.csv", "\n".join(run_rows) + "\n")


class RotationKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentence_follows_the_runs(self):
        rotation_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("spinning, verlet: linear ends at 5 times its starting radius of gyration "
                      "(largest 5), its elastic energy 0 J at the start and at most 0 J; "
                      "corotated stays rigid: the radius of gyration within 0.1 % of its start, "
                      "the elastic energy under 1 % of the starting kinetic energy (or 1e-9 J).",
                      facts)
        self.assertTrue((self.s.dir / "out" / "rotation.png").is_file())


def rigid_data(scratch):
    """A rigid experiment: symplectic Euler flips 2 % late, implicit Euler
    0.5 % early; a kappa sweep with the error falling as 1/kappa and a step
    limit at 1.01 times theory's."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "integrator", "dt", "t", "energy", "kinetic", "rigidity", "momentum_drift",
            "strain", "axis", "axis_reference", "orientation_error"]
    runs = ["task", "integrator", "dt", "status", "diverged_at", "energy_final",
            "energy_drift_max", "momentum_drift_max", "strain_max", "orientation_error_max",
            "reversals", "first_reversal", "flip_period", "reference_first_reversal",
            "reference_flip_period", "period_error", "steps", "wall_seconds", "failure"]
    kappa = ["task", "kappa", "integrator", "dt", "t_end", "status", "strain_max",
             "orientation_error_max", "energy_drift_max", "momentum_drift_max", "flip_period",
             "reference_flip_period", "period_error"]
    limits = ["task", "kappa", "integrator", "w_formula", "w_max", "dt_theory", "dt_max_stable",
              "lo", "hi", "ratio", "outcome"]
    scratch.json("rigid.json", {
        "name": "rigid", "experiment": "rigid", "title": "Rigid", "t_end": 10, "kappa_dt": 5e-5,
        "body": {"rigidity": 1e6},
        "tables": [{"file": "rigid.csv", "suffix": "", "columns": cols},
                   {"file": "rigid-runs.csv", "suffix": "runs", "columns": runs},
                   {"file": "rigid-kappa.csv", "suffix": "kappa", "columns": kappa},
                   {"file": "rigid-limits.csv", "suffix": "limits", "columns": limits}]})
    rows, run_rows = [",".join(cols)], [",".join(runs)]
    for task, (name, energy, period) in enumerate((("symplectic-euler", 1.001, 4.08),
                                                   ("implicit-euler", 0.9, 3.98))):
        for k in range(11):
            rows.append("%d,%s,0.001,%r,%r,1,0,1e-12,1e-4,%r,%r,0.01" % (
                task, name, float(k), 1 + (energy - 1) * k / 10, math.cos(k), math.cos(k)))
        run_rows.append("%d,%s,0.001,completed,,%r,0.1,1e-12,1e-4,0.01,3,2,%r,2,4,%r,10000,"
                        "0.1," % (task, name, energy, period, (period - 4) / 4))
    kappa_rows = [",".join(kappa)]
    limit_rows = [",".join(limits)]
    for task, k in enumerate((1e4, 1e5, 1e6)):
        kappa_rows.append("%d,%r,rk4,5e-05,7,completed,%r,%r,1e-9,1e-9,4,4,%r" % (
            task + 2, k, 400 / k, 40 / k, 1 / k))
        w = math.sqrt(9.6 * k)
        limit_rows.append("%d,%r,symplectic-euler,%r,%r,%r,%r,0,0,1.01,bracketed" % (
            task + 5, k, w, w, 2 / w, 2.02 / w))
    scratch.write("rigid.csv", "\n".join(rows) + "\n")
    scratch.write("rigid-runs.csv", "\n".join(run_rows) + "\n")
    scratch.write("rigid-kappa.csv", "\n".join(kappa_rows) + "\n")
    scratch.write("rigid-limits.csv", "\n".join(limit_rows) + "\n")


class RigidKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentences_follow_the_runs(self):
        rigid_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("The exact rigid body reverses its spin axis first at t = 2 s and then "
                      "every 4 s (the flip period).", facts)
        self.assertIn("Flip period within 1 % of the exact one: implicit-euler (-0.5 %).", facts)
        self.assertIn("Flip period off by more than 1 %: symplectic-euler (2 %).", facts)
        self.assertIn("Energy at the end, E / E₀: implicit-euler 0.9, symplectic-euler 1.001.",
                      facts)
        self.assertIn("As κ grows from 1e+04 to 1e+06 Pa (rk4 at dt = 5e-05 s), the largest "
                      "|A − R_exact|_F falls from 0.004 to 4e-05 (fitted slope -1) and the "
                      "largest strain from 0.04 to 0.0004 (slope -1); the flip period's error "
                      "from 0.01 % to 0.0001 %.", facts)
        self.assertIn("Largest stable step as κ grows: symplectic-euler from 0.00652 s to "
                      "0.000652 s (slope -0.5), 1.01 to 1.01 times theory's. The fastest mode "
                      "found numerically matches ω_κ = √(8κV / min J_i) to 0 (relative).", facts)
        self.assertTrue((self.s.dir / "out" / "rigid.png").is_file())


def pile_data(scratch):
    """The rigid experiment above with its box pile: implicit Euler stands
    (energy 9 -> 8 J), newmark diverges at t = 0.2 s after its energy
    reached 40 J (at t = 0.1 s), generalized-alpha fails at t = 0.1 s."""
    rigid_data(scratch)
    definition = json.loads((scratch.dir / "rigid.json").read_text())
    cols = ["task", "integrator", "dt", "t", "top_height", "energy", "kinetic", "smallest_gap"]
    runs = ["task", "integrator", "dt", "status", "diverged_at", "steps", "newton_per_step",
            "top_height_final", "energy_initial", "energy_final", "smallest_gap",
            "wall_seconds", "failure"]
    definition["pile"] = {"scene": "box-pile", "bodies": 8}
    definition["tables"] += [{"file": "rigid-pile.csv", "suffix": "pile", "columns": cols},
                             {"file": "rigid-pile_runs.csv", "suffix": "pile_runs",
                              "columns": runs}]
    scratch.json("rigid.json", definition)
    rows = [",".join(cols)]
    for t in (0.0, 0.1, 0.2, 0.3):
        rows.append("1,implicit-euler,0.001,%r,0.41,%r,0,0.001" % (t, 9 - 1 * t / 0.3))
    for t, e in ((0.0, 9.0), (0.1, 40.0), (0.2, 20.0)):
        rows.append("2,newmark,0.001,%r,0.41,%r,0,0.001" % (t, e))
    for t in (0.0, 0.1):
        rows.append("3,generalized-alpha,0.001,%r,0.41,9,0,0.001" % t)
    run_rows = [",".join(runs),
                "1,implicit-euler,0.001,completed,,300,1.2,0.41,9,8,0.001,0.1,",
                "2,newmark,0.001,diverged,0.2,200,7,0.41,9,20,0.001,0.1,rigidity",
                "3,generalized-alpha,0.001,failed,0.1,100,2,0.41,9,9,0.001,0.1,Newton"]
    scratch.write("rigid-pile.csv", "\n".join(rows) + "\n")
    scratch.write("rigid-pile_runs.csv", "\n".join(run_rows) + "\n")


class RigidPile(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_caption_names_the_run_that_leaves_the_energy_axis(self):
        pile_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        text = html.unescape(page)
        # The axis ends at 1.25 x 9 J (implicit Euler's highest): newmark's
        # 40 J is above it, generalized-alpha's 9 J is not.
        self.assertIn("The energy axis ends at 1.25 times the highest energy of the runs that "
                      "completed; above it: newmark at 0.001 s (40 J at t = 0.1 s).", text)
        self.assertNotIn("generalized-alpha at 0.001 s (", text)
        self.assertIn("Stopped: newmark at 0.001 s diverged at t = 0.2 s (rigidity); "
                      "generalized-alpha at 0.001 s failed at t = 0.1 s (Newton).", text)
        self.assertTrue((self.s.dir / "out" / "rigid-pile.png").is_file())

    def test_caption_says_how_the_collisions_dissipate(self):
        """From the pile's scene as the experiment wrote it: each box's
        contact_damping (absent: 0, elastic)."""
        self.assertEqual(rigid.pile_damping({"scene": "box-pile"}), "")
        box = {"shape": "box", "size": [0.2, 0.1, 0.15]}
        damped = {"scene": {"bodies": [dict(box, contact_damping=2.0)] * 3}}
        self.assertEqual(rigid.pile_damping(damped),
                         "every box with contact damping alpha = 2 s/m")
        self.assertEqual(rigid.pile_damping({"scene": {"bodies": [box, box]}}),
                         "elastic contact: no contact damping")
        mixed = {"scene": {"bodies": [box, dict(box, contact_damping=5.0)]}}
        self.assertEqual(rigid.pile_damping(mixed),
                         "the boxes' contact damping alpha from 0 to 5 s/m")


class FluidPlayer(unittest.TestCase):
    """The player's fluid particles: which they are, their speed between
    frames, and one byte scale for every panel."""

    def test_speeds_between_frames_on_one_scale(self):
        scene = {"particles": [{"x": [0, 0]}, {"x": [1, 0], "fixed": True}, {"x": [2, 0]},
                               {"x": [3, 0]}],
                 "fluids": [{"particles": [0, 3]}]}
        self.assertEqual(motion.fluid_particles(scene, 4), [0, 2])
        self.assertEqual(motion.fluid_particles({"particles": []}, 0), [])
        xyz = np.zeros((3, 4, 3))
        xyz[1:, 0, 0] = 0.3           # particle 0 moves 0.3 m in the first 0.1 s
        xyz[2, 2, 1] = 0.4            # particle 2 moves 0.4 m in the second
        speeds = motion.frame_speeds(xyz, np.array([0.0, 0.1, 0.2]), [0, 2])
        np.testing.assert_allclose(speeds, [[0, 0], [3, 0], [0, 4]])
        panels = [{"speed": speeds, "past": [0, 0, 0]},
                  {"speed": 5 * speeds, "past": [0, 0, 1]}]
        # The second panel's 20 m/s is past the blow-up bound: the scale is its 15 m/s.
        self.assertAlmostEqual(motion.encode_speeds(panels), 15.0, places=12)
        first = np.frombuffer(base64.b64decode(panels[0]["speed"]), dtype=np.uint8)
        second = np.frombuffer(base64.b64decode(panels[1]["speed"]), dtype=np.uint8)
        self.assertEqual(list(first), [0, 0, 51, 0, 0, 68])
        self.assertEqual(list(second), [0, 0, 255, 0, 0, 255])
        # A panel flagged for its energy gain does not set the scale.
        panels = [{"speed": speeds, "past": [0, 0, 0]},
                  {"speed": 5 * speeds, "past": [0, 0, 0], "gain": 2 * motion.GAIN_FLAG_ES}]
        self.assertAlmostEqual(motion.encode_speeds(panels), 4.0, places=12)


def fluid_data(scratch):
    """A fluid experiment: symplectic Euler's front 5 % ahead of Martin and
    Moyce at T = 2, implicit Euler's 10 % behind and twice as dear, explicit
    Euler diverged, projective dynamics refused; two step limits."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "integrator", "dt", "t", "T", "Z", "kinetic", "gravity", "pressure", "total",
            "viscous_work", "numerical", "compression"]
    runs = ["task", "integrator", "dt", "substeps", "iterations", "status", "diverged_at",
            "t_final", "steps", "force_evals", "newton_iterations", "wall_seconds",
            "cpu_seconds", "cost_per_second", "Z_T2", "Z_T2_measured", "Z_T2_error", "front_speed_max",
            "ritter_speed", "compression_max", "energy_initial", "viscous_work", "numerical",
            "particles", "failure"]
    limits = ["task", "sound", "c", "integrator", "particles", "h", "hydrostatic", "w_max",
              "dt_theory",
              "C_theory", "dt_max_stable", "lo", "hi", "v_max", "C_measured", "ratio", "outcome"]
    scratch.json("fluid.json", {
        "name": "fluid", "experiment": "fluid", "title": "Fluid",
        "dam_break": {"a": 0.1, "g": 9.81, "spacing": 0.01, "speed_of_sound": 14.0,
                      "water_particles": 200, "particles": 518, "energy_scale": 2.0,
                      "time_scale": 14.0},
        "reference": {"file": "reference/mm.csv", "source": "Martin and Moyce (1952): the surge"},
        "tables": [{"file": "fluid.csv", "suffix": "", "columns": cols},
                   {"file": "fluid-runs.csv", "suffix": "runs", "columns": runs},
                   {"file": "fluid-reference.csv", "suffix": "reference", "columns": ["task", "T", "Z"]},
                   {"file": "fluid-limits.csv", "suffix": "limits", "columns": limits}]})
    rows, run_rows = [",".join(cols)], [",".join(runs)]
    for task, (name, speed, work) in enumerate((("symplectic-euler", 1.1, 0.2),
                                                ("implicit-euler", 1.0, 0.3))):
        for k in range(11):
            T = 0.3 * k
            rows.append("%d,%s,0.001,%r,%r,%r,0,0,0,%r,%r,%r,0.01" % (
                task, name, T / 14, T, 1 + speed * T, 10 - work * k, work * k, 0.0))
    run_rows.append("0,symplectic-euler,0.0002,0,0,completed,,0.24,1200,1200,0,2,1.92,8.0,2.4684,"
                    "2.3509,0.05,1.5,2.8,0.012,10,0.4,-0.02,518,")
    run_rows.append("1,implicit-euler,0.001,0,0,completed,,0.24,240,900,600,4,3.84,16.0,2.1158,"
                    "2.3509,-0.1,1.2,2.8,0.01,10,0.6,-0.2,518,")
    run_rows.append("2,explicit-euler,5e-05,0,0,diverged,0.0125,0.0125,250,250,0,0.1,0.1,8,,2.3509,,"
                    "0,2.8,0,10,0,0,518,")
    run_rows.append("3,projective-dynamics,0.004,0,0,failed,0,0,0,0,0,0,0,,,2.3509,,0,2.8,0,10,0,0,"
                    "518,projective-dynamics: fluid forces have no projective form")
    ref_rows = ["task,T,Z", "0,0.41,1.11", "0,1.98,2.33", "0,2.2,2.56"]
    lim_rows = [",".join(limits)]
    for task, c in enumerate((7.0, 14.0)):
        w = 1000.0 * c / 7.0
        lim_rows.append("%d,%r,%r,symplectic-euler,250,0.026,%r,%r,%r,%r,%r,0,0,1.0,%r,%r,"
                        "bracketed" % (task + 4, c / 1.4, c, 1.962 / c ** 2, w, 2 / w,
                                       2 / w * c / 0.026, 1.8 / w, 1.8 / w * (c + 1) / 0.026, 0.9))
    scratch.write("fluid.csv", "\n".join(rows) + "\n")
    scratch.write("fluid-runs.csv", "\n".join(run_rows) + "\n")
    scratch.write("fluid-reference.csv", "\n".join(ref_rows) + "\n")
    scratch.write("fluid-limits.csv", "\n".join(lim_rows) + "\n")


class FluidKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentences_follow_the_runs(self):
        fluid_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("Refused at the start: projective-dynamics: fluid forces have no projective "
                      "form.", facts)
        self.assertIn("Stopped: explicit-euler at 0.05 ms diverged at t = 0.0125 s "
                      "(T = 0.175).", facts)
        self.assertIn("At T = 2 Martin and Moyce measured Z = 2.35; the runs give "
                      "symplectic-euler at 0.2 ms 2.47 (5 %), implicit-euler at 1 ms 2.12 "
                      "(-10 %).", facts)
        self.assertIn("Within 15 % of the measured front at T = 2: symplectic-euler at 0.2 ms "
                      "and implicit-euler at 1 ms.", facts)
        self.assertIn("The fastest front of any completed run, 1.5 m/s (symplectic-euler at "
                      "0.2 ms), is below Ritter's bound 2√(2ga) = 2.8 m/s.", facts)
        self.assertIn("Cost per simulated second: cheapest symplectic-euler at 0.2 ms (8 s), "
                      "dearest implicit-euler at 1 ms (16 s), 2 times as much.", facts)
        self.assertIn("Largest compression ρ/ρ₀ − 1 in any sampled state: 1.2 % "
                      "(symplectic-euler at 0.2 ms); the weakly compressible model aims at "
                      "about 1 %.", facts)
        self.assertIn("Energy at the end, in units of M g a (viscous work, then the integrator's "
                      "own change E − E₀ + W_visc): implicit-euler at 1 ms 0.3 viscous, -0.1 "
                      "numerical; symplectic-euler at 0.2 ms 0.2 viscous, -0.01 numerical.",
                      facts)
        self.assertIn("Largest stable step as the speed of sound grows: symplectic-euler from "
                      "0.0018 s at c = 7 m/s to 0.0009 s at c = 14 m/s, 0.9 to 0.9 times the "
                      "acoustic mode's (ωh)*/ω_max, C = dt (c + |v|max)/h from 0.519 to "
                      "0.554.", facts)
        self.assertIn("Meanwhile the compression at the column's foot at rest, g 2a / c², falls "
                      "from 4 % to 1 %: the Tait law is stiff only in compression, and the "
                      "linearization at rest takes the stiff side everywhere.", facts)
        self.assertTrue((self.s.dir / "out" / "fluid.png").is_file())


def solver_error_data(scratch):
    """A solver-error experiment: implicit Euler's discretization error 1e-3
    m; Newton below it, XPBD above it in solver error but closer to the true
    motion."""
    scratch.json("integrators.json", INTEGRATORS)
    options = ["option_newton_tol", "option_solver", "option_substeps", "option_iterations",
               "option_chebyshev", "option_rtol"]
    cols = ["task", "case", "scene", "integrator", "variant"] + options + [
            "dt", "step", "t", "status", "solver_error", "total_error", "discretization_error",
            "wall_seconds", "iterations", "failure"]
    scratch.json("se.json", {"name": "se", "experiment": "solver-error", "title": "SE",
                             "dt": 0.02,
                             "tables": [{"file": "se.csv", "suffix": "", "columns": cols}]})
    rows = [",".join(cols)]
    # The option columns say what the label says (the report reads them, not the label).
    runs = [("implicit-euler", "newton-tol 0.01", "0.01,,,,,", 1e-5, 1e-3, 0.02),
            ("xpbd", "substeps 10; iterations 1", ",,10,1,,", 3e-3, 1e-4, 0.001)]
    for task, (name, variant, opts, se, te, wall) in enumerate(runs):
        for k in (0, 5):
            rows.append("%d,0,cloth,%s,%s,%s,0.02,%d,%r,completed,%r,%r,0.001,%r,3," % (
                task, name, variant, opts, k, k * 0.02, se, te, wall))
    scratch.write("se.csv", "\n".join(rows) + "\n")
    # The whole runs: XPBD at equal cost S x N = 4, and tight Newton.
    runs_cols = ["task", "case", "scene", "integrator", "variant"] + options + [
                 "dt", "status", "t_final", "energy_initial", "energy_lost", "max_strain",
                 "wall_seconds_per_step", "failure"]
    settings = json.loads((scratch.dir / "se.json").read_text())
    settings["tables"].append({"file": "se-runs.csv", "suffix": "runs", "columns": runs_cols})
    scratch.json("se.json", settings)
    runs = [",".join(runs_cols), "0,0,cloth,implicit-euler,newton-tol 1e-06,1e-06,,,,,,0.02,"
            "completed,1,0,1.5,0.2,0.02,"]
    for task, (S, N, lost, strain) in enumerate(((1, 4, -10.0, 1.2), (2, 2, -2.0, 0.5),
                                                 (4, 1, -0.5, 0.3)), start=1):
        runs.append("%d,0,cloth,xpbd,substeps %d; iterations %d,,,%d,%d,,,0.02,completed,1,0,%r,"
                    "%r,0.001," % (task, S, N, S, N, lost, strain))
    scratch.write("se-runs.csv", "\n".join(runs) + "\n")


class SolverErrorKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_sentences_follow_the_rows(self):
        solver_error_data(self.s)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        facts = [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]
        self.assertIn("Solver error below it (as good as solving the step exactly), cheapest "
                      "first: implicit-euler (newton-tol 0.01) 20 ms (1e-05 m).", facts)
        self.assertIn("Solver error above it: xpbd (substeps 10; iterations 1) 1 ms (0.003 m).",
                      facts)
        self.assertIn("Closer to the true motion than the exact implicit Euler step (less than "
                      "half its error), cheapest first: xpbd (substeps 10; iterations 1) 1 ms "
                      "(0.0001 m).", facts)
        self.assertTrue((self.s.dir / "out" / "se-0.png").is_file())
        self.assertIn("xpbd at equal cost S x N = 4: 1 x 4 reaches a largest strain of 120 % and "
                      "gains 10 J; 4 x 1 reaches 30 % and gains 0.5 J.", facts)
        self.assertIn("Dashed: implicit Euler solved by Newton (newton-tol 1e-06): largest "
                      "strain 20 %, energy lost 1.5 J.", facts)
        self.assertTrue((self.s.dir / "out" / "se-0-small-steps.png").is_file())


def rewrite(scratch, name, keep, extra):
    """The CSV `name` without the lines `keep` rejects, plus the lines `extra`."""
    lines = [x for x in (scratch.dir / name).read_text().splitlines() if keep(x)]
    scratch.write(name, "\n".join(lines + extra) + "\n")


def linked_files(page):
    """The relative links of the page (href and src, not data: or #)."""
    return [h for h in re.findall(r'(?:href|src)="([^"]+)"', page)
            if not h.startswith(("data:", "#", "http:", "https:"))]


class MotionFlags(unittest.TestCase):
    """The sentences under a player: a completed run that gains more than
    E_s is flagged, a run's message is shown as written (escaped once)."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def implicit_euler_energies(self, energies):
        rewrite(self.s, "motion-frames.csv", lambda x: ",implicit-euler," not in x, [
            "0,pair,implicit-euler,0.1,%r,0,%r" % (t, e)
            for t, e in zip((0, 0.1, 0.2), energies)])

    def test_a_completed_run_that_gains_more_than_es_is_flagged(self):
        motion_data(self.s)
        self.implicit_euler_energies((0.0, 5.0, 3.0))  # E(0) = 0, E_s = 2: up to +2.5 E_s
        status, page = render(self.s)
        self.assertEqual(status, 0)
        text = html.unescape(page)
        self.assertIn("implicit-euler ran to t = 0.2 s; energy change at its last good frame 1.5 "
                      "E_s \u2014 but it completed with an energy gain of up to 2.5 E_s (more than "
                      "1 E_s)", text)
        self.assertEqual(page.count('class="player-flag"'), 1)
        self.assertIn("energy gain up to +2.5 E_s: not a physical motion", text)

    def test_a_gain_below_es_is_not_flagged(self):
        motion_data(self.s)
        self.implicit_euler_energies((0.0, 1.8, 1.0))  # up to +0.9 E_s
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertNotIn("player-flag", page.split("<body>")[1])
        self.assertNotIn("but it completed with an energy gain", page)

    def test_a_message_is_escaped_once(self):
        motion_data(self.s)
        message = "this scene's triangle elements need poisson >= 0 & <corotated>"
        rewrite(self.s, "motion-runs.csv", lambda x: ",explicit-euler," not in x,
                ["1,pair,explicit-euler,0.1,failed,0,0,0.001,0,2,%s" % message])
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertIn("explicit-euler failed at t = 0 s: " + message, html.unescape(page))
        for twice in ("&amp;#x27;", "&amp;gt;", "&amp;lt;", "&amp;amp;"):
            self.assertNotIn(twice, page)


class MotionBudget(unittest.TestCase):
    """A case whose positions would exceed the player's budget embeds every
    k-th frame (k as small as fits), the last good one and the frames past
    the blow-up bound, and says so."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_long_runs_are_thinned_and_the_caption_says_so(self):
        n, frames = 300, 220
        motion_data(self.s)
        settings = json.loads((self.s.dir / "motion.json").read_text())
        scene = settings["cases"][0]["scene"]
        scene["particles"] = [{"x": [float(i), 0.0]} for i in range(n)]
        settings["cases"][0]["cells"] = []
        settings["cases"][0]["t_end"] = (frames - 1) * 0.1
        self.s.json("motion.json", settings)
        rows, energy = [], []
        for f in range(frames):
            t = round(0.1 * f, 10)
            rows += ["0,pair,implicit-euler,0.1,%r,0,%d,%r,%r,0" % (t, i, float(i), -t)
                     for i in range(n)]
            energy.append("0,pair,implicit-euler,0.1,%r,0,%r" % (t, -t))
        for f, past in ((0, 0), (1, 0), (2, 0), (3, 1)):
            rows += ["1,pair,explicit-euler,0.1,%r,%d,%d,%r,0,0" % (0.1 * f, past, i,
                                                                  float(i) * (1 + 1e3 * past))
                     for i in range(n)]
        rewrite(self.s, "motion.csv", lambda x: x.startswith("task"), rows)
        rewrite(self.s, "motion-frames.csv", lambda x: x.startswith("task"), energy)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        data = json.loads(re.search(r'class="player-data">(.*?)</script>', page, re.S).group(1))
        # 224 frames of 300 particles as int16 in base64: 537,600 characters.
        chars = (frames + 4) * n * 3 * 2 * 4 / 3
        k = int(np.ceil(chars / motion.PLAYER_BUDGET_CHARS))
        self.assertGreater(k, 1)
        self.assertEqual(data["thinned"], k)
        ie = {p["name"]: p for p in data["panels"]}["implicit-euler"]
        ee = {p["name"]: p for p in data["panels"]}["explicit-euler"]
        good = [round(0.1 * f, 10) for f in range(frames)]
        expect = sorted(set(good[::k]) | {good[-1]})
        self.assertEqual([round(t, 10) for t in ie["t"]], expect)
        self.assertEqual(ee["past"][-1], 1)   # the frame past the bound is kept
        self.assertLessEqual(sum(len(p["x"]) for p in data["panels"]),
                             motion.PLAYER_BUDGET_CHARS)
        self.assertIn("one in %d of those is embedded" % k, page)


class PageWeight(unittest.TestCase):
    """A scene of megabytes in the settings stays out of the page: the page
    shows it shortened and links the files, copied beside it."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_big_settings_are_linked_not_embedded(self):
        energy_data(self.s, {"implicit-euler": ([0, 1, 2], [1.0, 0.9, 0.8])})
        settings = json.loads((self.s.dir / "energy.json").read_text())
        n = 6000
        big = {"name": "big", "dimension": 3, "gravity": [0, -9.81, 0],
               "particles": [{"x": [i * 1e-3, 0.5, 0.25], "mass": 0.01} for i in range(n)],
               "springs": [{"i": i, "j": i + 1, "k": 1000.0} for i in range(n - 1)]}
        settings["cases"] = [{"scene": big, "dt": 0.01}]
        self.s.json("energy.json", settings)
        settings_bytes = (self.s.dir / "energy.json").stat().st_size
        self.assertGreater(settings_bytes, 400_000)
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertLess(len(page.encode("utf-8")), 100_000)
        self.assertIn("6000 particles, 5999 springs", page)
        self.assertIn("\u2026 5997 more", page)
        links = linked_files(page)
        for name in ("data/energy.csv", "data/energy-runs.csv", "data/energy.json"):
            self.assertIn(name, links)
        out = self.s.dir / "out"
        for link in links:
            self.assertTrue((out / link).is_file(), link)
        self.assertEqual((out / "data" / "energy.json").read_bytes(),
                         (self.s.dir / "energy.json").read_bytes())


class MotionCases(unittest.TestCase):
    """Two cases with the same scene name and step (the cloth with and
    without the ground): each player shows its own case's runs."""

    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_each_case_plays_its_own_runs(self):
        motion_data(self.s)
        settings = json.loads((self.s.dir / "motion.json").read_text())
        settings["cases"].append(dict(settings["cases"][0]))
        self.s.json("motion.json", settings)
        rows = (self.s.dir / "motion.csv").read_text().splitlines()
        frames = (self.s.dir / "motion-frames.csv").read_text().splitlines()
        runs = (self.s.dir / "motion-runs.csv").read_text().splitlines()
        # The second case: tasks 2 and 3, implicit Euler falls twice as far.
        for t, y in ((0, 0.0), (0.1, -1.0), (0.2, -2.0)):
            for i, x in ((0, 0.0), (1, 1.0)):
                rows.append("2,pair,implicit-euler,0.1,%r,0,%d,%r,%r,0" % (t, i, x, y if i else 0))
            frames.append("2,pair,implicit-euler,0.1,%r,0,%r" % (t, -4.0 * t))
        rows += ["3,pair,explicit-euler,0.1,0,0,0,0,0,0", "3,pair,explicit-euler,0.1,0,0,1,1,0,0"]
        frames += ["3,pair,explicit-euler,0.1,0,0,0"]
        runs += ["2,pair,implicit-euler,0.1,completed,,2,0.001,0,2,",
                 "3,pair,explicit-euler,0.1,failed,0,0,0.001,0,2,no way"]
        self.s.write("motion.csv", "\n".join(rows) + "\n")
        self.s.write("motion-frames.csv", "\n".join(frames) + "\n")
        self.s.write("motion-runs.csv", "\n".join(runs) + "\n")
        status, page = render(self.s)
        self.assertEqual(status, 0)
        players = [json.loads(m) for m in re.findall(
            r'<script type="application/json" class="player-data">(.*?)</script>', page, re.S)]
        self.assertEqual(len(players), 2)
        ys = []
        for data in players:
            ie = {p["name"]: p for p in data["panels"]}["implicit-euler"]
            x = motion.decode_frames(ie["x"], ie["q"], 2)
            ys.append(round(float(x[2, 1, 1]), 12))
        self.assertEqual(ys, [-1.0, -2.0])
        ee = {p["name"]: p for p in players[1]["panels"]}["explicit-euler"]
        self.assertEqual((ee["status"], ee["failure"]), ("failed", "no way"))


class SpectralTheory(unittest.TestCase):
    """The closed-form amplification matrices the spectral figure draws as
    theory, against the textbook's formulas (Hughes 1987, sec. 9.1;
    Chung and Hulbert 1993)."""

    wh = np.logspace(-2, 3, 51)

    def test_average_acceleration_is_undamped_with_the_trapezoid_period(self):
        rho, xi, period = spectral.theory(spectral.newmark_parameters("newmark"), self.wh)
        np.testing.assert_allclose(rho, 1.0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(xi, 0.0, rtol=0, atol=1e-12)
        # wh / arg - 1 cancels at small w h: round-off of arg, absolute.
        np.testing.assert_allclose(period, self.wh / (2 * np.arctan(self.wh / 2)) - 1,
                                   rtol=1e-9, atol=1e-10)

    def test_generalized_alpha_reaches_its_rho_inf(self):
        for rho_inf in (0.0, 0.5, 1.0):
            params = spectral.generalized_alpha_parameters(rho_inf)
            self.assertEqual(spectral.newmark_parameters("generalized-alpha",
                                                         {"rho_inf": rho_inf}), params)
            rho, _, _ = spectral.theory(params, [1e6])
            self.assertAlmostEqual(float(rho[0]), rho_inf, delta=1e-3, msg=rho_inf)
            # Second order, barely damped where resolved.
            rho, xi, _ = spectral.theory(params, [0.01])
            self.assertLess(abs(float(rho[0]) - 1.0), 1e-5)
        # The default (rho_inf 0.5) and HHT's default alpha = -0.1: (1 + a) / (1 - a).
        rho, _, _ = spectral.theory(spectral.newmark_parameters("generalized-alpha"), [1e6])
        self.assertAlmostEqual(float(rho[0]), 0.5, delta=1e-3)
        rho, _, _ = spectral.theory(spectral.newmark_parameters("hht-alpha"), [1e6])
        self.assertAlmostEqual(float(rho[0]), 0.9 / 1.1, delta=1e-3)

    def test_central_difference_limit_is_two(self):
        params = spectral.newmark_parameters("central-difference")
        self.assertEqual(params, (0.0, 0.0, 0.0, 0.5))
        rho, xi, period = spectral.theory(params, [1.999, 2.001])
        self.assertAlmostEqual(float(rho[0]), 1.0, delta=1e-12)
        self.assertGreater(float(rho[1]), 1.0 + 1e-3)
        # Below the limit: undamped, the period shortened (theta = 2 asin(w h / 2));
        # above it the roots are real: no damping ratio, no period.
        self.assertAlmostEqual(float(xi[0]), 0.0, delta=1e-12)
        self.assertAlmostEqual(float(period[0]), 1.999 / (2 * math.asin(1.999 / 2)) - 1, 12)
        self.assertTrue(math.isnan(xi[1]) and math.isnan(period[1]))
        # Fox-Goodwin's period error is O((w h)^4); outside the family there is no theory.
        _, _, period = spectral.theory(spectral.newmark_parameters("fox-goodwin"), [0.01])
        self.assertLess(abs(float(period[0])), 1e-9)
        self.assertIsNone(spectral.newmark_parameters("rk4"))


def spectral_data(scratch, implicit_euler_power=0.5, newmark_bump=0.0):
    """A spectral experiment on a grid of 5 points per decade: newmark and
    generalized-alpha rho_inf=0 exactly as theory, implicit Euler with
    rho = (1 + (w h)^2)^-power (1/2 is the method's), symplectic Euler with
    the central difference's roots. newmark_bump is added to newmark's
    measured rho at w h = 1."""
    scratch.json("integrators.json", INTEGRATORS)
    cols = ["task", "method", "integrator", "wh", "spectral_radius", "damping_ratio",
            "period_error", "degree"]
    methods = [{"label": "newmark", "integrator": "newmark"},
               {"label": "generalized-alpha rho_inf=0", "integrator": "generalized-alpha",
                "rho_inf": 0.0},
               {"label": "implicit-euler", "integrator": "implicit-euler"},
               {"label": "symplectic-euler", "integrator": "symplectic-euler"}]
    scratch.json("spectral.json", {"name": "spectral", "experiment": "spectral",
                                   "title": "Spectral", "methods": methods, "wh_min": 0.01,
                                   "wh_max": 1000, "points_per_decade": 5,
                                   "tables": [{"file": "spectral.csv", "suffix": "",
                                               "columns": cols}]})
    rows = [",".join(cols)]

    def f(v):
        return repr(float(v)) if math.isfinite(v) else ""

    for task, m in enumerate(methods):
        for k in range(26):
            wh = 0.01 * 10 ** (k / 5)
            if m["integrator"] == "implicit-euler":
                rho = (1 + wh * wh) ** -implicit_euler_power
                xi = -math.log(rho) / math.atan(wh)
                period = wh / math.atan(wh) - 1
            elif m["integrator"] == "symplectic-euler":
                if wh < 2:
                    rho, xi, period = 1.0, 0.0, wh / (2 * math.asin(wh / 2)) - 1
                else:
                    b = abs(2 - wh * wh)
                    rho, xi, period = (b + math.sqrt(b * b - 4)) / 2, math.nan, math.nan
            else:
                params = spectral.newmark_parameters(m["integrator"], m)
                rho, xi, period = (float(a[0]) for a in spectral.theory(params, [wh]))
                if m["integrator"] == "newmark" and k == 10:
                    rho += newmark_bump
            rows.append("%d,%s,%s,%r,%s,%s,%s,2" % (task, m["label"], m["integrator"], wh,
                                                    f(rho), f(xi), f(period)))
    scratch.write("spectral.csv", "\n".join(rows) + "\n")


class SpectralKind(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def facts(self):
        status, page = render(self.s)
        self.assertEqual(status, 0)
        self.assertNotIn("&amp;#", page)  # escaped once, never twice
        return [html.unescape(f) for f in re.findall(r"<li>([^<]*)</li>", page)]

    def test_sentences_follow_the_data(self):
        spectral_data(self.s)
        facts = self.facts()
        self.assertTrue((self.s.dir / "out" / "spectral.png").is_file())
        self.assertIn("Stable at every w h and damping the unresolved modes, ρ at w h = 1000 "
                      "(the smaller, the more of a stiff mode one step removes): implicit-euler "
                      "0.001, generalized-alpha rho_inf=0 0.01.", facts)
        self.assertIn("No numerical damping (ρ within 1e-06 of 1) at every w h up to 1000: "
                      "newmark; up to their last stable w h: symplectic-euler (1.585).", facts)
        self.assertIn("Conditionally stable: the stability limit lies between the last w h "
                      "with ρ ≤ 1 and the first with ρ > 1 on the grid: symplectic-euler "
                      "(1.585, 2.512] (stated 2).", facts)
        theory = [f for f in facts if f.startswith("Measured against the closed-form")]
        self.assertEqual(len(theory), 1)
        self.assertTrue(theory[0].endswith("every one within 1e-06."), theory[0])
        self.assertTrue(any(f.startswith("At w h = 0.1 the relative period error is 0.000833 "
                                         "for newmark (theory (w h)²/12 = 0.000833)")
                            for f in facts), facts)

    def test_changed_data_changes_the_sentences(self):
        # Implicit Euler damps less than generalized-alpha rho_inf=0 at 1000, and
        # newmark's measured rho leaves theory by 1e-3 at w h = 1.
        spectral_data(self.s, implicit_euler_power=0.25, newmark_bump=1e-3)
        facts = self.facts()
        self.assertIn("Stable at every w h and damping the unresolved modes, ρ at w h = 1000 "
                      "(the smaller, the more of a stiff mode one step removes): "
                      "generalized-alpha rho_inf=0 0.01, implicit-euler 0.032.", facts)
        theory = [f for f in facts if f.startswith("Measured against the closed-form")][0]
        self.assertIn("differs by at most 0.001 (newmark at w h = 1;", theory)
        self.assertTrue(theory.endswith("beyond 1e-06: newmark."), theory)
        self.assertNotIn("newmark;", [f for f in facts if f.startswith("No numerical")][0])


class Reading(unittest.TestCase):
    def setUp(self):
        self.s = Scratch()

    def tearDown(self):
        self.s.close()

    def test_header_must_match_the_settings_file(self):
        self.s.write("a.csv", "task,scene,x\n0,s,1\n")
        with self.assertRaisesRegex(DataError, r"a\.csv:1: header is task,scene,x, but the "
                                               r"settings file says task,scene,y"):
            read_table(self.s.dir / "a.csv", ["task", "scene", "y"])

    def test_a_bad_number_names_file_line_and_column(self):
        self.s.write("a.csv", "task,x\n0,1\n1,one\n")
        t = read_table(self.s.dir / "a.csv", ["task", "x"])
        self.assertEqual(t.text("x"), ["1", "one"])  # text is fine
        with self.assertRaisesRegex(DataError, r"a\.csv:3: column 'x': 'one' is not a number"):
            t.num("x")

    def test_missing_column_is_named(self):
        self.s.write("a.csv", "task,x\n0,1\n")
        with self.assertRaisesRegex(DataError, r"missing column 'status'"):
            read_table(self.s.dir / "a.csv").require("status")


class StabilityGroups(unittest.TestCase):
    """Methods whose measured limits agree within SAME_LIMIT at every point
    share one marker; the never-diverging ones are listed once."""

    def setUp(self):
        self.s = Scratch()
        self.s.json("integrators.json", INTEGRATORS)
        self.integrators = Integrators.load(self.s.dir / "integrators.json")

    def tearDown(self):
        self.s.close()

    def table(self, explicit_factor):
        cols = "scene,integrator,k,w_max,t_end,max_stable_dt,bracket_lo,bracket_hi,theory_dt,ratio"
        rows = [cols]
        for scene in ("oscillator", "chain"):
            for k in (1.0, 100.0):
                w = math.sqrt(k)
                m = 2 / w
                rows.append("%s,symplectic-euler,%r,%r,1,%r,%r,%r,%r,1" % (scene, k, w, m, m,
                                                                           m * 1.001, m))
                e = m * explicit_factor
                rows.append("%s,explicit-euler,%r,%r,1,%r,%r,%r,,"
                            % (scene, k, w, e, e, e * 1.001))
                rows.append("%s,implicit-euler,%r,%r,1,10,10,10,," % (scene, k, w))
        self.s.write("stability.csv", "\n".join(rows) + "\n")
        return stability.limits_table(FakeExp(read_table(self.s.dir / "stability.csv")))

    def test_groups_follow_the_numbers(self):
        for factor, expected in ((1.01, [["explicit-euler", "symplectic-euler"]]),
                                 (1.05, [["explicit-euler"], ["symplectic-euler"]])):
            st = self.table(factor)
            nolimit = stability.no_limit_rows(st, 10.0)
            self.assertEqual(stability.limit_series(st, nolimit, self.integrators), expected)
            self.assertEqual(int(nolimit.sum()), 4)  # implicit-euler, 2 scenes x 2 k

    def test_free_methods_named_once_or_per_panel(self):
        same = stability.free_text({"oscillator": ["implicit-euler"],
                                    "chain": ["implicit-euler"], "cloth": []}, 10.0)
        self.assertEqual(same.replace("\n", " "), "No divergence up to dt_max = 10 s on "
                                                   "oscillator and chain: implicit-euler.")
        apart = stability.free_text({"oscillator": ["implicit-euler", "bdf2"],
                                     "chain": ["implicit-euler"]}, None)
        self.assertIn("Also on oscillator: bdf2.", apart)
        self.assertEqual(stability.free_text({"a": [], "b": []}, 1.0), "")


class FakeExp:
    def __init__(self, table):
        self._table = table

    def table(self, suffix=""):
        return self._table


class RigidStrainWindows(unittest.TestCase):
    """The strain panel draws each window's maximum: a ramp's maximum is its
    value at the window's right end, and an empty window is left out."""

    def test_window_max_of_a_ramp(self):
        from springlab_report.kinds.rigid import window_max
        t = np.linspace(0.0, 4.0, 401)
        centres, top = window_max(t, 2 * t, 4)
        np.testing.assert_allclose(centres, [0.5, 1.5, 2.5, 3.5])
        # windows [0,1), [1,2), [2,3), [3,4]: the last sample before each edge
        np.testing.assert_allclose(top, [1.98, 3.98, 5.98, 8.0])
        gap = np.array([0.0, 0.1, 3.9, 4.0])
        centres, top = window_max(gap, gap, 4)
        np.testing.assert_allclose(centres, [0.5, 3.5])


class RunOptions(unittest.TestCase):
    """A method listed twice in the settings is told apart by its run's options."""

    def test_options_follow_the_runs(self):
        from springlab_report.page import run_options
        names = ["linear-implicit-euler", "linear-implicit-euler", "implicit-euler"]
        runs = [{"integrator": "linear-implicit-euler", "stiffness": "exact"},
                {"integrator": "linear-implicit-euler", "stiffness": "definite"},
                {"integrator": "implicit-euler"}]
        self.assertEqual(run_options(names, runs),
                         [" (stiffness exact)", " (stiffness definite)", ""])
        # Runs that do not line up with the names: no labels rather than wrong ones.
        self.assertEqual(run_options(names, runs[:2]), ["", "", ""])
        self.assertEqual(run_options(names, None), ["", "", ""])


class Styles(unittest.TestCase):
    def test_colours_and_markers_come_from_the_integrator_table(self):
        s = Scratch()
        try:
            s.json("integrators.json", INTEGRATORS)
            integ = Integrators.load(s.dir / "integrators.json")
            self.assertEqual(integ.colour("implicit-euler"), "#9467bd")
            self.assertEqual(integ.marker("symplectic-euler"), "^")
            self.assertEqual(integ.family("explicit-euler"), "explicit")
            # A method the table does not list: the same fallback every time.
            self.assertEqual(integ.colour("new-method"), integ.colour("new-method"))
            self.assertEqual(integ.sort(["implicit-euler", "explicit-euler",
                                         "symplectic-euler"]),
                             ["explicit-euler", "symplectic-euler", "implicit-euler"])
        finally:
            s.close()


class VariantStyles(unittest.TestCase):
    """Runs of one integrator side by side (step-energy's two linear-implicit
    variants) never share a colour or a marker."""

    def test_every_run_looks_different(self):
        s = Scratch()
        try:
            s.json("integrators.json", INTEGRATORS)
            integ = Integrators.load(s.dir / "integrators.json")
            runs = [("implicit-euler", "exact"), ("implicit-euler", "definite"),
                    ("implicit-euler", "third"), ("explicit-euler", "")]
            styles = integ.variant_styles(runs)
            self.assertEqual(styles[runs[0]]["color"], "#9467bd")  # the first keeps its own
            self.assertEqual(len({st["color"] for st in styles.values()}), len(runs))
            self.assertEqual(len({st["marker"] for st in styles.values()}), len(runs))
        finally:
            s.close()


class Labels(unittest.TestCase):
    """label_points on a crowded cluster: the labels it draws overlap neither
    each other nor the markers, stay inside the axes, and some are left out."""

    def test_crowded_labels_do_not_overlap(self):
        import matplotlib.pyplot as plt
        from springlab_report.figures import label_points
        rng = np.random.default_rng(3)
        x = 10 ** rng.uniform(1, 1.3, 40)
        y = 10 ** rng.uniform(-3, -2.7, 40)
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.plot(x, y, "o")
        ax.set_xscale("log")
        ax.set_yscale("log")
        drawn = label_points(ax, [(a, b, "S=%d; N=%d" % (k, 40 - k), "k")
                                  for k, (a, b) in enumerate(zip(x, y))],
                             avoid=list(zip(x, y)))
        fig.draw_without_rendering()
        renderer = fig.canvas.get_renderer()
        boxes = [t.get_window_extent(renderer) for t in ax.texts]
        self.assertEqual(len(boxes), drawn)
        self.assertGreater(drawn, 0)
        self.assertLess(drawn, 40)
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                self.assertFalse(boxes[i].overlaps(boxes[j]), (i, j))
        frame = ax.get_window_extent(renderer)
        for b in boxes:
            self.assertTrue(frame.x0 <= b.x0 and b.x1 <= frame.x1 and frame.y0 <= b.y0
                            and b.y1 <= frame.y1)
        plt.close(fig)


class Convergence(unittest.TestCase):
    def test_coinciding_lines_are_grouped(self):
        x = np.array([1e-3, 2e-3, 4e-3])
        drawn = {"a": (x, 2 * x), "b": (x, 2.05 * x), "c": (x, 4 * x)}
        self.assertEqual(_coinciding(drawn), [["a", "b"]])


class Registry(unittest.TestCase):
    def test_every_kind_module_has_what_the_page_needs(self):
        self.assertIn("stability-region", KINDS)
        for kind, module in KINDS.items():
            self.assertEqual(module.KIND, kind)
            self.assertTrue(module.TITLE and module.ABOUT)
            self.assertTrue(callable(module.render))
        # Every kind the program has is one this report draws.
        kinds = set()
        for source in (Path(__file__).resolve().parents[2] / "experiments" / "kinds").glob(
                "*_experiment.cc"):
            kinds.update(re.findall(r'ExperimentKind kind\{"([a-z-]+)", &make_',
                                    source.read_text()))
        self.assertEqual(kinds, set(KINDS))


if __name__ == "__main__":
    unittest.main()
