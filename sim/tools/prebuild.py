"""Build, one after another, every simulator model that ``make test`` runs: the core and its
presets on Verilator and Icarus, the bus tops, the campaigns' build, the C driver.

``make test`` calls this before its pytest workers start. The workers share the build
directories (sim/shared/runner.py: one lock per directory), so without it the first worker to
need a model builds it while the other waits on the lock; built here first, each model is built
once with the whole machine (Verilator's make runs its own jobs) and the workers find them up
to date. Building is all this does: nothing is checked, the tests do that.

    python -m sim.tools.prebuild
"""

import functools
import sys

from sim.shared import discovery, runner


def models():
    """(name, build) for every model the regression, the bus and driver scenarios and the
    campaign slice use, read from the scenario modules' markers."""
    build = functools.partial
    out = []
    for sim in runner.SIMULATORS:
        presets = {b for module in runner.REGRESSION_SCENARIOS
                   for s in discovery.scenarios(module) for b in s.builds}
        out += [(f"{sim} {p}", build(runner.build_once, sim, p)) for p in sorted(presets)]
        out += [(f"{sim} {bus} bus top", build(runner.build_bus_once, sim, bus))
                for bus in runner.BUSES]
    presets = {b for s in discovery.scenarios(runner.CAMPAIGN_SCENARIOS) for b in s.builds}
    out += [(f"verilator campaigns {p}",
             build(runner.build_once, "verilator", p, internal_clock=True)) for p in sorted(presets)]
    out.append(("C driver", runner.build_driver))
    return out


def main():
    for name, build in models():
        print(f"prebuild: {name}", flush=True)
        build()
    return 0


if __name__ == "__main__":
    sys.exit(main())
