"""The page: one section per experiment (its kind module draws it), the
integrator table, the benchmarks, and the settings each experiment used."""

import json
import shutil
import traceback
from urllib.parse import quote

import matplotlib.pyplot as plt

from .figures import esc, fmt, note_html, swatch
from .integrators import FAMILY_TITLES

CSS = """
body { box-sizing: border-box; font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 0 auto;
       max-width: 1400px; padding: 0 1.5em 3em; color: #222; line-height: 1.45; }
h1 { margin-top: 0.8em; } h2 { border-bottom: 2px solid #ddd; padding-bottom: 0.2em; margin-top: 2em; }
figure { margin: 1em 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.92em; color: #444; max-width: 75em; }
table { border-collapse: collapse; margin: 0.6em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }
th { background: #f3f3f3; } td { font-variant-numeric: tabular-nums; }
tr.off td { background: #ffe1dc; }
table.kv th { font-weight: normal; color: #555; }
.sw { display: inline-block; width: 0.9em; height: 0.9em; margin-right: 0.35em;
      vertical-align: -0.1em; border-radius: 2px; }
.facts { background: #eef6ee; border-left: 4px solid #5a9a5a; padding: 0.4em 0.8em; max-width: 75em; }
.facts ul { margin: 0.3em 0; padding-left: 1.3em; }
.theory { max-width: 75em; }
.report-note { background: #fff8d6; border-left: 4px solid #e0b400; padding: 0.4em 0.8em; }
.report-error { background: #ffd9d9; border-left: 4px solid #c00000; padding: 0.4em 0.8em;
                white-space: pre-wrap; font-family: monospace; }
pre { background: #f7f7f7; padding: 0.6em; overflow-x: auto; font-size: 0.82em; max-height: 40em; }
details { margin: 0.4em 0; overflow-x: auto; } summary { cursor: pointer; }
.player-panels { display: flex; flex-wrap: wrap; gap: 6px; }
.player-panel { border: 1px solid #ddd; background: #fff; }
.player-panel canvas { display: block; }
.player-label { font-size: 0.8em; padding: 0 4px 3px; max-width: 292px; }
.player-value { color: #555; }
.player-flag { color: #b00000; font-weight: bold; }
.player-controls { margin: 0.3em 0; } .player-slider { width: 30em; vertical-align: middle; }
#report-status { color: #888; font-size: 0.8em; margin-top: 3em; }
"""

# Marks the page for tests/report/check_report.py: counts images that did not
# load, and turns script errors and failed images into .report-error elements.
SCRIPT = """
(function () {
  function fail(text) {
    var d = document.createElement('div');
    d.className = 'report-error';
    d.textContent = text;
    (document.body || document.documentElement).appendChild(d);
  }
  window.addEventListener('error', function (e) {
    var t = e.target;
    if (t && t.tagName === 'IMG') fail('image failed to load: ' + (t.alt || t.src.slice(0, 60)));
    else fail('script error: ' + e.message);
  }, true);
  window.addEventListener('load', function () {
    var imgs = document.images, broken = [];
    for (var i = 0; i < imgs.length; i++) {
      if (!imgs[i].complete || imgs[i].naturalWidth === 0) broken.push(imgs[i].alt || ('#' + i));
    }
    document.body.dataset.imagesTotal = String(imgs.length);
    document.body.dataset.imagesBroken = String(broken.length);
    var s = document.getElementById('report-status');
    s.dataset.state = 'checked';
    s.textContent = 'Page check: ' + imgs.length + ' images, ' + broken.length + ' broken' +
      (broken.length ? ' (' + broken.join(', ') + ')' : '') + '.';
  });
})();
"""


# The experiments' files are copied beside the page, into OUTDIR/data/, and
# linked relatively: the page holds summaries, the full tables are a click
# away, also when the page is opened from file://.
DATA_SUBDIR = "data"
# A scene shown inline in its settings only up to this size (a 64 x 64
# cloth is megabytes of JSON); larger ones are shortened, the file linked.
SCENE_INLINE_CHARS = 20000
# In the settings shown on the page, lists of objects longer than this keep
# their first few entries (the whole file is linked beside them).
LIST_KEEP = 3
LIST_LIMIT = 12


class DataFiles:
    """Copies data files into OUTDIR/data/ and gives the relative links to them."""

    def __init__(self, outdir):
        self.dir = outdir / DATA_SUBDIR
        self.copied = []

    def link(self, path, text=None):
        """A link to a copy of `path` beside the page (copied once)."""
        if path.name not in self.copied:
            self.dir.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, self.dir / path.name)
            self.copied.append(path.name)
        return '<a href="%s/%s">%s</a>' % (DATA_SUBDIR, esc(quote(path.name)),
                                           esc(text if text is not None else path.name))


def size_text(nbytes):
    """A file size as a reader wants it: "512 B", "38 kB", "18.2 MB"."""
    if nbytes < 1000:
        return "%d B" % nbytes
    if nbytes < 1e6:
        return "%.0f kB" % (nbytes / 1e3)
    return "%.1f MB" % (nbytes / 1e6)


