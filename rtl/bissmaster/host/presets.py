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
    if m and 1 <= int(m.group(1)) <= 64:
        return {"data_bits": int(m.group(1)), **_C}, None
    raise KeyError(f"no preset {name!r}; presets: {', '.join(PRESETS)}, biss-c-N (N 1..64)")


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
        "quiet_time": 0, "noise_limit": 0, "delay_tolerance": 0, "confirm_frames": 0,
        # The presets are BiSS encoders: SSI mode off.
        "ssi": 0, "ssi_error": 0, "ssi_error_low": 0, "ssi_double": 0, "ssi_delay": 0,
    }
    for n, word in ((0, w0), (1, w1 or {"data_bits": 0, "nenw": 0, "lc": 0, "crc": "none"})):
        settings.update({f"w{n}_data_bits": word["data_bits"], f"w{n}_nenw": word["nenw"],
                         f"w{n}_lc": word["lc"], f"w{n}_crc": regmap.CRC_CODES[word["crc"]],
                         f"w{n}_gray": 0, f"w{n}_signed": 0})
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


# -- A word's CRC by name (config --w0-crc / --w1-crc) ----------------------------------------

#: iC-MB4's named CRCs by width: the polynomial with its top term (docs/protocol.md, section
#: 6). Each starts at 0 and is sent inverted; 6 and 16 are BiSS's CRC-6 and CRC-16.
ICMB4_CRCS = {3: 0xB, 4: 0x13, 5: 0x25, 6: 0x43, 7: 0x89, 8: 0x12F, 16: 0x190D9}
#: The widest custom CRC: the register polynomial's field (cfg_crc0.w0_crc_poly).
CUSTOM_CRC_MAX_WIDTH = regmap.FIELDS["cfg_crc0"]["w0_crc_poly"][1]
#: How a CRC is named on the command line (docs/bench.md, Host tool).
CRC_SYNTAX = ("none | crc6 | crc16 | icmb4-N (N " + "/".join(map(str, ICMB4_CRCS)) + ") | "
              "custom:WIDTH,POLY[,START[,inverted|plain]]")
_CUSTOM_SENT = {"inverted": 1, "plain": 0}


def _number(text, what):
    try:
        return int(text, 0)
    except ValueError:
        raise ValueError(f"{what} is not a number: {text!r}") from None


def _custom_crc(args):
    """(width, poly, start, inverted) of ``WIDTH,POLY[,START[,inverted|plain]]``; ValueError
    for what the core cannot run: width 1..16, poly and start below 2**width."""
    parts = [p.strip() for p in args.split(",")]
    if not 2 <= len(parts) <= 4:
        raise ValueError(f"custom:{args}: give WIDTH,POLY[,START[,inverted|plain]]")
    width = _number(parts[0], "WIDTH")
    poly = _number(parts[1], "POLY")
    start = _number(parts[2], "START") if len(parts) > 2 else 0
    sent = parts[3] if len(parts) > 3 else "inverted"
    if not 1 <= width <= CUSTOM_CRC_MAX_WIDTH:
        raise ValueError(f"custom CRC width {width}: the core runs 1..{CUSTOM_CRC_MAX_WIDTH} bits")
    for name, value in (("POLY", poly), ("START", start)):
        if not 0 <= value < 1 << width:
            raise ValueError(f"custom CRC {name} {value:#x} does not fit {width} bits (POLY is "
                             f"the polynomial without its top term: x^8+x^2+x+1 is 0x07)")
    if sent not in _CUSTOM_SENT:
        raise ValueError(f"custom CRC: {sent!r} is neither 'inverted' nor 'plain'")
    return width, poly, start, _CUSTOM_SENT[sent]


def crc_settings(word, spec):
    """Word ``word``'s CRC fields (``{field: value}``: ``wN_crc`` and the four ``wN_crc_*``)
    for a CRC named as :data:`CRC_SYNTAX` says: ``none``, ``crc6``, ``crc16`` (the custom
    settings 0), ``icmb4-N`` (iC-MB4's CRC of N bits as a custom CRC) or ``custom:...``.
    ValueError, with the syntax, for anything else."""
    spec = spec.strip().lower()
    kind, _, args = spec.partition(":")
    custom = (0, 0, 0, 0)
    if spec in ("none", "crc6", "crc16"):
        code = regmap.CRC_CODES[spec]
    elif spec.startswith("icmb4-"):
        width = _number(spec[len("icmb4-"):], "icmb4-N")
        if width not in ICMB4_CRCS:
            raise ValueError(f"iC-MB4 names no CRC of {width} bits (widths: "
                             f"{', '.join(map(str, ICMB4_CRCS))})")
        code = regmap.CRC_CODES["custom"]
        custom = (width, ICMB4_CRCS[width] & ((1 << width) - 1), 0, 1)
    elif kind == "custom" and args:
        code = regmap.CRC_CODES["custom"]
        custom = _custom_crc(args)
    else:
        raise ValueError(f"not a CRC: {spec!r}; give {CRC_SYNTAX}")
    settings = {f"w{word}_crc": code}
    settings.update({f"w{word}_crc_{k}": v
                     for k, v in zip(("width", "poly", "start", "inverted"), custom)})
    return settings
