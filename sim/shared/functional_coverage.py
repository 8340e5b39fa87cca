"""Functional coverage of the campaigns: what was tried, as bins and crosses, with the holes.

Every request cycle of a campaign is sampled once with its encoder preset, MA rate, round trip
(in MA bit periods), injected fault kind and the status the core reported. Coverage is the
fraction of the *defined* bins that were hit; the report names every bin never hit.

Two crosses are defined, because the full product of all five points is mostly illegal (a CRC
fault cannot end in NO_ACK, a stuck line cannot end OK):

* ``setup``: preset x MA rate x delay range: every encoder at every rate over every cable;
* ``fault x status``: each fault kind with each status it can legitimately produce
  (:data:`LEGAL`), so a fault that never produced one of its outcomes shows as a hole.

Each test writes its samples to a JSON file; :func:`merge` adds files together and
:func:`report` prints the table. (cocotb-coverage would do the same with decorators; this keeps
the dependency list short and the bins in one readable place.)
"""

import json
from collections import Counter
from pathlib import Path

from master_contract import ENCODER_PRESETS, STATUS, STATUS_NAME

#: The setup cross's presets: every named encoder and five BP3 lengths.
PRESETS = [*ENCODER_PRESETS, "bp3_1", "bp3_13", "bp3_24", "bp3_40", "bp3_55"]
MA_RATES = ["250k", "1M", "2.5M", "5M", "10M"]
#: Round trip in MA bit periods: the sampler's hard cases are "less than one bit" and "many".
DELAY_RANGES = ["<0.5 bit", "0.5-2 bits", "2-8 bits", ">8 bits"]
FAULTS = ["none", "crc_1bit", "crc_2bit", "crc_3to5bit", "crc_burst", "slo_stuck_low",
          "slo_stuck_high", "unplug", "glitch", "jitter", "jitter_beyond_votes", "delay_change",
          "abort",
          "no_response", "ack_forever", "timeout_stuck", "lc_repeat", "lc_skip", "lc_zero",
          "lc_random", "spw_offset", "bad_config", "config_change", "after_glitch", "noise",
          "cable_step", "glitch_cost",
          # the SSI campaign (sim/scenarios/campaigns.py, ssi): one event per cycle
          "ssi_none", "ssi_bit_flip", "ssi_copy2_flip", "ssi_stuck_high", "ssi_stuck_low",
          "ssi_glitch",
          # the chain campaign (chain_crc): errors inside one word, one bit in each of two
          "chain_word_error", "chain_two_words"]

