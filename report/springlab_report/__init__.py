"""The springlab report: reads what `springlab experiment` and `springlab
list --json` wrote (experiments/README.md is the data contract) and draws
one self-contained HTML page. Entry point: report/make_report.py."""
