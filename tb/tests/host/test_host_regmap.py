"""The host tool's own copy of the register map (rtl/bissmaster/host/regmap.py) and of the
encoder presets (host/presets.py), checked against their sources: the SystemRDL file (read by
the test side's sim/shared/regspec.py, the compiler the host never imports), the status
tables of the test side's contract (tb/master_contract.py), docs/driver.md's preset table and
the encoder model's formats (tb/encoder_model/frames.py)."""

import math
import re
import subprocess
import sys

import pytest

from bissmaster.host import presets, regmap
from encoder_model import frames
from master_contract import CA_STATUS, FRAME_STATUSES, STATUS
from sim.shared import regspec
from testkit import REPO

MAP = regspec.load()


def test_global_and_channel_addresses_are_the_rdl_ones():
    assert regmap.GLOBALS == {path: spec.offset for path, spec in MAP.globals.items()}
    assert regmap.CHANNEL == {path: spec.offset for path, spec in MAP.channel.items()}
    assert (regmap.CHANNEL_BASE, regmap.CHANNEL_STRIDE, regmap.MAX_CHANNELS) == \
        (MAP.channel_base, MAP.channel_stride, MAP.channel_slots)
    assert MAP.channel["ca.rbuf"].count == MAP.channel["ca.wbuf"].count == regmap.BUFFER_WORDS
    for ch in (0, 3, 7):
        for path in ("ctrl", "result.status", "ca.rbuf"):
            assert regmap.address(path, ch) == MAP.address(path, ch)
    with pytest.raises(ValueError):
        regmap.channel_base(8)


def test_every_field_is_the_rdl_one():
    want = {}
    for spec in [*MAP.globals.values(), *MAP.channel.values()]:
        if spec.path in ("ca.wbuf", "ca.rbuf"):
            continue                            # byte lanes of a buffer: read as whole words
        want[spec.path] = {n: (f.lsb, f.width) for n, f in spec.fields.items()}
    assert regmap.FIELDS == want


def test_constants_and_register_groups():
    assert MAP.globals["id"].fields["id"].reset == regmap.ID_VALUE
    assert MAP.globals["version"].fields["major"].reset == regmap.MAP_MAJOR
    def chain(path):
        """A register of words 2..7 of a chain (their own groups below)."""
        return re.match(r"(cfg_w\d|count_chain)", path) is not None

    for runs, prefix, wanted in (
            (regmap.CONFIG_RUNS, "cfg_", lambda p: not chain(p)),
            ((regmap.RESULT_REGISTERS,), "result.", None),
            ((regmap.COUNTER_REGISTERS,), "count_", lambda p: not chain(p)),
            ((regmap.CA_COUNTER_REGISTERS,), "ca.count_", None),
            (regmap.CHAIN_CONFIG_RUNS, "cfg_w", chain),
            ((regmap.CHAIN_COUNTER_REGISTERS,), "count_chain", None)):
        rdl = sorted((p for p in MAP.channel if p.startswith(prefix)
                      and (wanted is None or wanted(p))),
                     key=lambda p: MAP.channel[p].offset)
        assert [r for run in runs for r in run] == rdl, prefix
        for run in runs:
            offsets = [MAP.channel[p].offset for p in run]
            assert offsets == list(range(offsets[0], offsets[0] + 4 * len(run), 4)), \
                f"{prefix}: one READ_BURST needs consecutive registers"
    # 64 bytes per access, registers 0x00..0x7F: the request fields' widths.
    req = MAP.channel["ca.request"].fields
    assert regmap.ENCODER_REGISTERS == 1 << req["address"].width
    assert regmap.MAX_ACCESS_BYTES == 4 * MAP.channel["ca.rbuf"].count


def test_status_codes_are_the_contract_ones():
    assert regmap.STATUS == STATUS
    assert regmap.CA_STATUS == CA_STATUS
    assert regmap.FRAME_STATUSES == set(FRAME_STATUSES)
    assert regmap.NO_ENCODER_STATUSES <= set(STATUS) - set(FRAME_STATUSES)
    assert {"NO_ACK", "SLO_STUCK_LOW"} <= regmap.NO_ENCODER_STATUSES


