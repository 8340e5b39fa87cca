"""The C driver (sw/) without a simulator: it builds warning-free as strict C99 with every
compiler installed, and its tables agree with the test side's.

Its behaviour against the RTL is tested in sim/scenarios/driver.py (sim/test_driver.py). Here:
the encoder presets against the encoder model's formats (tb/encoder_model/frames.PRESETS), the
status names against tb/master_contract.py, the preset-to-configuration arithmetic and its
range checks, and the example of docs/driver.md being the file the build compiles.
"""

import ctypes
import re
import shutil
import subprocess
from ctypes import byref, c_uint8
from pathlib import Path

import pytest

from encoder_model import frames
from master_contract import (CA_STATUS, CRC_CODE, ENCODER_PRESETS, STATUS_NAME,
                             SYS_CLK_HZ)
from sim.shared import c_driver, regspec

from testkit import REPO as ROOT
COMPILERS = ("gcc", "clang", "clang-14")


def _build(tmp_path, cc="cc"):
    subprocess.run(["make", "-s", "-C", str(ROOT / "sw"), f"BUILD={tmp_path}", f"CC={cc}"],
                   check=True, capture_output=True, text=True)
    return tmp_path / "libbissmaster.so"


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    return c_driver.load(_build(tmp_path_factory.mktemp("driver")))


def test_builds_strict_with_every_installed_compiler(tmp_path):
    """-std=c99 -pedantic -Wall -Wextra -Werror -Wconversion -Wshadow (sw/Makefile): the
    library, the static library, the docs' examples and the Linux example program (linked;
    tested in test_linux_example.py), with gcc and clang where installed."""
    found = [cc for cc in COMPILERS if shutil.which(cc)]
    assert found, f"none of {COMPILERS} is installed"
    for cc in found:
        out = tmp_path / cc
        r = subprocess.run(["make", "-C", str(ROOT / "sw"), f"BUILD={out}", f"CC={cc}"],
                           capture_output=True, text=True)
        assert r.returncode == 0, f"{cc}:\n{r.stdout}\n{r.stderr}"
        assert "warning" not in r.stderr, r.stderr
        for name in ("libbissmaster.so", "libbissmaster.a", "two_axes.o", "bp3_identify.o",
                     "biss_linux"):
            assert (out / name).is_file(), f"{cc}: no {name}"


def test_ctypes_mirror_matches_the_c_layouts(tmp_path):
    """sim/shared/c_driver.py's structs have the C compiler's layout: a program built here
    prints sizeof of every struct of biss_master.h the mirror holds and offsetof of each of its
    fields; a field out of place (or a member appended in C and not in the mirror) differs."""
    lines, want = [], {}
    for cname, cls in c_driver.STRUCTS.items():
        lines.append(f'printf("{cname} %zu\\n", sizeof({cname}));')
        want[cname] = ctypes.sizeof(cls)
        for field, _ in cls._fields_:
            lines.append(f'printf("{cname}.{field} %zu\\n", offsetof({cname}, {field}));')
            want[f"{cname}.{field}"] = getattr(cls, field).offset
    src = tmp_path / "layout.c"
    src.write_text('#include <stdio.h>\n#include <stddef.h>\n#include "biss_master.h"\n'
                   "int main(void)\n{\n    " + "\n    ".join(lines) + "\n    return 0;\n}\n")
    exe = tmp_path / "layout"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", f"-I{ROOT / 'sw' / 'include'}",
                    "-o", str(exe), str(src)], check=True)
    got = dict(line.rsplit(" ", 1) for line in
               subprocess.run([str(exe)], check=True, capture_output=True,
                              text=True).stdout.splitlines())
    bad = {k: (int(got[k]), v) for k, v in want.items() if int(got[k]) != v}
    assert not bad, f"(C, ctypes) differ: {bad}"
    assert ctypes.sizeof(c_driver.Channel) > 0 and "biss_result_t.chain" in got


def test_driver_includes_only_freestanding_headers():
    """No C library beyond <stdint.h>, <stdbool.h>, <stddef.h> (and the generated header)."""
    allowed = {"stdint.h", "stdbool.h", "stddef.h", "biss_master.h", "biss_master_regs.h"}
    for path in ("include/biss_master.h", "src/biss_master.c", "include/biss_master_regs.h"):
        includes = set(re.findall(r'#include\s+[<"]([^>"]+)[>"]', (ROOT / "sw" / path).read_text()))
        assert includes <= allowed, f"{path}: {includes - allowed}"


def test_presets_are_the_encoder_models_formats(lib):
    """Every preset of the driver is a format of the encoder model under the same name, word by
    word; every named encoder of the contract (BP3 lengths aside) is a preset."""
    names = []
    for i in range(lib.biss_preset_count()):
        p = lib.biss_preset_at(i).contents
        name = p.name.decode()
        names.append(name)
        fmt = frames.PRESETS[name]
        assert p.words == len(fmt.words), name
        for w, word in enumerate(fmt.words):
            got = p.word[w]
            assert (got.data_bits, got.crc, got.nenw, got.lc) == \
                (word.data_bits, CRC_CODE[word.crc], word.nenw, word.lc), f"{name} word {w}"
        assert p.spw_check == fmt.is_safety, name
    assert sorted(names) == sorted(ENCODER_PRESETS)
    assert not lib.biss_preset_at(len(names))
    assert not lib.biss_preset_find(b"resolute_c_2")      # a prefix is not a name
    assert lib.biss_preset_find(b"evolute_36").contents.word[0].data_bits == 36


