"""Methods written in Python (springlab.Integrator) and springlab.check.

A Python symplectic Euler steps the built-in's trajectory (to round-off) and
reports the same statistics; the model hands over the mass, the force and
the Jacobians (SciPy CSC, the library's arrays); exceptions, StepFailed and
Ctrl-C behave as documented (docs/your-own-integrator.md); experiments take
Python methods beside built-ins; check passes the tutorial's methods and
fails seeded mistakes written in Python, naming the claim.
Run by ctest with SPRINGLAB set and the module on PYTHONPATH.
"""
import csv
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
import unittest
import warnings

import numpy as np
import scipy.sparse as sp

import springlab

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples")
sys.path.insert(0, EXAMPLES)
from my_methods import MyBackwardEuler, MyEuler  # noqa: E402


class WrongHalfKickVerlet(springlab.Integrator):
    """velocity Verlet, its closing half-kick at the old position (a seeded mistake)"""
    order = 2
    symplectic = True
    stability_limit = 2.0

    def step(self, model, t, x, v, h):
        a = model.force(t, x, v) / model.mass()
        v = v + 0.5 * h * a
        x = x + h * v
        return x, v + 0.5 * h * a  # should be a(x_{n+1})


class NoisyEuler(springlab.Integrator):
    """symplectic Euler plus a random nudge: not deterministic (a seeded mistake)"""
    order = 1

    def step(self, model, t, x, v, h):
        v = v + h * model.force(t, x, v) / model.mass()
        return x + h * v + 1e-12 * random.random(), v


class Probe(springlab.Integrator):
    """records what a step is given"""
    seen = {}

    def step(self, model, t, x, v, h):
        if not Probe.seen:
            K, D = model.jacobians(t, x, v)
            Probe.seen = dict(x_shape=x.shape, mass_shape=model.mass().shape,
                              force=model.force(t, x, v), K=K, D=D,
                              stiffness=model.stiffness(t, x, v),
                              energies=model.energies(t, x, v), dofs=model.dofs,
                              potential=model.potential(t, x), shape=model.shape)
        return MyEuler().step(model, t, x, v, h)


class Raises(springlab.Integrator):
    def step(self, model, t, x, v, h):
        raise ValueError("a bug in my step")


class Fails(springlab.Integrator):
    def step(self, model, t, x, v, h):
        if t > 0.05:
            raise springlab.StepFailed("Newton did not converge: try a smaller dt")
        return x, v


