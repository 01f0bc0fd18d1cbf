"""Step cost: springlab_bench's Google Benchmark JSON (optional). Read from
--bench FILE.json, or else from benchmarks.json in the data directory (where
`cmake --workflow --preset bench` writes it). Families, by name (the size n is
the scene's own parameter; counters carry the real size: particles, unknowns,
springs):
  BM_Step/<integrator>/<scene>/<n>        one step (adaptive: 1/60 s)
  BM_OdeintStep/<method>/<scene>/<n>      Boost.Odeint's peer of a step
  BM_OdeintPair/<method>/<scene>/<n>      both in alternation: the ratio
  BM_Force/<scene>/<n>, BM_ForceJacobian/<scene>/<n>
  BM_LinearSolver/<solver>/<scene>/<n>
Times are CPU time of the (single) benchmark thread: a one-core figure that a
busy machine disturbs less than wall time (both are in the step table)."""

import math
import re
from pathlib import Path

import numpy as np

from .data import DataError, finite, read_json

from .figures import (count, esc, facts_html, figure_html, fmt, log_log, new_figure,
                      note_html, swatch)

BENCH_FILE = "benchmarks.json"
TIME_UNITS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}
BENCH_STANDARD_KEYS = {"name", "family_index", "per_family_instance_index", "run_name", "run_type",
                       "repetitions", "repetition_index", "threads", "iterations", "real_time",
                       "cpu_time", "time_unit", "aggregate_name", "aggregate_unit", "label",
                       "error_occurred", "error_message"}
# Family -> index of the size argument in the name.
BENCH_FAMILIES = {"BM_Step": 3, "BM_OdeintStep": 3, "BM_OdeintPair": 3, "BM_Force": 2,
                  "BM_ForceJacobian": 2, "BM_LinearSolver": 3}
# Performance targets (issue 5), shown beside the measured figures.
TARGET_FORCE_NS = 5.0            # force evaluation, cloth 128, ns per spring
TARGET_PEER_RATIO = 0.7          # springlab / odeint time, rk4 and symplectic-euler
TARGET_STEP_MS = {"implicit-euler": 15.0, "linear-implicit-euler": 8.0}  # cloth 64, dt 1/60
TARGET_EXPONENT_EXPLICIT = (0.85, 1.15)  # "about 1.0"
TARGET_EXPONENT_IMPLICIT = 1.3


def read_bench(path):
    """Every springlab_bench entry, by family; time per iteration in s."""
    doc = read_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("benchmarks"), list):
        raise DataError(path, None, "not a Google Benchmark JSON file (no \"benchmarks\" list)")
    raw = {}
    errors = []
    ignored = 0
    for j, b in enumerate(doc["benchmarks"]):
        if not isinstance(b, dict) or not isinstance(b.get("name"), str):
            raise DataError(path, None, "benchmarks[%d]: expected an object with a \"name\"" % j)
        base = b.get("run_name") if isinstance(b.get("run_name"), str) else b["name"]
        parts = base.split("/")
        k = BENCH_FAMILIES.get(parts[0])
        if k is None or len(parts) <= k or not re.fullmatch(r"\d+", parts[k]):
            ignored += 1
            continue
        key = (parts[0], parts[1] if k == 3 else "", parts[k - 1], int(parts[k]))
        if b.get("error_occurred"):
            if key not in [e[0] for e in errors]:
                errors.append((key, str(b.get("error_message", ""))))
            continue
        unit = b.get("time_unit", "ns")
        if unit not in TIME_UNITS:
            raise DataError(path, None, "benchmarks[%d] (%s): unknown time_unit '%s'"
                            % (j, b["name"], unit))
        for field in ("real_time", "cpu_time"):
            if not isinstance(b.get(field), (int, float)) or isinstance(b.get(field), bool):
                raise DataError(path, None, "benchmarks[%d] (%s): '%s' is not a number"
                                % (j, b["name"], field))
        run_type = b.get("run_type", "iteration")
        agg = b.get("aggregate_name") if run_type == "aggregate" else None
        if agg not in (None, "mean", "median"):
            continue  # stddev, cv, ...
        counters = {c: float(v) for c, v in b.items()
                    if c not in BENCH_STANDARD_KEYS and isinstance(v, (int, float))
                    and not isinstance(v, bool)}
        entry = {"family": key[0], "what": key[1], "scene": key[2], "n": key[3],
                 "real_time": float(b["real_time"]) * TIME_UNITS[unit],
                 "cpu_time": float(b["cpu_time"]) * TIME_UNITS[unit],
                 "counters": counters, "label": str(b.get("label", ""))}
        raw.setdefault(key, {}).setdefault(agg, []).append(entry)
    families = {f: [] for f in BENCH_FAMILIES}
    for key in sorted(raw):
        by_agg = raw[key]
        pick = by_agg.get("median") or by_agg.get("mean")
        if pick:
            e = dict(pick[0])
        else:
            its = by_agg[None]
            e = dict(its[0])
            e["real_time"] = float(np.mean([x["real_time"] for x in its]))
            e["cpu_time"] = float(np.mean([x["cpu_time"] for x in its]))
        e["size"] = e["counters"].get("particles", float(e["n"]))
        families[key[0]].append(e)
    entries = []
    for e in families["BM_Step"]:
        c = e["counters"]
        e["integrator"] = e["what"]
        e["kind"] = ("adaptive" if c.get("adaptive") else "implicit" if c.get("implicit")
                     else "explicit")
        entries.append(e)
    context = doc.get("context") if isinstance(doc.get("context"), dict) else {}
    return {"entries": entries, "families": families, "errors": errors, "ignored": ignored,
            "context": context, "path": path}