def test_status_names_are_the_contracts(lib):
    known = dict(STATUS_NAME)
    for code, name in known.items():
        assert lib.biss_status_name(code).decode() == name
    assert lib.biss_status_name(max(known) + 1).decode() == "?"


@pytest.mark.parametrize("ma_hz,half", [(10_000_000, 5), (5_000_000, 10), (3_000_000, 17),
                                        (80_000, 625)])
def test_preset_ma_rate_rounds_the_half_period_up(lib, ma_hz, half):
    """MA = f_clk / (2 * half period) at most the rate asked for (100 MHz clock)."""
    cfg = c_driver.Config()
    assert lib.biss_config_from_preset(byref(cfg), b"resolute_fs_rsh", SYS_CLK_HZ, ma_hz) == 0
    assert cfg.ma_half_period == half
    assert SYS_CLK_HZ / (2 * half) <= ma_hz < SYS_CLK_HZ / (2 * (half - 1))
    assert (cfg.request_period, cfg.break_time, cfg.ack_limit, cfg.timeout_limit) == (0, 0, 0, 0)


@pytest.mark.parametrize("name,clk,ma,err", [
    (b"resolute_c_26", SYS_CLK_HZ, 79_999, "BISS_ERR_MA_RATE"),         # below 80 kHz
    (b"resolute_c_26", SYS_CLK_HZ, 10_000_001, "BISS_ERR_MA_RATE"),     # above 10 MHz
    (b"resolute_c_26", 0, 1_000_000, "BISS_ERR_MA_RATE"),
    (b"resolute_c_26", 19_999_999, 10_000_000, "BISS_ERR_MA_HALF_PERIOD"),   # 1 clock
    (b"resolute_c_26", 20_000_001, 10_000_000, "BISS_OK"),                   # 2 clocks
    (b"no_such_encoder", SYS_CLK_HZ, 1_000_000, "BISS_ERR_UNKNOWN_PRESET"),
])
def test_preset_refuses_rates_it_cannot_make(lib, name, clk, ma, err):
    cfg = c_driver.Config()
    got = lib.biss_error_name(lib.biss_config_from_preset(byref(cfg), name, clk, ma)).decode()
    assert got == err


@pytest.mark.parametrize("name", ["two_axes.c", "bp3_identify.c"])
def test_docs_example_is_the_compiled_example(name):
    """docs/driver.md shows the examples of sw/examples/ (which `make driver` compiles)
    verbatim."""
    example = (ROOT / "sw" / "examples" / name).read_text()
    body = example.split("\n", 1)[1]                      # without its first comment line
    assert body.strip() in (ROOT / "docs" / "driver.md").read_text()


def test_error_names_are_the_headers(lib):
    """biss_error_name gives, for every code of biss_err_t in biss_master.h, that code's name."""
    header = (ROOT / "sw" / "include" / "biss_master.h").read_text()
    enum = header.split("typedef enum {", 1)[1].split("} biss_err_t;", 1)[0]
    codes = {name: int(value) for name, value in re.findall(r"(BISS_\w+) = (-?\d+)", enum)}
    assert len(codes) > 10 and codes["BISS_OK"] == 0
    for name, value in codes.items():
        assert lib.biss_error_name(value).decode() == name
    assert lib.biss_error_name(min(codes.values()) - 1).decode() == "?"
    assert lib.biss_error_name(1).decode() == "?"


# -- BP3: the decoders on banks built here from the spec's table (docs/protocol.md, section 7) --------
#: (field, address, bytes) of the BP3 EDS bank; U16 / U32 big endian. Written from the spec's
#: table, not from the driver or rtl/bissmaster.
EDS_TABLE = (
    ("bp_ver", 0x00, 1), ("bp_len", 0x01, 1), ("bp_id", 0x02, 1), ("dl", 0x03, 1),
    ("fb1", 0x04, 1), ("fb2", 0x05, 1), ("pon_pdl", 0x06, 1), ("en_typ", 0x08, 1),
    ("pos_num", 0x09, 1), ("mt_len", 0x0A, 1), ("mt_fmt", 0x0B, 1), ("co_len", 0x0C, 1),
    ("co_fmt", 0x0D, 1), ("fi_len", 0x0E, 1), ("fi_fmt", 0x0F, 1), ("mt_cnt", 0x10, 4),
    ("sip_cnt", 0x14, 4), ("sip_res", 0x18, 4), ("cpoly", 0x1C, 4), ("cstart", 0x20, 4),
    ("abs_acu", 0x24, 2), ("rel_acu", 0x26, 2), ("spd_acu", 0x28, 2), ("hyst", 0x2A, 2),
    ("spd_max", 0x2C, 2), ("acc_max", 0x2E, 2), ("tmp_min", 0x30, 2), ("tmp_max", 0x32, 2),
    ("vlt_min", 0x34, 2), ("vlt_max", 0x36, 2), ("cur_max", 0x38, 2),
)
#: A valid bank's fields: every multi-byte value with distinct bytes, so that a wrong byte
#: order or a wrong offset shows. BP_ID 0x62 (ID 0b0110, VER 1, C 0), DL 26 + 2.
EDS_VALUES = {
    "bp_ver": 1, "bp_len": 1, "bp_id": 0x62, "dl": 28, "fb1": 1, "fb2": 2, "pon_pdl": 254,
    "en_typ": 1, "pos_num": 2, "mt_len": 12, "mt_fmt": 1, "co_len": 14, "co_fmt": 0xA7,
    "fi_len": 3, "fi_fmt": 0x5C, "mt_cnt": 0x01020304, "sip_cnt": 0x0A0B0C0D,
    "sip_res": 0x11223344, "cpoly": 0x21, "cstart": 0, "abs_acu": 0x1234, "rel_acu": 0x2345,
    "spd_acu": 0x3456, "hyst": 0x4567, "spd_max": 0x5678, "acc_max": 0x6789,
    "tmp_min": 233, "tmp_max": 0x0178, "vlt_min": 4500, "vlt_max": 5500, "cur_max": 0xBEEF,
}


