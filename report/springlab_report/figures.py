"""Saving figures deterministically and the drawing helpers several kinds
share (log axes, slope triangles, legends), plus the small HTML pieces a
figure comes with."""

import base64
import html
import io
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402  (matplotlib's own dependency)

DPI = 100
# No "Software" (matplotlib version) in the PNG: the same data gives the same bytes.
SAVE_METADATA = {"Software": None}
RC = {"font.size": 10, "axes.titlesize": 11, "svg.hashsalt": "springlab", "path.simplify": True,
      "agg.path.chunksize": 20000, "legend.fontsize": 8}


# Figures are stored as 256-colour PNGs: line plots on white use few
# colours, and the palette makes each PNG (and so the page, which embeds
# them) about a third of the full-colour size. No dithering, so the same
# figure gives the same bytes.
PALETTE_COLOURS = 256


def palette_png(rgba_png):
    """A PNG's bytes as a 256-colour PNG (median cut, no dithering)."""
    image = Image.open(io.BytesIO(rgba_png)).convert("RGB")
    quantized = image.quantize(colors=PALETTE_COLOURS, method=Image.Quantize.MEDIANCUT,
                               dither=Image.Dither.NONE)
    out = io.BytesIO()
    quantized.save(out, format="PNG", optimize=True)
    return out.getvalue()


class Figures:
    """Writes each figure as a PNG into the output directory and keeps its bytes."""

    def __init__(self, outdir):
        self.outdir = outdir
        self.saved = []  # (filename, png bytes)

    def save(self, fig, filename):
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=DPI, metadata=SAVE_METADATA, bbox_inches="tight",
                    pad_inches=0.12)
        plt.close(fig)
        data = palette_png(buf.getvalue())
        (self.outdir / filename).write_bytes(data)
        self.saved.append((filename, data))
        return filename, data


def new_figure(width, height):
    return plt.figure(figsize=(width, height), layout="constrained")


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return "%.*g" % (digits, x)


def count(x):
    """A count or a large number, whole: "4860", not "4.86e+03"."""
    return "%d" % round(x) if abs(x) >= 100 else fmt(x, 3)


def names_list(names):
    """"a", "a and b", "a, b and c"."""
    names = list(names)
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def fraction(x):
    """A fraction of a scale, unsigned: "100%", "6.9%", "0.62%" from 1e-3 up,
    else plain: "4e-15"."""
    x = abs(x)
    if x >= 0.1:
        return "%.0f%%" % (100.0 * x)
    if x >= 1e-3:
        return "%.2g%%" % (100.0 * x)
    return fmt(x, 2)


def esc(text):
    return html.escape(str(text), quote=True)


def figure_html(saved, alt, caption):
    filename, data = saved
    uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    return ('<figure><img src="%s" alt="%s"><figcaption>%s <a href="%s">(%s)</a></figcaption>'
            '</figure>\n' % (uri, esc(alt), caption, esc(filename), esc(filename)))


def note_html(text, cls="report-note"):
    return '<p class="%s">%s</p>\n' % (cls, text)


def facts_html(sentences, heading="What the data shows"):
    """Sentences computed from the data, as a list under a figure."""
    if not sentences:
        return ""
    return ('<div class="facts"><b>%s</b><ul>%s</ul></div>\n'
            % (esc(heading), "".join("<li>%s</li>" % esc(s) for s in sentences)))


def swatch(integrators, name):
    return '<span class="sw" style="background:%s"></span>%s' % (integrators.colour(name),
                                                                 esc(name))


def log_log(ax, empty_text="no points to draw (none finite and positive)"):
    """Log scales on both axes when the panel has something to show;
    otherwise a message instead of an empty (or unscalable) panel."""
    if any(len(line.get_xdata()) for line in ax.lines):
        ax.set_xscale("log")
        ax.set_yscale("log")
        return True
    ax.set_xticks([])
    ax.set_yticks([])
    ax.text(0.5, 0.5, empty_text, transform=ax.transAxes, ha="center", va="center", color="0.4")
    return False


def slope_triangle(ax, x0, y0, slope, width_decades=0.5, below=True, label=None, color="0.25"):
    """A right triangle of the given slope on log-log axes with its corner at
    (x0, y0): a run of `width_decades` decades and the matching rise, the
    slope written beside the vertical leg."""
    x1 = x0 * 10.0 ** width_decades
    y1 = y0 * 10.0 ** (slope * width_decades)
    if below:
        pts = [(x0, y0), (x1, y0), (x1, y1)] if slope > 0 else [(x0, y0), (x1, y1), (x0, y1)]
    else:
        pts = [(x0, y0), (x0, y1), (x1, y1)]
    xs = [p[0] for p in pts] + [pts[0][0]]
    ys = [p[1] for p in pts] + [pts[0][1]]
    ax.plot(xs, ys, color=color, lw=1.0, zorder=1)
    ax.text(x1 * 10.0 ** 0.04, math.sqrt(y0 * y1), label if label is not None else "%g" % slope,
            color=color, fontsize=9, va="center", ha="left")


def legend_outside(ax, **kw):
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        opts = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False, borderaxespad=0.0,
                    handlelength=2.6)
        opts.update(kw)
        ax.legend(handles, labels, **opts)


def finite_positive(*arrays):
    mask = np.ones(len(arrays[0]), dtype=bool)
    for a in arrays:
        mask &= np.isfinite(a) & (a > 0)
    return mask


# Offsets (points) tried for a point's label, in order: right above, right
# below, left above, left below.
LABEL_OFFSETS = ((5, 4, "left", "bottom"), (5, -4, "left", "top"),
                 (-5, 4, "right", "bottom"), (-5, -4, "right", "top"))


def label_points(ax, candidates, fontsize=7.0, most=None, avoid=()):
    """Labels some points without piling them up: candidates (x, y, text,
    colour) in order of importance; each is drawn at the first offset where
    it stays inside the axes and overlaps no label drawn before it, no text
    already in the axes and no marker at the points `avoid` (x, y), else
    left out. At most `most` labels. Returns the number drawn."""
    from matplotlib.transforms import Bbox
    fig = ax.figure
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    box = ax.get_window_extent(renderer)
    blocked = [t.get_window_extent(renderer) for t in ax.texts]
    r = 3.0 * fig.dpi / 72.0  # a marker's half size
    for x, y in avoid:
        px, py = ax.transData.transform((x, y))
        if np.isfinite(px) and np.isfinite(py):
            blocked.append(Bbox([[px - r, py - r], [px + r, py + r]]))
    placed = []
    for x, y, text, colour in candidates:
        if most is not None and len(placed) >= most:
            break
        for dx, dy, ha, va in LABEL_OFFSETS:
            t = ax.annotate(text, (x, y), textcoords="offset points", xytext=(dx, dy), ha=ha,
                            va=va, fontsize=fontsize, color=colour)
            bb = t.get_window_extent(renderer)
            if bb.x0 >= box.x0 and bb.x1 <= box.x1 and bb.y0 >= box.y0 and bb.y1 <= box.y1 \
                    and not any(bb.overlaps(p) for p in placed + blocked):
                placed.append(bb)
                break
            t.remove()
    return len(placed)
