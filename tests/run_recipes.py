"""Runs the recipes of docs/recipes.md, so that they cannot rot.

A recipe is a fenced block whose info string is `sh recipe` (run with
bash -e -o pipefail) or `python recipe` (run as a script by the Python the
module was built for). A `text output` block after a recipe holds lines its
output (stdout or stderr) must contain:
- each non-blank line must match some output line, spaces collapsed;
- numbers match to the digits written (a float within one unit of its last
  written digit, a whole number exactly), so 0.00287214 stands for
  0.002872135 to 0.002872145 but not for 0.0029;
- `...` inside a line matches any text (a wall time, say); a line that is
  only `...` stands for lines left out and is not checked.
The blocks run in order in one fresh scratch folder (a later block may read
what an earlier one wrote) with the build's springlab and python3 first on
PATH, the Python module on PYTHONPATH, `experiments`, `examples` and `report`
linked to the source's folders (and, with --build-dir, `build/release` to
the build), as if run from the repository's root with
`export PATH=$PWD/build/release:$PATH PYTHONPATH=$PWD/build/release/python`.
Fails (exit 1) on a non-zero exit, a missing expected line, or a document
without recipes.

    python3 tests/run_recipes.py --doc docs/recipes.md --springlab build/release/springlab \
        --pythonpath build/release/python --source-dir . --work /tmp/recipes
"""

import argparse
import decimal
import os
import re
import shutil
import subprocess
import sys
import time

FENCE = re.compile(r"^(`{3,})\s*(\S*)\s*(\S*)\s*$")
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?![\w.])")


class Block:
    def __init__(self, kind, line, text):
        self.kind, self.line, self.text = kind, line, text
        self.expected = []  # (line number, expected line)


def read_blocks(path):
    """The recipe blocks of a Markdown file, each with its expected lines."""
    blocks, current = [], None
    lines = open(path, encoding="utf-8").read().split("\n")
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, lang, marker = m.groups()
        start = i + 1
        i += 1
        while i < len(lines) and not lines[i].startswith(fence):
            i += 1
        if i == len(lines):
            sys.exit("%s:%d: unterminated code block" % (path, start))
        body = lines[start:i]
        i += 1
        if marker == "recipe":
            if lang not in ("sh", "python"):
                sys.exit("%s:%d: a recipe is `sh recipe` or `python recipe`, not `%s recipe`"
                         % (path, start, lang))
            current = Block(lang, start, "\n".join(body) + "\n")
            blocks.append(current)
        elif marker == "output":
            if current is None:
                sys.exit("%s:%d: an output block before any recipe" % (path, start))
            for k, text in enumerate(body):
                if text.strip() and text.strip() != "...":
                    current.expected.append((start + 1 + k, text))
    return blocks


def line_pattern(expected):
    """A regex for one expected line and the numbers written in it."""
    parts, numbers = [], []
    for n, piece in enumerate(" ".join(expected.split()).split("...")):
        if n:
            parts.append(".*")
        pos = 0
        for m in NUMBER.finditer(piece):
            parts.append(re.escape(piece[pos:m.start()]))
            parts.append(r"([-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|nan|inf)")
            numbers.append(m.group())
            pos = m.end()
        parts.append(re.escape(piece[pos:]))
    return re.compile("".join(parts).replace(r"\ ", r"\s+")), numbers


def numbers_agree(written, actual):
    if actual in ("nan", "inf"):
        return False
    if re.fullmatch(r"[-+]?\d+", written):
        return re.fullmatch(r"[-+]?\d+", actual) is not None and int(written) == int(actual)
    digit = decimal.Decimal(1).scaleb(decimal.Decimal(written).as_tuple().exponent)
    return abs(decimal.Decimal(actual) - decimal.Decimal(written)) <= digit