def _fit_exponent(points):
    """Least-squares slope of log(time) against log(size), or None."""
    pts = [(x, y) for x, y in points if finite(x) and finite(y) and x > 0 and y > 0]
    if len(set(x for x, _ in pts)) < 2:
        return None
    xs = np.log([x for x, _ in pts])
    ys = np.log([y for _, y in pts])
    return float(np.polyfit(xs, ys, 1)[0])


def _met(ok):
    return "met" if ok else "<b>not met</b>"


def _ms(seconds, digits=3):
    return fmt(seconds * 1e3, digits)


def _bench_context_html(bench):
    ctx = bench["context"]
    bits = []
    if ctx.get("date"):
        bits.append("run %s" % esc(ctx["date"]))
    if ctx.get("num_cpus"):
        bits.append("%s CPUs at %s MHz" % (esc(ctx["num_cpus"]), esc(fmt(ctx.get("mhz_per_cpu"), 4))))
    load = ctx.get("load_avg")
    if isinstance(load, list) and load:
        bits.append("load average at start %s" % esc(", ".join(fmt(x, 3) for x in load)))
    if ctx.get("library_build_type"):
        bits.append("Google Benchmark library built as %s" % esc(ctx["library_build_type"]))
    text = ("Measured by <code>springlab_bench</code> (%s). Times are the CPU time of the one "
            "benchmark thread (a one-core figure; wall time, which other processes on a busy "
            "machine inflate, is in the step table too)." % "; ".join(bits))
    return "<p>%s</p>\n" % text


def _exponents(entries):
    """{(integrator, scene): exponent} over the sizes measured (CPU time)."""
    out = {}
    for integ in set(e["integrator"] for e in entries):
        for scene in set(e["scene"] for e in entries):
            pts = [(e["size"], e["cpu_time"]) for e in entries
                   if e["integrator"] == integ and e["scene"] == scene]
            s = _fit_exponent(pts)
            if s is not None:
                out[(integ, scene)] = s
    return out


