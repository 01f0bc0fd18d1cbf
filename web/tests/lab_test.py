#!/usr/bin/env python3
"""Tests of the lab page (docs/browser-lab.md) in headless Chromium.

    lab_test.py --lab build/web/lab.html equality --springlab build/release/springlab
    lab_test.py --lab build/web/lab.html controls --work DIR
    lab_test.py --lab build/web/lab.html frame-rate [--seconds 4]

Chromium is driven over the DevTools protocol on a pipe
(--remote-debugging-pipe: JSON messages separated by NUL bytes on file
descriptors 3 and 4), so nothing but the Python standard library is needed.
Every check goes through the page's own API, window.springlab (web/lab.js).

equality: the page's runs (the C++ core compiled to WebAssembly) end where
  the native `springlab run ... --json` ends, to 1e-12 relative, for
  symplectic-euler, implicit-euler and xpbd: springs, elements, a pile of
  rigid bodies in contact (their p and A compared too) and a fluid (SPH
  under symplectic Euler, position-based fluids under xpbd).
controls: with the page's own controls (setDt, step), symplectic Euler on a
  cloth is stable at 0.9 x its dt limit 2 / w_max and diverges at 1.1 x,
  the panel's "diverged at t = ..." mark says the time the native run
  reports for the same settings, and two screenshots of the running page
  taken 0.5 s apart differ; a rigid body scene and a fluid scene draw
  (pixels on the panel's canvas) and their pictures change as they run;
  projective dynamics, which refuses fluids, shows the command line's
  refusal message in its panel, and xpbd on a neo-Hookean block names the
  remedy (model = corotated); the explicit-Euler panel says "no stable
  step without damping" once.
frame-rate: prints frames per second, steps per frame, the time a frame
  spends stepping and drawing (wall clock, in the page) and the CPU time
  Chromium's processes used per frame, for the cloth 32 under pairs of
  methods (a measurement, not a check).
"""

import argparse
import base64
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PROG = "lab_test.py"
REL_TOL = 1e-12


class Fail(Exception):
    pass


