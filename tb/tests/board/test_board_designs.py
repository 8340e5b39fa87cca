"""The board designs (rtl/bissmaster/boards, docs/bench.md): each elaborates on its
amaranth-boards platform, its pins are the ones docs/bench.md's pinout tables give, the
Xilinx board's vendor plan (``make board PLAN=1``) holds the expected constraints, the PLL
settings are the vendor calculators', and the build script's timing check fails a design that
misses the board clock. The builds themselves (``make board``) run outside the tests.
"""

import re
import subprocess
import zipfile

import pytest

from bissmaster.boards import BOARDS, BoardTop
from bissmaster.boards.clocking import MHZ, ecp5_pll, ice40_pll
from testkit import REPO

import board as board_script  # scripts/board.py (scripts/ is on pytest's pythonpath)
from venvtools import tool

BENCH = REPO / "docs" / "bench.md"
#: The constraint file of each family's plan and how it places a port on a pin.
CONSTRAINTS = {
    "ecp5": ("top.lpf", r'LOCATE COMP "(\w+)" SITE "(\w+)";'),
    "ice40": ("top.pcf", r"set_io (\w+) (\w+)"),
    "xilinx": ("top.xdc", r'set_property LOC (\w+) \[get_ports "(\w+)"\]'),
}


@pytest.fixture(scope="module", params=sorted(BOARDS))
def prepared(request):
    board = BOARDS[request.param]
    platform = board.make_platform()
    plan = platform.prepare(BoardTop(board), name="top")
    return board, platform, plan


def placed(board, plan):
    """{port: FPGA pin} of the plan's constraint file."""
    name, pattern = CONSTRAINTS[board.family]
    text = plan.files[name]
    text = text.decode() if isinstance(text, bytes) else text
    pairs = re.findall(pattern, text)
    if board.family == "xilinx":
        pairs = [(port, pin) for pin, port in pairs]
    return dict(pairs)


def test_each_board_elaborates_with_its_pins_and_clock(prepared):
    board, platform, plan = prepared
    pins = placed(board, plan)
    n = len(board.channels)
    assert n >= 1
    # the UART, every channel's transceiver pins, every LED, the reset button and the clock
    assert {"uart_0__rx__io", "uart_0__tx__io"} <= set(pins)
    for ch in range(n):
        assert f"biss_{ch}__ma__io" in pins and f"biss_{ch}__de__io" in pins
        assert (f"biss_{ch}__slo__io" in pins) != (f"biss_{ch}__slo__p" in pins)
    # heartbeat, and a valid and a fault LED per channel, each on a pin of its own
    led_pins = [pins[f"{name}_{number}__{sub[0]}__io" if sub else f"{name}_{number}__io"]
                for name, number, *sub in board.leds.values()]
    assert len(led_pins) == 1 + 2 * n and len(set(led_pins)) == len(led_pins)
    assert f"{board.clock}_0__io" in pins
    # the PLL where the board clock is not the design's, and the reset synchronizer
    text = plan.files.get("top.il") or plan.files["top.v"]
    text = text.decode() if isinstance(text, bytes) else text
    primitive = {"ecp5": "EHXPLLL", "ice40": "SB_PLL40_PAD"}.get(board.family)
    if board.sys_clk_hz != board.clock_hz:
        assert primitive in text
    elif primitive:
        assert primitive not in text
    assert "reset_sync" in text


def _doc_tables():
    """{board name: [row dicts]} of docs/bench.md's pinout tables: under ``## Wiring``, each
    ``### `<board>`[, `<board>`]`` heading's table (one table for boards with the same pins)."""
    text = BENCH.read_text()
    wiring = text.split("\n## Wiring", 1)[1].split("\n## ", 1)[0]
    tables = {}
    for section in wiring.split("\n### ")[1:]:
        names = re.findall(r"`([\w-]+)`", section.splitlines()[0])
        lines = [l for l in section.splitlines() if l.startswith("|")]
        head = [c.strip() for c in lines[0].strip("|").split("|")]
        for name in names:
            tables[name] = [dict(zip(head, (c.strip().strip("`") for c in l.strip("|").split("|"))))
                            for l in lines[2:]]
    return tables