def _step_table(entries, slopes, integrators):
    order = integrators.sort(set(e["integrator"] for e in entries))
    out = ["<details open><summary>Step cost, every entry (%d)</summary>\n<table><tr>"
           "<th>integrator</th><th>scene</th><th>n</th><th>particles</th><th>step</th>"
           "<th>CPU / step [ms]</th><th>wall / step [ms]</th><th>CPU s per simulated s</th>"
           "<th>force evals / step</th><th>Newton / step</th><th>linear solves / step</th>"
           "<th>factorizations / step</th><th>internal steps / step</th><th>restarts</th>"
           "<th>exponent</th></tr>\n" % len(entries)]
    for e in sorted(entries, key=lambda e: (e["scene"], order.index(e["integrator"]), e["size"])):
        c = e["counters"]
        s = slopes.get((e["integrator"], e["scene"]))
        out.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                   "<td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                   "<td>%s</td><td>%s</td></tr>\n"
                   % (swatch(integrators, e["integrator"]), esc(e["scene"]), e["n"],
                      fmt(e["size"], 6), esc(e["label"]), _ms(e["cpu_time"], 4),
                      _ms(e["real_time"], 4), fmt(c.get("cpu_per_sim_second"), 3),
                      fmt(c.get("force_evals_per_step"), 3), fmt(c.get("newton_per_step"), 3),
                      fmt(c.get("linear_solves_per_step"), 3),
                      fmt(c.get("factorizations_per_step"), 3),
                      fmt(c.get("internal_steps_per_step"), 3), fmt(c.get("restarts"), 3),
                      "%.2f" % s if s is not None else "–"))
    out.append("</table></details>\n")
    return "".join(out)


def _exponent_table(entries, slopes, integrators):
    kinds = {e["integrator"]: e["kind"] for e in entries}
    rows = []
    for integ in integrators.sort(kinds):
        for scene in sorted(set(e["scene"] for e in entries)):
            s = slopes.get((integ, scene))
            if s is None:
                continue
            sizes = sorted(set(e["n"] for e in entries
                               if e["integrator"] == integ and e["scene"] == scene))
            kind = kinds[integ]
            if kind == "explicit":
                target = "≈ 1.0"
                verdict = _met(TARGET_EXPONENT_EXPLICIT[0] <= s <= TARGET_EXPONENT_EXPLICIT[1])
            elif kind == "implicit":
                target = "≤ %.1f" % TARGET_EXPONENT_IMPLICIT
                verdict = _met(s <= TARGET_EXPONENT_IMPLICIT)
            else:
                target, verdict = "– (cost of 1/60 s)", ""
            rows.append("<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%.2f</td><td>%s</td>"
                        "<td>%s</td></tr>\n" % (swatch(integrators, integ), esc(kind), esc(scene),
                                                esc(", ".join(str(n) for n in sizes)), s,
                                                esc(target), verdict))
    if not rows:
        return ""
    return ("<h3>Step-cost exponents</h3>\n<p>Least-squares slope of log CPU time per step "
            "against log free particles (cost ∝ particles<sup>exponent</sup>).</p>\n"
            "<table><tr><th>integrator</th><th>kind</th><th>scene</th><th>n</th>"
            "<th>exponent</th><th>target</th><th></th></tr>\n%s</table>\n" % "".join(rows))


def _peer_ratios(bench, method=None):
    """{(method, scene, n): (paired ratio or None, separate-run CPU ratio or None)}."""
    fam = bench["families"]
    mine = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    peer = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintStep"]}
    pair = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintPair"]}
    out = {}
    for key in set(peer) | set(pair):
        if method is not None and key[0] != method:
            continue
        paired = pair[key]["counters"].get("ratio") if key in pair else None
        separate = None
        if key in peer and key in mine and peer[key]["cpu_time"] > 0:
            separate = mine[key]["cpu_time"] / peer[key]["cpu_time"]
        out[key] = (paired, separate)
    return out