def eds_bank(**changes):
    """64 bytes: EDS_VALUES with ``changes``, CHKSUM (0x3F) = sum of 0x00..0x3E mod 256;
    ``chksum=`` overrides it, ``pad=`` fills the bytes that are no field (0x07, 0x3A..0x3E)."""
    values = {**EDS_VALUES, **changes}
    pad = values.pop("pad", 0)
    bank = bytearray([pad] * 64)
    for name, address, size in EDS_TABLE:
        bank[address:address + size] = values[name].to_bytes(size, "big")
    bank[0x3F] = values.get("chksum", sum(bank[:0x3F]) & 0xFF)
    return bytes(bank)


def decode_eds(lib, bank):
    eds = c_driver.Bp3Eds()
    err = lib.biss_bp3_decode_eds((c_uint8 * 64).from_buffer_copy(bank), byref(eds))
    return lib.biss_error_name(err).decode(), eds.as_dict()


@pytest.mark.parametrize("pad", [0x00, 0x9D])
def test_eds_decode_gives_every_field(lib, pad):
    """Every field of the table from its bytes, big endian; the padding bytes count in the
    checksum only."""
    bank = eds_bank(pad=pad)
    err, got = decode_eds(lib, bank)
    assert err == "BISS_OK"
    for name, _, _ in EDS_TABLE:
        assert got[name] == EDS_VALUES[name], name
    assert got["chksum"] == bank[0x3F] == sum(bank[:0x3F]) & 0xFF
    assert (got["eds_bank"], got["profile_bank"]) == (0, 0)


@pytest.mark.parametrize("changes,want", [
    ({"chksum": (sum(eds_bank()[:0x3F]) + 1) & 0xFF}, "BISS_ERR_EDS_CHECKSUM"),
    ({"chksum": 0, "bp_id": 0x70}, "BISS_ERR_EDS_CHECKSUM"),     # the checksum is checked first
    ({"bp_id": 0x72}, "BISS_ERR_NOT_BP3"),                      # ID 0b0111
    ({"bp_id": 0x64}, "BISS_ERR_BP3_FIELD"),                    # VER 2 (reserved)
    ({"bp_id": 0x60}, "BISS_ERR_BP3_FIELD"),                    # VER 0 (not allowed)
    ({"dl": 0x01}, "BISS_ERR_BP3_FIELD"),
    ({"dl": 0x3A}, "BISS_ERR_BP3_FIELD"),                       # C = 0: at most 0x39
    ({"dl": 0x82}, "BISS_ERR_BP3_FIELD"),                       # 0x43 bit 7 set
    ({"bp_ver": 2}, "BISS_ERR_BP3_FIELD"), ({"bp_len": 0}, "BISS_ERR_BP3_FIELD"),
    ({"fb1": 3}, "BISS_ERR_BP3_FIELD"), ({"fb2": 0}, "BISS_ERR_BP3_FIELD"),
    ({"pon_pdl": 0}, "BISS_ERR_BP3_FIELD"), ({"pon_pdl": 255}, "BISS_ERR_BP3_FIELD"),
    ({"en_typ": 2}, "BISS_ERR_BP3_FIELD"), ({"pos_num": 3}, "BISS_ERR_BP3_FIELD"),
    ({"mt_fmt": 2}, "BISS_ERR_BP3_FIELD"),
    ({"bp_id": 0x63, "dl": 0x3F}, "BISS_OK"),                   # C = 1: up to 0x3F
])
def test_eds_decode_refuses_what_the_profile_does_not_allow(lib, changes, want):
    assert decode_eds(lib, eds_bank(**changes))[0] == want


@pytest.mark.parametrize("r42,r43,want", [
    (0x62, 0x1C, ("BISS_OK", 1, 0, 0x1C, 26)),
    (0x63, 0x3F, ("BISS_OK", 1, 1, 0x3F, 0)),           # C = 1: no DL_POS split
    (0x62, 0x02, ("BISS_OK", 1, 0, 0x02, 0)),
    (0x62, 0x39, ("BISS_OK", 1, 0, 0x39, 55)),
    (0x52, 0x1C, ("BISS_ERR_NOT_BP3",)),
    (0x66, 0x1C, ("BISS_ERR_BP3_FIELD",)),               # VER 3
    (0x62, 0x40, ("BISS_ERR_BP3_FIELD",)),
])
def test_profile_id_decode(lib, r42, r43, want):
    pid = c_driver.Bp3Id()
    err = lib.biss_error_name(lib.biss_bp3_decode_id(r42, r43, byref(pid))).decode()
    got = (err,) if err != "BISS_OK" else \
        (err, pid.version, pid.crc_mode, pid.data_length, pid.position_bits)
    assert got == want


