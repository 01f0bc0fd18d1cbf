"""Pieces several kinds share: grouping a per-case table into panels, the
panel titles, and the collapsible table of runs."""

from ..figures import esc, fmt, swatch


def case_panels(table):
    """Panels of a per-case table (energy, damping budget): rows grouped by
    task and integrator; the k-th run of an integrator on the same (scene, dt)
    belongs to the k-th case with that scene and dt (two cases may share a
    scene's name). Returns {(scene, dt text, case number): {integrator: rows}}."""
    seen = {}
    panels = {}
    for (task, name), idx in table.groups("task", "integrator").items():
        base = (table.text("scene")[idx[0]], table.text("dt")[idx[0]])
        k = seen.get((base, name), 0)
        seen[(base, name)] = k + 1
        panels.setdefault(base + (k,), {})[name] = idx
    return panels


def panel_title(scene, dt, case, panels):
    title = scene
    if any(key[:2] == (scene, dt) and key[2] > 0 for key in panels):
        title += " (case %d)" % (case + 1)
    if dt:
        title += ", dt = %s s" % fmt(float(dt), 6)
    return title


def runs_table(runs, integrators, heading, cols):
    out = ['<details><summary>%s (%d)</summary>\n<table><tr><th>scene</th><th>integrator</th>'
           '<th>dt [s]</th>' % (esc(heading), len(runs))]
    out += ["<th>%s</th>" % esc(label) for _, label, _ in cols]
    out.append("</tr>\n")
    for r in range(len(runs)):
        row = runs.row(r)
        bad = row.get("status", "completed") != "completed"
        out.append('<tr%s><td>%s</td><td>%s</td><td>%s</td>' % (
            ' class="off"' if bad else "", esc(row["scene"]), swatch(integrators, row["integrator"]),
            fmt(float(row["dt"]), 6) if row.get("dt") else "–"))
        for c, _, digits in cols:
            v = row.get(c, "")
            if digits is None or v == "":
                out.append("<td>%s</td>" % (esc(v) if v != "" else "–"))
            else:
                out.append("<td>%s</td>" % fmt(float(v), digits))
        out.append("</tr>\n")
    out.append("</table></details>\n")
    return "".join(out)
