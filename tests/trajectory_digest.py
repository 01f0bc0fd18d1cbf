#!/usr/bin/python3
"""A digest of every integrator's trajectory on the built-in scenes.

Runs every integrator of `springlab list --json` (and the option variants
below) on every case of CASES (each built-in scene at a small size and a
short t_end, and a few variants: barrier contact, drag and wind, large steps
(indefinite Newton matrices), the damped scene file of the spec) with `springlab run ... --energy F
--trajectory G --json`, and records, per (integrator, case), the SHA-256 of
the energy CSV, the trajectory CSV and the JSON summary (its `wall_seconds`
removed: the only field that is not a result; `verdict`, which `failure`
says in words, and an empty `warnings` list removed too). A pairing the method refuses
before its first step (exit 1, one line on stderr) is recorded as refused,
with the digest of that line.

A refactoring that must not change any result (issue 32: the Newton solver)
is checked by recording the digests before and after it:

    tests/trajectory_digest.py build/release/springlab > before.txt
    ... change, rebuild ...
    tests/trajectory_digest.py build/release/springlab --compare before.txt

--compare prints the pairs whose digest differs and exits 1 if any does.
The digests are those of one build on one machine (another compiler or BLAS
may round differently): compare runs of the same toolchain. A couple of
minutes on two cores (--jobs, default 2).
"""
import argparse
import concurrent.futures
import hashlib
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))

# (label, scene, parameters, dt, t_end): small and short, so the whole
# digest takes minutes; every built-in scene at least once.
CASES = [
    ("spring", "spring", [], "0.01", "0.5"),
    ("oscillator", "oscillator", [], "0.05", "1"),
    ("chain", "chain", ["n=6", "horizontal=1"], "0.01", "0.3"),
    ("chain-large-step", "chain", ["n=6", "horizontal=1"], "0.1", "1"),
    ("cloth", "cloth", ["n=4"], "0.0166667", "0.3"),
    ("cloth-large-step", "cloth", ["n=6"], "0.1", "0.6"),
    ("cloth-drag-wind", "cloth", ["n=5", "drag=0.2", "wind=3"], "0.0166667", "0.2"),
    ("cloth-ground-penalty", "cloth", ["n=5", "ground=0.3", "contact=0"], "0.0166667", "0.4"),
    ("cloth-ground-barrier", "cloth", ["n=5", "ground=0.3", "contact=1"], "0.0166667", "0.4"),
    ("beam", "beam", ["nx=4", "ny=1"], "0.005", "0.05"),
    ("beam-3d", "beam", ["dimension=3", "nx=3", "ny=1"], "0.005", "0.03"),
    ("membrane", "membrane", ["n=4"], "0.0166667", "0.2"),
    ("slope", "slope", ["speed=1"], "0.01", "0.3"),
    ("block", "block", ["n=1", "height=0.05"], "0.01", "0.2"),
    ("block-barrier", "block", ["n=1", "height=0.05", "contact=1"], "0.01", "0.2"),
    ("block-small", "block", ["n=2", "height=0.05", "model=1"], "0.01", "0.1"),
    ("tumbling-box", "tumbling-box", [], "0.01", "0.2"),
    ("box-on-slope", "box-on-slope", ["speed=0.5"], "0.01", "0.2"),
    ("box-pile", "box-pile", ["n=2"], "0.01", "0.2"),
    ("box-tower", "box-tower", ["n=3"], "0.01", "0.2"),
    ("box-drop", "box-drop", ["n=4", "columns=2", "width=0.4"], "0.01", "0.2"),
    ("box-chain", "box-chain", ["n=2"], "0.005", "0.05"),
    ("dam-break", "dam-break", ["spacing=0.025"], "0.002", "0.02"),
    ("dam-break-obstacle", "dam-break-obstacle", ["spacing=0.25"], "0.005", "0.05"),
    ("sloshing", "sloshing", ["spacing=0.05"], "0.002", "0.02"),
    ("tank", "tank", ["spacing=0.05"], "0.002", "0.02"),
    ("spec-damped", os.path.join(HERE, "data", "scenes", "spec_example.json"), [], "0.01", "0.3"),
]