class Chromium:
    """Headless Chromium with one page, spoken to over the DevTools pipe."""

    def __init__(self, binary, timeout=120.0):
        self.timeout = timeout
        self.profile = tempfile.TemporaryDirectory(prefix="lab-test-")
        to_chrome_r, to_chrome_w = os.pipe()
        from_chrome_r, from_chrome_w = os.pipe()
        # Chromium reads commands on fd 3 and writes replies on fd 4: move
        # the pipe ends above 4 first, so that dup2 cannot clobber one.
        keep_r = os.dup(to_chrome_r) if to_chrome_r <= 4 else to_chrome_r
        keep_w = os.dup(from_chrome_w) if from_chrome_w <= 4 else from_chrome_w
        while keep_r <= 4:
            keep_r = os.dup(keep_r)
        while keep_w <= 4:
            keep_w = os.dup(keep_w)

        def child_fds():
            os.dup2(keep_r, 3)
            os.dup2(keep_w, 4)

        cmd = [binary, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               "--remote-debugging-pipe", "--user-data-dir=" + self.profile.name,
               "--window-size=1400,1000", "about:blank"]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, preexec_fn=child_fds,
                                     pass_fds=(3, 4))
        for fd in {to_chrome_r, from_chrome_w, keep_r, keep_w}:
            os.close(fd)
        self.out = os.fdopen(to_chrome_w, "wb", buffering=0)
        self.inp = os.fdopen(from_chrome_r, "rb", buffering=0)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.send("Target.attachToTarget",
                                 {"targetId": target, "flatten": True})["sessionId"]
        self.send("Page.enable", session=True)
        self.send("Runtime.enable", session=True)

    def _read_message(self):
        while b"\0" not in self.buffer:
            chunk = self.inp.read(1 << 16)
            if not chunk:
                err = self.proc.stderr.read().decode("utf-8", "replace").strip().splitlines()
                raise Fail("Chromium closed the DevTools pipe:\n  " + "\n  ".join(err[-5:]))
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, params=None, session=False):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = self.session
        self.out.write(json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise Fail("%s: %s" % (method, reply["error"].get("message")))
                return reply.get("result", {})
            self.events.append(reply)

    def open(self, url):
        self.events.clear()
        self.send("Page.navigate", {"url": url}, session=True)
        # The page's API resolves window.springlab.ready once the module runs.
        deadline = time.time() + self.timeout
        while time.time() < deadline:
            ready = self.evaluate("!!(window.springlab && window.springlab.ready)")
            if ready:
                return self.evaluate("window.springlab.ready.then(() => true)")
            time.sleep(0.1)
        raise Fail("the page did not define window.springlab within %g s" % self.timeout)

    def evaluate(self, expression):
        """The value of a JavaScript expression (awaited when a promise)."""
        result = self.send("Runtime.evaluate", {"expression": expression, "awaitPromise": True,
                                                "returnByValue": True}, session=True)
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise Fail("the page threw: %s\n  (evaluating %s)" % (text, expression[:200]))
        return result["result"].get("value")

    def screenshot(self):
        return base64.b64decode(self.send("Page.captureScreenshot", {"format": "png"},
                                          session=True)["data"])

    def cpu_seconds(self, renderer_main=False):
        """CPU time (user + system) so far of Chromium and all its processes,
        or of its renderers' main threads only (the page's JavaScript and
        WebAssembly run there; a main thread's task id is its process id)."""
        parent, times, renderer = {}, {}, set()
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            try:
                with open("/proc/%s/stat" % entry) as f:
                    fields = f.read().rsplit(")", 1)[1].split()
                with open("/proc/%s/task/%s/stat" % (entry, entry)) as f:
                    main = f.read().rsplit(")", 1)[1].split()
                with open("/proc/%s/cmdline" % entry, "rb") as f:
                    if b"--type=renderer" in f.read():
                        renderer.add(int(entry))
            except OSError:
                continue
            parent[int(entry)] = int(fields[1])
            # utime + stime of the process (all its threads) or of its main thread
            times[int(entry)] = (int(main[11]) + int(main[12])) if renderer_main else \
                (int(fields[11]) + int(fields[12]))
        total = 0
        for pid in times:
            p = pid
            while p in parent and p != self.proc.pid:
                p = parent[p]
            if p == self.proc.pid and (not renderer_main or pid in renderer):
                total += times[pid]
        return total / os.sysconf("SC_CLK_TCK")

    def close(self):
        try:
            self.send("Browser.close")
        except Fail:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self.profile.cleanup()


def native_run(springlab, scene, params, integrator, dt, t_end, extra=()):
    cmd = [springlab, "run", scene, "--integrator", integrator, "--dt", repr(dt),
           "--t-end", repr(t_end), "--json"] + list(extra)
    for key, value in params.items():
        cmd += ["-p", "%s=%s" % (key, value)]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False)
    if proc.returncode != 0:
        raise Fail("%s failed: %s" % (" ".join(cmd), proc.stderr.decode().strip()))
    return json.loads(proc.stdout)


def final_rows(run, positions):
    """The positions' rows, then each rigid body's p and the rows of its A."""
    rows = list(positions)
    for body in run.get("bodies") or []:
        rows += [body["p"]] + body["A"]
    return rows


def largest_relative_difference(a, b):
    """max |a - b| / max |b| over the positions (their scale: the scene's size)."""
    flat_a = [x for row in a for x in row]
    flat_b = [x for row in b for x in row]
    if not flat_b:
        raise Fail("no positions to compare")
    if len(flat_a) != len(flat_b):
        raise Fail("%d coordinates in the page, %d in the native run" % (len(flat_a), len(flat_b)))
    scale = max(abs(x) for x in flat_b)
    return max(abs(x - y) for x, y in zip(flat_a, flat_b)) / scale