class Runs(unittest.TestCase):
    def test_python_symplectic_euler_is_the_builtin_to_round_off(self):
        # The built-in multiplies by 1/m where the Python divides by m: the
        # same method, rounded differently in the last bit.
        for scene in (springlab.load_scene("spring"), springlab.load_scene("cloth", n=6),
                      springlab.load_scene("chain", n=5, horizontal=1)):
            mine = springlab.run(scene, MyEuler(), dt=1e-3, t_end=0.2)
            theirs = springlab.run(scene, "symplectic-euler", dt=1e-3, t_end=0.2)
            self.assertEqual(mine["integrator"], "my-euler")
            self.assertEqual(mine["status"], "completed")
            np.testing.assert_allclose(mine["x"], theirs["x"], rtol=0, atol=1e-12)
            np.testing.assert_allclose(mine["v"], theirs["v"], rtol=0, atol=1e-10)
            self.assertEqual(mine["stats"]["force_evals"], theirs["stats"]["force_evals"])
            self.assertEqual(mine["stats"]["steps"], 200)
            self.assertEqual(set(mine), set(theirs))

    def test_backward_euler_matches_the_builtin_to_newton_tolerance(self):
        cloth = springlab.load_scene("cloth", n=6)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # an implicit method reads --newton-tol: no note
            mine = springlab.run(cloth, MyBackwardEuler(), dt=0.02, t_end=0.4, newton_tol=1e-10)
        theirs = springlab.run(cloth, "implicit-euler", dt=0.02, t_end=0.4, newton_tol=1e-10)
        self.assertEqual(mine["status"], "completed")
        self.assertLess(abs(mine["x"] - theirs["x"]).max(), 1e-7)
        self.assertGreater(mine["stats"]["newton_iterations"], 20)
        self.assertEqual(mine["stats"]["jacobian_evals"], mine["stats"]["newton_iterations"])

    def test_the_model_a_step_sees(self):
        Probe.seen = {}
        cloth = springlab.load_scene("cloth", n=5)
        springlab.run(cloth, Probe(), dt=1e-3, t_end=1e-3)
        s = Probe.seen
        self.assertEqual(s["x_shape"], (23, 3))  # 25 particles, two corners fixed
        self.assertEqual(s["shape"], (23, 3))
        self.assertEqual(s["mass_shape"], (23, 3))
        self.assertEqual(s["dofs"], 69)
        self.assertEqual(s["force"].shape, (23, 3))
        for m in (s["K"], s["D"], s["stiffness"]):
            self.assertTrue(sp.isspmatrix_csc(m))
            self.assertEqual(m.shape, (69, 69))
        # dF/dx of springs is symmetric; the separate call gives the same values.
        self.assertLess(abs(s["K"] - s["K"].T).max(), 1e-9 * abs(s["K"]).max())
        self.assertEqual(abs(s["K"] - s["stiffness"]).max(), 0.0)
        self.assertAlmostEqual(s["energies"]["total"],
                               s["energies"]["kinetic"] + s["potential"], places=9)

    def test_an_exception_in_step_is_raised_with_its_type(self):
        with self.assertRaises(ValueError) as e:
            springlab.run(springlab.load_scene("spring"), Raises(), dt=0.01, t_end=1)
        self.assertIn("a bug in my step", str(e.exception))

    def test_step_failed_is_a_result(self):
        r = springlab.run(springlab.load_scene("spring"), Fails(), dt=0.01, t_end=1)
        self.assertEqual(r["status"], "failed")
        self.assertIn("Newton did not converge: try a smaller dt", r["failure"])
        self.assertAlmostEqual(r["diverged_at"], 0.07)

    def test_a_class_defined_again_replaces_the_old(self):
        class Redefined(springlab.Integrator):
            name = "redefined"
            def step(self, model, t, x, v, h):
                return x, v
        springlab.run(springlab.load_scene("spring"), Redefined(), dt=0.1, t_end=0.1)

        class Redefined(springlab.Integrator):  # noqa: F811 - a notebook cell run again
            name = "redefined"
            def step(self, model, t, x, v, h):
                return x + 1.0, v
        r = springlab.run(springlab.load_scene("spring"), Redefined(), dt=0.1, t_end=0.1)
        self.assertEqual(r["stats"]["steps"], 1)
        self.assertGreater(abs(r["x"][-1] - r["x"][0]).max(), 0.5)

    def test_a_builtin_name_is_refused(self):
        class Clash(springlab.Integrator):
            name = "verlet"
            def step(self, model, t, x, v, h):
                return x, v
        with self.assertRaises(springlab.Error) as e:
            springlab.run(springlab.load_scene("spring"), Clash(), dt=0.1, t_end=1)
        self.assertIn("'verlet' is already the name of a built-in", str(e.exception))
        with self.assertRaises(TypeError):
            springlab.run(springlab.load_scene("spring"), object(), dt=0.1, t_end=1)

    def test_ctrl_c_stops_a_python_method(self):
        script = (
            "import sys, time, springlab\n"
            "class Slow(springlab.Integrator):\n"
            "    def step(self, model, t, x, v, h):\n"
            "        time.sleep(0.01)\n"
            "        return x, v\n"
            "print('started', flush=True)\n"
            "start = time.monotonic()\n"
            "try:\n"
            "    springlab.run(springlab.load_scene('spring'), Slow(), dt=0.01, t_end=1000)\n"
            "    print('completed')\n"
            "except KeyboardInterrupt:\n"
            "    print('interrupted %.3f' % (time.monotonic() - start), flush=True)\n")
        process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True)
        try:
            self.assertEqual(process.stdout.readline().strip(), "started")
            time.sleep(1.0)
            sent = time.monotonic()
            process.send_signal(signal.SIGINT)
            out, err = process.communicate(timeout=60)
            waited = time.monotonic() - sent
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
        self.assertTrue(out.startswith("interrupted"), (out, err))
        self.assertLess(waited, 10.0)