class Context:
    """What a kind module draws with: the integrator table, the figure saver,
    the data files beside the page."""

    def __init__(self, integrators, figs, files=None):
        self.integrators = integrators
        self.figs = figs
        self.files = files if files is not None else DataFiles(figs.outdir)


def attempt(errors, what, fn, *args):
    """fn(*args) as HTML; a failure becomes a .report-error on the page and an
    error in the exit status, and the rest of the page is still drawn."""
    try:
        return fn(*args)
    except Exception:  # noqa: BLE001 - shown on the page and in the exit status
        plt.close("all")
        tb = traceback.format_exc()
        errors.append("%s: %s" % (what, tb.strip().splitlines()[-1]))
        return '<div class="report-error">%s failed:\n%s</div>\n' % (esc(what), esc(tb))


def section(exp, module, ctx, errors, first_of_kind=None):
    """One experiment's section. `first_of_kind`: the earlier section of the
    same kind (name, title), whose "What to look for" this one would repeat
    word for word: it links there instead."""
    body = [note_html(esc(n)) for n in exp.notes]
    if first_of_kind is None:
        body.append('<p class="theory"><b>What to look for.</b> %s</p>\n' % esc(module.ABOUT))
    else:
        body.append('<p class="theory"><b>What to look for.</b> The same as in '
                    '<a href="#%s">%s</a> (the same kind of experiment, %s); this section\'s '
                    'settings below say what differs.</p>\n'
                    % (esc(first_of_kind[0]), esc(first_of_kind[1]), esc(exp.kind)))
    if exp.tables:
        body.append(attempt(errors, "%s (%s)" % (exp.name, exp.kind), module.render, exp, ctx))
    else:
        body.append(note_html("No data for this experiment: skipped."))
    body.append(attempt(errors, "%s settings" % exp.name, settings_html, exp, ctx.integrators,
                        ctx.files))
    return ('<section id="%s"><h2>%s <small>(%s: %s)</small></h2>\n%s</section>\n'
            % (esc(exp.name), esc(exp.title()), esc(exp.kind), esc(exp.name), "".join(body)))


def marker_text(marker):
    """A marker as a reader sees it: matplotlib's mathtext markers ("$4$",
    "$\\alpha$") are drawn as the text between the dollars."""
    if len(marker) > 2 and marker.startswith("$") and marker.endswith("$"):
        inner = marker[1:-1]
        return {"\\alpha": "\u03b1"}.get(inner, inner)
    return marker


def integrators_html(integrators, names):
    """The integrators of this report with the facts springlab states for them."""
    rows = []
    for n in integrators.sort(names):
        s = integrators.stability(n)
        rows.append("<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n"
                    % (swatch(integrators, n), esc(FAMILY_TITLES.get(integrators.family(n),
                                                                     integrators.family(n))),
                       esc(fmt(integrators.order(n))), esc(s.get("text", "–")),
                       esc(marker_text(integrators.marker(n))),
                       esc(integrators.get(n, "scheme", "–"))))
    source = ("from %s (springlab list --json)" % esc(integrators.source.name)
              if integrators.source else "<b>integrators.json is missing</b>: colours from a "
              "fixed palette, families and stability unknown")
    return ('<section id="integrators"><h2>The integrators</h2>\n<p>Every figure draws each '
            'method in its own colour and marker, %s; fixed-step methods solid, adaptive ones '
            'dashed. The stability property is the one the program declares and '
            'tests/test_stability_property.cc measures.</p>\n<table><tr><th>integrator</th>'
            '<th>family</th><th>order</th><th>stability</th><th>marker</th><th>scheme</th></tr>\n'
            '%s</table></section>\n' % (source, "".join(rows)))


def find_scenes(obj, path=""):
    """Every scene-file-like object (one with a "particles" list) in the
    settings, outside the copied definition: (where, scene)."""
    if isinstance(obj, dict):
        if isinstance(obj.get("particles"), list):
            return [(path or "scene", obj)]
        out = []
        for k, v in obj.items():
            if k != "definition":
                out.extend(find_scenes(v, "%s.%s" % (path, k) if path else k))
        return out
    if isinstance(obj, list):
        out = []
        for j, v in enumerate(obj):
            out.extend(find_scenes(v, "%s[%d]" % (path, j)))
        return out
    return []