def _peer_table(bench):
    fam = bench["families"]
    mine = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    peer = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintStep"]}
    pair = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_OdeintPair"]}
    ratios = _peer_ratios(bench)
    rows = []
    for key in sorted(ratios, key=lambda k: (k[0], k[1], k[2])):
        paired, separate = ratios[key]
        s, o, p = mine.get(key), peer.get(key), pair.get(key)
        best = paired if paired is not None else separate
        rows.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(key[0]), esc(key[1]), key[2],
                       fmt(s["cpu_time"] * 1e6, 4) if s else "–",
                       fmt(o["cpu_time"] * 1e6, 4) if o else "–", fmt(separate, 3),
                       fmt(p["counters"].get("springlab_us"), 4) if p else "–",
                       fmt(p["counters"].get("odeint_us"), 4) if p else "–", fmt(paired, 3),
                       _met(best <= TARGET_PEER_RATIO) if finite(best) else "–"))
    if not rows:
        return ""
    return ("<h3>springlab against Boost.Odeint</h3>\n<p>The same model, scene and step "
            "(dt = 0.5/w_max), odeint's <code>runge_kutta4</code> and "
            "<code>symplectic_euler</code> calling the model's own force function. Separate "
            "runs: BM_Step against BM_OdeintStep (CPU time, median of the repetitions). Paired: "
            "BM_OdeintPair, which alternates batches of both inside one benchmark (wall clock), "
            "so a change in the machine's load hits both alike; the verdict uses it when "
            "present. Target: springlab at most %.1f× odeint's time.</p>\n"
            "<table><tr><th>method</th><th>scene</th><th>n</th><th>springlab CPU / step [µs]"
            "</th><th>odeint CPU / step [µs]</th><th>ratio (separate)</th>"
            "<th>springlab / step, paired [µs]</th><th>odeint / step, paired [µs]</th>"
            "<th>ratio (paired)</th><th>≤ %.1f</th></tr>\n%s</table>\n"
            % (TARGET_PEER_RATIO, TARGET_PEER_RATIO, "".join(rows)))


def _force_table(bench):
    force = {(e["scene"], e["n"]): e for e in bench["families"]["BM_Force"]}
    jac = {(e["scene"], e["n"]): e for e in bench["families"]["BM_ForceJacobian"]}
    keys = sorted(set(force) | set(jac), key=lambda k: (k[0], k[1]))
    if not keys:
        return ""
    rows = []
    for k in keys:
        f, j = force.get(k), jac.get(k)
        any_e = f or j
        c = any_e["counters"]
        note = ""
        if f and k == ("cloth", 128):
            note = "target ≤ %g ns/spring: %s" % (TARGET_FORCE_NS, _met(
                f["counters"].get("ns_per_spring", math.inf) <= TARGET_FORCE_NS))
        rows.append("<tr><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(k[0]), k[1], fmt(c.get("springs"), 6), fmt(c.get("unknowns"), 6),
                       fmt(f["cpu_time"] * 1e6, 4) if f else "–",
                       fmt(f["counters"].get("ns_per_spring"), 3) if f else "–",
                       fmt(f["counters"].get("unknowns_per_second"), 3) if f else "–",
                       fmt(j["cpu_time"] * 1e6, 4) if j else "–",
                       fmt(j["counters"].get("ns_per_spring"), 3) if j else "–", note))
    return ("<h3>Force evaluation</h3>\n<p>One evaluation of all forces "
            "(<code>Model::force</code>), and force plus both Jacobians on the "
            "model's fixed pattern (what an implicit method assembles per Newton iteration).</p>\n"
            "<table><tr><th>scene</th><th>n</th><th>springs</th><th>unknowns</th>"
            "<th>force [µs]</th><th>force ns / spring</th><th>unknowns / s</th>"
            "<th>force + Jacobians [µs]</th><th>ns / spring</th><th></th></tr>\n%s</table>\n"
            % "".join(rows))


