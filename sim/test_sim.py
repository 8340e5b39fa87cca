"""pytest entry: the cocotb regression on Verilator and Icarus.

``SIM=verilator`` or ``SIM=icarus`` picks one simulator; by default both run.
"""

import os
import xml.etree.ElementTree as ET

import pytest

import runner

TESTS = [
    "safety_and_biss_c_presets", "bp3_lengths", "long_round_trip_many_bit_periods",
    "edge_jitter", "crc_errors_each_word", "encoder_error_and_warning_bits",
    "sign_of_life_faults", "spw_plausibility", "line_faults_and_recovery", "abort_and_break",
    "bad_configuration", "config_change_during_a_cycle", "periodic_requests_and_overrun",
]
SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)

_built = {}


def _build(sim):
    if sim not in _built:
        _built[sim] = runner.build(sim)
    return _built[sim]


# With pytest-xdist (--dist loadgroup), one worker per simulator: each has one build directory.
@pytest.mark.parametrize("sim,test", [pytest.param(sim, test, marks=pytest.mark.xdist_group(sim))
                                      for sim in SIMS for test in TESTS])
def test_cocotb(sim, test):
    r, build_dir = _build(sim)
    xml = runner.run(r, build_dir, "cocotb_master", testcase=test)
    cases = ET.parse(xml).getroot().findall(".//testcase")
    assert len(cases) == 1, f"expected one cocotb test case, got {len(cases)}"
    failures = cases[0].findall("failure") + cases[0].findall("error")
    assert not failures, failures[0].get("message")
