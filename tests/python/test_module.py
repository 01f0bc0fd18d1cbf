"""The Python module `springlab` against the command line it wraps.

Runs give the same numbers as `springlab run` (digit for digit: one
library), bad input raises springlab.Error with the line the command line
prints after "springlab: error: ", and experiments write the same tables.
Run by ctest with SPRINGLAB (the executable) set and the module on PYTHONPATH.
"""
import csv
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest
import warnings

import numpy as np

import springlab

SPRINGLAB = os.environ["SPRINGLAB"]
TEST_DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")


def cli(*args):
    return subprocess.run([SPRINGLAB, *args], capture_output=True, text=True)


def cli_error(*args):
    r = cli(*args)
    assert r.returncode == 1, r
    line = r.stderr.strip()
    assert line.startswith("springlab: error: "), line
    return line[len("springlab: error: "):]


class Runs(unittest.TestCase):
    def test_run_equals_the_command_line_digit_for_digit(self):
        scene = springlab.load_scene("cloth", n=6)
        run = springlab.run(scene, "implicit-euler", dt=0.02, t_end=0.3, newton_tol=1e-6)
        with tempfile.TemporaryDirectory() as tmp:
            energy = os.path.join(tmp, "e.csv")
            r = cli("run", "cloth", "-p", "n=6", "--integrator", "implicit-euler", "--dt", "0.02",
                    "--t-end", "0.3", "--newton-tol", "1e-6", "--energy", energy, "--json")
            summary = json.loads(r.stdout)
            with open(energy) as f:
                rows = list(csv.DictReader(f))
        np.testing.assert_array_equal(run["x"][-1], np.array(summary["final_state"]["x"]))
        np.testing.assert_array_equal(run["v"][-1], np.array(summary["final_state"]["v"]))
        np.testing.assert_array_equal(run["t"], [float(row["t"]) for row in rows])
        self.assertEqual(list(run["energies"]), summary["energy_columns"])
        for column in summary["energy_columns"]:
            np.testing.assert_array_equal(run["energies"][column], [float(row[column]) for row in rows])
        for key in ("steps", "force_evals", "jacobian_evals", "linear_solves", "newton_iterations",
                    "factorizations", "rejected_steps"):
            self.assertEqual(run["stats"][key], summary[key], key)
        self.assertEqual(run["status"], "completed")
        self.assertEqual(run["x"].shape, (16, 36, 3))

    def test_scene_sources_agree(self):
        builtin = springlab.load_scene("chain", n=5)
        from_dict = springlab.load_scene(builtin.to_dict())
        with tempfile.NamedTemporaryFile("w", suffix=".json") as f:
            json.dump(builtin.to_dict(), f)
            f.flush()
            from_file = springlab.load_scene(f.name)
        runs = [springlab.run(s, "verlet", dt=0.01, t_end=0.5) for s in (builtin, from_dict, from_file)]
        for other in runs[1:]:
            np.testing.assert_array_equal(runs[0]["x"], other["x"])
        self.assertEqual(builtin.cells(), [(i, i + 1) for i in range(4)])

    def test_every_keeps_every_kth_state_and_the_last(self):
        scene = springlab.load_scene("oscillator")
        run = springlab.run(scene, "rk4", dt=0.1, t_end=1.05, every=4)
        np.testing.assert_allclose(run["t"], [0, 0.4, 0.8, 1.05])

    def test_divergence_is_a_result(self):
        run = springlab.run(springlab.load_scene("cloth", n=6), "explicit-euler", dt=0.05, t_end=5)
        self.assertTrue(run["diverged"])
        self.assertEqual(run["t"][-1], run["t_final"])
        self.assertLess(run["t_final"], 5)

    def test_an_option_the_method_does_not_read_is_a_warning(self):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            springlab.run(springlab.load_scene("oscillator"), "rk4", dt=0.1, t_end=0.2, rtol=1e-3)
        self.assertEqual([str(w.message) for w in caught], ["rk4 does not use --rtol (ignored)"])

    def test_lists_match_the_command_line(self):
        listed = json.loads(cli("list", "--json").stdout)
        self.assertEqual(springlab.integrators(), listed["integrators"])
        self.assertEqual(springlab.scenes(), listed["scenes"])


