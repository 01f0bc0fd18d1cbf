"""`springlab run ... --vtk DIR` read back with VTK's own XML reader.

Each frame must hold the run's state exactly (positions and velocities
against the --trajectory CSV of the same run, digit for digit), its time,
and the scene's elements as cells (springs as lines, triangles, tetrahedra;
a particle no element joins as a vertex). Run by ctest with the environment
variable SPRINGLAB naming the executable.
"""
import csv
import json
import os
import subprocess
import tempfile
import unittest
import xml.etree.ElementTree as ET

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

SPRINGLAB = os.environ["SPRINGLAB"]
VTK_LINE, VTK_TRIANGLE, VTK_TETRA, VTK_VERTEX = 3, 5, 10, 1


def springlab(*args, check=True):
    return subprocess.run([SPRINGLAB, *args], capture_output=True, text=True, check=check)


def read_frame(path):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        raise AssertionError(f"{path}: VTK could not read it")
    return reader.GetOutput()


def cells_of(grid):
    """[(vtk type, (node, ...)), ...] in cell order."""
    out = []
    for c in range(grid.GetNumberOfCells()):
        cell = grid.GetCell(c)
        ids = cell.GetPointIds()
        out.append((grid.GetCellType(c), tuple(ids.GetId(k) for k in range(ids.GetNumberOfIds()))))
    return out


