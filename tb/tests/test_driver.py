"""The C driver (sw/) without a simulator: it builds warning-free as strict C99 with every
compiler installed, and its tables agree with the test side's.

Its behaviour against the RTL is tested in sim/scenarios/driver.py (sim/test_driver.py). Here:
the encoder presets against the encoder model's formats (tb/encoder_model/frames.PRESETS), the
status names against tb/master_contract.py, the preset-to-configuration arithmetic and its
range checks, and the example of docs/driver.md being the file the build compiles.
"""

import re
import shutil
import subprocess
from ctypes import byref
from pathlib import Path

import pytest

from encoder_model import frames
from master_contract import CRC_CODE, ENCODER_PRESETS, STATUS_NAME, SYS_CLK_HZ
from sim.shared import c_driver

ROOT = Path(__file__).resolve().parents[2]
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
    library, the static library and the docs' example, with gcc and clang where installed."""
    found = [cc for cc in COMPILERS if shutil.which(cc)]
    assert found, f"none of {COMPILERS} is installed"
    for cc in found:
        out = tmp_path / cc
        r = subprocess.run(["make", "-C", str(ROOT / "sw"), f"BUILD={out}", f"CC={cc}"],
                           capture_output=True, text=True)
        assert r.returncode == 0, f"{cc}:\n{r.stdout}\n{r.stderr}"
        assert "warning" not in r.stderr, r.stderr
        for name in ("libbissmaster.so", "libbissmaster.a", "two_axes.o"):
            assert (out / name).is_file(), f"{cc}: no {name}"


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
    for code, name in STATUS_NAME.items():
        assert lib.biss_status_name(code).decode() == name
    assert lib.biss_status_name(max(STATUS_NAME) + 1).decode() == "?"


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


def test_docs_example_is_the_compiled_example():
    """docs/driver.md shows sw/examples/two_axes.c (which `make driver` compiles) verbatim."""
    example = (ROOT / "sw" / "examples" / "two_axes.c").read_text()
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