def _connector(board_name, label):
    """A connector pin's label in the docs -> (connector name, number, pin) of amaranth-boards."""
    if board_name.startswith("ulx3s"):
        m = re.fullmatch(r"G([PN])(\d+)", label)
        return ("gpio", 0, m.group(2) + ("+" if m.group(1) == "P" else "-"))
    if board_name == "icebreaker":
        m = re.fullmatch(r"PMOD(1A|1B|2)-(\d+)", label)
        return ("pmod", ["1A", "1B", "2"].index(m.group(1)), m.group(2))
    m = re.fullmatch(r"J([A-D])(\d+)", label)
    return ("pmod", "ABCD".index(m.group(1)), m.group(2))


def pinout_mismatches(board, platform, pins, rows):
    """What differs between a docs pinout table (``rows``) and the design's placed ``pins``:
    a port on another FPGA pin, a board pin label that is not that FPGA pin on the board's
    connector, a channel, UART or LED pin of the design missing from the table."""
    bad = []
    documented = set()
    for row in rows:
        port, fpga, label = row["port"], row["FPGA pin"], row["board pin"]
        documented.add(port)
        if pins.get(port) != fpga:
            bad.append(f"{port}: docs {fpga}, design {pins.get(port)}")
        if port.startswith("biss_"):
            name, number, pin = _connector(board.name, label)
            if platform.connectors[name, number].mapping[pin] != fpga:
                bad.append(f"{port}: {label} is {platform.connectors[name, number].mapping[pin]}, "
                           f"not {fpga}")
    wanted = {p for p in pins if p.startswith(("biss_", "uart_0__rx", "uart_0__tx", "led",
                                                "rgb_led")) and not p.endswith("__b__io")}
    bad += [f"{port}: not in the docs" for port in sorted(wanted - documented)]
    return bad


def test_pins_are_the_documented_pinout(prepared):
    board, platform, plan = prepared
    tables = _doc_tables()
    assert board.name in tables, f"docs/bench.md has no pinout table for {board.name}"
    assert pinout_mismatches(board, platform, placed(board, plan), tables[board.name]) == []


def test_a_wrong_pinout_row_is_found():
    board = BOARDS["icebreaker"]
    platform = board.make_platform()
    pins = placed(board, platform.prepare(BoardTop(board), name="top"))
    rows = _doc_tables()["icebreaker"]
    moved = [dict(r, **{"FPGA pin": "2"}) if r["port"] == "biss_0__ma__io" else r for r in rows]
    relabelled = [dict(r, **{"board pin": "PMOD1A-2"}) if r["port"] == "biss_0__ma__io" else r
                  for r in rows]
    dropped = [r for r in rows if r["port"] != "biss_0__de__io"]
    assert len(pinout_mismatches(board, platform, pins, moved)) == 2     # pin and its label
    assert len(pinout_mismatches(board, platform, pins, relabelled)) == 1
    assert pinout_mismatches(board, platform, pins, dropped) == ["biss_0__de__io: not in the docs"]


def test_vendor_plan_holds_the_constraints(tmp_path, monkeypatch):
    """``make board BOARD=arty-a7-35 PLAN=1``: the Vivado plan (no tool run) as files and a zip:
    the part, the clock, the pins with their I/O standards, the SLO pair through IBUFDS."""
    monkeypatch.setattr(board_script, "OUT", tmp_path)
    board_script.main(["arty-a7-35", "--plan"])
    with zipfile.ZipFile(tmp_path / "arty-a7-35-plan.zip") as z:
        files = {n: z.read(n).decode() for n in z.namelist()}
    assert {"top.tcl", "top.xdc", "top.v", "build_top.sh"} <= set(files)
    assert (tmp_path / "arty-a7-35-plan" / "top.xdc").read_text() == files["top.xdc"]
    tcl, xdc, v = files["top.tcl"], files["top.xdc"], files["top.v"]
    assert "create_project -force -name top -part xc7a35ticsg324-1L" in tcl
    assert "write_bitstream" in tcl and "read_xdc top.xdc" in tcl
    assert 'create_clock -name clk100_0__io -period 10.0' in xdc
    for port, pin in [("uart_0__rx__io", "A9"), ("uart_0__tx__io", "D10"),
                      ("biss_0__ma__io", "G13"), ("biss_0__slo__io", "B11"),
                      ("biss_0__de__io", "A11"), ("biss_0__re__io", "D12"),
                      ("biss_1__ma__io", "U14"), ("biss_1__de__io", "V14"),
                      ("biss_1__slo__p", "U12"), ("biss_1__slo__n", "V12")]:
        assert f'set_property LOC {pin} [get_ports "{port}"]' in xdc, port
    assert 'set_property IOSTANDARD "LVDS_25" [get_ports "biss_1__slo__p"]' in xdc
    assert 'set_property DIFF_TERM "FALSE" [get_ports "biss_1__slo__p"]' in xdc
    assert 'set_property IOSTANDARD "LVCMOS33" [get_ports "biss_0__slo__io"]' in xdc
    assert 'set_property PULLUP "TRUE" [get_ports "biss_0__slo__io"]' in xdc
    assert len(re.findall(r"^\s*IBUFDS\b", v, re.M)) == 1
    # the synchronizers of the asynchronous inputs carry Amaranth's Vivado false-path marks
    assert "amaranth.vivado.false_path" in v and "ASYNC_REG" in v