# Each case: a scene, an integrator, dt, t_end and method options; long
# enough for the motion to be far from the start (the cloth falls ~0.3 m in
# 0.25 s). The explicit and fast methods run the same arithmetic in both
# builds. Implicit Euler factors its Newton matrix with CHOLMOD natively and
# with Eigen's SimplicialLLT in the page: the same factor up to rounding, and
# its Newton iteration (CG preconditioned by that factor) stops within
# --newton-tol of the step's solution, so the two runs agree to that
# tolerance (5e-9 relative on the cloth at the default 1e-4 m/s, printed as
# information); solved to the round-off floor (--newton-tol 1e-12) they
# agree to 1e-12.
EQUALITY_CASES = [
    ("cloth", {"n": 8}, "symplectic-euler", 0.0005, 0.25, {}),
    ("chain", {"n": 10, "horizontal": 1}, "symplectic-euler", 0.001, 1.0, {}),
    ("cloth", {"n": 8}, "implicit-euler", 0.01, 0.5, {"newton_tol": 1e-12}),
    ("beam", {"nx": 8, "ny": 2}, "implicit-euler", 0.005, 0.1, {"newton_tol": 1e-12}),
    ("cloth", {"n": 8}, "xpbd", 0.01, 0.5, {}),
    ("chain", {"n": 10, "horizontal": 1}, "xpbd", 0.005, 1.0, {}),
    ("cloth", {"n": 8}, "vbd", 0.01, 0.5, {}),
    # Rigid bodies (affine bodies): three boxes hinged by springs between
    # body points swinging down from horizontal, and a box tumbling about
    # its middle axis (their p and A compared too).
    ("box-chain", {}, "symplectic-euler", 0.0002, 0.5, {}),
    ("tumbling-box", {}, "symplectic-euler", 0.0002, 0.5, {}),
    # A fluid: the dam break's column (200 particles, 10 x 20) under weakly
    # compressible SPH below its CFL step 0.25 h / c = 1.6e-4 s, and as
    # position-based fluids under xpbd.
    ("dam-break", {"a": 0.05}, "symplectic-euler", 0.0001, 0.1, {}),
    ("dam-break", {"a": 0.05}, "xpbd", 0.005, 0.2, {}),
]
INFORMATION_CASES = [
    ("cloth", {"n": 8}, "implicit-euler", 0.01, 0.5, {}),
    # Boxes falling onto the ground and one another: the two builds agree
    # to 1e-16 for 100 steps, then the contacts amplify a last-bit
    # difference (2e-11 at 1000 steps, 7e-8 at 2500). Not the same arithmetic
    # everywhere, then: see docs/browser-lab.md "Tests".
    ("box-pile", {}, "symplectic-euler", 0.0002, 0.5, {}),
]
CLI_OPTION = {"newton_tol": "--newton-tol", "substeps": "--substeps", "iterations": "--iterations"}


