"""The register map's one source and everything made from it.

The committed PeakRDL outputs (C header, docs/registers.md, IP-XACT) and bus-top Verilog are
what `make regmap` / `make rtl` make today; the map names every runtime setting, result field
and counter of the core, each once, at least as wide as the core's port; bad maps and bad bus
parameters are refused with a clear message.
"""

import re
from pathlib import Path

import pytest

from bissmaster.bus import regmap
from bissmaster.bus.bus_top import BusTop
from bissmaster.generate import generate_bus
from bissmaster.layouts import (RAM_COUNTERS, access_request_layout, access_result_layout,
                                config_ports, counter_ports, flat_fields, result_layout)
from bissmaster.params import Crc, MasterParams

from testkit import REPO as ROOT
from testkit.block_sim import refused
OUTPUTS = {
    "header": ("sw/include/biss_master_regs.h", regmap.write_header),
    "markdown": ("docs/registers.md", regmap.write_markdown),
    "ipxact": ("rtl/generated/biss_master_regs.xml", regmap.write_ipxact),
}


@pytest.mark.parametrize("kind", OUTPUTS)
def test_committed_regmap_outputs_are_up_to_date(kind, tmp_path):
    committed, write = OUTPUTS[kind]
    out = tmp_path / Path(committed).name
    write(regmap.compile_rdl(), out)
    assert out.read_text() == (ROOT / committed).read_text(), \
        f"{committed} is stale: run `make regmap` and commit it"


@pytest.mark.parametrize("bus", ["axil", "wb", "uart"])
def test_committed_bus_tops_are_up_to_date(bus):
    committed = ROOT / "rtl" / "generated" / f"biss_master_{bus}.v"
    assert committed.read_text() == generate_bus(bus), \
        f"{committed.name} is stale: run `make rtl` and commit it"


def _fields_by_signal(registers):
    found = {}
    for reg in registers:
        for f in reg.fields:
            if f.signal:
                found.setdefault(f.signal, []).append(f)
    return found


def test_map_covers_every_setting_result_and_counter_once():
    rm = regmap.load()
    signals = _fields_by_signal(rm.channel)
    # The bus tops' cores: the engine included, the data channel's counters in memory.
    p = MasterParams(counter_ram=True)
    wanted = {name: shape for name, _, shape in config_ports(p)}
    wanted.update({name: shape for name, _, shape in flat_fields(result_layout(p))})
    wanted.update({f"count_{n}": p.counter_width for n in counter_ports(p)})
    # The core's `done` reaches the map as the channel's frame_done (held for the counts).
    wanted.update({n: 1 for n in ("start", "periodic", "abort_cycle", "clear_counters",
                                  "busy", "config_error", "frame_done")})
    wanted.update({name: shape for name, _, shape in flat_fields(access_request_layout(), "ca_")})
    wanted.update({name: shape for name, _, shape in flat_fields(access_result_layout(), "ca_")})
    wanted.update({n: 1 for n in ("ca_start", "ca_abort", "ca_busy", "ca_done")})
    for name in wanted:
        assert name in signals, f"the register map has no field for {name}"
        bits = sum(f.width for f in signals[name])
        covered = {f.signal_lsb + i for f in signals[name] for i in range(f.width)}
        assert len(covered) == bits, f"{name}: two fields hold the same bits"
        if name.startswith("cfg_"):
            assert len(signals[name]) == 1, f"{name}: one field per setting"


def test_counter_memory_words_are_the_cores_slots():
    """The map's counter registers are the words of the core's counter memory, two counts
    each, low half first, in the core's slot order; 16-bit fields."""
    rm = regmap.load()
    assert rm.memories(rm.channel)["count"] == (0x060, 8)
    words = sorted((r for r in rm.channel if r.memory == "count"), key=lambda r: r.offset)
    fields = [(f.name, f.lsb, f.width) for r in words
              for f in sorted(r.fields, key=lambda f: f.lsb)]
    assert fields == [(name, 16 * (i % 2), 16) for i, name in enumerate(RAM_COUNTERS)]


def test_config_fields_match_port_widths():
    """Every configuration field is as wide as the default core's port, except the words'
    lengths: 7 bits for every word (1..64, docs/bus.md), wider than a 6-bit port of a core
    whose words are all shorter than 64 bits."""
    rm = regmap.load()
    signals = _fields_by_signal(rm.channel)
    from amaranth.hdl import Shape
    for name, _, shape in config_ports(MasterParams()):
        width = Shape.cast(shape).width
        if re.fullmatch(r"cfg_w\d_data_bits", name):
            assert signals[name][0].width == 7 >= width, name
        else:
            assert signals[name][0].width == width, name