@pytest.mark.parametrize("changes,want", [
    ({}, ("BISS_OK", 26, CRC_CODE["crc6"])),
    ({"dl": 57}, ("BISS_OK", 55, CRC_CODE["crc6"])),
    ({"cpoly": 0x190D9 >> 1}, ("BISS_OK", 26, CRC_CODE["crc16"])),
    ({"cpoly": 0}, ("BISS_ERR_UNSUPPORTED",)),                  # no CRC
    # Other CRCs are custom ones: (width, register polynomial, start), worked out by hand from
    # CPOLY = the polynomial without x^0 shifted down one bit (docs/protocol.md, section 7).
    ({"cpoly": 0x30}, ("BISS_OK", 26, CRC_CODE["custom"], (6, 0x21, 0))),   # 0x61
    ({"cstart": 1}, ("BISS_OK", 26, CRC_CODE["custom"], (6, 0x03, 1))),     # 0x43 from 1
    ({"cpoly": 0x8810, "cstart": 0xFFFF},
     ("BISS_OK", 26, CRC_CODE["custom"], (16, 0x1021, 0xFFFF))),          # 0x11021
    ({"cpoly": 0x10000}, ("BISS_ERR_UNSUPPORTED",)),            # 17 bits
    ({"cstart": 0x40}, ("BISS_ERR_UNSUPPORTED",)),              # start wider than 6 bits
    ({"fb1": 2, "fb2": 1}, ("BISS_ERR_UNSUPPORTED",)),          # nW before nE
    ({"bp_id": 0x63}, ("BISS_ERR_UNSUPPORTED",)),               # C = 1: BiSS Safety
    ({"dl": 2}, ("BISS_ERR_UNSUPPORTED",)),                     # DL_POS 0
])
def test_bp3_config_from_the_eds(lib, changes, want):
    """word 0 = DL - 2 position bits, nE/nW, no LC, the CRC CPOLY names; word 1 and the SPW
    check off; the MA and time settings kept as they were."""
    eds = c_driver.Bp3Eds()
    err = lib.biss_bp3_decode_eds((c_uint8 * 64).from_buffer_copy(eds_bank(**changes)),
                                  byref(eds))
    assert lib.biss_error_name(err).decode() == "BISS_OK"
    cfg = c_driver.Config()
    assert lib.biss_config_from_preset(byref(cfg), b"resolute_fs_rsh", SYS_CLK_HZ, 5_000_000) == 0
    before = (cfg.ma_half_period, cfg.break_time, cfg.ack_limit)
    got = lib.biss_error_name(lib.biss_bp3_config(byref(eds), byref(cfg))).decode()
    if got != "BISS_OK":
        assert (got,) == want
        return
    w0 = cfg.word[0]
    assert (got, w0.data_bits, w0.crc) == want[:3]
    if w0.crc == CRC_CODE["custom"]:
        assert (w0.crc_width, w0.crc_poly, w0.crc_start, w0.crc_inverted) == (*want[3], True)
    assert (w0.nenw, w0.lc, cfg.word1_enable, cfg.spw_check, cfg.word[1].data_bits) == \
        (True, False, False, False, 0)
    assert (cfg.ma_half_period, cfg.break_time, cfg.ack_limit) == before


#: iC-MB4's CRCs by length with their top term (issue 26 / docs/protocol.md section 6).
ICMB4_CRCS = {3: 0xB, 4: 0x13, 5: 0x25, 6: 0x43, 7: 0x89, 8: 0x12F, 16: 0x190D9}


@pytest.mark.parametrize("width", range(0, 18))
def test_crc_named_gives_icmb4s_crcs(lib, width):
    word = c_driver.WordFormat(data_bits=20)
    err = lib.biss_error_name(lib.biss_crc_named(byref(word), width)).decode()
    if width not in ICMB4_CRCS:
        assert err == "BISS_ERR_CRC"
        return
    assert err == "BISS_OK"
    top = ICMB4_CRCS[width]
    assert (word.crc, word.crc_width, word.crc_poly | 1 << width, word.crc_start,
            word.crc_inverted) == (CRC_CODE["custom"], width, top, 0, True)


@pytest.mark.parametrize("cap", (55, 40, 36, 13, 1))
def test_signed_data_extends_from_the_register_width(lib, cap):
    """biss_signed_data reads a word's register (sign-extended by the core to its width, the
    channel's max_data_bits) as a 64-bit signed number; a one-word build's word 1 (cap 0)
    and a word past 1 return the data as it is."""
    ch = c_driver.Channel()
    ch.max_data_bits[0], ch.max_data_bits[1] = cap, 0
    top = 1 << (cap - 1)
    low = 5 % top
    for data, want in (((1 << cap) - 1, -1), (top, -top), (top - 1, top - 1), (0, 0),
                       (top | low, low - top), (low, low)):
        assert lib.biss_signed_data(byref(ch), 0, data) == want, (hex(data), want)
        assert lib.biss_signed_data(byref(ch), 1, data) == data
        assert lib.biss_signed_data(byref(ch), 2, data) == data


