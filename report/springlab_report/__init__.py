"""The springlab report: reads what `springlab experiment` and `springlab
list --json` wrote (experiments/README.md is the data contract) and draws
one HTML page with the full tables beside it. Entry point: report/make_report.py."""