class Errors(unittest.TestCase):
    def assert_same_error(self, call, *cli_args):
        expected = cli_error(*cli_args)
        with self.assertRaises(springlab.Error) as caught:
            call()
        self.assertEqual(str(caught.exception), expected)

    def test_option_errors(self):
        scene = springlab.load_scene("oscillator")
        base = ["run", "oscillator", "--integrator"]
        self.assert_same_error(lambda: springlab.run(scene, "rk4", dt=-1, t_end=1),
                               *base, "rk4", "--dt", "-1", "--t-end", "1")
        self.assert_same_error(lambda: springlab.run(scene, "rk5", dt=0.1, t_end=1),
                               *base, "rk5", "--dt", "0.1", "--t-end", "1")
        self.assert_same_error(lambda: springlab.run(scene, "rk4", dt=0.1, t_end=1, bogus=1),
                               *base, "rk4", "--dt", "0.1", "--t-end", "1", "--bogus", "1")
        self.assert_same_error(lambda: springlab.run(scene, "ida", dt=0.1, t_end=1, max_order=6),
                               *base, "ida", "--dt", "0.1", "--t-end", "1", "--max-order", "6")
        self.assert_same_error(lambda: springlab.run(scene, "implicit-euler", dt=0.1, t_end=1, newton_tol="x"),
                               *base, "implicit-euler", "--dt", "0.1", "--t-end", "1", "--newton-tol", "x")
        # issue 46: NaN was the default in disguise; a value out of range is
        # printed as given, not rounded into the range.
        self.assert_same_error(lambda: springlab.run(scene, "newmark", dt=0.1, t_end=1, beta=float("nan")),
                               *base, "newmark", "--dt", "0.1", "--t-end", "1", "--beta", "nan")
        self.assert_same_error(lambda: springlab.run(scene, "newmark", dt=0.1, t_end=1, beta=0.5000001),
                               *base, "newmark", "--dt", "0.1", "--t-end", "1", "--beta", "0.5000001")

    def test_a_refused_pairing_raises_instead_of_a_failed_result(self):
        # issue 38.6: xpbd has no form for the block's neo-Hookean material;
        # it used to return status "failed" at t = 0.
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "block.json")
            with open(path, "w") as f:
                f.write(cli("scene", "block", "-p", "n=2").stdout)
            scene = springlab.load_scene(path)
            self.assert_same_error(lambda: springlab.run(scene, "xpbd", dt=0.01, t_end=0.05),
                                   "run", path, "--integrator", "xpbd", "--dt", "0.01", "--t-end", "0.05")
        with self.assertRaises(springlab.Error) as caught:
            springlab.run(springlab.load_scene("cloth", n=4, ground=0.5, contact=1),
                          "projective-dynamics", dt=0.01, t_end=0.05)
        self.assertIn("--integrator projective-dynamics: this scene's contact is the barrier",
                      str(caught.exception))

    def test_counts_over_the_cap(self):
        scene = springlab.load_scene("oscillator")
        base = ["run", "oscillator", "--integrator"]
        self.assert_same_error(lambda: springlab.run(scene, "xpbd", dt=0.1, t_end=1, substeps=2147483647),
                               *base, "xpbd", "--dt", "0.1", "--t-end", "1", "--substeps", "2147483647")
        self.assert_same_error(lambda: springlab.run(scene, "xpbd", dt=0.1, t_end=1, iterations=100001),
                               *base, "xpbd", "--dt", "0.1", "--t-end", "1", "--iterations", "100001")

    def test_scene_errors(self):
        self.assert_same_error(lambda: springlab.load_scene("cloth", n=1), "run", "cloth", "-p", "n=1",
                               "--integrator", "rk4", "--dt", "0.1", "--t-end", "1")
        self.assert_same_error(lambda: springlab.load_scene("no-such-scene"), "run", "no-such-scene",
                               "--integrator", "rk4", "--dt", "0.1", "--t-end", "1")
        bad = os.path.join(TEST_DATA, "..", "malformed", "scenes")
        case = sorted(f for f in os.listdir(bad) if f.endswith(".json"))[0]
        path = os.path.join(bad, case)
        self.assert_same_error(lambda: springlab.load_scene(path), "run", path,
                               "--integrator", "rk4", "--dt", "0.1", "--t-end", "1")


class Bodies(unittest.TestCase):
    def test_a_bodies_only_run_keeps_each_bodys_state(self):
        # issue 46.10: nothing of the body was in the result; `run --json` has
        # "bodies" (the last state), which the result now holds digit for
        # digit, with p and A at every kept time.
        scene = springlab.load_scene("tumbling-box")
        run = springlab.run(scene, "rk4", dt=0.01, t_end=0.1)
        frames = len(run["t"])
        self.assertEqual(run["body_p"].shape, (frames, 1, 3))
        self.assertEqual(run["body_A"].shape, (frames, 1, 3, 3))
        ours = json.loads(json.dumps(run["bodies"]))
        theirs = json.loads(cli("run", "tumbling-box", "--integrator", "rk4", "--dt", "0.01",
                                "--t-end", "0.1", "--json").stdout)["bodies"]
        self.assertEqual(ours, theirs)
        np.testing.assert_array_equal(run["body_p"][-1, 0], theirs[0]["p"])
        np.testing.assert_array_equal(run["body_A"][-1, 0], theirs[0]["A"])

    def test_a_bodies_only_run_is_capped_like_any_other(self):
        # It kept every frame uncapped (MemoryError at dt 1e-6 for 30 s).
        scene = springlab.load_scene("tumbling-box")
        with self.assertRaises(springlab.Error) as caught:
            springlab.run(scene, "symplectic-euler", dt=1e-6, t_end=30)
        self.assertTrue(str(caught.exception).startswith(
            "every: the run would keep 30000002 states of 0 particles and 1 body, over the cap of "
            "10000000 rows"), str(caught.exception))


