"""Confirmation on Amaranth's simulator: random report sequences against the documented rule.

The rule (docs/ports.md, "Confirmation after a fault"): after a cycle reported with any status
but OK, ABORTED, BAD_CONFIG and UNCONFIRMED, ``pending`` holds until ``cfg_confirm_frames``
(0: 1; 15: off) reports of UNCONFIRMED; a fault among them starts the count again; the setting
15 ends it at once, and a fault while it is 15 leaves nothing pending. Cycle conventions:
``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.confirmation import Confirmation
from master_contract import CHECK_OFF, CONFIRM_NEUTRAL, STATUS, ConfirmationAccount

from testkit.block_sim import run_clocks

FAULTS = [code for name, code in STATUS.items() if name not in CONFIRM_NEUTRAL]
NEUTRAL_NO_FRAME = [STATUS["ABORTED"], STATUS["BAD_CONFIG"]]


class Reference(ConfirmationAccount):
    """The rule, as a user reads it (master_contract)."""

    def pending(self, setting):
        return int(super().pending(setting))

    def report(self, status, setting):
        self.reported(status, setting)


def _run(steps):
    trace = run_clocks(Confirmation(), steps, ["pending"])
    ref = Reference()
    for i, (step, got) in enumerate(zip(steps, trace)):
        assert got["pending"] == ref.pending(step["setting"]), (i, steps[max(0, i - 4):i + 1])
        if step["report"]:
            ref.report(step["status"], step["setting"])


def _frame_status(ref, setting, rng):
    """What a core would report for a frame: a fault now and then, else OK or UNCONFIRMED as
    the rule says (the block only ever sees statuses the verdict can give)."""
    if rng.random() < 0.2:
        return rng.choice(FAULTS + NEUTRAL_NO_FRAME)
    return STATUS["UNCONFIRMED"] if ref.pending(setting) else STATUS["OK"]


@pytest.mark.parametrize("setting", [0, 1, 2, 3, 14, CHECK_OFF, "random"])
def test_confirmation_follows_the_rule(setting):
    rng = random.Random(f"confirm-{setting}")
    ref = Reference()
    steps = []
    value = 0
    for _ in range(3000):
        if setting == "random":
            if rng.random() < 0.01:
                value = rng.choice([0, 1, 2, 5, CHECK_OFF])
        else:
            value = setting
        report = int(rng.random() < 0.3)
        status = _frame_status(ref, value, rng) if report else rng.randrange(16)
        if report:
            ref.report(status, value)
        steps.append({"report": report, "status": status, "setting": value})
    _run(steps)


def test_default_is_one_frame_and_a_fault_restarts_the_count():
    ok, unconfirmed, crc = STATUS["OK"], STATUS["UNCONFIRMED"], STATUS["CRC_ERROR_WORD0"]
    seq = [(1, crc), (1, unconfirmed), (1, ok), (1, STATUS["NOISY_LINE"]), (0, ok),
           (1, STATUS["ABORTED"]), (1, unconfirmed), (1, ok)]
    trace = run_clocks(Confirmation(), [{"report": r, "status": s, "setting": 0} for r, s in seq],
                       ["pending"])
    # Pending in the clock after a fault until the UNCONFIRMED report; ABORTED keeps it.
    assert [t["pending"] for t in trace] == [0, 1, 0, 0, 1, 1, 1, 0]


def test_a_fault_with_the_setting_off_leaves_nothing_pending():
    seq = [({"report": 1, "status": STATUS["NO_ACK"], "setting": CHECK_OFF}),
           ({"report": 0, "status": 0, "setting": 3})]
    trace = run_clocks(Confirmation(), seq, ["pending"])
    assert [t["pending"] for t in trace] == [0, 0]