# Option variants of the Newton methods, beside each method at its defaults.
VARIANTS = [
    ("implicit-euler:quasi-newton", "implicit-euler", ["--solver", "quasi-newton"]),
    ("implicit-euler:tol-1e-9", "implicit-euler", ["--newton-tol", "1e-9"]),
    ("linear-implicit-euler:definite", "linear-implicit-euler", ["--stiffness", "definite"]),
    ("newmark:gamma-0.6", "newmark", ["--gamma", "0.6", "--beta", "0.3"]),
    ("hht-alpha:-0.3", "hht-alpha", ["--alpha", "-0.3"]),
    ("generalized-alpha:0", "generalized-alpha", ["--rho-inf", "0"]),
]


def run_one(exe, label, integrator, options, case):
    name, scene, params, dt, t_end = case
    with tempfile.TemporaryDirectory() as tmp:
        energy = os.path.join(tmp, "e.csv")
        trajectory = os.path.join(tmp, "x.csv")
        command = [exe, "run", scene, "--integrator", integrator, "--dt", dt, "--t-end", t_end,
                   "--energy", energy, "--trajectory", trajectory, "--json"] + options
        for p in params:
            command += ["-p", p]
        done = subprocess.run(command, capture_output=True, text=True, timeout=600)
        digest = hashlib.sha256()
        if done.returncode != 0:
            digest.update(done.stderr.encode())
            return label, name, "refused", digest.hexdigest()[:16]
        summary = json.loads(done.stdout)
        summary.pop("wall_seconds", None)
        # The verdict's data (issue 46) says again what `failure` says in
        # words; an empty warning list is no news. Dropped, so that digests
        # recorded before they existed still compare: a run with warnings
        # differs.
        summary.pop("verdict", None)
        if summary.get("warnings") == []:
            summary.pop("warnings")
        digest.update(json.dumps(summary, sort_keys=True).encode())
        for path in (energy, trajectory):
            with open(path, "rb") as f:
                digest.update(f.read())
        return label, name, summary["status"], digest.hexdigest()[:16]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("exe", help="the springlab executable")
    parser.add_argument("--compare", help="a digest file written before: report differences")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--only", help="run only integrators whose label contains this")
    args = parser.parse_args()

    listing = json.loads(subprocess.run([args.exe, "list", "--json"], capture_output=True,
                                        text=True, check=True).stdout)
    runs = [(i["name"], i["name"], []) for i in listing["integrators"]] + VARIANTS
    if args.only:
        runs = [r for r in runs if args.only in r[0]]
    scenes = {s["name"] for s in listing["scenes"]}
    covered = {c[1] for c in CASES}
    missing = scenes - covered
    if missing:
        sys.exit("trajectory_digest.py: no case for the built-in scenes " + ", ".join(sorted(missing)))

    jobs = [(args.exe, label, integrator, options, case)
            for label, integrator, options in runs for case in CASES]
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(lambda j: run_one(*j), jobs))
    lines = [f"{label} {case} {status} {digest}" for label, case, status, digest in rows]

    if not args.compare:
        print("\n".join(lines))
        return 0
    with open(args.compare) as f:
        before = {" ".join(l.split()[:2]): l.strip() for l in f if l.strip()}
    differ = 0
    for line in lines:
        key = " ".join(line.split()[:2])
        if before.get(key) != line:
            differ += 1
            print(f"differs: before {before.get(key)!r}, now {line!r}")
    statuses = {}
    for _, _, status, _ in rows:
        statuses[status] = statuses.get(status, 0) + 1
    print(f"{len(lines)} pairs compared ({', '.join(f'{n} {s}' for s, n in sorted(statuses.items()))}): "
          f"{len(lines) - differ} identical, {differ} differ")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