class Experiments(unittest.TestCase):
    def test_jobs_below_one_are_refused(self):
        definition = os.path.join(TEST_DATA, "experiments", "energy.json")
        with tempfile.TemporaryDirectory() as tmp:
            for jobs in (0, -5):
                with self.assertRaises(springlab.Error) as caught:
                    springlab.experiment(definition, tmp, jobs=jobs)
                self.assertEqual(str(caught.exception), "jobs: must be at least 1 (got %d)" % jobs)
            self.assertEqual(os.listdir(tmp), [])


    def test_experiment_writes_the_tables_the_command_line_writes(self):
        definition = os.path.join(TEST_DATA, "experiments", "energy.json")
        with tempfile.TemporaryDirectory() as tmp:
            ours, theirs = os.path.join(tmp, "py"), os.path.join(tmp, "cli")
            summary = springlab.experiment(definition, ours)
            self.assertEqual(summary["tasks_done"], summary["tasks_total"])
            self.assertEqual(cli("experiment", definition, "--out", theirs, "--jobs", "1").returncode, 0)
            tables = sorted(f for f in os.listdir(theirs) if f.endswith(".csv"))
            self.assertTrue(tables)
            self.assertEqual(sorted(f for f in os.listdir(ours) if f.endswith(".csv")), tables)
            def read(path):  # every column but the wall-clock times
                with open(path) as f:
                    rows = list(csv.DictReader(f))
                return [{k: v for k, v in row.items() if "wall" not in k} for row in rows]
            for table in tables:
                self.assertEqual(read(os.path.join(ours, table)), read(os.path.join(theirs, table)), table)
            with open(definition) as f:
                as_dict = json.load(f)
            from_dict = springlab.experiment(as_dict, os.path.join(tmp, "dict"))
            self.assertEqual(from_dict["tasks_done"], summary["tasks_done"])


class Interrupt(unittest.TestCase):
    def test_ctrl_c_stops_a_run_with_keyboard_interrupt(self):
        # A run of minutes (cloth 24 at 1 ms for 30 s: about 90 s and more on
        # a shared machine); SIGINT once it is under way must end it within
        # seconds with KeyboardInterrupt, as a notebook's "interrupt kernel".
        script = (
            "import sys, time, springlab\n"
            "scene = springlab.load_scene('cloth', n=24)\n"
            "print('started', flush=True)\n"
            "start = time.monotonic()\n"
            "try:\n"
            "    springlab.run(scene, 'implicit-euler', dt=0.001, t_end=30, every=100)\n"
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
        self.assertEqual(process.returncode, 0, err)
        self.assertLess(waited, 10.0)


    def test_ctrl_c_stops_an_experiment_with_keyboard_interrupt(self):
        # issue 46.9: an experiment ran on to its end (22 s in the probe).
        # One task of minutes; SIGINT once it is under way ends it within
        # seconds, its tables written and marked incomplete.
        script = (
            "import json, os, sys, time, springlab\n"
            "out = sys.argv[1]\n"
            "definition = {'experiment': 'energy', 'name': 'long', 'integrators': ['implicit-euler'],\n"
            "              'cases': [{'scene': 'cloth', 'parameters': {'n': 24}, 'dt': 0.001,\n"
            "                         't_end': 30}]}\n"
            "print('started', flush=True)\n"
            "try:\n"
            "    springlab.experiment(definition, out)\n"
            "    print('completed')\n"
            "except KeyboardInterrupt:\n"
            "    with open(os.path.join(out, 'long.json')) as f:\n"
            "        print('interrupted', json.load(f)['complete'], flush=True)\n")
        with tempfile.TemporaryDirectory() as tmp:
            process = subprocess.Popen([sys.executable, "-c", script, tmp], stdout=subprocess.PIPE,
                                       stderr=subprocess.PIPE, text=True)
            try:
                self.assertEqual(process.stdout.readline().strip(), "started")
                time.sleep(1.5)
                sent = time.monotonic()
                process.send_signal(signal.SIGINT)
                out, err = process.communicate(timeout=60)
                waited = time.monotonic() - sent
            finally:
                if process.poll() is None:
                    process.kill()
                    process.wait()
        self.assertEqual(out.strip(), "interrupted False", (out, err))
        self.assertEqual(process.returncode, 0, err)
        self.assertLess(waited, 10.0)


if __name__ == "__main__":
    unittest.main()