class Experiments(unittest.TestCase):
    def test_python_methods_beside_builtins(self):
        with tempfile.TemporaryDirectory() as out:
            springlab.experiment({"experiment": "energy", "name": "energy",
                                  "cases": [{"scene": "oscillator", "dt": 0.05, "t_end": 2}]},
                                 out=out, integrators=[MyEuler(), "symplectic-euler"])
            with open(os.path.join(out, "energy.csv")) as f:
                rows = list(csv.DictReader(f))
            by = {}
            for r in rows:
                by.setdefault(r["integrator"], []).append(r["total"])
            self.assertEqual(set(by), {"my-euler", "symplectic-euler"})
            np.testing.assert_allclose(np.array(by["my-euler"], float),
                                       np.array(by["symplectic-euler"], float), rtol=1e-12)
            # The class's facts, for the report (it draws my-euler among the symplectic).
            with open(os.path.join(out, "energy.json")) as f:
                own = json.load(f)["own_integrators"]
            self.assertEqual([(e["name"], e["family"], e["order"], e["stability"]["limit_wh"])
                              for e in own], [("my-euler", "symplectic", 1, 2.0)])

    def test_a_definition_names_python_files(self):
        with tempfile.TemporaryDirectory() as folder:
            with open(os.path.join(folder, "methods.py"), "w") as f:
                f.write("import springlab\n"
                        "class FileEuler(springlab.Integrator):\n"
                        "    def step(self, model, t, x, v, h):\n"
                        "        v = v + h * model.force(t, x, v) / model.mass()\n"
                        "        return x + h * v, v\n")
            definition = os.path.join(folder, "d.json")
            with open(definition, "w") as f:
                f.write('{"experiment": "energy", "name": "e", "python": ["methods.py"],'
                        ' "integrators": ["file-euler"],'
                        ' "cases": [{"scene": "oscillator", "dt": 0.05, "t_end": 1}]}')
            springlab.experiment(definition, out=os.path.join(folder, "out"))
            with open(os.path.join(folder, "out", "e.csv")) as f:
                rows = list(csv.DictReader(f))
            self.assertEqual({r["integrator"] for r in rows}, {"file-euler"})
            # The command line cannot run Python: one line naming the key.
            r = subprocess.run([os.environ["SPRINGLAB"], "experiment", definition, "--out",
                                os.path.join(folder, "cli")], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1)
            self.assertIn("python: methods written in Python run from Python", r.stderr)


class Check(unittest.TestCase):
    def test_the_tutorial_methods_pass(self):
        # One check each (MyEuler's --symplectic steps 1e4 periods in Python: ~5 s).
        report = springlab.check(MyBackwardEuler())
        self.assertTrue(report["passed"], report["text"])
        self.assertEqual([c["claim"] for c in report["claims"]],
                         ["--order 1", "--a-stable", "--deterministic"])
        self.assertEqual(report["sanity"]["builtin"], "implicit-euler")
        report = springlab.check(MyEuler())
        self.assertTrue(report["passed"], report["text"])
        self.assertEqual([c["claim"] for c in report["claims"]],
                         ["--order 1", "--stable-limit 2", "--symplectic", "--deterministic"])
        self.assertEqual(report["sanity"]["builtin"], "symplectic-euler")
        self.assertLess(report["sanity"]["max_difference"], 1e-12)
        self.assertIn("springlab.run(springlab.load_scene(\"oscillator\", k=1, mass=1, amplitude=1), "
                      "MyEuler(), dt=", report["text"])

    def test_seeded_mistakes_fail_naming_the_claim(self):
        report = springlab.check(WrongHalfKickVerlet())
        self.assertFalse(report["passed"])
        failed = {c["claim"] for c in report["claims"] if not c["passed"]}
        self.assertIn("--order 2", failed, report["text"])
        report = springlab.check(NoisyEuler(), deterministic=True)
        self.assertEqual([(c["claim"], c["passed"]) for c in report["claims"]],
                         [("--deterministic", False)], report["text"])

    def test_a_builtin_by_name(self):
        report = springlab.check("verlet", order=2, momentum=True)
        self.assertTrue(report["passed"], report["text"])


if __name__ == "__main__":
    unittest.main()