def equality(browser, args):
    if not Path(args.springlab).is_file():
        raise Fail("%s: no such file (build the native springlab first: cmake --preset release "
                   "&& cmake --build build/release --target springlab)" % args.springlab)
    methods = browser.evaluate("window.springlab.list().integrators.map(m => m.name)")
    for needed in ("symplectic-euler", "implicit-euler", "xpbd"):
        if needed not in methods:
            raise Fail("the page's list has no %s (it has %s)" % (needed, ", ".join(methods)))
    problems = []
    for case in EQUALITY_CASES + INFORMATION_CASES:
        scene, params, integrator, dt, t_end, options = case
        request = dict({"scene": scene, "params": params, "integrator": integrator, "dt": dt,
                        "t_end": t_end}, **options)
        page = browser.evaluate("window.springlab.run(%s)" % json.dumps(request))
        if "error" in page:
            raise Fail("springlab.run(%s): %s" % (json.dumps(request), page["error"]))
        extra = [a for k, v in options.items() for a in (CLI_OPTION[k], repr(v))]
        native = native_run(args.springlab, scene, params, integrator, dt, t_end, extra)
        diff = largest_relative_difference(final_rows(page, page["x"]),
                                           final_rows(native, native["final_state"]["x"]))
        start = browser.evaluate("window.springlab.run(%s)" % json.dumps(
            dict(request, t_end=dt)))
        moved = largest_relative_difference(final_rows(page, page["x"]),
                                            final_rows(start, start["x"]))
        line = ("%-16s %-26s dt %-6g %-22s %4d steps: max |x_web - x_native| / max |x| = "
                "%.2e (moved %.2f)" % (integrator, scene + " " + json.dumps(params), dt,
                                       " ".join(extra), page["steps"], diff, moved))
        if case in INFORMATION_CASES:
            print(line + "  [information]")
            continue
        print(line)
        if page["status"] != native["status"] or page["steps"] != native["steps"]:
            problems.append("%s: page %s after %d steps, native %s after %d" % (
                line, page["status"], page["steps"], native["status"], native["steps"]))
        if not diff <= REL_TOL:
            problems.append(line + " > %g" % REL_TOL)
        if moved < 1e-3:
            problems.append(line + ": the scene hardly moved, the comparison says little")
    if problems:
        raise Fail("\n  ".join(problems))
    print("equality OK: %d runs equal the native ones to %g relative" % (
        len(EQUALITY_CASES), REL_TOL))


def controls(browser, args):
    scene, params = "cloth", {"n": 6}
    browser.evaluate("window.springlab.pause()")
    browser.evaluate("window.springlab.setScene('cloth', %s)" % json.dumps(params))
    browser.evaluate("window.springlab.setIntegrators(['explicit-euler', 'symplectic-euler'])")
    states = browser.evaluate("window.springlab.state()")
    w_max = states[1]["w_max"]
    limit = states[1]["dt_limit"]
    if not (w_max > 0 and abs(limit - 2.0 / w_max) <= 1e-12 * limit):
        raise Fail("symplectic Euler's dt limit on the page is %r, expected 2 / w_max = %r"
                   % (limit, 2.0 / w_max if w_max else None))
    steps = 400
    problems = []
    for factor in (0.9, 1.1):
        dt = factor * limit
        browser.evaluate("window.springlab.setDt(%r); window.springlab.reset()" % dt)
        states = browser.evaluate("window.springlab.step(%d)" % steps)
        explicit, symplectic = states
        # The stability sentence is said once: the limit w h <= 0 is in the
        # method's stability text, not repeated as a "limit".
        said = browser.evaluate("document.querySelectorAll('.status')[0].textContent")
        if said.count("no stable step without damping") != 1:
            problems.append("the explicit-euler panel says %r" % said)
        print("dt = %.3f x 2/w_max = %.6g s: explicit-euler mark %r; symplectic-euler mark %r"
              % (factor, dt, explicit["mark"], symplectic["mark"]))
        # Explicit Euler amplifies the fastest mode by sqrt(1 + (w h)^2) > 2
        # a step here: diverged either way.
        if not explicit["mark"].startswith("diverged at t = "):
            problems.append("explicit-euler at dt %.3g shows no divergence mark" % dt)
        stable = factor < 1.0
        if stable and symplectic["mark"]:
            problems.append("symplectic-euler at 0.9 x its limit shows %r" % symplectic["mark"])
        if not stable:
            if not symplectic["mark"].startswith("diverged at t = "):
                problems.append("symplectic-euler at 1.1 x its limit shows no divergence mark")
                continue
            native = native_run(args_springlab(args), scene, params, "symplectic-euler", dt,
                                steps * dt * (1 + 1e-12))
            marked = float(symplectic["mark"].split("=")[1].split()[0])
            if native["diverged_at"] is None:
                problems.append("the native run at dt %r does not diverge" % dt)
            elif abs(symplectic["diverged_at"] - native["diverged_at"]) > 1e-12 * native["diverged_at"] \
                    or abs(marked - native["diverged_at"]) > 1e-5 * native["diverged_at"]:
                problems.append("the page marks divergence at %r (%s), the native run at %r"
                                % (symplectic["diverged_at"], symplectic["mark"],
                                   native["diverged_at"]))
            else:
                print("symplectic-euler diverged at t = %r on the page, %r natively"
                      % (symplectic["diverged_at"], native["diverged_at"]))
    # Running: the picture changes.
    browser.evaluate("window.springlab.setIntegrators(['symplectic-euler', 'implicit-euler'])")
    browser.evaluate("window.springlab.setDt(%r); window.springlab.play()" % (0.5 * limit))
    time.sleep(0.3)
    first = browser.screenshot()
    time.sleep(0.5)
    second = browser.screenshot()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    (work / "first.png").write_bytes(first)
    (work / "second.png").write_bytes(second)
    t = [s["t"] for s in browser.evaluate("window.springlab.state()")]
    print("screenshots %s, %s (%d, %d bytes); the panels at t = %s" % (
        work / "first.png", work / "second.png", len(first), len(second), t))
    if first == second:
        problems.append("two screenshots 0.5 s apart are identical: the page does not animate")
    if not all(x > 0 for x in t):
        problems.append("the running page's panels did not advance (t = %s)" % t)
    problems += drawn_scenes(browser, args)
    if problems:
        raise Fail("\n  ".join(problems))
    print("controls OK")


