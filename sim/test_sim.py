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


def _build(sim, one_word=False):
    """Build once per process. One build directory per pytest-xdist worker: workers never
    share a build in progress. ``one_word``: the BiSS-C-only build, generated here."""
    key = (sim, one_word)
    if key not in _built:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        verilog, tag = runner.VERILOG, f"-{worker}"
        if one_word:
            verilog, tag = runner.BUILD / f"biss_master_c36-{worker}.v", f"-c36-{worker}"
            verilog.parent.mkdir(parents=True, exist_ok=True)
            generate.main(ONE_WORD_ARGS + ["-o", str(verilog)])
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


#: The BiSS-C-only build (one 36-bit word, CRC-6 only), generated at test time.
ONE_WORD_ARGS = ["--max-data-bits", "36", "--word-crcs", "6"]



@pytest.mark.parametrize("sim", SIMS)
def test_cocotb_biss_c_only_build(sim):
    r, build_dir = _build(sim, one_word=True)
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
