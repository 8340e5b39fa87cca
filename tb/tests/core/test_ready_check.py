"""ReadyCheck on Amaranth's simulator: every input combination against the documented priority.

The decision of WAIT_READY (docs/timing.md, "States"; the block's docstring): a configuration
refused in the wait's first clock ends the request (BAD_CONFIG) before anything else, then an
abort, then SLO high for the quiet time starts the cycle (SLO high for less: wait on, never
stuck), then SLO low past the timeout limit is SLO_STUCK_LOW; both limits taken from the live
setting in the first clock (the latched one is not valid yet).
"""

import itertools

from bissmaster.core.ready_check import ReadyCheck

from testkit.block_sim import run_clocks

INPUTS = ["first_clock", "config_ok", "abort", "slo", "slo_stuck", "slo_stuck_live", "quiet",
          "quiet_live"]
OUTPUTS = ["bad_config", "aborted", "ready", "stuck_low"]


def expected(first_clock, config_ok, abort, slo, slo_stuck, slo_stuck_live, quiet, quiet_live):
    """The one way the wait ends in this clock, or None (wait on)."""
    if first_clock and not config_ok:
        return "bad_config"
    if abort:
        return "aborted"
    if slo:
        return "ready" if (quiet_live if first_clock else quiet) else None
    if (slo_stuck_live if first_clock else slo_stuck):
        return "stuck_low"
    return None


def test_ready_check_every_input_combination():
    combos = list(itertools.product((0, 1), repeat=len(INPUTS)))
    trace = run_clocks(ReadyCheck(), [dict(zip(INPUTS, c)) for c in combos], OUTPUTS)
    for combo, row in zip(combos, trace):
        want = expected(*combo)
        assert {name for name in OUTPUTS if row[name]} == ({want} if want else set()), combo
