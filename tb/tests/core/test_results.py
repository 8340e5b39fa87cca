"""ResultRegisters on Amaranth's simulator: each field changes only on its own strobe.

Cycle conventions and where expected values come from: ``block_sim.py``. The contract (the
block's docstring, docs/ports.md "Result"): ``done`` and ``valid`` are the ``report`` and
``valid`` strobes one clock later; in that clock ``status`` is new with every report,
``line_delay`` with ``report_delay``, every other field with ``report_frame`` only; otherwise every
field holds. The strobes are driven independently here (the block must not care how the
controller combines them).
"""

import random

import pytest

from bissmaster.layouts import result_layout
from bissmaster.params import Crc, MasterParams
from bissmaster.core.results import ResultRegisters

from testkit.block_sim import pack, run_clocks, unpack

BUILDS = {
    "default": MasterParams(),
    "one_word_no_timestamp": MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),),
                                          timestamp_width=0),
}
#: The field that each strobe renews (any other field: ``report_frame``).
OWN_STROBE = {"status": "report", "line_delay": "report_delay"}


@pytest.mark.parametrize("build", BUILDS)
def test_results_fields_update_only_on_their_strobes(build):
    p = BUILDS[build]
    layout = result_layout(p)
    rng = random.Random(7600 + len(build))
    steps = []
    for _ in range(1500):
        strobes = {name: int(rng.random() < 0.15)
                   for name in ("report", "report_frame", "report_delay", "valid")}
        steps.append({"frame": rng.getrandbits(layout.size), **strobes})
    trace = run_clocks(ResultRegisters(p), steps, ["done", "valid_out", "result"])

    held = unpack(layout, 0)
    for t in range(1, len(steps)):
        prev = steps[t - 1]
        new = unpack(layout, prev["frame"])
        for name in held:
            if prev[OWN_STROBE.get(name, "report_frame")]:
                held[name] = new[name]
        got = trace[t]
        assert (got["done"], got["valid_out"]) == (prev["report"], prev["valid"]), t
        assert unpack(layout, got["result"]) == held, t
    # Every strobe alone happened, so each field was seen held while another changed.
    for name in ("report", "report_frame", "report_delay"):
        assert any(s[name] and sum(s[k] for k in OWN_STROBE.values() if k != name) == 0
                   for s in steps)


def test_results_fault_keeps_the_last_frame():
    # A frame, then a fault (report alone): only the status changes.
    p = BUILDS["default"]
    layout = result_layout(p)
    frame = {"status": 0, "timestamp": 1234, "line_delay": 17, "cds": 1, "lc": 9,
             "word0": {"position": 0x12345, "ne": 1, "nw": 1, "crc_ok": 1},
             "word1": {"position": 0x777, "ne": 1, "nw": 0, "crc_ok": 1}}
    fault = {**frame, "status": 6, "timestamp": 99, "line_delay": 3, "lc": 1,
             "word0": {"position": 1, "ne": 0, "nw": 0, "crc_ok": 0}}
    steps = [{"frame": pack(layout, frame), "report": 1, "report_frame": 1, "report_delay": 1,
              "valid": 1},
             {"frame": pack(layout, fault), "report": 1},
             {"frame": pack(layout, fault)}, {}]
    trace = run_clocks(ResultRegisters(p), steps, ["done", "valid_out", "result"],
                       defaults={"report": 0, "report_frame": 0, "report_delay": 0, "valid": 0})
    assert [(x["done"], x["valid_out"]) for x in trace] == [(0, 0), (1, 1), (1, 0), (0, 0)]
    assert unpack(layout, trace[1]["result"]) == unpack(layout, pack(layout, frame))
    assert unpack(layout, trace[2]["result"]) == {**unpack(layout, pack(layout, frame)),
                                                  "status": 6}
    assert trace[3]["result"] == trace[2]["result"]
