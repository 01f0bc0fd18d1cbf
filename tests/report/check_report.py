#!/usr/bin/env python3
"""Check a rendered springlab report in headless Chromium.

    python3 tests/report/check_report.py --html OUTDIR/index.html
        [--chromium /usr/bin/chromium] [--screenshot OUT.png] [--timeout SECONDS]

Loads the page with `chromium --headless --dump-dom` and reads the marker that
the report page's inline script (report/springlab_report/page.py) writes on window load: the body's
data-images-total / data-images-broken and the element id="report-status".
Fails (exit 1, naming the problem) when an image did not load, when the page
has no images, when the page shows an error (an element with class
"report-error", which the script also adds for a script error or a failed
image), when the marker is missing (the script did not run), when a motion
player did not advance at least 5 frames or left a panel's canvas empty (its
data-frames-drawn, data-panels and data-nonempty-panels, which player.js
computes from the canvas pixels), or when Chromium is not installed or fails.
Before Chromium it reads the file itself: it fails when the page is larger
than --max-bytes (default 6 MB), when a relative link (href, src) names a
file that is not there (the CSV tables and settings copied beside the page),
or when the page holds text escaped twice (`&amp;#x27;`, `&amp;gt;`: shown
to the reader as raw entities). Prints "report OK: N images" on success.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote

PROG = "check_report.py"
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync"]
CANDIDATES = ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"]


class Fail(Exception):
    pass


class DomScan(HTMLParser):
    """Collects what the check needs from the dumped DOM."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.body_attrs = None
        self.status_attrs = None
        self.status_text = []
        self.in_status = 0
        self.images = 0
        self.players = []      # attributes of each <figure class="player">
        self.errors = []       # texts of .report-error elements
        self._error_depth = []  # stack of open elements; index of .report-error openings
        self._stack = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "body":
            self.body_attrs = a
        if tag == "img":
            self.images += 1
        if tag == "figure" and "player" in (a.get("class") or "").split():
            self.players.append(a)
        if tag in VOID:
            return
        classes = (a.get("class") or "").split()
        is_error = "report-error" in classes
        self._stack.append((tag, is_error))
        if is_error:
            self.errors.append([])
        if a.get("id") == "report-status":
            self.status_attrs = a
            self.in_status = len(self._stack)

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        # Pop to the matching tag (the dumped DOM is well formed).
        while self._stack:
            t, _ = self._stack.pop()
            if self.in_status and len(self._stack) < self.in_status:
                self.in_status = 0
            if t == tag:
                break

    def handle_data(self, data):
        if self.in_status:
            self.status_text.append(data)
        if any(err for _, err in self._stack) and self.errors:
            self.errors[-1].append(data)


VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source",
        "track", "wbr"}


def find_chromium(given):
    if given:
        if os.path.isfile(given) and os.access(given, os.X_OK):
            return given
        found = shutil.which(given)
        if found:
            return found
        raise Fail("Chromium not found at %s (install it: apt-get install -y "
                   "--no-install-recommends chromium)" % given)
    for name in CANDIDATES:
        found = shutil.which(name)
        if found:
            return found
    raise Fail("Chromium is not installed (looked for %s on PATH); install it: "
               "apt-get install -y --no-install-recommends chromium" % ", ".join(CANDIDATES))


def run_chromium(chromium, extra, url, timeout):
    with tempfile.TemporaryDirectory(prefix="check-report-") as profile:
        cmd = [chromium] + CHROMIUM_FLAGS + ["--user-data-dir=" + profile] + extra + [url]
        try:
            proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired:
            raise Fail("Chromium did not finish within %g s: %s" % (timeout, " ".join(cmd))) \
                from None
        except OSError as exc:
            raise Fail("cannot run %s: %s" % (chromium, exc)) from None
    if proc.returncode != 0:
        tail = proc.stderr.decode("utf-8", "replace").strip().splitlines()[-5:]
        raise Fail("Chromium exited with status %d:\n  %s" % (proc.returncode, "\n  ".join(tail)))
    return proc.stdout.decode("utf-8", "replace")


# An entity whose '&' was escaped again: the reader sees "&#x27;" or "&gt;".
TWICE_ESCAPED = re.compile(r"&amp;(#x?[0-9a-fA-F]+|[a-zA-Z]+);")
LINK = re.compile(r'(?:href|src)="([^"]*)"')


