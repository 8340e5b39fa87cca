"""CdmHold on Amaranth's simulator: random input sequences against a model of its contract.

The contract (docs/timing.md, "CDM"; docs/control.md; the block's docstring): the cycle's CDM
bit is copied in every idle clock; MA is held low after a CDM = 1 frame: while the frame is
clocked out unless aborted, and after it until SLO is seen high, SLO has been low for the
timeout limit, or an abort (the release); never otherwise.
"""

import random

import pytest

from bissmaster.core.cdm_hold import CdmHold

from testkit.block_sim import run_clocks

OUTPUTS = ["cdm_cycle", "ma_hold"]


def model(steps):
    cdm_cycle = 0
    rows = []
    for s in steps:
        if s["framing"]:
            hold = cdm_cycle and not s["abort"]
        elif s["holding"]:
            hold = cdm_cycle and not (s["slo"] or s["slo_stuck"] or s["abort"])
        else:
            hold = 0
        rows.append({"cdm_cycle": cdm_cycle, "ma_hold": int(hold)})
        if s["idle"]:
            cdm_cycle = s["cdm"]
    return rows


@pytest.mark.parametrize("seed", range(3))
def test_cdm_hold_random_sequences_follow_the_contract(seed):
    rng = random.Random(seed)
    steps = []
    for _ in range(400):
        state = rng.choice(["idle", "framing", "holding", "other"])   # one state at a time
        steps.append({"idle": int(state == "idle"), "framing": int(state == "framing"),
                      "holding": int(state == "holding"), "cdm": rng.randint(0, 1),
                      "slo": int(rng.random() < 0.3), "slo_stuck": int(rng.random() < 0.1),
                      "abort": int(rng.random() < 0.1)})
    trace = run_clocks(CdmHold(), steps, OUTPUTS)
    want = model(steps)
    for t, (row, exp) in enumerate(zip(trace, want)):
        assert row == exp, (t, steps[t])
    assert sum(r["ma_hold"] for r in want) > 10 and sum(r["cdm_cycle"] for r in want) > 10
