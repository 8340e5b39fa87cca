"""pytest entry: self-checks of the cocotb SSI encoder + cable model on Icarus.

Builds the empty harness tb/testkit/hdl/ma_loopback.v and runs tb/testkit/cocotb_ssi_checks.py
(Python is the master; the model under test drives SLO).
"""

from cocotb_tools.check_results import get_results
from cocotb_tools.runner import get_runner

from testkit import HDL, REPO

# train_timing 12 + faults_and_force 1 + retrigger_within_tm 1 + jitter_keeps_order 1
EXPECTED_TESTS = 15


def test_ssi_encoder_model():
    build_dir = REPO / "sim_build" / "ssi_driver"
    runner = get_runner("icarus")
    runner.build(sources=[HDL / "ma_loopback.v"], hdl_toplevel="ma_loopback",
                 build_dir=build_dir, timescale=("1ns", "1ps"), always=True)
    results = runner.test(test_module="testkit.cocotb_ssi_checks", hdl_toplevel="ma_loopback",
                          build_dir=build_dir, test_dir=build_dir, timescale=("1ns", "1ps"))
    num_tests, num_failed = get_results(results)
    assert num_failed == 0
    assert num_tests == EXPECTED_TESTS, f"ran {num_tests} cocotb tests, expected {EXPECTED_TESTS}"