def compact_json(obj, indent=0):
    """Pretty JSON that keeps short arrays/objects (particles, springs) on one line."""
    flat = json.dumps(obj, separators=(", ", ": "), ensure_ascii=False)
    if len(flat) <= 100 or not isinstance(obj, (dict, list)):
        return flat
    pad = "  " * (indent + 1)
    if isinstance(obj, dict):
        items = ["%s%s: %s" % (pad, json.dumps(k, ensure_ascii=False), compact_json(v, indent + 1))
                 for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + "  " * indent + "}"
    items = [pad + compact_json(v, indent + 1) for v in obj]
    return "[\n" + ",\n".join(items) + "\n" + "  " * indent + "]"


def shortened(obj):
    """The settings as shown on the page: a list of more than LIST_LIMIT
    objects or lists (particles, springs, cells), or of more than 40 numbers,
    keeps its first LIST_KEEP entries and says how many more there are."""
    if isinstance(obj, dict):
        return {k: shortened(v) for k, v in obj.items()}
    if isinstance(obj, list):
        nested = any(isinstance(v, (dict, list)) for v in obj)
        if len(obj) > (LIST_LIMIT if nested else 40):
            return [shortened(v) for v in obj[:LIST_KEEP]] + [
                "\u2026 %d more" % (len(obj) - LIST_KEEP)]
        return [shortened(v) for v in obj]
    return obj


def data_files_html(exp, files):
    """Links to the experiment's settings file and its full tables, copied
    beside the page, with their sizes and rows."""
    items = []
    for suffix in sorted(exp.tables, key=lambda k: (k != "", k)):
        t = exp.tables[suffix]
        items.append("%s (%s row%s, %s)" % (files.link(t.path), "{:,}".format(len(t)),
                                            "" if len(t) == 1 else "s",
                                            size_text(t.path.stat().st_size)))
    items.append("%s (the settings, %s)" % (files.link(exp.settings_path),
                                            size_text(exp.settings_path.stat().st_size)))
    return "<p><b>Data</b> (CSV tables and the settings file, beside this page): %s.</p>\n" % (
        ", ".join(items))


def run_options(names, runs):
    """Per integrator of the settings, " (key value, ...)" from its run's
    options when the settings list one run per integrator (so that a method
    run twice, e.g. with stiffness exact and definite, is told apart), else
    ""."""
    if not (isinstance(runs, list) and len(runs) == len(names) and
            all(isinstance(r, dict) and r.get("integrator") == n for r, n in zip(runs, names))):
        return [""] * len(names)
    out = []
    for r in runs:
        options = ["%s %s" % (k, v if isinstance(v, str) else json.dumps(v))
                   for k, v in r.items() if k != "integrator"]
        out.append(" (%s)" % ", ".join(options) if options else "")
    return out


def settings_html(exp, integrators, files=None):
    s = exp.settings
    if not s:
        return ""
    out = ["<h3>Scene and settings used <small>(%s)</small></h3>\n" % esc(exp.settings_path.name)]
    if files is not None:
        out.append(data_files_html(exp, files))
    desc = s.get("description")
    if isinstance(desc, str) and desc:
        out.append("<p>%s</p>\n" % esc(desc))
    names = s.get("integrators")
    if isinstance(names, list):
        out.append("<p><b>Integrators</b>: %s</p>\n" % ", ".join(
            swatch(integrators, str(n)) + esc(options) for n, options in
            zip(names, run_options(names, s.get("runs")))))
    simple = []
    for k, v in s.items():
        if k in ("name", "experiment", "title", "description", "integrators", "definition",
                 "tables"):
            continue
        if isinstance(v, (int, float, str)) and not isinstance(v, bool) or \
                (isinstance(v, list) and len(v) <= 40 and all(isinstance(x, (int, float, str))
                                                              for x in v)):
            simple.append("<tr><th>%s</th><td>%s</td></tr>" % (esc(k), esc(json.dumps(v))))
    if simple:
        out.append("<table class=\"kv\">%s</table>\n" % "".join(simple))
    seen = []
    for where, scene in find_scenes(s):
        text = compact_json(scene)
        name = scene.get("name") if isinstance(scene.get("name"), str) else where
        npart, nspring = len(scene.get("particles") or []), len(scene.get("springs") or [])
        label = "Scene %s — %d particle%s, %d spring%s" % (
            esc(name), npart, "" if npart == 1 else "s", nspring, "" if nspring == 1 else "s")
        if text in seen:
            continue
        seen.append(text)
        if len(text) > SCENE_INLINE_CHARS:
            label += " (%s of JSON, shortened here: the whole scene is %s in %s)" % (
                size_text(len(text)), esc(where), esc(exp.settings_path.name))
            text = compact_json(shortened(scene))
        out.append("<details><summary>%s</summary><pre>%s</pre></details>\n" % (label, esc(text)))
    out.append("<details><summary>The settings file %s (long lists shortened; the whole file is "
               "linked above)</summary><pre>%s</pre></details>\n"
               % (esc(exp.settings_path.name), esc(compact_json(shortened(s)))))
    return "".join(out)


def page(title, intro, notes, toc, body, errors):
    out = ["<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
           "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
           "<title>%s</title>\n<style>%s</style>\n<script>%s</script>\n</head>\n<body>\n"
           % (esc(title), CSS, SCRIPT), "<h1>%s</h1>\n" % esc(title), intro]
    if errors:
        out.append('<div class="report-error">%d part%s of this report failed to render: %s</div>\n'
                   % (len(errors), "" if len(errors) == 1 else "s", esc("; ".join(errors))))
    out.extend(note_html(esc(n)) for n in notes)
    out.append("<nav><b>Contents</b><ul>%s</ul></nav>\n" % "".join(
        '<li><a href="#%s">%s</a></li>' % (esc(anchor), esc(text)) for anchor, text in toc))
    out.extend(body)
    out.append('<p id="report-status" data-state="pending">Page check pending (needs '
               'JavaScript).</p>\n</body>\n</html>\n')
    return "".join(out)