# -- Register access against a bus of this test's own (no simulator) --------------------------
class FakeEngine:
    """A bus whose registers are a dict, addresses from the register map source
    (sim/shared/regspec.py); ``irq_status`` reads ``done_after`` polls later with access_done
    set (never with None), ``ca.state`` reads ``state``; every access is logged."""

    def __init__(self, lib, done_after=None, state=0, rbuf=b""):
        self.map = regspec.load()
        self.log, self.mem = [], {}
        self.done_after, self.polls, self.state = done_after, 0, state
        self.irq_status = self.map.address("irq_status", 0)
        self.rbuf = {self.map.address("ca.rbuf", 0, i // 4): int.from_bytes(
            rbuf[i:i + 4].ljust(4, b"\0"), "little") for i in range(0, len(rbuf), 4)}
        self._rd = c_driver.READ32(self.read)
        self._wr = c_driver.WRITE32(self.write)
        self.bus = c_driver.Bus(0, self._rd, self._wr, None)
        self.ch = c_driver.Channel()
        self.ch.bus, self.ch.base, self.ch.index = self.bus, self.map.address("ctrl", 0), 0
        self.ch.has_register_access, self.ch.max_polls = True, 50

    def read(self, ctx, addr):
        self.log.append(("r", addr))
        if addr == self.irq_status:
            self.polls += 1
            done = self.done_after is not None and self.polls > self.done_after
            return self.map.reg("irq_status", 0).fields["access_done"].put(0, int(done))
        if addr == self.map.address("ca.state", 0):
            return self.state
        return self.rbuf.get(addr, 0)

    def write(self, ctx, addr, value):
        self.log.append(("w", addr, value))
        self.mem[addr] = value


@pytest.mark.parametrize("slave,address,count,access,want", [
    (8, 0x48, 1, True, "BISS_ERR_SLAVE_ID"),
    (0, 0x80, 1, True, "BISS_ERR_ADDRESS"),
    (0, 0x7F, 2, True, "BISS_ERR_ADDRESS"),             # last register 0x80
    (0, 0x41, 64, True, "BISS_ERR_ADDRESS"),
    (0, 0x00, 0, True, "BISS_ERR_COUNT"),
    (0, 0x00, 65, True, "BISS_ERR_COUNT"),
    (0, 0x48, 1, False, "BISS_ERR_NO_REGISTER_ACCESS"),
])
def test_register_access_checks_arguments_before_the_bus(lib, slave, address, count, access,
                                                         want):
    bus = FakeEngine(lib, done_after=0)
    bus.ch.has_register_access = access
    buf = (c_uint8 * 65)()
    for fn in ("biss_reg_read", "biss_reg_write"):
        err = getattr(lib, fn)(byref(bus.ch), slave, address, buf, count, None)
        assert lib.biss_error_name(err).decode() == want, fn
    assert bus.log == [], "a refused access touched the bus"


def test_register_access_poll_limit_aborts(lib):
    """An access that never ends: max_polls reads of irq_status, then ca.ctrl.abort and
    BISS_ERR_TIMEOUT."""
    bus = FakeEngine(lib, done_after=None)
    buf, done = (c_uint8 * 4)(), c_driver.c_uint(99)
    err = lib.biss_reg_read(byref(bus.ch), 0, 0x48, buf, 4, byref(done))
    assert lib.biss_error_name(err).decode() == "BISS_ERR_TIMEOUT"
    assert (bus.polls, done.value) == (bus.ch.max_polls, 0)
    ctrl = bus.map.reg("ca.ctrl", 0).fields
    assert bus.log[-1] == ("w", bus.map.address("ca.ctrl", 0), ctrl["abort"].put(0, 1))


@pytest.mark.parametrize("fn", ("biss_reg_read", "biss_reg_write"))
@pytest.mark.parametrize("bytes_done", (0, 3))
def test_register_access_ok_with_bytes_missing_is_an_error(lib, fn, bytes_done):
    """docs/control.md: status OK means every byte was done. A window that says OK with fewer
    bytes (a broken or foreign map) gives BISS_ERR_CA_SHORT and *done 0: no byte is trusted,
    so the BP3 decoders never see a buffer the engine did not fill."""
    state = FakeEngine(lib).map.reg("ca.state", 0).fields
    bus = FakeEngine(lib, done_after=1, state=state["bytes_done"].put(0, bytes_done),
                     rbuf=bytes(range(1, 5)))
    buf, done = (c_uint8 * 4)(0xEE, 0xEE, 0xEE, 0xEE), c_driver.c_uint(99)
    err = getattr(lib, fn)(byref(bus.ch), 0, 0x48, buf, 4, byref(done))
    assert (lib.biss_error_name(err).decode(), done.value) == ("BISS_ERR_CA_SHORT", 0)
    if fn == "biss_reg_read":
        assert bytes(buf) == b"\xee" * 4, "a short read copied bytes"


