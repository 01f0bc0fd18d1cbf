"""Pieces several kinds share: grouping a per-case table into panels, the
panel titles, and the collapsible table of runs."""

from ..figures import esc, fmt, new_figure, swatch
from ..integrators import FAMILIES, FAMILY_TITLES


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


class FamilyGrid:
    """The energy and damping-budget figures: one row of panels per case, one
    column per family of methods, each panel a set of time series on its own
    linear scale with the methods' colours and markers."""

    def __init__(self, integrators, panels, ylabel):
        present = set(integrators.family(n) for s in panels.values() for n in s)
        self.families = [f for f in FAMILIES if f in present] + sorted(present - set(FAMILIES))
        self.integrators = integrators
        self.ylabel = ylabel
        self.rows = len(panels)
        self.fig = new_figure(3.9 * len(self.families) + 0.3, 3.1 * self.rows + 0.3)
        self.axes = self.fig.subplots(self.rows, len(self.families), squeeze=False)

    def members(self, series, family):
        return [n for n in self.integrators.sort(series) if self.integrators.family(n) == family]

    def line(self, ax, name, k, t, y, label, stopped):
        """The k-th line of a panel: lines drawn first are wider and markers
        are staggered, so lines that coincide (implicit and linear-implicit
        Euler on a linear force) still show every one of them."""
        integ = self.integrators
        ax.plot(t, y, color=integ.colour(name), ls=integ.linestyle(name),
                lw=max(1.0, 3.2 - 1.1 * k), marker=integ.marker(name), ms=6, mfc="none", mew=1.3,
                markevery=(k * max(1, len(t) // 40), max(1, len(t) // 8)), label=label,
                zorder=2 + k)
        if stopped:
            ax.plot([t[-1]], [y[-1]], marker="x", ms=12, mew=2.5, ls="none",
                    color=integ.colour(name), zorder=10)

    def finish(self, row, col, title, t_max, drawn):
        ax = self.axes[row, col]
        family = self.families[col]
        ax.axhline(0.0, color="0.5", lw=0.7, zorder=1)
        ax.set_xlim(0, t_max)
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3), useMathText=True)
        ax.set_title("%s — %s" % (title, FAMILY_TITLES.get(family, family)), loc="left",
                     fontsize=10, fontweight="bold")
        if row == self.rows - 1:
            ax.set_xlabel("t [s]")
        if col == 0:
            ax.set_ylabel(self.ylabel)
        if drawn:
            ax.legend(loc="best", fontsize=7, frameon=True, framealpha=0.85, handlelength=2.8)
        else:
            ax.text(0.5, 0.5, "no %s method in this run" % family, transform=ax.transAxes,
                    ha="center", va="center", color="0.5")


def case_parameters(exp, k):
    """The built-in scene parameters case k of the definition asked for
    ({"n": 64}), or {}: the settings file holds the definition as given."""
    d = exp.setting("definition")
    cases = d.get("cases") if isinstance(d, dict) else None
    if not isinstance(cases, list) or not 0 <= k < len(cases) or not isinstance(cases[k], dict):
        return {}
    p = cases[k].get("parameters")
    return p if isinstance(p, dict) else {}


def case_particles(exp, k):
    """The number of particles of case k's scene in the settings, or None."""
    cases = exp.setting("cases")
    try:
        return len(cases[k]["scene"]["particles"])
    except (KeyError, IndexError, TypeError):
        return None


def scene_title(exp, k, scene):
    """A scene's name with what sets its size: "cloth (n = 64, 4096 particles)"."""
    parts = ["%s = %s" % (key, fmt(v) if isinstance(v, (int, float)) else v)
             for key, v in case_parameters(exp, k).items()]
    particles = case_particles(exp, k)
    if particles is not None:
        parts.append("%d particles" % particles)
    return "%s (%s)" % (scene, ", ".join(parts)) if parts else scene


def case_index(exp, scene, dt):
    """The index of the first case of the settings with this scene name and
    step (dt as text from a table), or None."""
    cases = exp.setting("cases")
    if not isinstance(cases, list):
        return None
    for k, c in enumerate(cases):
        try:
            if c["scene"]["name"] == scene and (dt is None or float(c["dt"]) == float(dt)):
                return k
        except (KeyError, TypeError, ValueError):
            continue
    return None