def line_found(expected, output_lines):
    pattern, numbers = line_pattern(expected)
    for out in output_lines:
        m = pattern.fullmatch(" ".join(out.split()))
        if m and all(numbers_agree(w, a) for w, a in zip(numbers, m.groups())):
            return True
    return False


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--doc", required=True)
    ap.add_argument("--springlab", required=True, help="the springlab executable")
    ap.add_argument("--python", default=sys.executable, help="python3 for the recipes")
    ap.add_argument("--pythonpath", help="folder of the springlab module (none: recipes "
                    "that import springlab are skipped)")
    ap.add_argument("--source-dir", required=True, help="the repository (for experiments/)")
    ap.add_argument("--work", required=True, help="scratch folder (emptied first)")
    ap.add_argument("--build-dir", help="the build, linked as build/release (for recipes that "
                    "install it)")
    ap.add_argument("--timeout", type=float, default=240, help="seconds per recipe")
    args = ap.parse_args()

    blocks = read_blocks(args.doc)
    if not blocks:
        sys.exit("%s: no `sh recipe` or `python recipe` block" % args.doc)
    work = os.path.abspath(args.work)
    shutil.rmtree(work, ignore_errors=True)
    bin_dir = os.path.join(work, ".bin")
    os.makedirs(bin_dir)
    os.symlink(os.path.abspath(args.springlab), os.path.join(bin_dir, "springlab"))
    os.symlink(os.path.abspath(args.python), os.path.join(bin_dir, "python3"))
    for folder in ("experiments", "examples", "report"):
        os.symlink(os.path.join(os.path.abspath(args.source_dir), folder), os.path.join(work, folder))
    if args.build_dir:
        os.makedirs(os.path.join(work, "build"))
        os.symlink(os.path.abspath(args.build_dir), os.path.join(work, "build", "release"))
    env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""),
               MPLBACKEND="Agg", PYTHONDONTWRITEBYTECODE="1")
    if args.pythonpath:
        env["PYTHONPATH"] = os.path.abspath(args.pythonpath)

    failures = 0
    total = time.monotonic()
    for n, b in enumerate(blocks, 1):
        where = "%s:%d" % (args.doc, b.line)
        if not args.pythonpath and re.search(r"\bimport springlab\b", b.text):
            print("recipe %d (%s): skipped: the Python module was not built" % (n, where))
            continue
        if b.kind == "sh":
            command = ["bash", "-e", "-o", "pipefail", "-c", b.text]
        else:
            command = [args.python, "-c", b.text]
        start = time.monotonic()
        try:
            r = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True,
                               timeout=args.timeout)
            rc, out, err = r.returncode, r.stdout, r.stderr
        except subprocess.TimeoutExpired as e:
            rc, out, err = "timeout after %g s" % args.timeout, str(e.stdout or ""), \
                str(e.stderr or "")
        seconds = time.monotonic() - start
        output_lines = (out + "\n" + err).split("\n")
        missing = [(k, line) for k, line in b.expected if not line_found(line, output_lines)]
        if rc == 0 and not missing:
            print("recipe %d (%s): ok, %d expected line%s, %.1f s"
                  % (n, where, len(b.expected), "" if len(b.expected) == 1 else "s", seconds))
            continue
        failures += 1
        print("recipe %d (%s): FAILED%s" % (n, where, "" if rc == 0 else " (exit %s)" % rc))
        print("  --- the recipe:\n" + "".join("  | " + t + "\n" for t in b.text.rstrip().split("\n")))
        for k, line in missing:
            print("  missing (%s:%d): %s" % (args.doc, k, line))
        print("  --- its stdout:\n" + "".join("  | " + t + "\n" for t in out.rstrip().split("\n")))
        print("  --- its stderr:\n" + "".join("  | " + t + "\n" for t in err.rstrip().split("\n")))
    print("%d recipe%s, %d failed, %.1f s (scratch folder %s)"
          % (len(blocks), "" if len(blocks) == 1 else "s", failures, time.monotonic() - total, work))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