def test_get_put_and_config_field():
    word = regmap.put("cfg_words", w0_data_bits=26, w0_nenw=1, w0_crc=1, w1_enable=1)
    f = MAP.channel["cfg_words"].fields
    assert word == f["w0_data_bits"].put(f["w0_nenw"].put(f["w0_crc"].put(
        f["w1_enable"].put(0, 1), 1), 1), 26)
    assert regmap.get("cfg_words", word, "w0_data_bits") == 26
    assert regmap.get("cfg_words", word)["w1_enable"] == 1
    with pytest.raises(ValueError, match="7 bit"):
        regmap.put("cfg_words", w0_data_bits=128)
    with pytest.raises(KeyError):
        regmap.put("cfg_words", nonsense=1)
    assert regmap.config_field("cfg_spw_check") == ("cfg_checks", "spw_check")
    assert regmap.config_field("ma_half_period") == ("cfg_ma", "ma_half_period")
    with pytest.raises(KeyError, match="no configuration field"):
        regmap.config_field("periodic")


# -- Presets --------------------------------------------------------------------------------

def doc_presets():
    """The preset names of docs/driver.md's "Encoder presets" table."""
    text = (REPO / "docs" / "driver.md").read_text()
    table = text.split("### Encoder presets", 1)[1].split("\n\n", 3)[2]
    return re.findall(r"`([a-z0-9_]+)`", table)


def test_presets_are_the_documented_and_the_models():
    names = doc_presets()
    assert len(names) == 11 and set(names) == set(presets.PRESETS)
    for name in names:
        fmt = frames.PRESETS[name]
        mine = [w for w in presets.words_of(name) if w]
        assert len(mine) == len(fmt.words), name
        for w, word in zip(mine, fmt.words):
            assert (w["data_bits"], bool(w["nenw"]), bool(w["lc"]), w["crc"]) == \
                (word.data_bits, word.nenw, word.lc, word.crc), name


def test_preset_config_sets_every_field():
    cfg = presets.config("resolute_fs_rsh", 100e6, 3e6)
    every = {n for r in regmap.CONFIG_REGISTERS for n in regmap.FIELDS[r]}
    assert set(cfg) == every
    assert cfg["ma_half_period"] == math.ceil(100e6 / 6e6) == 17       # at most 3 MHz
    assert (cfg["w0_data_bits"], cfg["w1_data_bits"], cfg["w1_lc"], cfg["w1_crc"]) == \
        (36, 28, 1, regmap.CRC_CODES["crc16"])
    assert (cfg["spw_check"], cfg["spw_tolerance"], cfg["w1_enable"]) == (1, 1, 1)
    c = presets.config("biss-c-19", 100e6, 1e6)
    assert (c["w0_data_bits"], c["w0_crc"], c["w1_enable"], c["spw_check"]) == (19, 1, 0, 0)
    c = presets.config("biss-c-64", 100e6, 1e6)
    assert (c["w0_data_bits"], c["w0_crc"]) == (64, 1)
    for bad in ("biss-c-65", "biss-c-0", "resolute_c_99", "biss-c"):
        with pytest.raises(KeyError):
            presets.words_of(bad)
    for clock, ma in ((100e6, 11e6), (100e6, 50e3), (4e6, 3e6), (20e9, 100e3)):
        with pytest.raises(ValueError):
            presets.half_period(clock, ma)


def test_host_tool_imports_only_the_standard_library():
    """cli, board, regmap, presets: no Amaranth, no pyserial, no matplotlib at import time."""
    code = ("import sys, bissmaster.host.cli; "
            "bad = [m for m in sys.modules if m.split('.')[0] in "
            "('amaranth', 'serial', 'matplotlib', 'numpy', 'systemrdl')]; "
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)