def test_register_access_bytes_and_lanes(lib):
    """A 6-byte write: byte i in lane i % 4 of ca.wbuf[i / 4]; the request's fields; a 6-byte
    read with status OK takes the bytes from ca.rbuf the same way; a status of the engine
    becomes its error code with the bytes done."""
    data = bytes([0x10, 0x21, 0x32, 0x43, 0x54, 0x65])
    state = FakeEngine(lib).map.reg("ca.state", 0).fields
    ok = state["bytes_done"].put(0, 6)
    bus = FakeEngine(lib, done_after=3, state=ok)
    done = c_driver.c_uint()
    err = lib.biss_reg_write(byref(bus.ch), 5, 0x50, (c_uint8 * 6).from_buffer_copy(data), 6,
                             byref(done))
    assert (lib.biss_error_name(err).decode(), done.value) == ("BISS_OK", 6)
    assert bus.mem[bus.map.address("ca.wbuf", 0, 0)] == 0x43322110
    assert bus.mem[bus.map.address("ca.wbuf", 0, 1)] == 0x6554
    req = bus.map.reg("ca.request", 0).fields
    assert bus.mem[bus.map.address("ca.request", 0)] == req["write"].put(
        req["count"].put(req["address"].put(req["slave_id"].put(0, 5), 0x50), 6), 1)
    bus = FakeEngine(lib, done_after=2, state=ok, rbuf=data)
    buf = (c_uint8 * 6)()
    err = lib.biss_reg_read(byref(bus.ch), 0, 0x50, buf, 6, byref(done))
    assert (lib.biss_error_name(err).decode(), bytes(buf), done.value) == ("BISS_OK", data, 6)
    for name, code in CA_STATUS.items():
        if name == "OK":
            continue
        st = state["status"].put(state["bytes_done"].put(0, 1), code)
        bus = FakeEngine(lib, done_after=0, state=st, rbuf=data)
        buf = (c_uint8 * 6)()
        err = lib.biss_reg_read(byref(bus.ch), 0, 0x50, buf, 6, byref(done))
        assert (lib.biss_error_name(err).decode(), done.value, buf[0]) == \
            (f"BISS_ERR_CA_{name.replace('_ERROR', '')}", 1, data[0])


# -- Chains (words 2..7): checks, signed data and the read rule, without a simulator ----------
def chain_channel(words=4, chain_bits=(24, 16), read32=None, write32=None):
    """A channel handle as biss_channel_init fills it for a build of ``words`` words (word 0 and
    word 1 of 40 and 32 bits, the chain words ``chain_bits``), on hooks of the caller's (or
    hooks that read 0)."""
    ch = c_driver.Channel()
    hooks = (c_driver.READ32(read32 or (lambda ctx, addr: 0)),
             c_driver.WRITE32(write32 or (lambda ctx, addr, value: None)))
    ch.bus = c_driver.Bus(0, *hooks)
    ch.base = regspec.load().address("ctrl", 0)
    ch._hooks = hooks                   # the callbacks must outlive the calls
    ch.max_data_bits[0], ch.max_data_bits[1] = 40, 32
    ch.timer_width, ch.words, ch.chain_words = 24, words, max(words - 2, 0)
    for i, bits in enumerate(chain_bits):
        ch.chain_data_bits[i] = bits
    return ch


def chain_config(lib, chain_words=2):
    """A chain of ``chain_words`` + 2 words: word 0 26 bits CRC-6, word 1 17 bits CRC-6, word 2
    12 bits CRC-6, word 3 16 bits CRC-16 (nE/nW each)."""
    cfg = c_driver.Config()
    assert lib.biss_config_from_preset(byref(cfg), b"resolute_c_26", SYS_CLK_HZ, 5_000_000) == 0
    cfg.word1_enable = True
    cfg.word[1].data_bits, cfg.word[1].crc, cfg.word[1].nenw = 17, CRC_CODE["crc6"], True
    cfg.chain_words = chain_words
    for i, (bits, crc) in enumerate(((12, "crc6"), (16, "crc16"))[:chain_words]):
        cfg.chain[i].data_bits, cfg.chain[i].crc, cfg.chain[i].nenw = bits, CRC_CODE[crc], True
    return cfg


def _changed(cfg, **changes):
    c = c_driver.Config.from_buffer_copy(cfg)
    for path, value in changes.items():
        obj, *rest = path.split("__")
        if rest:                        # chain<i>__field
            setattr(c.chain[int(obj[5:])], rest[0], value)
        else:
            setattr(c, obj, value)
    return c