# The canvases of the panels: pixels drawn (alpha > 0; the canvas starts
# transparent) and pixels that differ from the ones kept by the last call.
CANVAS_PIXELS = """(() => {
  const now = [...document.querySelectorAll('canvas.view')].map((c) =>
      c.getContext('2d').getImageData(0, 0, c.width, c.height).data);
  const before = window.labTestPixels || now.map(() => null);
  window.labTestPixels = now;
  return now.map((d, k) => {
    let drawn = 0, changed = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (d[i + 3] > 0) ++drawn;
      const b = before[k];
      if (b && (b[i] !== d[i] || b[i + 1] !== d[i + 1] || b[i + 2] !== d[i + 2] ||
                b[i + 3] !== d[i + 3])) ++changed;
    }
    return {drawn: drawn, changed: changed};
  });
})()"""
MIN_DRAWN, MIN_CHANGED = 2000, 200  # pixels of a 440 x 360 canvas

# A rigid body scene and a fluid scene, paused and stepped through the API:
# each panel draws (its bodies' faces, its fluid's dots) and its picture
# changes over the steps.
DRAWN_SCENES = [
    ("box-pile", {}, ["symplectic-euler", "implicit-euler"], 0.0002, 500),
    # The pile of eight at a frame step, as the scene menu starts it: 2 s.
    ("box-pile", {"n": 8}, ["implicit-euler", "bdf2"], 1.0 / 60.0, 120),
    ("dam-break", {"a": 0.05}, ["symplectic-euler", "xpbd"], 0.0001, 400),
]