_FRAME_ERR = ["CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH"]
#: Which statuses each fault kind can legitimately end in: the bins of the fault x status cross.
_SOL = "SIGN_OF_LIFE"   # any frame after a lost or faulty LC frame may show it as a skip
#: A frame that passed every check within cfg_confirm_frames frames of a fault (docs/ports.md,
#: "Confirmation after a fault"): any frame that may follow one.
_UNC = "UNCONFIRMED"
_LATE = ["OK", _SOL, _UNC]   # a fault that came after the verdict leaves the frame as it was
_NOISE = ["NOISY_LINE", "DELAY_JUMP"]   # issue 28's checks: noise seen, a round trip off
LEGAL = {
    "none": ["OK", _SOL, _UNC],
    "crc_1bit": _FRAME_ERR[:2],                    # errors sit in one word: never both
    "crc_2bit": _FRAME_ERR[:2],
    # beyond the Hamming distance a CRC-6 misses 1/64: the frame may pass, and then fail the
    # SPW plausibility or the sign-of-life check instead
    "crc_3to5bit": ["OK", "SPW_MISMATCH", _SOL, _UNC] + _FRAME_ERR[:2],
    "crc_burst": ["OK", "SPW_MISMATCH", _SOL, _UNC] + _FRAME_ERR[:2],
    # a chain (issue 26): errors in one word fail that word alone (word 0: WORD0, a later
    # word: WORD1), or pass beyond what its CRC must detect; one bit in each of two words is
    # always seen in both (BOTH with word 0, WORD1 without)
    "chain_word_error": ["OK", _UNC] + _FRAME_ERR[:2],
    "chain_two_words": _FRAME_ERR[1:],
    "slo_stuck_low": _LATE + _FRAME_ERR + ["NO_START", "DELAY_RANGE", "SLO_STUCK_LOW"],
    "slo_stuck_high": _LATE + _FRAME_ERR + ["NO_ACK", "NO_STOP"],     # NO_STOP: end check
    "unplug": ["NO_ACK"],
    # a glitch on the Ack edge or in the Ack: NO_ACK, NO_START, DELAY_RANGE (see LINE_ALLOWED)
    "glitch": _LATE + _FRAME_ERR + ["NO_ACK", "NO_START", "DELAY_RANGE", "NO_STOP"] + _NOISE,
    # at +/-25 % the eye closes in the worst case: a rare bit error, caught by the CRC, or on
    # the stop bit NO_STOP (end check; the soak found one, see LINE_ALLOWED)
    "jitter": _LATE + _FRAME_ERR + ["NO_STOP"],
    # an edge jittered onto a slot's centre vote (campaigns.jitter_beyond_votes): the votes
    # may split, and the noise check may say so
    "jitter_beyond_votes": _LATE + _FRAME_ERR + ["NO_STOP", "NOISY_LINE"],
    "delay_change": _LATE + ["DELAY_RANGE"],
    "abort": ["ABORTED"] + _LATE,                  # _LATE: the abort came after the verdict
    "no_response": ["NO_ACK"],
    "ack_forever": ["NO_START"],
    "timeout_stuck": ["SLO_STUCK_LOW"],
    # after a resync (a fault that went through the break) any LC is accepted: OK
    "lc_repeat": [_SOL, "OK", _UNC],
    "lc_skip": [_SOL, "OK", _UNC],
    "lc_zero": [_SOL],
    "lc_random": ["OK", _SOL, _UNC],
    "spw_offset": ["OK", "SPW_MISMATCH", _SOL, _UNC],
    "bad_config": ["BAD_CONFIG"],
    "config_change": ["OK", _UNC],
    # the clean cycle requested right after a glitched one (glitch_immunity): it may clock the
    # tail of a slipped frame the encoder is still sending (issue 12)
    "after_glitch": _LATE + _FRAME_ERR + ["NO_ACK", "NO_START", "DELAY_RANGE", "NO_STOP"]
    + _NOISE,
    # continuous noise (noise_baseline, noise_immunity; issue 28) on BiSS C 36 and BiSS Safety
    # RSH: a misread frame (the SPW and LC checks too), a faked or hidden Ack or Start, a
    # misread stop bit, issue 28's checks
    "noise": ["OK", _SOL, "SPW_MISMATCH", _UNC] + _FRAME_ERR + ["NO_ACK", "NO_START", "DELAY_RANGE",
                                                          "SLO_STUCK_LOW", "NO_STOP"] + _NOISE,
    # a cable that changes length between cycles (cable_step): 4 frames DELAY_JUMP, then one
    # UNCONFIRMED, then OK
    "cable_step": ["OK", "DELAY_JUMP", _UNC],
    # one 1..20 ns glitch per cycle (glitch_cost, BiSS C 36): the cycle it hit and the next
    "glitch_cost": ["OK", _UNC, "CRC_ERROR_WORD0", "NO_ACK", "NO_START", "DELAY_RANGE",
                    "SLO_STUCK_LOW", "NO_STOP"] + _NOISE,
    # SSI (docs/ports.md, "SSI mode"): a clean cycle; one bit of the word wrong on the line
    # (plain SSI cannot tell: OK with a wrong reading; extended SSI: its CRC; double
    # transmission: the copies differ); copy 2 or the separator wrong; the line stuck high
    # (the bit after the word is 1) or low (the encoder never ready); a glitch on a vote
    "ssi_none": ["OK", _UNC],
    "ssi_bit_flip": ["OK", _UNC, "CRC_ERROR_WORD0", "SPW_MISMATCH"],
    "ssi_copy2_flip": ["SPW_MISMATCH"],
    "ssi_stuck_high": ["NO_STOP"],
    "ssi_stuck_low": ["SLO_STUCK_LOW"],
    "ssi_glitch": ["NOISY_LINE"],
}