def test_open_flow_board_without_plan_and_vendor_board_without_plan_flag(capsys):
    with pytest.raises(SystemExit):
        board_script.main(["arty-a7-35"])
    assert "PLAN=1" in capsys.readouterr().err


# -- PLL settings -------------------------------------------------------------------------------

def _tool_output(name, *args):
    run = subprocess.run([tool(name), *args], capture_output=True, text=True, timeout=300,
                         cwd=REPO / "sim_build" if (REPO / "sim_build").exists() else REPO)
    assert run.returncode == 0, run.stderr
    return run.stdout + run.stderr


@pytest.mark.parametrize("f_out", [80, 50, 100, 60])
def test_ecp5_pll_is_ecppll(f_out, tmp_path):
    ours = ecp5_pll(25 * MHZ, f_out * MHZ)
    assert ours.f_out == f_out * MHZ and 400 * MHZ <= ours.f_vco <= 800 * MHZ
    text = _tool_output("yowasp-ecppll", "-i", "25", "-o", str(f_out))
    theirs = {k: int(v) for k, v in re.findall(r"(Refclk divisor|Feedback divisor|clkout0 divisor): (\d+)", text)}
    assert (ours.clki_div, ours.clkfb_div, ours.clkop_div) == (
        theirs["Refclk divisor"], theirs["Feedback divisor"], theirs["clkout0 divisor"])


@pytest.mark.parametrize("f_out", [24, 48, 36])
def test_ice40_pll_is_icepll(f_out):
    ours = ice40_pll(12 * MHZ, f_out * MHZ)
    assert ours.f_out == f_out * MHZ
    text = _tool_output("yowasp-icepll", "-i", "12", "-o", str(f_out))
    theirs = {k: int(v) for k, v in re.findall(r"^(DIVR|DIVF|DIVQ|FILTER_RANGE):\s+(\d+)", text, re.M)}
    assert (ours.divr, ours.divf, ours.divq, ours.filter_range) == (
        theirs["DIVR"], theirs["DIVF"], theirs["DIVQ"], theirs["FILTER_RANGE"])


def test_pll_refuses_what_it_cannot_make():
    with pytest.raises(ValueError, match="no setting"):
        ecp5_pll(25 * MHZ, 77_777_777)
    with pytest.raises(ValueError, match="range"):
        ice40_pll(12 * MHZ, 12 * MHZ)       # below the iCE40 PLL's 16 MHz


# -- The build script's timing check ----------------------------------------------------------

def test_timing_check_passes_and_fails(tmp_path):
    tim = tmp_path / "top.tim"
    tim.write_text("Info: Critical path report for clock 'clk' (posedge -> posedge):\n"
                   "Info:  curr total\nInfo:  1.0  1.0 Source a.Q\nInfo:  9.0 41.0 Sink b.D\n"
                   "Info: Max frequency for clock 'clk': 24.39 MHz (FAIL at 30.00 MHz)\n")
    met = {"clk": {"achieved": 26.6, "constraint": 24.0}}
    missed = {"clk": {"achieved": 24.39, "constraint": 30.0}}
    assert board_script.timing_failures(met) == []
    assert board_script.timing_failures(missed) == ["clk"]
    path = board_script.critical_path(tim, "clk")
    assert path[0].startswith("Info: Critical path report for clock 'clk'")
    assert any("Sink b.D" in line for line in path)