@pytest.mark.parametrize("changes,want", [
    ({}, "BISS_OK"),
    ({"chain_words": 0}, "BISS_OK"),
    ({"chain_words": 3}, "BISS_ERR_CHAIN"),                 # word 4 of a 4-word build
    ({"chain_words": 4}, "BISS_ERR_CHAIN"),                 # word 5
    ({"chain_words": 7}, "BISS_ERR_CHAIN"),                 # beyond word 7
    ({"word1_enable": False}, "BISS_ERR_CHAIN"),            # a gap: words 2, 3 without word 1
    ({"chain0__data_bits": 25}, "BISS_ERR_DATA_BITS"),      # word 2 is at most 24 bits
    ({"chain0__data_bits": 0}, "BISS_ERR_DATA_BITS"),
    ({"chain1__data_bits": 17}, "BISS_ERR_DATA_BITS"),      # word 3 at most 16
    ({"chain1__data_bits": 16}, "BISS_OK"),
    ({"chain1__crc": 4}, "BISS_ERR_CRC"),
    ({"chain1__crc": CRC_CODE["custom"]}, "BISS_ERR_CRC"),  # custom, width 0
    ({"chain1__crc": CRC_CODE["custom"], "chain1__crc_width": 4,
      "chain1__crc_poly": 0x13}, "BISS_ERR_CRC"),           # polynomial wider than 4 bits
    ({"chain1__crc": CRC_CODE["custom"], "chain1__crc_width": 4, "chain1__crc_poly": 0x3,
      "chain1__crc_start": 0x9}, "BISS_OK"),
    ({"chain1__lc": True}, "BISS_OK"),                      # one LC per frame ...
    ({"chain1__lc": True, "chain0__lc": True}, "BISS_ERR_LC"),      # ... not two
    ({"chain1__lc": True, "word__0__lc": None}, "BISS_ERR_LC"),
    ({"chain_words": 1, "chain1__lc": True, "chain1__data_bits": 0}, "BISS_OK"),  # not in the frame
    ({"ssi": True, "word1_enable": False, "chain_words": 0}, "BISS_OK"),
])
def test_chain_config_check(lib, changes, want):
    """biss_config_check on a 4-word build (words 2 and 3 of up to 24 and 16 bits)."""
    changes = dict(changes)
    word0_lc = changes.pop("word__0__lc", False) is None
    cfg = _changed(chain_config(lib), **changes)
    if word0_lc:
        cfg.word[0].lc = True
    ch = chain_channel()
    ch.has_ssi = True
    assert lib.biss_error_name(lib.biss_config_check(byref(ch), byref(cfg))).decode() == want


def test_chain_config_check_on_builds_without_chains(lib):
    """A two-word build refuses any chain word (a one-word build word 1 first); SSI with chain
    words is refused (as SSI or as a chain)."""
    cfg = chain_config(lib, chain_words=1)
    for words, want in ((2, "BISS_ERR_CHAIN"), (1, "BISS_ERR_WORD1")):
        ch = chain_channel(words=words, chain_bits=())
        ch.max_data_bits[1] = 32 if words == 2 else 0
        err = lib.biss_error_name(lib.biss_config_check(byref(ch), byref(cfg))).decode()
        assert err == want, words
    ch = chain_channel()
    ch.has_ssi = True
    cfg = _changed(cfg, ssi=True)
    assert lib.biss_error_name(lib.biss_config_check(byref(ch), byref(cfg))).decode() in (
        "BISS_ERR_SSI", "BISS_ERR_CHAIN")


def test_signed_data_of_chain_words(lib):
    """Words 2..7 extend from chain_data_bits (a word not built: the data as it is)."""
    ch = chain_channel(chain_bits=(24, 16))
    assert lib.biss_signed_data(byref(ch), 2, 0xFFF800) == -0x800
    assert lib.biss_signed_data(byref(ch), 2, 0x7FF800) == 0x7FF800
    assert lib.biss_signed_data(byref(ch), 3, 0x8000) == -0x8000
    assert lib.biss_signed_data(byref(ch), 3, 0xFFFF) == -1
    assert lib.biss_signed_data(byref(ch), 4, 0xFFFF) == 0xFFFF       # not built
    assert lib.biss_signed_data(byref(ch), 8, 0xFFFF) == 0xFFFF       # no such word


class ChainBus:
    """A map whose chain.updates advances by one on each of the reads listed in ``bumps``
    (counting the reads of chain.updates from 1); chain.wN_lo reads ``frame`` (the update
    count) so a torn read shows; every read logged."""

    def __init__(self, bumps=()):
        self.map = regspec.load()
        self.updates, self.reads, self.bumps, self.log = 0, 0, set(bumps), []

    def read(self, ctx, addr):
        self.log.append(addr)
        if addr == self.map.address("chain.updates", 0):
            self.reads += 1
            if self.reads in self.bumps:
                self.updates += 1
            return self.updates
        if addr in (self.map.address(f"chain.w{w}_lo", 0) for w in range(2, 8)):
            return 0x100 + self.updates
        return 0


@pytest.mark.parametrize("bumps,tries,err", [
    ((), 1, "BISS_OK"),
    ((2,), 2, "BISS_OK"),               # a frame ended during the first read: read again
    ((2, 3, 4), 4, "BISS_OK"),
    (tuple(range(2, 10)), 8, "BISS_ERR_TORN"),      # never settled within BISS_READ_RETRIES
])
def test_chain_read_rule(lib, bumps, tries, err):
    """biss_read_result on a 4-word build: chain.updates, then result.status, chain.flags and
    the chain words, then chain.updates: equal, done; else again from result.status (the
    second count is the next first one); after 8 tries BISS_ERR_TORN."""
    bus = ChainBus(bumps)
    ch = chain_channel(read32=bus.read)
    res = c_driver.Result()
    got = lib.biss_error_name(lib.biss_read_result(byref(ch), byref(res))).decode()
    assert got == err
    status = bus.map.address("result.status", 0)
    assert (bus.log.count(status), bus.reads) == (tries, tries + 1)
    assert bus.log[0] == bus.map.address("chain.updates", 0) and bus.log[1] == status
    # The words of the last try: read after `tries` reads of chain.updates.
    assert res.chain_words == 2
    assert res.chain[0].data == 0x100 + len([b for b in bumps if b <= tries])
    assert res.chain[2].data == 0, "a word not read is 0"


