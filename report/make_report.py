#!/usr/bin/env python3
"""Render the springlab course experiments as one HTML page.

    python3 report/make_report.py --data DIR --out OUTDIR [--bench FILE.json] [--lab LAB.html]

Reads only what springlab writes (the data contract is experiments/README.md):
each experiment's settings file <name>.json, which names its tables and their
columns, the tables themselves, integrators.json (`springlab list --json`:
every integrator's family, stability, colour and marker), and optionally
springlab_bench's Google Benchmark JSON (--bench FILE.json, or else
benchmarks.json in DIR). Writes one PNG per figure into OUTDIR and
OUTDIR/index.html with every figure embedded; the experiments' full tables
and settings files are copied into OUTDIR/data/ and linked from the page,
which shows summaries (docs/experiments-and-report.md "The report page and
its data"). With --lab build/web/lab.html (the WebAssembly lab page,
docs/browser-lab.md) the page is copied to OUTDIR/lab.html and linked when it
exists.

The code is the package report/springlab_report/: data.py reads, one module
per experiment kind in kinds/ draws (kinds/__init__.py is the registry),
page.py assembles the page. An experiment whose files are missing is skipped
with a note on the page; a malformed file stops the script with a message
naming the file and line (exit status 1); a figure that fails to draw is
shown as an error on the page (exit status 1). Without matplotlib/numpy the
exit status is 2. The same data gives byte-identical PNGs and HTML.
"""

import sys
from pathlib import Path

PROG = "make_report.py"

try:
    import matplotlib  # noqa: F401
    import numpy  # noqa: F401
except Exception as exc:  # noqa: BLE001 - any import failure means "not usable"
    sys.stderr.write("%s: error: cannot import matplotlib/numpy (%s); install python3-matplotlib "
                     "python3-numpy\n" % (PROG, exc))
    sys.exit(2)

sys.path.insert(0, str(Path(__file__).resolve().parent))

from springlab_report.main import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
