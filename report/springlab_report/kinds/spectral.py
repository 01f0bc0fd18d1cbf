"""spectral: the classic figure of structural dynamics (Hughes, "The Finite
Element Method", 1987, ch. 9; Chung and Hulbert 1993, figs. 1-3): for each
fixed-step method, the spectral radius of its amplification matrix, its
algorithmic damping ratio and its relative period error against w h on the
undamped oscillator x'' = -w^2 x, as the C++ side measured them from the
method's own steps (experiments/analysis/spectral.h). Beside them, the theory of the
Newmark family and the alpha methods, computed here from their closed-form
amplification matrix, so the figure checks the measurement and the
implementation at once."""

import math

import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.lines import Line2D

from ..data import Columns
from ..figures import esc, facts_html, figure_html, fmt, names_list, new_figure

KIND = "spectral"
TITLE = "Spectral radius, damping and period error"
ABOUT = (
    "One step of a fixed-step method multiplies the state of an undamped oscillator x'' = −w² x "
    "by its amplification matrix, which depends on w h alone. Its spectral radius ρ (the largest "
    "|eigenvalue|) must stay ≤ 1: explicit methods leave at a limit w h (2 for the central "
    "difference, Verlet and symplectic Euler, 2.83 for RK4), A-stable ones never do. A method "
    "that conserves a linear system's energy (Newmark's average acceleration, the implicit "
    "midpoint rule) keeps ρ = 1 and a damping ratio ξ = 0 at every w h; the alpha methods keep "
    "ρ ≈ 1 for the resolved modes (small w h) and fall to their ρ∞ for the unresolved ones, "
    "and L-stable methods (implicit Euler, BDF2) to 0. The relative period error T_h/T − 1 "
    "grows like (w h)² for the second-order methods ((w h)²/12 for average acceleration), "
    "faster for the higher-order ones.")

# Thresholds of the sentences and the table.
STABLE_TOL = 1e-9       # rho <= 1 + this counts as stable (the measured limit)
UNDAMPED_TOL = 1e-6     # |rho - 1| <= this at every stable w h: no numerical damping
AGREE_TOL = 1e-6        # measured against theory: agreement
WH_SMALL = 0.1          # where the table reads xi and the period error

# The panels' y ranges (said in the caption).
RHO_RANGE = (0.0, 1.5)
XI_RANGE = (-0.15, 0.6)
PERIOD_RANGE = (1e-10, 1e3)

# The Newmark family's members as the C++ side defines them (integrators/
# newmark.h, generalized_alpha.h): the parameters when the settings give none.
NEWMARK_BETA = {"newmark": 0.25, "central-difference": 0.0, "linear-acceleration": 1.0 / 6.0,
                "fox-goodwin": 1.0 / 12.0}
HHT_DEFAULT_ALPHA = -0.1
GENERALIZED_ALPHA_DEFAULT_RHO = 0.5
# Drawn as theory curves (the others of the family are only compared in a sentence).
THEORY_DRAWN = ("newmark", "generalized-alpha")

GROUPS = (("newmark", "Newmark family and alpha methods"),
          ("implicit", "other implicit methods"),
          ("rest", "explicit and symplectic methods"))


# ---------------------------------------------------------------------------
# Theory: the generalized-alpha step (Chung and Hulbert 1993, eqs. 2-5) with
# Newmark (alpha_m = alpha_f = 0) and HHT (alpha_m = 0) as special cases.

def generalized_alpha_parameters(rho_inf):
    """(alpha_m, alpha_f, beta, gamma) from the spectral radius at infinity."""
    r = float(rho_inf)
    am = (2.0 * r - 1.0) / (r + 1.0)
    af = r / (r + 1.0)
    return am, af, (1.0 - am + af) ** 2 / 4.0, 0.5 - am + af


def hht_parameters(alpha):
    """(alpha_m, alpha_f, beta, gamma) of Hilber-Hughes-Taylor's alpha in [-1/3, 0]."""
    a = float(alpha)
    return 0.0, -a, (1.0 - a) ** 2 / 4.0, 0.5 - a