def ma_bin(ma_hz):
    for name, hz in zip(MA_RATES, (250e3, 1e6, 2.5e6, 5e6, 10e6)):
        if abs(ma_hz - hz) < 1:
            return name
    return None


def delay_bin(round_trip_s, ma_hz):
    bits = round_trip_s * ma_hz
    if bits < 0.5:
        return DELAY_RANGES[0]
    if bits < 2:
        return DELAY_RANGES[1]
    if bits < 8:
        return DELAY_RANGES[2]
    return DELAY_RANGES[3]


class Coverage:
    def __init__(self):
        self.hits = Counter()

    def sample(self, *, preset, ma_hz, round_trip_s, fault, status):
        """One request cycle. ``preset`` None: a fuzzed format (counts for the fault cross)."""
        fault = fault or "none"
        assert fault in FAULTS, fault
        status_name = STATUS_NAME[status]
        self.hits[("fault", fault, status_name)] += 1
        ma = ma_bin(ma_hz) if ma_hz else None
        if preset in PRESETS and ma is not None and round_trip_s is not None:
            self.hits[("setup", preset, ma, delay_bin(round_trip_s, ma_hz))] += 1
        self.hits[("status", status_name)] += 1

    def save(self, path):
        Path(path).write_text(json.dumps([[list(k), v] for k, v in self.hits.items()]))

    @classmethod
    def load(cls, path):
        cov = cls()
        for key, value in json.loads(Path(path).read_text()):
            cov.hits[tuple(key)] += value
        return cov

    def merge(self, other):
        self.hits.update(other.hits)
        return self


def bins():
    """Every defined bin, per cross."""
    setup = [("setup", p, m, d) for p in PRESETS for m in MA_RATES for d in DELAY_RANGES]
    fault = [("fault", f, s) for f in FAULTS for s in LEGAL[f]]
    status = [("status", s) for s in STATUS]
    return {"preset x MA rate x delay": setup, "fault x status": fault, "status": status}


def report(cov, *, max_holes=40):
    """Coverage table and holes, as text lines; also flags fault/status pairs outside LEGAL."""
    lines = ["| cross | bins | hit | coverage |", "|---|---:|---:|---:|"]
    holes = {}
    for name, keys in bins().items():
        hit = sum(1 for k in keys if cov.hits.get(k))
        holes[name] = [k for k in keys if not cov.hits.get(k)]
        lines.append(f"| {name} | {len(keys)} | {hit} | {100 * hit / len(keys):.1f} % |")
    total = sum(len(k) for k in bins().values())
    total_hit = total - sum(len(h) for h in holes.values())
    lines.append(f"| **all** | {total} | {total_hit} | {100 * total_hit / total:.1f} % |")
    illegal = [k for k in cov.hits if k[0] == "fault" and k[2] not in LEGAL.get(k[1], [])]
    lines.append("")
    for name, hs in holes.items():
        if not hs:
            continue
        shown = ", ".join("/".join(k[1:]) for k in hs[:max_holes])
        more = f" ... and {len(hs) - max_holes} more" if len(hs) > max_holes else ""
        lines.append(f"Holes in {name} ({len(hs)}): {shown}{more}")
    if illegal:
        lines.append("Outcomes outside the legal table: "
                     + ", ".join(f"{k[1]}->{k[2]} x{cov.hits[k]}" for k in illegal))
    return lines, illegal