def drawn_scenes(browser, args):
    problems = []
    browser.evaluate("window.springlab.pause()")
    for scene, params, methods, dt, steps in DRAWN_SCENES:
        browser.evaluate("window.springlab.setScene(%s, %s)"
                         % (json.dumps(scene), json.dumps(params)))
        browser.evaluate("window.springlab.setIntegrators(%s)" % json.dumps(methods))
        browser.evaluate("window.springlab.setDt(%r)" % dt)
        before = browser.evaluate(CANVAS_PIXELS)
        states = browser.evaluate("window.springlab.step(%d)" % steps)
        after = browser.evaluate(CANVAS_PIXELS)
        for method, b, a, state in zip(methods, before, after, states):
            print("%s, %s: %d pixels drawn at t = 0, %d at t = %g s, %d changed" % (
                scene, method, b["drawn"], a["drawn"], state["t"], a["changed"]))
            if state["error"] or state["status"] != "completed":
                problems.append("%s, %s: %s" % (scene, method, state["error"] or state["status"]))
            elif min(b["drawn"], a["drawn"]) < MIN_DRAWN or a["changed"] < MIN_CHANGED:
                problems.append("%s, %s draws %d then %d pixels, %d changed (expected >= %d "
                                "drawn, >= %d changed)" % (scene, method, b["drawn"], a["drawn"],
                                                          a["changed"], MIN_DRAWN, MIN_CHANGED))
    # A method that refuses the scene: its panel shows the command line's message.
    scene, params = "dam-break", {"a": 0.05}
    browser.evaluate("window.springlab.setIntegrators(['symplectic-euler', 'projective-dynamics'])")
    refused = browser.evaluate("window.springlab.state()")[1]["error"]
    cmd = [args_springlab(args), "run", scene, "-p", "a=0.05", "--integrator",
           "projective-dynamics", "--dt", "0.0001", "--t-end", "0.001"]
    native = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False)
    message = native.stderr.decode().strip()
    print("projective-dynamics on %s: page %r; native (exit %d) %r" % (
        scene, refused, native.returncode, message))
    if native.returncode != 1 or not refused or not message.endswith("--integrator " + refused):
        problems.append("projective-dynamics on %s: the page says %r, the command line %r"
                        % (scene, refused, message))
    # A refusal with a remedy (xpbd and a neo-Hookean block): the panel names
    # the scene setting that makes the pairing work, as the command line does.
    browser.evaluate("window.springlab.setScene('block', {model: 'neo-hookean'})")
    browser.evaluate("window.springlab.setIntegrators(['symplectic-euler', 'xpbd'])")
    said = browser.evaluate("document.querySelectorAll('.status')[1].textContent")
    print("xpbd on a neo-Hookean block: the panel says %r" % said)
    if not said.endswith("(for this scene: model = corotated)"):
        problems.append("xpbd on a neo-Hookean block: the panel says %r, without the remedy "
                        "model = corotated" % said)
    return problems


def args_springlab(args):
    if not args.springlab or not Path(args.springlab).is_file():
        raise Fail("the controls test compares with the native springlab: --springlab PATH")
    return args.springlab


def frame_rate(browser, args):
    dt_limit = None
    cases = [("xpbd", "projective-dynamics", 1.0 / 60.0),
             ("symplectic-euler", "xpbd", None),
             ("symplectic-euler", "projective-dynamics", None),
             ("symplectic-euler", "symplectic-euler", None)]
    browser.evaluate("window.springlab.setScene('cloth', {n: 32})")
    browser.evaluate("window.springlab.setIntegrators(['symplectic-euler', 'symplectic-euler'])")
    dt_limit = browser.evaluate("window.springlab.state()[0].dt_limit")
    step_cpu = cpu_costs(browser, args, dt_limit)
    for a, b, dt in cases:
        browser.evaluate("window.springlab.setIntegrators(%s)" % json.dumps([a, b]))
        if dt is None:
            dt = 0.9 * dt_limit
        browser.evaluate("window.springlab.setDt(%r); window.springlab.play()" % dt)
        time.sleep(1.0)  # the step cost is measured, the budget settles
        samples = []
        frames0 = browser.evaluate("window.springlab.stats().framesTotal")
        cpu0, main0 = browser.cpu_seconds(), browser.cpu_seconds(renderer_main=True)
        for _ in range(int(args.seconds / 0.5)):
            time.sleep(0.5)
            samples.append(browser.evaluate("window.springlab.stats()"))
        frames = samples[-1]["framesTotal"] - frames0
        cpu_ms = 1000 * (browser.cpu_seconds() - cpu0) / max(frames, 1)
        main_ms = 1000 * (browser.cpu_seconds(renderer_main=True) - main0) / max(frames, 1)
        fps = sum(s["fps"] for s in samples) / len(samples)
        per = sum(s["stepsPerFrame"] for s in samples) / len(samples)
        wanted = sum(s["wantedPerFrame"] for s in samples) / len(samples)
        speed = sum(s["speed"] for s in samples) / len(samples)
        ms = sum(s["msPerStep"] for s in samples) / len(samples)
        step_ms = sum(s["stepMsPerFrame"] for s in samples) / len(samples)
        draw_ms = sum(s["drawMsPerFrame"] for s in samples) / len(samples)
        # The page's thread less its steps' CPU: drawing and the browser's own work.
        rest_ms = main_ms - per * (step_cpu[a] + step_cpu[b])
        print("cloth 32, %s + %s, dt %.3g s: %.1f frames/s, %.1f steps/frame of %.1f wanted, "
              "%.2f ms per step (both panels), per frame %.1f ms stepping + %.1f ms drawing, "
              "%.0f%% of real time; CPU time per frame %.1f ms in the page's thread (%.1f ms of it not "
              "stepping), %.1f ms in all of Chromium; load average %.1f" % (
                  a, b, dt, fps, per, wanted, ms, step_ms, draw_ms, 100 * speed, main_ms, rest_ms,
                  cpu_ms, os.getloadavg()[0]))