def newmark_parameters(integrator, options=None):
    """(alpha_m, alpha_f, beta, gamma) of a Newmark-family method with the
    options of its settings entry, or None for a method outside the family."""
    o = options or {}

    def get(key, default):
        v = o.get(key)
        return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else default

    if integrator == "newmark":
        return 0.0, 0.0, get("beta", 0.25), get("gamma", 0.5)
    if integrator in NEWMARK_BETA:
        return 0.0, 0.0, NEWMARK_BETA[integrator], 0.5
    if integrator == "hht-alpha":
        return hht_parameters(get("alpha", HHT_DEFAULT_ALPHA))
    if integrator == "generalized-alpha":
        return generalized_alpha_parameters(get("rho_inf", GENERALIZED_ALPHA_DEFAULT_RHO))
    return None


def amplification_matrix(wh, params):
    """The 3x3 matrix A with (x, h v, h^2 a)_{n+1} = A (x, h v, h^2 a)_n on
    x'' = -w^2 x: the step's three equations, L y_{n+1} = R y_n,
        x1 = x0 + h v0 + h^2 ((1/2 - beta) a0 + beta a1)
        v1 = v0 + h ((1 - gamma) a0 + gamma a1)
        (1 - alpha_m) a1 + alpha_m a0 = -w^2 ((1 - alpha_f) x1 + alpha_f x0),
    solved for y_{n+1} (Hughes 1987, sec. 9.1.2; Chung and Hulbert 1993)."""
    am, af, beta, gamma = params
    o2 = float(wh) ** 2
    lhs = np.array([[1.0, 0.0, -beta],
                    [0.0, 1.0, -gamma],
                    [o2 * (1.0 - af), 0.0, 1.0 - am]])
    rhs = np.array([[1.0, 1.0, 0.5 - beta],
                    [0.0, 1.0, 1.0 - gamma],
                    [-o2 * af, 0.0, -am]])
    return np.linalg.solve(lhs, rhs)


def spectral_measures(matrix, wh):
    """(rho, xi, period error) of an amplification matrix, defined as the
    C++ side does: rho = max |lambda|; the principal pair is the complex pair
    of largest modulus, xi = -ln|lambda| / arg lambda, T_h/T - 1 =
    w h / arg lambda - 1; NaN for both without a complex root."""
    roots = np.linalg.eigvals(matrix)
    rho = float(np.max(np.abs(roots)))
    pair = [z for z in roots if abs(z.imag) > 1e-12 * abs(z)]
    if not pair:
        return rho, math.nan, math.nan
    z = max(pair, key=abs)
    angle = abs(math.atan2(z.imag, z.real))
    return rho, -math.log(abs(z)) / angle, wh / angle - 1.0


def theory(params, wh):
    """Arrays (rho, xi, period error) of a Newmark-family method over w h."""
    out = np.array([spectral_measures(amplification_matrix(x, params), x)
                    for x in np.atleast_1d(np.asarray(wh, dtype=float))])
    return out[:, 0], out[:, 1], out[:, 2]


# ---------------------------------------------------------------------------
# The measured rows, one record per method.

class Method:
    def __init__(self, label, integrator, options, wh, rho, xi, period, degree):
        order = np.argsort(wh)
        self.label, self.integrator, self.options = label, integrator, options
        self.wh, self.rho, self.xi = wh[order], rho[order], xi[order]
        self.period, self.degree = period[order], degree[order]
        self.params = newmark_parameters(integrator, options)
        # rho = 0 exactly after the method went unstable: its steps overflowed
        # and no sequence was left to fit (not a measurement; not drawn).
        grew = np.maximum.accumulate(np.where(np.isfinite(self.rho), self.rho, 0.0)) \
            > 1.0 + STABLE_TOL
        bad = np.zeros(len(self.rho), dtype=bool)
        bad[1:] = grew[:-1] & (self.rho[1:] == 0.0)
        self.overflowed = self.wh[bad]
        for a in (self.rho, self.xi, self.period):
            a[bad] = np.nan
        self.colour = None
        self.marker = None

    def limit(self):
        """(last stable w h or None, first unstable w h or None): the grid's
        bracket of the stability limit; points without a measurement skipped."""
        last = None
        for x, r in zip(self.wh, self.rho):
            if not np.isfinite(r):
                continue
            if r > 1.0 + STABLE_TOL:
                return last, float(x)
            last = float(x)
        return last, None

    def stable_everywhere(self):
        last, first_bad = self.limit()
        return last is not None and first_bad is None

    def at(self, wh):
        """Index of the grid point nearest to wh (on the log scale)."""
        return int(np.argmin(np.abs(np.log(self.wh / wh))))

    def last_finite(self):
        ok = np.flatnonzero(np.isfinite(self.rho))
        return int(ok[-1]) if len(ok) else None

    def missing(self):
        """Points without a measurement other than the overflowed ones."""
        return int(np.sum(~np.isfinite(self.rho))) - len(self.overflowed)


