"""Encoder presets for a channel's runtime configuration, by name.

The names and words are those of the C driver's table (docs/driver.md, "Encoder presets"),
written here from that page: tb/tests/host/test_presets.py checks them against it and against
the encoder model's formats. ``biss-c-N`` is any BiSS C (or BP3 Standard Encoder) single word of
N position bits with nE, nW and CRC-6.

A preset gives every configuration field of the register map (docs/registers.md, ``cfg_*``):
its words, the SPW check, the MA half period for an MA rate (``ceil(clock / (2 * rate))``: the
MA rate is at most the one asked for, as ``biss_config_from_preset``), every time setting 0 (the
core's defaults) and ``end_check`` 0.
"""

import math
import re

from . import regmap

#: MA rates BiSS C allows (docs/driver.md: biss_config_from_preset's BISS_ERR_MA_RATE).
MA_HZ_MIN = 80_000
MA_HZ_MAX = 10_000_000

_C = {"nenw": 1, "lc": 0, "crc": "crc6"}
_SPW = {"nenw": 1, "lc": 1, "crc": "crc16"}

#: name -> (word 0, word 1 or None); a word is {data_bits, nenw, lc, crc}.
PRESETS = {
    **{f"resolute_c_{n}": ({"data_bits": n, **_C}, None) for n in (18, 26, 32, 36)},
    **{f"evolute_{n}": ({"data_bits": n, **_C}, None) for n in (26, 32, 36)},
    "resolute_fs_lmm": ({"data_bits": 32, **_C}, {"data_bits": 32, **_SPW}),
    "resolute_fs_rsm": ({"data_bits": 28, **_C}, {"data_bits": 24, **_SPW}),
    "resolute_fs_rsh": ({"data_bits": 36, **_C}, {"data_bits": 28, **_SPW}),
    "fortis_fs_rsh": ({"data_bits": 36, **_C}, {"data_bits": 28, **_SPW}),
}
#: The SPW check of the two-word presets: on, tolerance 1 SPW LSB.
SPW_TOLERANCE = 1

_GENERIC = re.compile(r"biss-c-(\d+)$")


def words_of(name):
    """(word 0, word 1 or None) of preset ``name``; KeyError with the known names if none."""
    if name in PRESETS:
        return PRESETS[name]
    m = _GENERIC.match(name)
    if m and 1 <= int(m.group(1)) <= 55:
        return {"data_bits": int(m.group(1)), **_C}, None
    raise KeyError(f"no preset {name!r}; presets: {', '.join(PRESETS)}, biss-c-N (N 1..55)")


def half_period(clock_hz, ma_hz):
    """The MA half period in clocks for an MA rate of at most ``ma_hz``; ValueError outside
    BiSS C's rates or below the core's 2 clocks."""
    if not MA_HZ_MIN <= ma_hz <= MA_HZ_MAX:
        raise ValueError(f"MA rate {ma_hz:g} Hz: BiSS C runs {MA_HZ_MIN / 1e3:g} kHz.."
                         f"{MA_HZ_MAX / 1e6:g} MHz")
    hp = math.ceil(clock_hz / (2 * ma_hz))
    if hp < 2:
        raise ValueError(f"MA rate {ma_hz:g} Hz at a {clock_hz:g} Hz clock: a half period of "
                         f"{hp} clock(s), the core needs 2 or more")
    if hp >= 1 << regmap.FIELDS["cfg_ma"]["ma_half_period"][1]:
        raise ValueError(f"MA rate {ma_hz:g} Hz at a {clock_hz:g} Hz clock: a half period of "
                         f"{hp} clocks does not fit cfg_ma.ma_half_period")
    return hp


def config(name, clock_hz, ma_hz):
    """Every configuration field (``{field: value}``) for preset ``name`` at ``ma_hz``."""
    w0, w1 = words_of(name)
    settings = {
        "ma_half_period": half_period(clock_hz, ma_hz), "delay_limit": 0,
        "request_period": 0, "break_time": 0, "ack_limit": 0, "timeout_limit": 0,
        "end_check": 0, "spw_check": int(w1 is not None),
        "spw_tolerance": SPW_TOLERANCE if w1 is not None else 0,
        "w1_enable": int(w1 is not None),
        # The line checks at their defaults (docs/ports.md, "Noise: the line checks").
        "quiet_time": 0, "noise_limit": 0, "delay_tolerance": 0,
    }
    for n, word in ((0, w0), (1, w1 or {"data_bits": 0, "nenw": 0, "lc": 0, "crc": "none"})):
        settings.update({f"w{n}_data_bits": word["data_bits"], f"w{n}_nenw": word["nenw"],
                         f"w{n}_lc": word["lc"], f"w{n}_crc": regmap.CRC_CODES[word["crc"]],
                         f"w{n}_gray": 0})
        # The presets' encoders use the named CRCs: no custom CRC (its settings cleared).
        settings.update({f"w{n}_crc_{k}": 0 for k in ("width", "poly", "start", "inverted")})
    return settings


def describe(name):
    """One line: the preset's words."""
    parts = []
    for n, word in enumerate(words_of(name)):
        if word:
            flags = " nE nW" * word["nenw"] + " LC" * word["lc"]
            parts.append(f"word {n} {word['data_bits']} bits{flags} {word['crc'].upper()}")
    return ", ".join(parts)
