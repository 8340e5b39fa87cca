"""Build, one after another, every simulator model that ``make test`` runs: the core and its
presets on Verilator and Icarus, the bus tops, the campaigns' build, the C driver.

``make test`` calls this before its pytest workers start. The workers share the build
directories (sim/shared/runner.py: one lock per directory), so without it the first worker to
need a model builds it while the other waits on the lock; built here first, each model is built
once with the whole machine (Verilator's make runs its own jobs) and the workers find them up
to date. Building is all this does: nothing is checked, the tests do that.

Each build's output (the compilers') goes to its log, sim_build/prebuild/<model>.log; the
terminal gets one line per model: its name, the time and ok. A build that fails prints its
log's last lines and stops the prebuild with exit status 1.

    python -m sim.tools.prebuild
"""

import functools
import re
import sys
import time

from sim.shared import discovery, runner
from sim.shared.runner import output_to

LOGS = runner.BUILD / "prebuild"
#: Lines of a failed build's log printed.
TAIL = 40


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


def log_path(name):
    """sim_build/prebuild/<name>.log, the name in lower case with '-' for what is not a letter
    or digit ("verilator axil bus top" -> verilator-axil-bus-top.log)."""
    return LOGS / (re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") + ".log")


def main():
    todo = models()
    LOGS.mkdir(parents=True, exist_ok=True)
    width = max(len(name) for name, _ in todo)
    for name, build in todo:
        log = log_path(name)
        t0 = time.perf_counter()
        error = None
        try:
            with output_to(log):
                build()
        except KeyboardInterrupt:
            raise
        except BaseException as e:          # the runner raises SystemExit on a failed build
            error = e
        took = f"{time.perf_counter() - t0:6.1f} s"
        if error is None:
            print(f"prebuild: {name:<{width}} {took}  ok", flush=True)
            continue
        print(f"prebuild: {name:<{width}} {took}  FAILED ({error!r})")
        lines = log.read_text(errors="replace").splitlines()
        print(f"--- the last {min(TAIL, len(lines))} of {len(lines)} lines of {log} ---")
        print("\n".join(lines[-TAIL:]))
        print(f"--- end of {log} ---", flush=True)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