def read_methods(exp):
    t = Columns(exp.table(), numbers=("wh", "spectral_radius", "damping_ratio", "period_error",
                                      "degree"), texts=("method", "integrator"))
    options = {}
    for entry in exp.setting("methods") or []:
        if isinstance(entry, dict) and isinstance(entry.get("label"), str):
            options[entry["label"]] = entry
    methods = []
    for (label, integrator), idx in t.groups("method", "integrator").items():
        methods.append(Method(label, integrator, options.get(label), t["wh"][idx],
                              t["spectral_radius"][idx], t["damping_ratio"][idx],
                              t["period_error"][idx], t["degree"][idx]))
    return methods


def group_of(integ, m):
    if m.params is not None:
        return "newmark"
    return "implicit" if integ.family(m.integrator) == "implicit" else "rest"


def ordered(integ, methods):
    """Methods by group, then as the integrator table sorts them (family,
    name), variants of one integrator in the order of the data."""
    rank = {n: k for k, n in enumerate(integ.sort(m.integrator for m in methods))}
    first = {}
    for k, m in enumerate(methods):
        first.setdefault(m.label, k)
    keys = [g for g, _ in GROUPS]
    return sorted(methods, key=lambda m: (keys.index(group_of(integ, m)), rank[m.integrator],
                                          first[m.label]))


def style(integ, methods):
    """Each method's colour and marker: its integrator's; a second or third
    variant of one integrator darker, then lighter, so they stay apart."""
    seen = {}
    for m in methods:
        k = seen.get(m.integrator, 0)
        seen[m.integrator] = k + 1
        base = np.array(to_rgb(integ.colour(m.integrator)))
        if k == 0:
            rgb = base
        elif k % 2 == 1:
            rgb = base * (0.55 if k == 1 else 0.35)
        else:
            rgb = base + (1.0 - base) * 0.5
        m.colour = "#%02x%02x%02x" % tuple(int(round(255 * c)) for c in np.clip(rgb, 0, 1))
        m.marker = integ.marker(m.integrator)


# ---------------------------------------------------------------------------
# The figure.

