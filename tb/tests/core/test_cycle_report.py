"""CycleReport on Amaranth's simulator: the report of a cycle's end, every input combination.

A reported frame reports its line delay too; a DELAY_RANGE fault at the Ack edge reports the
delay alone; a fault reports its status with exactly the one strobe named after it (docs/ports.md,
``done``, ``status``; the counters count the strobes). Status codes from ``tb/master_contract.py``.
"""

import itertools

from bissmaster.core.cycle_report import CycleReport
from master_contract import STATUS

from testkit.block_sim import run_clocks

#: The statuses that end a cycle without a frame (docs/ports.md: codes 6..12); NOISY_LINE and
#: DELAY_JUMP judge a frame (FrameVerdict).
FAULT_NAMES = [name for name, code in STATUS.items()
               if STATUS["NO_ACK"] <= code <= STATUS["NO_STOP"]]
OUTPUTS = (["report_frame", "report_delay", "fault", "fault_status"]
           + [f"faults.{name.lower()}" for name in FAULT_NAMES])


def test_cycle_report_every_input_combination():
    # The controller sets ``status`` only with ``fail`` (OK otherwise).
    combos = [(frame, delay, 0, "OK") for frame, delay in itertools.product((0, 1), repeat=2)]
    combos += [(0, delay, 1, name) for delay in (0, 1) for name in FAULT_NAMES]
    steps = [{"frame": f, "delay": d, "fail": x, "status": STATUS[s]} for f, d, x, s in combos]
    trace = run_clocks(CycleReport(), steps, OUTPUTS)
    for (frame, delay, fail, name), row in zip(combos, trace):
        assert row["report_frame"] == frame
        assert row["report_delay"] == (frame | delay)
        assert row["fault"] == fail
        assert row["fault_status"] == STATUS[name]
        strobes = {n for n in FAULT_NAMES if row[f"faults.{n.lower()}"]}
        assert strobes == ({name} if fail else set()), (frame, delay, fail, name)