def _linear_table(bench):
    lin = bench["families"]["BM_LinearSolver"]
    failed = [(key, msg) for key, msg in bench["errors"] if key[0] == "BM_LinearSolver"]
    if not lin and not failed:
        return ""
    rows = []
    keyed = [((e["scene"], e["n"], e["cpu_time"]), e, None) for e in lin]
    keyed += [((key[2], key[3], math.inf), {"what": key[1], "scene": key[2], "n": key[3]}, msg)
              for key, msg in failed]
    for _, e, msg in sorted(keyed, key=lambda r: r[0]):
        if msg is not None:
            rows.append('<tr class="off"><td>%s</td><td>%s</td><td>%d</td><td colspan="7">%s</td>'
                        '</tr>\n' % (esc(e["what"]), esc(e["scene"]), e["n"], esc(msg)))
            continue
        c = e["counters"]
        rows.append("<tr><td>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                    "<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (esc(e["what"]), esc(e["scene"]), e["n"], fmt(c.get("unknowns"), 6),
                       fmt(c.get("factor_nonzeros"), 4), fmt(c.get("factorize_ms"), 4),
                       fmt(c.get("solve_ms"), 4), _ms(e["cpu_time"], 4),
                       fmt(c.get("cg_iterations"), 4), fmt(c.get("initial_residual"), 3)))
    label = next((e["label"] for e in lin if e["label"]), "")
    return ("<h3>Linear solvers</h3>\n<p>The implicit methods' matrix A = M − h dF/dv − "
            "h² dF/dx of the same cloth state (%s), one Newton-iteration's worth of work per "
            "row: direct solvers factorize (symbolic analysis reused, except "
            "<code>ldlt-scratch</code>) and solve; CG sets up its Jacobi preconditioner and "
            "iterates to a relative residual of 1e-8 (warm: from the previous step's solution). "
            "Factorize and solve are the wall-clock split of one iteration, CPU total is the "
            "benchmark's CPU time. Sorted by size, fastest first.</p>\n"
            "<table><tr><th>solver</th><th>scene</th><th>n</th><th>unknowns</th>"
            "<th>factor nonzeros</th><th>factorize [ms]</th><th>solve [ms]</th>"
            "<th>CPU total [ms]</th><th>CG iterations</th><th>CG initial residual</th></tr>\n"
            "%s</table>\n" % (esc(label), "".join(rows)))


def _targets_table(bench, slopes):
    """The performance targets that this file can answer, with the measured figure."""
    fam = bench["families"]
    rows = []
    f = next((e for e in fam["BM_Force"] if (e["scene"], e["n"]) == ("cloth", 128)), None)
    if f and finite(f["counters"].get("ns_per_spring")):
        v = f["counters"]["ns_per_spring"]
        rows.append(("force evaluation, cloth 128: ns per spring", "≤ %g" % TARGET_FORCE_NS,
                     fmt(v, 3), v <= TARGET_FORCE_NS))
    steps = {(e["what"], e["scene"], e["n"]): e for e in fam["BM_Step"]}
    for method in ("rk4", "symplectic-euler"):
        ratios = []
        for key, (paired, separate) in _peer_ratios(bench, method).items():
            r = paired if paired is not None else separate
            if finite(r):
                ratios.append((r, "%s %d" % (key[1], key[2])))
        if ratios:
            worst = max(ratios)
            rows.append(("%s / odeint time, worst scene (%s)" % (method, worst[1]),
                         "≤ %.1f" % TARGET_PEER_RATIO, "%s (best %s)" % (
                             fmt(worst[0], 3), fmt(min(ratios)[0], 3)),
                         worst[0] <= TARGET_PEER_RATIO))
    for method, limit in TARGET_STEP_MS.items():
        e = steps.get((method, "cloth", 64))
        if e:
            ms = e["cpu_time"] * 1e3
            rows.append(("%s, cloth 64, dt 1/60: ms per step" % method, "≤ %g" % limit,
                         fmt(ms, 3), ms <= limit))
    kinds = {e["integrator"]: e["kind"] for e in bench["entries"]}
    for kind, test, target in (
            ("explicit", lambda s: TARGET_EXPONENT_EXPLICIT[0] <= s <= TARGET_EXPONENT_EXPLICIT[1],
             "≈ 1.0"),
            ("implicit", lambda s: s <= TARGET_EXPONENT_IMPLICIT,
             "≤ %.1f" % TARGET_EXPONENT_IMPLICIT)):
        found = sorted((s, integ) for (integ, scene), s in slopes.items()
                       if scene == "cloth" and kinds.get(integ) == kind)
        if found:
            rows.append(("step-cost exponent, %s methods (cloth)" % kind, target,
                         ", ".join("%s %.2f" % (integ, s) for s, integ in found),
                         all(test(s) for s, _ in found)))
    if not rows:
        return ""
    body = "".join('<tr%s><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n'
                   % ("" if ok else ' class="off"', esc(what), esc(target), esc(value), _met(ok))
                   for what, target, value, ok in rows)
    return ("<h3>Measured against the performance targets</h3>\n<table><tr><th>figure</th>"
            "<th>target</th><th>measured</th><th></th></tr>\n%s</table>\n" % body)