def _line(ax, m, k, x, y, **extra):
    n = len(x)
    step = max(1, n // 7)
    kw = dict(color=m.colour, lw=1.6, marker=m.marker, ms=6.5, mfc="none", mew=1.3,
              markevery=((k * max(1, step // 4)) % step, step), zorder=3 + 0.1 * k)
    kw.update(extra)
    ax.plot(x, y, **kw)


def _period_parts(ax, m, k):
    """|T_h/T - 1| on a log axis: solid where the period lengthens, dotted
    where it shortens (T_h < T)."""
    p = m.period
    for sign, ls in ((1.0, "-"), (-1.0, ":")):
        y = np.where(np.isfinite(p) & (sign * p > 0), np.abs(p), np.nan)
        if np.any(np.isfinite(y)):
            _line(ax, m, k, m.wh, y, ls=ls)


def draw(integ, methods, theory_methods, wh_range):
    groups = [(key, title, [m for m in methods if group_of(integ, m) == key])
              for key, title in GROUPS]
    groups = [g for g in groups if g[2]]
    fig = new_figure(16.0, 3.5 * len(groups) + 0.4)
    axes = fig.subplots(len(groups), 3, squeeze=False)
    dense = np.logspace(math.log10(wh_range[0]), math.log10(wh_range[1]), 400)
    curves = {m.label: theory(m.params, dense) for m in theory_methods}
    dashed = dict(color="black", lw=0.9, ls=(0, (4, 2.5)), zorder=20)
    for row, (key, title, members) in enumerate(groups):
        ax_r, ax_x, ax_p = axes[row]
        for k, m in enumerate(members):
            _line(ax_r, m, k, m.wh, m.rho, label=m.label)
            _line(ax_x, m, k, m.wh, m.xi)
            _period_parts(ax_p, m, k)
        drawn = [m for m in theory_methods if m in members]
        for m in drawn:
            rho, xi, period = curves[m.label]
            ax_r.plot(dense, rho, **dashed)
            ax_x.plot(dense, xi, **dashed)
            ax_p.plot(dense, np.where(period > 0, period, np.nan), **dashed)
            ax_p.plot(dense, np.where(period < 0, -period, np.nan), **dashed)
        ax_r.axhline(1.0, color="0.45", lw=0.8, zorder=1)
        ax_x.axhline(0.0, color="0.45", lw=0.8, zorder=1)
        ax_r.set_ylim(*RHO_RANGE)
        ax_x.set_ylim(*XI_RANGE)
        ax_p.set_yscale("log")
        ax_p.set_ylim(*PERIOD_RANGE)
        for ax, what in ((ax_r, "spectral radius ρ"), (ax_x, "damping ratio ξ"),
                         (ax_p, "period error |T_h / T − 1|")):
            ax.set_xscale("log")
            ax.set_xlim(*wh_range)
            ax.grid(True, which="major", alpha=0.3)
            ax.set_ylabel(what)
            ax.set_xlabel("w h")
        # The row's header: across its three panels (the others have no title).
        ax_r.set_title(title[0].upper() + title[1:], loc="left", fontsize=11.5,
                       fontweight="bold")
        handles, labels = ax_r.get_legend_handles_labels()
        if drawn:
            handles.append(Line2D([], [], **dashed))
            labels.append("theory (closed form)")
        ax_p.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.03, 1.0),
                    frameon=False, fontsize=9, handlelength=2.6, borderaxespad=0.0)
    return fig


# ---------------------------------------------------------------------------
# Sentences and table.

def _wh(x):
    """A w h of the grid: "0.01", "2.51", "1000"."""
    return "%d" % round(x) if x >= 100 else fmt(x, 3)


def _num(x, digits=3):
    return fmt(float(x) + 0.0, digits)  # no "-0"


def theory_deviation(m):
    """(max |rho measured - rho theory| / max(rho theory, 1), at w h, max
    |xi difference|) over the w h where both are finite: relative where the
    method is unstable (rho grows without bound there)."""
    rho, xi, _ = theory(m.params, m.wh)
    d = np.abs(m.rho - rho) / np.maximum(rho, 1.0)
    ok = np.isfinite(d)
    if not np.any(ok):
        return None
    j = int(np.flatnonzero(ok)[np.argmax(d[ok])])
    dx = np.abs(m.xi - xi)
    dxi = float(np.max(dx[np.isfinite(dx)])) if np.any(np.isfinite(dx)) else math.nan
    return float(d[j]), float(m.wh[j]), dxi


def facts(integ, methods):
    out = []
    # Theory against measurement, for the Newmark family.
    family = [m for m in methods if m.params is not None]
    devs = [(m, theory_deviation(m)) for m in family]
    devs = [(m, d) for m, d in devs if d is not None]
    if devs:
        worst, (dmax, at, _) = max(devs, key=lambda e: e[1][0])
        xi_max = max((d[2] for _, d in devs if np.isfinite(d[2])), default=math.nan)
        bad = [m.label for m, d in devs if d[0] > AGREE_TOL]
        out.append(
            "Measured against the closed-form amplification matrix of the Newmark family "
            "(%d method%s: %s): the spectral radius differs by at most %s (%s at w h = %s; "
            "relative to ρ where ρ > 1), the damping ratio by at most %s; %s." % (
                len(devs), "" if len(devs) == 1 else "s", names_list([m.label for m, _ in devs]),
                _num(dmax, 2), worst.label, _wh(at), _num(xi_max, 2),
                "every one within %s" % fmt(AGREE_TOL) if not bad else
                "beyond %s: %s" % (fmt(AGREE_TOL), names_list(bad))))
    # No numerical damping.
    undamped_all, undamped_limit = [], []
    for m in methods:
        last, first_bad = m.limit()
        if last is None:
            continue
        ok = np.isfinite(m.rho) & (m.wh <= last)
        if np.all(np.abs(m.rho[ok] - 1.0) <= UNDAMPED_TOL):
            if first_bad is None:
                undamped_all.append(m.label)
            else:
                undamped_limit.append("%s (%s)" % (m.label, fmt(last, 4)))
    parts = []
    if undamped_all:
        parts.append("at every w h up to %s: %s" % (_wh(max(m.wh[-1] for m in methods)),
                                                   names_list(undamped_all)))
    if undamped_limit:
        parts.append("up to their last stable w h: %s" % names_list(undamped_limit))
    if parts:
        out.append("No numerical damping (ρ within %s of 1) %s." % (
            fmt(UNDAMPED_TOL), "; ".join(parts)))
    else:
        out.append("Every method damps (ρ more than %s below 1) somewhere below its limit."
                   % fmt(UNDAMPED_TOL))
    # The damping of the unconditionally stable ones at the largest w h.
    damped = []
    for m in methods:
        j = m.last_finite()
        if j is None or not m.stable_everywhere() or m.rho[j] >= 1.0 - UNDAMPED_TOL:
            continue
        damped.append((float(m.rho[j]), m.label, float(m.wh[j])))
    if damped:
        damped.sort()
        whs = set(x for _, _, x in damped)
        where = "at w h = %s" % _wh(damped[0][2]) if len(whs) == 1 else "at the largest w h"
        out.append("Stable at every w h and damping the unresolved modes, ρ %s (the smaller, "
                   "the more of a stiff mode one step removes): %s." % (where, ", ".join(
                       "%s %s" % (label, _num(r, 2) if len(whs) == 1 else
                                  "%s (w h = %s)" % (_num(r, 2), _wh(x)))
                       for r, label, x in damped)))
    # The limits of the conditionally stable ones against integrators.json.
    limits = []
    for m in methods:
        last, first_bad = m.limit()
        if first_bad is None:
            continue
        stated = integ.stability(m.integrator).get("limit_wh")
        stated = float(stated) if isinstance(stated, (int, float)) and stated > 0 else None
        if m.label != m.integrator:
            stated = None  # a variant: the table states the default's limit
        if last is None:
            text = "%s none (ρ > 1 from w h = %s)" % (m.label, _wh(first_bad))
        else:
            text = "%s (%s, %s]" % (m.label, fmt(last, 4), fmt(first_bad, 4))
        if stated is not None:
            if last is not None and stated < last * (1 - 1e-9):
                text += " (stated %s, but ρ ≤ 1 at the grid point %s above it)" % (
                    fmt(stated, 4), fmt(last, 4))
            elif stated > first_bad * (1 + 1e-9):
                text += " (stated %s, but ρ > 1 at the grid point %s below it)" % (
                    fmt(stated, 4), fmt(first_bad, 4))
            else:
                text += " (stated %s)" % fmt(stated, 4)
        limits.append(text)
    if limits:
        out.append("Conditionally stable: the stability limit lies between the last w h with "
                   "ρ ≤ 1 and the first with ρ > 1 on the grid: %s." % "; ".join(limits))
    # Period error at w h = 0.1.
    at = []
    for m in methods:
        j = m.at(WH_SMALL)
        if np.isfinite(m.period[j]):
            at.append((abs(float(m.period[j])), float(m.period[j]), m.label, float(m.wh[j])))
    if at:
        x = at[0][3]
        newmark = [e for e in at if e[2] == "newmark"]
        head = "At w h = %s the relative period error is" % _wh(x)
        bits = []
        if newmark and newmark[0][3] == x:
            bits.append("%s for newmark (theory (w h)²/12 = %s)" % (_num(newmark[0][1], 3),
                                                                    _num(x * x / 12.0, 3)))
        at.sort()
        small = at[:3]
        large = at[-3:][::-1]
        bits.append("smallest in magnitude for %s" % ", ".join("%s (%s)" % (label, _num(v, 2))
                                                          for _, v, label, _ in small))
        bits.append("largest for %s" % ", ".join("%s (%s)" % (label, _num(v, 2))
                                                 for _, v, label, _ in large))
        shorter = [label for _, v, label, _ in sorted(at, key=lambda e: e[2]) if v < 0]
        if shorter:
            bits.append("negative (a shorter period) for %s" % names_list(shorter))
        out.append("%s %s." % (head, "; ".join(bits)))
    overflowed = [m for m in methods if len(m.overflowed)]
    if overflowed:
        out.append("Reported ρ = 0 after going unstable (the steps overflowed and nothing was "
                   "left to measure; not drawn, not counted): %s." % ", ".join(
                       "%s from w h = %s (%d point%s)" % (
                           m.label, _wh(m.overflowed[0]), len(m.overflowed),
                           "" if len(m.overflowed) == 1 else "s") for m in overflowed))
    missing = [(m.label, m.missing()) for m in methods if m.missing()]
    if missing:
        out.append("No measurement (a step failed) at some w h: %s." % ", ".join(
            "%s (%d)" % e for e in missing))
    return out


def table_html(methods):
    last_wh = max((m.wh[-1] for m in methods), default=math.nan)
    x = methods[0].wh[methods[0].at(WH_SMALL)] if methods else WH_SMALL
    out = ['<table><tr><th>method</th><th>ρ at w h = %s</th><th>stable up to w h '
           '(ρ ≤ 1 + %s)</th><th>ξ at w h = %s</th><th>T_h/T − 1 at w h = %s</th>'
           '<th>order of the recurrence seen</th></tr>\n' % (
               esc(_wh(last_wh)), esc(fmt(STABLE_TOL)), esc(_wh(x)), esc(_wh(x)))]
    for m in methods:
        j = m.last_finite()
        rho_last = "–" if j is None else (esc(_num(m.rho[j], 3)) if m.wh[j] == last_wh else
                                          "%s (w h = %s)" % (esc(_num(m.rho[j], 3)),
                                                             esc(_wh(m.wh[j]))))
        last, first_bad = m.limit()
        if first_bad is None:
            limit = "every w h (%s)" % esc(_wh(last)) if last is not None else "–"
        elif last is None:
            limit = "none (ρ > 1 from %s)" % esc(_wh(first_bad))
        else:
            limit = esc(fmt(last, 4))
        k = m.at(WH_SMALL)
        degrees = sorted(set(int(d) for d in m.degree if np.isfinite(d)))
        out.append('<tr><td><span class="sw" style="background:%s"></span>%s</td><td>%s</td>'
                   '<td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n' % (
                       esc(m.colour), esc(m.label), rho_last, limit, esc(_num(m.xi[k], 3)),
                       esc(_num(m.period[k], 3)),
                       esc("–".join(str(d) for d in (degrees[0], degrees[-1]))
                           if len(degrees) > 1 else (str(degrees[0]) if degrees else "–"))))
    out.append("</table>\n")
    return "".join(out)


def render(exp, ctx):
    integ = ctx.integrators
    methods = ordered(integ, read_methods(exp))
    style(integ, methods)
    finite_wh = [x for m in methods for x in m.wh if np.isfinite(x) and x > 0]
    lo = exp.setting("wh_min", min(finite_wh) if finite_wh else 1e-2)
    hi = exp.setting("wh_max", max(finite_wh) if finite_wh else 1e3)
    theory_methods = [m for m in methods if m.integrator in THEORY_DRAWN
                      and m.params is not None]
    fig = draw(integ, methods, theory_methods, (float(lo), float(hi)))
    saved = ctx.figs.save(fig, exp.name + ".png")
    caption = (
        "What one step does to an undamped mode of frequency w, against w h (log axis), one row "
        "of panels per group of methods: the spectral radius ρ of the amplification matrix "
        "(axis clipped to [%s, %s]: an unstable method leaves through the top at its limit), "
        "the algorithmic damping ratio ξ (axis clipped to [%s, %s]; no point where the "
        "method's principal roots are real, i.e. it no longer oscillates) and the relative "
        "period error |T_h/T − 1| (log axis from %s; solid where the period lengthens, dotted "
        "where it shortens). Coloured lines with markers are measured from each method's own "
        "steps; thin black dashed lines are the theory of %s from the closed-form "
        "amplification matrix." % (
            fmt(RHO_RANGE[0]), fmt(RHO_RANGE[1]), fmt(XI_RANGE[0]), fmt(XI_RANGE[1]),
            fmt(PERIOD_RANGE[0]),
            names_list([m.label for m in theory_methods]) if theory_methods
            else "no method of this run"))
    return (figure_html(saved, "spectral radius, damping ratio and period error against w h",
                        esc(caption)) + facts_html(facts(integ, methods)) +
            "<details open><summary>Per method</summary>\n" + table_html(methods) +
            "</details>\n")
