"""pytest entry: self-checks of the cocotb encoder + cable model on Icarus.

Builds the empty harness tb/testkit/hdl/ma_loopback.v and runs tb/testkit/cocotb_encoder_checks.py
(Python is the master; the model under test drives SLO).
"""


from cocotb_tools.check_results import get_results
from cocotb_tools.runner import get_runner

from testkit import HDL, REPO


# frame_timing 6 + processing_time_edges 1 + early_request_ignored 1 + abort 5 + faults 5
# + jitter 2 + ma_held_low_at_end 2 + force_and_set_cable 1 + control_channel 1
EXPECTED_TESTS = 24


def test_encoder_model():
    build_dir = REPO / "sim_build" / "encoder_driver"
    runner = get_runner("icarus")
    runner.build(
        sources=[HDL / "ma_loopback.v"],
        hdl_toplevel="ma_loopback",
        build_dir=build_dir,
        timescale=("1ns", "1ps"),
        always=True,
    )
    # The simulator's Python gets this process's sys.path (cocotb's runner passes it on):
    # pytest.ini's pythonpath, on which tb/ holds the testkit package.
    results = runner.test(
        test_module="testkit.cocotb_encoder_checks",
        hdl_toplevel="ma_loopback",
        build_dir=build_dir,
        test_dir=build_dir,
        timescale=("1ns", "1ps"),
    )
    num_tests, num_failed = get_results(results)
    assert num_failed == 0
    assert num_tests == EXPECTED_TESTS, f"ran {num_tests} cocotb tests, expected {EXPECTED_TESTS}"
