"""LineFaults on Amaranth's simulator: random input sequences against a model of its contract.

The contract (docs/timing.md, "Faults"; the block's docstring): the frame is armed from the
cycle's second MA rise and locked from the Ack edge, both learned only while the frame is
clocked (``watch``) and forgotten in WAIT_READY (``clear``); the timer restarts at the second rise
and at the Ack edge; the line fault is the first of: SLO low when armed (DELAY_RANGE), no Ack
by the Ack limit (NO_ACK), the Ack edge with the round trip over its limit (DELAY_RANGE, delay
reported), no Start by the NO_START limit or with every slot taken (NO_START). Status codes
from ``tb/master_contract.py``.
"""

import random

import pytest

from bissmaster.core.line_faults import LineFaults
from master_contract import STATUS

from testkit.block_sim import run_clocks

INPUTS = ["clear", "watch", "ma_arm", "locked", "early", "started", "slots_full",
          "ack_expired", "no_start_expired", "delay_over"]
OUTPUTS = ["restart_timer", "fault", "status", "delay"]


def model(steps):
    """The outputs expected in each clock."""
    armed = locked_seen = 0
    rows = []
    for s in steps:
        newly_locked = s["locked"] and not locked_seen
        fault, status, delay = 1, None, 0
        if armed and s["early"]:
            status = "DELAY_RANGE"
        elif armed and not locked_seen and not s["locked"] and s["ack_expired"]:
            status = "NO_ACK"
        elif newly_locked and s["delay_over"]:
            status, delay = "DELAY_RANGE", 1
        elif locked_seen and not s["started"] and (s["no_start_expired"] or s["slots_full"]):
            status = "NO_START"
        else:
            fault, status = 0, "OK"
        rows.append({"restart_timer": int(s["ma_arm"] or newly_locked), "fault": fault,
                     "status": STATUS[status], "delay": delay})
        if s["clear"]:
            armed = locked_seen = 0
        if s["watch"]:
            armed |= s["ma_arm"]
            locked_seen |= int(newly_locked)
    return rows


@pytest.mark.parametrize("seed", range(4))
def test_line_faults_random_sequences_follow_the_contract(seed):
    rng = random.Random(seed)
    steps = []
    for _ in range(600):
        # The controller's states: WAIT_READY (clear), CLOCK (watch), or neither; rare arms
        # and Ack edges, so that long watched stretches reach every fault.
        mode = rng.choice(["clear", "watch", "watch", "watch", "other"])
        step = {name: int(rng.random() < 0.15) for name in INPUTS[2:]}
        step.update(clear=int(mode == "clear"), watch=int(mode == "watch"))
        steps.append(step)
    trace = run_clocks(LineFaults(), steps, OUTPUTS)
    want = model(steps)
    seen = set()
    for t, (row, exp) in enumerate(zip(trace, want)):
        assert row == exp, (t, steps[t])
        seen.add((exp["status"], exp["delay"]))
    # Every outcome came up (the test is not vacuous).
    assert seen >= {(STATUS["OK"], 0), (STATUS["DELAY_RANGE"], 0), (STATUS["DELAY_RANGE"], 1),
                    (STATUS["NO_ACK"], 0), (STATUS["NO_START"], 0)}, seen
