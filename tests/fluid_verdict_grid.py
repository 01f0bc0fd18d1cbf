#!/usr/bin/python3
"""Issue 46 item 1's fluid grid: no "completed" run over a physical blow-up.

Runs the built-in fluid scenes (dam-break at spacing 0.01, tank and
sloshing at 0.025) under the fixed-step methods that run fluids at steps
from 0.5 ms to 1/60 s, and judges every run that `springlab run` calls
completed by two checks that do not use springlab's own rule:

  - energy: the scenes are unforced (gravity, pressure, viscosity: the
    exact energy can only fall), so a final energy above 1.5 x the initial
    one is a blow-up;
  - place: a free particle at the end further than 0.1 m beyond the walls
    (the box of the fluid's fixed particles) at the sides or below the
    floor, or above the walls' top by more than the box's width (a splash
    goes up: the dam break with -p lid=0 throws water 0.2-0.4 m over walls
    0.27 m high with every stable step; by default a lid closes its box),
    is one that left the tank.

    tests/fluid_verdict_grid.py build/release/springlab [--jobs 2]

prints one line per run (status, energy ratio, the furthest particle's
distance out of the tank) and a summary; exits 1 when a completed
run fails either check. About a minute on two cores.
"""
import argparse
import concurrent.futures
import json
import subprocess
import sys

SCENES = [
    ("dam-break", ["spacing=0.01"], "0.5"),
    ("dam-break", ["spacing=0.01", "sound=1000"], "0.5"),
    ("tank", ["spacing=0.025"], "1"),
    ("sloshing", ["spacing=0.025"], "1"),
]
EXPLICIT = ["explicit-euler", "symplectic-euler", "verlet", "central-difference", "yoshida4",
            "yoshida6", "rk4"]
STEPS = ["0.0005", "0.001", "0.002", "0.005", "0.01", "0.0166667", "0.02"]
# xpbd at a frame's step, with its substeps (position-based fluids).
XPBD = [("xpbd", "0.0166667", ["--substeps", s]) for s in ("1", "4", "8")] + \
       [("xpbd", "0.005", ["--substeps", "1"])]


def walls_box(exe, scene, params):
    text = subprocess.run([exe, "scene", scene] + sum((["-p", p] for p in params), []),
                          capture_output=True, text=True, check=True).stdout
    s = json.loads(text)
    fixed = [p["x"] for p in s["particles"] if p.get("fixed")]
    dim = s["dimension"]
    return [(min(x[r] for x in fixed), max(x[r] for x in fixed)) for r in range(dim)]


def outside(x, box):
    """How far the furthest particle is past the sides, the floor, or the
    open top's allowance (the box's width) above the walls (y is up)."""
    width = box[0][1] - box[0][0]
    worst = 0.0
    for p in x:
        d2 = 0.0
        for r, (lo, hi) in enumerate(box):
            d = max(lo - p[r], p[r] - (hi + width if r == 1 else hi), 0.0)
            d2 += d * d
        worst = max(worst, d2 ** 0.5)
    return worst


def run(exe, scene, params, t_end, integrator, dt, options, box):
    command = [exe, "run", scene, "--integrator", integrator, "--dt", dt, "--t-end", t_end,
               "--json"] + options + sum((["-p", p] for p in params), [])
    done = subprocess.run(command, capture_output=True, text=True, timeout=900)
    label = f"{scene} {' '.join(params)} {integrator} {' '.join(options)} --dt {dt}"
    if done.returncode != 0:
        return label, "refused", None, None, done.stderr.strip()
    j = json.loads(done.stdout)
    ratio = j["energy_final"] / j["energy_initial"]
    return label, j["status"], ratio, outside(j["final_state"]["x"], box), j.get("failure")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("exe")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    jobs = []
    for scene, params, t_end in SCENES:
        box = walls_box(args.exe, scene, params)
        for integrator in EXPLICIT:
            for dt in STEPS:
                jobs.append((args.exe, scene, params, t_end, integrator, dt, [], box))
        for integrator, dt, options in XPBD:
            jobs.append((args.exe, scene, params, t_end, integrator, dt, options, box))
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(lambda j: run(*j), jobs))
    bad = 0
    counts = {}
    for label, status, ratio, away, failure in rows:
        counts[status] = counts.get(status, 0) + 1
        blown = status == "completed" and (ratio > 1.5 or away > 0.1)
        bad += blown
        tail = f" energy x{ratio:.4g}, {away:.3g} m outside" if ratio is not None else ""
        print(f"{'BLOW-UP ' if blown else ''}{label}: {status}{tail}"
              + (f" ({failure})" if failure and status != "completed" else ""))
    print(f"{len(rows)} runs ({', '.join(f'{n} {s}' for s, n in sorted(counts.items()))}): "
          f"{bad} completed over a blow-up")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