def test_map_layout():
    rm = regmap.load()
    assert (rm.channel_base, rm.channel_stride, rm.channel_slots) == (0x200, 0x200, 8)
    core = [r for r in rm.channel if not r.path.startswith(("ca.", "chain."))]
    assert max(r.offset for r in core) < 0x100, "0x100.. is the access engine's block"
    chain = [r for r in rm.channel if r.path.startswith("chain.")]
    assert min(r.offset for r in chain) == 0x1C0, "the chain results follow the read buffer"
    assert max(r.offset for r in chain) < 0x200 and not any(r.snapshot for r in chain)
    access = {r.path: r for r in rm.channel if r.path.startswith("ca.")}
    assert max(r.offset for r in access.values() if not r.window) < 0x140
    windows = {(r.window, r.offset, r.count, r.writable) for r in access.values() if r.window}
    assert windows == {("ca_wbuf", 0x140, 16, True), ("ca_rbuf", 0x180, 16, False)}
    snap = [r for r in rm.channel if r.snapshot]
    assert [r.path for r in snap if r.takes_snapshot] == ["result.status"]
    assert min(r.offset for r in snap) == rm.channel[[r.path for r in rm.channel]
                                                     .index("result.status")].offset


@pytest.mark.parametrize("kwargs, message", [
    ({"bus": "apb"}, "bus must be one of"),
    ({"channels": 0}, "channels must be an integer from 1 to 8"),
    ({"channels": 9}, "channels must be an integer from 1 to 8"),
    ({"params": [MasterParams()] * 3}, "one per channel"),
    ({"params": MasterParams(timer_width=32)}, "holds 24 bits of cfg_request_period"),
])
def test_bad_bus_parameters_are_refused(kwargs, message):
    refused(lambda: BusTop(**kwargs), message)


def test_one_word_build_connects(tmp_path):
    text = generate_bus("axil", 1, MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),)))
    assert "module biss_master_axil(" in text and "ch0_ma" in text and "ch1_ma" not in text


def test_build_without_register_access_connects():
    text = generate_bus("wb", 1, MasterParams(register_access=False))
    assert "module biss_master_wb(" in text and "access_fsm" not in text      # no engine


@pytest.mark.parametrize("old, new, message", [
    ('hdl_path = "ca_rbuf";', "", "an hdl_path"),
    ("rbuf[16] @ 0x80 += 4;", "rbuf[8] @ 0x80 += 8;", "adjacent words"),
    ("rbuf_f #(.DESC(\"Byte 4 n + 3.\")) byte3[31:24];", "", "byte lanes"),
    ('} count_noise @ 0x07C;', '} count_noise @ 0x0AC;', "adjacent words"),
    ('count_f #(.DESC("Status NO_ACK.")) no_ack[15:0] = 0;',
     'live_f #(.PATH("count_no_ack")) no_ack[15:0] = 0;', "no hdl_path_slice"),
])
def test_bad_window_or_memory_is_refused(tmp_path, old, new, message):
    src = regmap.RDL.read_text()
    assert old in src
    bad = tmp_path / "bad.rdl"
    bad.write_text(src.replace(old, new))
    with pytest.raises(ValueError, match=message):
        rm = regmap.load(bad)
        rm.signals(rm.channel)


def test_unknown_signal_in_map_is_refused(tmp_path):
    src = regmap.RDL.read_text().replace('.PATH("cfg_spw_tolerance")', '.PATH("cfg_spw_tolerence")')
    bad = tmp_path / "bad.rdl"
    bad.write_text(src)
    refused(lambda: BusTop(regmap=regmap.load(bad)), "cfg_spw_tolerence")


def test_chain_memory_words_are_the_chain_words_data():
    """The chain words' data registers are the words of the core's chain memory: w2_lo,
    w2_hi, ... w7_hi from 0x1C0 (aligned to the 16 words that hold them), each 32 bits; the
    flags and the update count follow, outside it (docs/bus.md, Chains)."""
    rm = regmap.load()
    assert rm.memories(rm.channel)["chain"] == (0x1C0, 12)
    words = sorted((r for r in rm.channel if r.memory == "chain"), key=lambda r: r.offset)
    assert [r.path for r in words] == [f"chain.w{w}_{h}" for w in range(2, 8)
                                       for h in ("lo", "hi")]
    assert all([(f.lsb, f.width) for f in r.fields] == [(0, 32)] for r in words)
    offsets = {r.path: r.offset for r in rm.channel}
    assert (offsets["chain.flags"], offsets["chain.updates"]) == (0x1F0, 0x1F4)