@pytest.mark.parametrize("words,chain_words", [(2, 0), (4, 0)])
def test_result_reads_without_chain_words_are_unchanged(lib, words, chain_words):
    """With no chain word to read (a two-word build, or a chain build configured for two
    words): the reads of before chains, result.status first, no chain register."""
    bus = ChainBus()
    ch = chain_channel(words=words, read32=bus.read)
    ch.chain_words = chain_words
    res = c_driver.Result()
    assert lib.biss_read_result(byref(ch), byref(res)) == 0
    m = bus.map
    assert bus.log == [m.address(f"result.{r}", 0) for r in
                       ("status", "seq", "w0_lo", "w0_hi", "w1_lo", "w1_hi", "timestamp",
                        "line")]
    assert res.chain_words == 0


def test_configure_writes_every_chain_word_the_build_has(lib):
    """biss_configure on a 4-word build, chain_words 1: cfg_w2 enabled with its fields, word 2's
    custom CRC registers, cfg_w3 written 0 (disabled) with its CRC registers 0, no register of
    words 4..7; the handle's chain_words becomes 1."""
    m = regspec.load()
    writes = {}
    ch = chain_channel(write32=lambda ctx, addr, value: writes.__setitem__(addr, value))
    cfg = chain_config(lib, chain_words=2)
    c2 = cfg.chain[0]
    c2.crc, c2.crc_width, c2.crc_poly, c2.crc_start, c2.crc_inverted = 3, 4, 0x3, 0x9, False
    c2.gray, c2.is_signed = True, True
    cfg.chain_words = 1
    assert lib.biss_error_name(lib.biss_configure(byref(ch), byref(cfg))).decode() == "BISS_OK"
    f = {n: m.reg("cfg_w2", 0).fields[n] for n in m.reg("cfg_w2", 0).fields}
    want = 0
    for name, value in dict(data_bits=12, nenw=1, lc=0, crc=3, gray=1, is_signed=1,
                            enable=1).items():
        want = f[name].put(want, value)
    assert writes[m.address("cfg_w2", 0)] == want
    crc = m.reg("cfg_w2_crc", 0).fields
    assert writes[m.address("cfg_w2_crc", 0)] == crc["crc_inverted"].put(
        crc["crc_width"].put(crc["crc_poly"].put(0, 0x3), 4), 0)
    assert writes[m.address("cfg_w2_crc_start", 0)] == 0x9
    for r in ("cfg_w3", "cfg_w3_crc", "cfg_w3_crc_start"):
        assert writes[m.address(r, 0)] == 0, r
    for w in range(4, 8):
        assert m.address(f"cfg_w{w}", 0) not in writes
    assert ch.chain_words == 1


@pytest.mark.parametrize("words,chain,want_words,want_bits", [
    (4, (24, 16, 0, 0, 0, 0), 4, (24, 16, 0, 0, 0, 0)),
    (8, (63, 1, 20, 33, 7, 12), 8, (63, 1, 20, 33, 7, 12)),
    (2, (), 2, (0,) * 6),
    (0, (), 2, (0,) * 6),               # a map without caps.words: two words from data_bits_w1
])
def test_channel_init_reads_the_chain_caps(lib, words, chain, want_words, want_bits):
    """biss_channel_init: caps.words, and caps_chain / caps_chain2 (read only when the build
    has more than two words) into chain_data_bits; chain_words = the build's chain words."""
    m = regspec.load()
    caps = m.reg("caps", 0).fields
    version = m.reg("version").fields
    regs = {m.address("id"): 0x42695353,            # "BiSS", docs/registers.md
            m.address("version"): version["major"].put(0, 2),
            m.address("channels"): 1,
            m.address("caps", 0): caps["words"].put(caps["data_bits_w1"].put(
                caps["data_bits_w0"].put(0, 40), 32), words)}
    for reg, names, values in (("caps_chain", "abcd", chain[:4]), ("caps_chain2", "ab", chain[4:])):
        f = m.reg(reg, 0).fields
        word = 0
        for n, v in zip(names, values):
            word = f[f"data_bits_{n}"].put(word, v)
        regs[m.address(reg, 0)] = word
    log = []

    def read(ctx, addr):
        log.append(addr)
        return regs.get(addr, 0)
    hooks = (c_driver.READ32(read), c_driver.WRITE32(lambda ctx, addr, value: None))
    bus = c_driver.Bus(0, *hooks)
    ch = c_driver.Channel()
    assert lib.biss_error_name(lib.biss_channel_init(byref(ch), byref(bus), 0)).decode() == \
        "BISS_OK"
    assert (ch.words, tuple(ch.chain_data_bits), ch.chain_words) == \
        (want_words, want_bits, max(want_words - 2, 0))
    chain_caps = {m.address("caps_chain", 0), m.address("caps_chain2", 0)}
    assert bool(chain_caps & set(log)) == (want_words > 2)
    assert all(log.count(a) <= 1 for a in chain_caps), "a caps register read twice"
