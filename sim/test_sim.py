"""pytest entry: the cocotb regression on Verilator and Icarus.

``SIM=verilator`` or ``SIM=icarus`` picks one simulator; by default both run.
"""

import os
import xml.etree.ElementTree as ET

import pytest

import runner
from bissmaster import generate

TESTS = [
    "safety_and_biss_c_presets", "bp3_lengths", "long_round_trip_many_bit_periods",
    "edge_jitter", "crc_errors_each_word", "encoder_error_and_warning_bits",
    "sign_of_life_faults", "spw_plausibility", "line_faults_and_recovery", "abort_and_break",
    "bad_configuration", "config_change_during_a_cycle", "periodic_requests_and_overrun",
    "verdict_latency", "end_check",
]
SIMS = [os.environ["SIM"]] if os.environ.get("SIM") else list(runner.SIMULATORS)

_built = {}


def _build(sim, preset="default"):
    """Build once per process. One build directory per pytest-xdist worker: workers never
    share a build in progress. A ``preset`` other than the default (the committed Verilog) is
    generated here (bissmaster.generate's presets)."""
    key = (sim, preset)
    if key not in _built:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        verilog, tag = runner.VERILOG, f"-{worker}"
        if preset != "default":
            verilog, tag = runner.BUILD / f"biss_master_{preset}-{worker}.v", f"-{preset}-{worker}"
            verilog.parent.mkdir(parents=True, exist_ok=True)
            generate.main(["--preset", preset, "-o", str(verilog)])
        _built[key] = runner.build(sim, verilog=verilog, tag=tag)
    return _built[key]


#: The same Verilog at another system clock (the core's times are all in clocks): 200 MHz gives
#: 10..400 clocks per MA half period over the five MA rates.
FAST_CLOCK_TESTS = ["safety_and_biss_c_presets", "long_round_trip_many_bit_periods",
                    "line_faults_and_recovery"]
FAST_CLK_HZ = 200_000_000

CASES = [pytest.param(sim, test, runner.CLK_HZ, id=f"{sim}-{test}")
         for sim in SIMS for test in TESTS]
CASES += [pytest.param("verilator", test, FAST_CLK_HZ, id=f"verilator-200MHz-{test}")
          for test in FAST_CLOCK_TESTS if "verilator" in SIMS]


#: The BiSS-C-only builds (one 36-bit word, CRC-6 only; the lean one also without counters
#: and timestamp, with 16-bit time settings), generated at test time.
@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize("preset", ["biss-c", "biss-c-lean"])
def test_cocotb_biss_c_only_build(sim, preset):
    r, build_dir = _build(sim, preset)
    xml = runner.run(r, build_dir, "cocotb_master", testcase="biss_c_only_build")
    _check(xml)


@pytest.mark.parametrize("sim,test,clk_hz", CASES)
def test_cocotb(sim, test, clk_hz):
    r, build_dir = _build(sim)
    xml = runner.run(r, build_dir, "cocotb_master", testcase=test,
                     extra_env={"BISS_CLK_HZ": str(clk_hz)})
    _check(xml)


def _check(xml):
    cases = ET.parse(xml).getroot().findall(".//testcase")
    assert len(cases) == 1, f"expected one cocotb test case, got {len(cases)}"
    failures = cases[0].findall("failure") + cases[0].findall("error")
    assert not failures, failures[0].get("message")
