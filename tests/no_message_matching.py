"""No code decides by the words of a message (issue 47 item 4).

A refusal, a failure or a parse error travels as data (a type, a field, a
remedy: models/core/refusal.h, experiments/cli/parse_errors.h); no layer
reads another's sentence to decide what to do. This scans the production
sources for a search or comparison against a string literal holding a space
(a phrase: "no projective form", "At Most 1 required"), the shape such
matching takes, and fails naming each. It first proves it catches the lines
the command line once had.

    python3 tests/no_message_matching.py SOURCE_DIR
"""
import pathlib
import re
import sys

# .find("a phrase"), .rfind(...), .startswith/.endswith/.count(...), ==/!= "a phrase",
# "a phrase" in text (Python): a literal holding a space, searched for or compared.
PHRASE = r'"[^"\n]* [^"\n]*"'
PATTERNS = [
    re.compile(r"\.(find|rfind|compare|starts_with|ends_with|startswith|endswith|count|index)\(\s*" + PHRASE),
    re.compile(r"[=!]=\s*" + PHRASE),
    re.compile(PHRASE + r"\s*[=!]="),
    re.compile(PHRASE + r"\s+(not\s+)?in\s+\w"),
]
ROOTS = ["models", "integrators", "experiments", "python", "web", "report"]
SUFFIXES = {".cc", ".h", ".py", ".js"}

# Lines that search a literal holding a space, each with why it stays. An
# entry is a (path, text on the line) pair. The report's three are labels
# the experiments write as text (to become columns of their own).
ALLOWED = [
    # nlohmann's exception text starts with its id; dropped for display only.
    ("models/core/strict_json.cc", 'message.find("] ")'),
    # The loop's own axis name (cost "wall time" or "steps"), not a message.
    ("report/springlab_report/kinds/work_precision.py", 'what == "wall time"'),
    # The caption shortens the reference's source sentence at its clause.
    ("report/springlab_report/kinds/fluid.py", 'source.find(": the surge front")'),
]


def hits(text):
    for number, line in enumerate(text.splitlines(), 1):
        code = line.split("//")[0] if not line.lstrip().startswith("#") else ""
        if any(p.search(code) for p in PATTERNS):
            yield number, line.strip()


def main():
    root = pathlib.Path(sys.argv[1])
    # The check catches what it is for: the lines cli.cc had before.
    old = '''    if (why.find("no projective form") != std::string::npos && has("model")) {
      what.find("At Most 1 required") != std::string::npos) {
  if (what == "A subcommand is required") {
    cut = source.find(": the surge front")'''
    caught = len(list(hits(old)))
    if caught != 4:
        print("no_message_matching: the scan caught %d of the 4 sample lines" % caught)
        return 1
    found = []
    for top in ROOTS:
        for path in sorted((root / top).rglob("*")):
            if path.suffix not in SUFFIXES or not path.is_file() or "tests" in path.parts:
                continue
            relative = path.relative_to(root).as_posix()
            for number, line in hits(path.read_text(errors="replace")):
                if any(relative == p and t in line for p, t in ALLOWED):
                    continue
                found.append("%s:%d: %s" % (relative, number, line))
    for f in found:
        print(f)
    if found:
        print("no_message_matching: %d line(s) decide by a message's words: carry the "
              "decision as data instead" % len(found))
        return 1
    print("no_message_matching: no code matches message text (%s scanned)" % ", ".join(ROOTS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