class VtkOutput(unittest.TestCase):
    def run_scene(self, scene, params, integrator, dt, t_end, tmp):
        out = os.path.join(tmp, "frames")
        traj = os.path.join(tmp, "traj.csv")
        args = ["run", scene, "--integrator", integrator, "--dt", str(dt), "--t-end", str(t_end),
                "--vtk", out, "--trajectory", traj, "--json"]
        for p in params:
            args += ["-p", p]
        result = json.loads(springlab(*args).stdout)
        return out, traj, result

    def check_series(self, scene, params, integrator, dt, t_end, expected_types):
        with tempfile.TemporaryDirectory() as tmp:
            out, traj, result = self.run_scene(scene, params, integrator, dt, t_end, tmp)
            if os.path.isfile(scene):
                with open(scene) as f:
                    scene_json = json.load(f)
            else:
                scene_json = json.loads(springlab("scene", scene, *sum((["-p", p] for p in params), [])).stdout)
            stem = scene_json["name"]
            pvd = ET.parse(os.path.join(out, stem + ".pvd")).getroot()
            datasets = pvd.findall("./Collection/DataSet")
            with open(traj) as f:
                rows = list(csv.DictReader(f))
            n = len(scene_json["particles"])
            dim = scene_json["dimension"]
            times = sorted({float(r["t"]) for r in rows})
            self.assertEqual([float(d.get("timestep")) for d in datasets], times)
            self.assertEqual(sorted(os.listdir(out)),
                             sorted([stem + ".pvd"] + [d.get("file") for d in datasets]))
            axes = "xyz"[:dim]
            for k, d in enumerate(datasets):
                grid = read_frame(os.path.join(out, d.get("file")))
                self.assertEqual(grid.GetNumberOfPoints(), n)
                t = float(d.get("timestep"))
                self.assertEqual(vtk_to_numpy(grid.GetFieldData().GetArray("TimeValue"))[0], t)
                frame_rows = rows[k * n:(k + 1) * n]
                x = np.array([[float(r[a]) for a in axes] for r in frame_rows])
                v = np.array([[float(r["v" + a]) for a in axes] for r in frame_rows])
                points = vtk_to_numpy(grid.GetPoints().GetData())
                velocity = vtk_to_numpy(grid.GetPointData().GetArray("velocity"))
                np.testing.assert_array_equal(points[:, :dim], x)   # exact: shortest round-trip text
                np.testing.assert_array_equal(velocity[:, :dim], v)
                if dim == 2:
                    np.testing.assert_array_equal(points[:, 2], 0.0)
                fixed = vtk_to_numpy(grid.GetPointData().GetArray("fixed"))
                np.testing.assert_array_equal(fixed, [1 if p.get("fixed") else 0 for p in scene_json["particles"]])
                if k == 0:
                    cells = cells_of(grid)
                    expected = [(VTK_LINE, (s["i"], s["j"])) for s in scene_json.get("springs", [])]
                    expected += [(VTK_TRIANGLE, tuple(t["nodes"])) for t in scene_json.get("triangles", [])]
                    expected += [(VTK_TETRA, tuple(t["nodes"])) for t in scene_json.get("tetrahedra", [])]
                    joined = {i for _, nodes in expected for i in nodes}
                    expected += [(VTK_VERTEX, (i,)) for i in range(n) if i not in joined]
                    self.assertEqual(cells, expected)
                    self.assertEqual({c[0] for c in cells}, expected_types)
            return result, len(datasets)

    def test_cloth_springs_as_lines(self):
        result, frames = self.check_series("cloth", ["n=6"], "implicit-euler", 0.05, 0.2, {VTK_LINE})
        self.assertEqual(frames, 5)

    def test_membrane_triangles(self):
        self.check_series("membrane", ["n=4"], "implicit-euler", 0.05, 0.1, {VTK_TRIANGLE})

    def test_block_tetrahedra_in_3d(self):
        self.check_series("block", ["n=2"], "implicit-euler", 0.02, 0.04, {VTK_TETRA})

    def test_particle_without_elements_is_a_vertex(self):
        with tempfile.TemporaryDirectory() as tmp:
            scene = os.path.join(tmp, "loose.json")
            with open(scene, "w") as f:
                json.dump({"name": "loose", "dimension": 2, "gravity": [0, -9.81],
                           "particles": [{"x": [0, 0], "fixed": True}, {"x": [1, 0]}, {"x": [3, 0]}],
                           "springs": [{"i": 0, "j": 1, "k": 10}]}, f)
            self.check_series(scene, [], "symplectic-euler", 0.01, 0.03, {VTK_LINE, VTK_VERTEX})

    def test_diverged_run_keeps_frames_to_last_good_state(self):
        with tempfile.TemporaryDirectory() as tmp:
            out, _, result = self.run_scene("cloth", ["n=6"], "explicit-euler", 0.05, 5.0, tmp)
            self.assertTrue(result["diverged"])
            pvd = ET.parse(os.path.join(out, "cloth.pvd")).getroot()
            last = float(pvd.findall("./Collection/DataSet")[-1].get("timestep"))
            self.assertEqual(last, result["t_final"])

    def test_a_file_in_the_way_is_refused_and_nothing_is_written(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "taken")
            with open(path, "w") as f:
                f.write("keep")
            r = springlab("run", "cloth", "-p", "n=4", "--integrator", "rk4", "--dt", "0.01",
                          "--t-end", "0.02", "--vtk", path, check=False)
            self.assertEqual(r.returncode, 1)
            self.assertEqual(r.stderr.count("\n"), 1)
            self.assertIn("taken: is not a folder", r.stderr)
            self.assertEqual(os.listdir(tmp), ["taken"])
            with open(path) as f:
                self.assertEqual(f.read(), "keep")

    def test_over_a_million_frames_is_refused_before_the_run(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "frames")
            r = springlab("run", "oscillator", "--integrator", "rk4", "--dt", "1e-7", "--t-end", "0.2",
                          "--vtk", out, check=False)
            self.assertEqual(r.returncode, 1)
            self.assertEqual(r.stderr, "springlab: error: --vtk: would write 2000001 frames, over the "
                             "cap of 1000000: write every K-th step with --every\n")
            self.assertEqual(os.listdir(tmp), [])

    def test_an_existing_folder_gets_the_new_series_only(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "frames")
            os.mkdir(out)
            with open(os.path.join(out, "mine.txt"), "w") as f:
                f.write("x")
            base = ["run", "cloth", "-p", "n=4", "--integrator", "rk4", "--dt", "0.01", "--vtk", out]
            springlab(*base, "--t-end", "0.05")
            self.assertEqual(len(os.listdir(out)), 1 + 1 + 6)
            springlab(*base, "--t-end", "0.02")  # shorter: the old frames 3..5 go
            self.assertEqual(sorted(os.listdir(out)),
                             ["cloth.pvd", "cloth_000000.vtu", "cloth_000001.vtu", "cloth_000002.vtu", "mine.txt"])


if __name__ == "__main__":
    unittest.main()