def render(bench, ctx):
    integrators, figs = ctx.integrators, ctx.figs
    entries = bench["entries"]
    out = [_bench_context_html(bench)]
    slopes = _exponents(entries)
    if entries:
        out.append(_targets_table(bench, slopes))
        saved, facts = _cost_figure(entries, integrators, figs)
        out.append(figure_html(saved, "CPU seconds per simulated second against size", esc(
            "What a second of simulated motion costs: CPU seconds per simulated second "
            "(counter cpu_per_sim_second = CPU time of one step / its dt) against the number of "
            "free particles, log-log, one panel per scene. Each method steps as it would be "
            "used: explicit ones at dt = 0.5/w_max (the step shrinks as the cloth gets finer), "
            "implicit ones at dt = 1/60 s, adaptive ones (dashed) over 1/60 s at rtol 1e-6. "
            "Above the grey line a second of motion takes more than a second of CPU.")))
        out.append(facts_html(facts))
        out.append(_exponent_table(entries, slopes, integrators))
        out.append(_step_table(entries, slopes, integrators))
    else:
        out.append(note_html("The benchmark file %s has no BM_Step/&lt;integrator&gt;/&lt;scene&gt;/"
                             "&lt;n&gt; entries: no step-cost figure."
                             % esc(Path(bench["path"]).name)))
    out.append(_peer_table(bench))
    out.append(_force_table(bench))
    out.append(_linear_table(bench))
    other = [(key, msg) for key, msg in bench["errors"] if key[0] != "BM_LinearSolver"]
    if other:
        out.append(note_html("Entries that reported an error (not shown): %s." % esc("; ".join(
            "%s: %s" % ("/".join(str(p) for p in key if p != ""), msg) for key, msg in other))))
    if bench["ignored"]:
        out.append(note_html("%d benchmark entr%s with a name this report does not know %s "
                             "not shown." % (bench["ignored"],
                                             "y" if bench["ignored"] == 1 else "ies",
                                             "is" if bench["ignored"] == 1 else "are")))
    return "".join(out)


def _per_sim_second(e):
    """CPU seconds per simulated second: the counter, or CPU per step / dt."""
    c = e["counters"]
    v = c.get("cpu_per_sim_second")
    if finite(v):
        return float(v)
    dt = c.get("dt")
    return e["cpu_time"] / dt if finite(dt) and dt > 0 else math.nan


# The cost figure is drawn for a slide: two panels a row, large type, thick
# lines, one legend for every panel.
COST_RC = {"font.size": 13, "axes.titlesize": 15, "axes.labelsize": 13, "xtick.labelsize": 12,
           "ytick.labelsize": 12, "legend.fontsize": 11}