def native_cpu_seconds(springlab, method, dt, steps):
    """CPU seconds (user + system) of `springlab run cloth -p n=32` for `steps` steps."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    native_run(springlab, "cloth", {"n": 32}, method, dt, steps * dt * (1 + 1e-12))
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def cpu_costs(browser, args, dt_limit):
    """CPU time per step of one cloth 32 panel, which the machine's load does
    not inflate as it does the wall clock: in the page (its renderer's main
    thread, paused, stepped through the API) and natively (`springlab run`:
    the difference of two run lengths, so that the setup cancels)."""
    browser.evaluate("window.springlab.pause()")
    cost = {}
    for method, dt, steps in (("xpbd", 1.0 / 60.0, 40), ("projective-dynamics", 1.0 / 60.0, 40),
                              ("symplectic-euler", 0.9 * dt_limit, 400)):
        browser.evaluate("window.springlab.setIntegrators(%s)" % json.dumps([method, method]))
        browser.evaluate("window.springlab.setDt(%r)" % dt)
        browser.evaluate("window.springlab.step(2)")
        main0 = browser.cpu_seconds(renderer_main=True)
        browser.evaluate("window.springlab.step(%d)" % steps)
        page = 1000 * (browser.cpu_seconds(renderer_main=True) - main0) / (2 * steps)
        cost[method] = page
        if args.springlab:
            native = 1000 * (native_cpu_seconds(args.springlab, method, dt, 2 * steps) -
                             native_cpu_seconds(args.springlab, method, dt, steps)) / steps
            native_text = "%.3f ms natively" % native
        else:
            native_text = "native not measured (--springlab)"
        print("cloth 32, %s at dt %.3g s: CPU per step of one panel %.3f ms in the page, %s; "
              "load average %.1f" % (method, dt, page, native_text, os.getloadavg()[0]))
    return cost


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("--lab", required=True, help="build/web/lab.html")
    ap.add_argument("--chromium", default="chromium")
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("test", choices=["equality", "controls", "frame-rate"])
    ap.add_argument("--springlab", help="the native springlab (equality, controls)")
    ap.add_argument("--work", default=".", help="controls: where the screenshots go")
    ap.add_argument("--seconds", type=float, default=4.0, help="frame-rate: seconds per case")
    args = ap.parse_args(argv)
    lab = Path(args.lab)
    if not lab.is_file():
        sys.stderr.write("%s: FAIL: %s: no such file (cmake --workflow --preset web builds it)\n"
                         % (PROG, lab))
        return 1
    browser = None
    try:
        browser = Chromium(args.chromium, args.timeout)
        browser.open(lab.resolve().as_uri())
        {"equality": equality, "controls": controls, "frame-rate": frame_rate}[args.test](
            browser, args)
    except Fail as exc:
        sys.stderr.write("%s: FAIL: %s\n" % (PROG, exc))
        return 1
    finally:
        if browser is not None:
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
