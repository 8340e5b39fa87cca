"""Command-line tools, each run as ``python -m sim.tools.<name>`` from the repository root:
demo, perf (make bench), soak, campaign_report."""