def _cost_figure(entries, integrators, figs):
    """Per scene: cost against size (log-log) when it was measured at several
    sizes, else one bar per method (log scale)."""
    import matplotlib.pyplot as plt
    scenes = sorted(set(e["scene"] for e in entries))
    sized = [sc for sc in scenes if len(set(e["size"] for e in entries if e["scene"] == sc)) > 1]
    ordered = sized + [sc for sc in scenes if sc not in sized]
    cols = min(2, len(ordered))
    rows = (len(ordered) + cols - 1) // cols
    facts = []
    with plt.rc_context(COST_RC):
        fig = new_figure(7.0 * cols + 3.2, 5.6 * rows)
        axes = fig.subplots(rows, cols, squeeze=False)
        for j, scene in enumerate(ordered):
            ax = axes[j // cols, j % cols]
            mine = [e for e in entries if e["scene"] == scene]
            if scene in sized:
                _cost_lines(ax, mine, integrators)
            else:
                _cost_bars(ax, mine, integrators)
            ax.set_title("%s%s" % (scene, "" if scene in sized else ", %d free particles"
                                   % int(mine[0]["size"])), loc="left", fontweight="bold")
            facts.extend(_cost_facts(scene, mine))
        for j in range(len(ordered), rows * cols):
            axes[j // cols, j % cols].set_visible(False)
        # One legend for all panels, in the integrators' order.
        handles = {}
        for ax in axes.flat:
            for h, label in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(label, h)
        names = integrators.sort(handles)
        if names:
            axes[0, cols - 1].legend([handles[n] for n in names], names, loc="upper left",
                                     bbox_to_anchor=(1.02, 1.0), frameon=False, borderaxespad=0.0,
                                     handlelength=2.6)
        saved = figs.save(fig, "bench-cost.png")
    return saved, facts


def _cost_lines(ax, mine, integrators):
    for name in integrators.sort(set(e["integrator"] for e in mine)):
        pts = sorted((e["size"], _per_sim_second(e)) for e in mine if e["integrator"] == name)
        n = np.array([p[0] for p in pts], dtype=float)
        c = np.array([p[1] for p in pts])
        ok = (n > 0) & np.isfinite(c) & (c > 0)
        ax.plot(n[ok], c[ok], ms=9, mfc="none", mew=1.8, lw=2.2, label=name,
                **integrators.style(name))
    if log_log(ax):
        ax.axhline(1.0, color="0.5", lw=1.6, zorder=1)
        ax.text(0.99, 1.0, "real time ", transform=ax.get_yaxis_transform(), va="bottom",
                ha="right", color="0.35", fontsize=12)
        sizes = sorted(set(e["size"] for e in mine if e["size"] > 0))
        if 0 < len(sizes) <= 12:
            from matplotlib.ticker import NullFormatter, ScalarFormatter
            ax.set_xticks(sizes)
            ax.xaxis.set_major_formatter(ScalarFormatter())
            ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("free particles")
    ax.set_ylabel("CPU s per simulated s")
    ax.grid(True, which="major", alpha=0.3)
    ax.grid(True, which="minor", alpha=0.1)


def _cost_bars(ax, mine, integrators):
    costs = sorted((_per_sim_second(e), e["integrator"]) for e in mine
                   if finite(_per_sim_second(e)) and _per_sim_second(e) > 0)
    ys = np.arange(len(costs))
    ax.barh(ys, [c for c, _ in costs], color=[integrators.colour(n) for _, n in costs],
            hatch=None, alpha=0.85)
    ax.set_yticks(ys, [n for _, n in costs], fontsize=11)
    ax.set_xscale("log")
    ax.axvline(1.0, color="0.5", lw=1.6)
    ax.text(1.0, 0.01, "real time ", transform=ax.get_xaxis_transform(), va="bottom",
            ha="right", color="0.35", fontsize=12)
    ax.set_xlabel("CPU s per simulated s")
    ax.grid(True, axis="x", which="major", alpha=0.3)


def _cost_facts(scene, mine):
    """At the largest size measured for every method of the scene: the cheapest
    and the dearest per simulated second, and how far apart."""
    by_size = {}
    for e in mine:
        v = _per_sim_second(e)
        if finite(v) and v > 0:
            by_size.setdefault(e["size"], {})[e["integrator"]] = (v, e)
    if not by_size:
        return []
    size = max(by_size, key=lambda s: (len(by_size[s]), s))
    costs = sorted((v, name, e) for name, (v, e) in by_size[size].items())
    if len(costs) < 2:
        return []
    (lo, lo_name, lo_e), (hi, hi_name, hi_e) = costs[0], costs[-1]
    return ["%s, %d free particles: cheapest per simulated second %s (%s CPU s per s, at %s), "
            "dearest %s (%s CPU s per s, at %s): %s times as much." % (
                scene, int(size), lo_name, fmt(lo), lo_e["label"] or "its step", hi_name, fmt(hi),
                hi_e["label"] or "its step", count(hi / lo) if hi / lo >= 100 else fmt(hi / lo, 2))]