def file_problems(page, max_bytes):
    """What is wrong with the page as a file: its size, links to files that
    are not there, text escaped twice."""
    problems = []
    size = page.stat().st_size
    if size > max_bytes:
        problems.append("the page is %d bytes, more than %d" % (size, max_bytes))
    text = page.read_text(encoding="utf-8")
    missing = []
    for link in LINK.findall(text):
        if not link or link.startswith(("data:", "#", "http:", "https:", "mailto:")):
            continue
        target = page.parent / Path(*unquote(link.split("#")[0]).split("/"))
        if not target.is_file():
            missing.append(link)
    if missing:
        problems.append("%d link(s) to files that are not beside the page: %s"
                        % (len(missing), ", ".join(sorted(set(missing))[:10])))
    twice = sorted(set(m.group(0) for m in TWICE_ESCAPED.finditer(text)))
    if twice:
        problems.append("text escaped twice (shown as raw entities): %s" % ", ".join(twice))
    return problems


def check(args):
    page = Path(args.html)
    if not page.is_file():
        raise Fail("%s: no such file" % page)
    problems = file_problems(page, args.max_bytes)
    chromium = find_chromium(args.chromium)
    url = page.resolve().as_uri()
    dom = run_chromium(chromium, ["--dump-dom", "--virtual-time-budget=10000"], url, args.timeout)
    if not dom.strip():
        raise Fail("Chromium dumped an empty DOM for %s" % url)
    scan = DomScan()
    scan.feed(dom)
    scan.close()
    if scan.errors:
        for text in scan.errors:
            first = " ".join("".join(text).split())
            problems.append("the page shows an error: %s" % (first[:300] or "(empty .report-error)"))
    body = scan.body_attrs or {}
    total, broken = body.get("data-images-total"), body.get("data-images-broken")
    if scan.status_attrs is None:
        problems.append('the page has no element id="report-status" (not made by make_report.py?)')
    elif scan.status_attrs.get("data-state") != "checked" or total is None or broken is None:
        problems.append("the page's check script did not run (no image counts on <body>; "
                        "report-status says: %s)" % " ".join("".join(scan.status_text).split()))
    else:
        try:
            total_n, broken_n = int(total), int(broken)
        except ValueError:
            raise Fail("bad image counts on <body>: total=%r broken=%r" % (total, broken)) from None
        if broken_n:
            problems.append("%d of %d images failed to load (%s)" % (
                broken_n, total_n, " ".join("".join(scan.status_text).split())))
        if total_n == 0 or scan.images == 0:
            problems.append("the page has no images")
        if total_n != scan.images:
            problems.append("the script counted %d images but the DOM has %d <img>"
                            % (total_n, scan.images))
    # The players (report/springlab_report/player.js) must have advanced and
    # drawn something in every panel (read from their canvas pixels).
    for p in scan.players:
        name = p.get("id", "a player")
        drawn, panels, nonempty = (p.get("data-frames-drawn"), p.get("data-panels"),
                                   p.get("data-nonempty-panels"))
        try:
            drawn, panels, nonempty = int(drawn), int(panels), int(nonempty)
        except (TypeError, ValueError):
            problems.append("%s did not run (frames drawn %r, panels %r, non-empty %r)"
                            % (name, drawn, panels, nonempty))
            continue
        if drawn < 5:
            problems.append("%s drew %d frames, expected it to play" % (name, drawn))
        if panels == 0 or nonempty != panels:
            problems.append("%s: %d of %d panels are empty" % (name, panels - nonempty, panels))
    if args.expect_players and not scan.players:
        problems.append("the page has no player (figure.player)")
    if args.screenshot:
        shot = Path(args.screenshot).resolve()
        shot.parent.mkdir(parents=True, exist_ok=True)
        run_chromium(chromium, ["--screenshot=" + str(shot), "--window-size=1400,3000",
                                "--hide-scrollbars", "--virtual-time-budget=10000"], url,
                     args.timeout)
        if not shot.is_file() or shot.stat().st_size == 0:
            problems.append("Chromium wrote no screenshot to %s" % shot)
        else:
            print("screenshot: %s" % shot)
    if problems:
        raise Fail("\n  ".join(["%s:" % page] + problems))
    return scan.images, len(scan.players)


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("--html", required=True, help="the report page (OUTDIR/index.html)")
    ap.add_argument("--chromium", help="Chromium binary (default: chromium on PATH)")
    ap.add_argument("--screenshot", help="also write a 1400x3000 screenshot PNG here")
    ap.add_argument("--expect-players", action="store_true",
                    help="fail when the page has no motion player")
    ap.add_argument("--max-bytes", type=int, default=6_000_000,
                    help="fail when the page is larger (default 6,000,000)")
    ap.add_argument("--timeout", type=float, default=120.0,
                    help="seconds to allow each Chromium run (default 120)")
    args = ap.parse_args(argv)
    try:
        n, players = check(args)
    except Fail as exc:
        sys.stderr.write("%s: FAIL: %s\n" % (PROG, exc))
        return 1
    print("report OK: %d images, %d players playing" % (n, players))
    return 0


if __name__ == "__main__":
    sys.exit(main())
