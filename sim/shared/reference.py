"""Reference model of the master's verdicts, written from the documentation, not from the RTL.

The campaigns (sim/scenarios/campaigns.py) predict every outcome with this model and compare it
with what the core reports. It knows nothing of the RTL's structure: it works on the bits the
encoder model sent (tb/encoder_model/frames.py) and on the rules in docs/ports.md:

* status priority: CRC errors, then sign-of-life, then SPW plausibility, then OK;
* sign-of-life: judged only when the LC word's CRC is good; 0 is flagged (``zero``) and not
  stored; the previous value again is a ``repeat``; anything but the successor (63 wraps to 1)
  is a ``skip``; after a resync (power-up, abort, line fault: every cycle that goes through the
  break) the next non-zero LC is accepted as it is;
* SPW plausibility: only with both CRCs good; the CPW's leading SPW-length bits against the SPW,
  distance taken both ways modulo 2^SPW bits, within the tolerance;
* confirmation after a fault: after a cycle reported with any status but OK, ABORTED,
  BAD_CONFIG and UNCONFIRMED, the next ``cfg_confirm_frames`` frames (0: 1; 15: never) that
  would be OK are UNCONFIRMED instead;
* configuration validity: the table of ``cfg_*`` ports.
"""

from dataclasses import dataclass, field

import protocol_facts as facts
from encoder_model import frames
from master_contract import (CRC_CODE, CRC_MAX_WIDTH, FRAME_STATUSES, MA_HALF_PERIOD_MIN, STATUS,
                             STATUS_NAME, ConfirmationAccount, crc_status)

#: Cycles that end in the break (MA high 40 us): the encoder restarts its LC check from scratch.
BREAK_STATUSES = {STATUS[n] for n in ("NO_ACK", "NO_START", "DELAY_RANGE", "SLO_STUCK_LOW",
                                      "ABORTED", "NO_STOP")}
#: Codes of the statuses that judge a received frame.
FRAME_STATUS_CODES = {STATUS[n] for n in FRAME_STATUSES}


def lc_successor(value):
    return facts.LC_FIRST if value >= facts.LC_MAX else value + 1


@dataclass
class Verdict:
    """What the core must report for one decoded frame."""
    status: int
    crc_ok: tuple
    lc_repeat: int = 0
    lc_skip: int = 0
    lc_zero: int = 0
    spw_mismatch: int = 0
    parsed: dict = field(default_factory=dict)

    @property
    def name(self):
        return STATUS_NAME[self.status]


class MasterReference:
    """The master's state that outlives a cycle (the stored LC, the frames still to confirm)
    and its frame verdict."""

    def __init__(self):
        self.last_lc = None         # None: not synchronised (the next LC is accepted as is)
        self.confirm_setting = 0    # cfg_confirm_frames
        self.confirmation = ConfirmationAccount()

    def resync(self):
        self.last_lc = None

    def after_status(self, status):
        """Update for every reported cycle, with or without a frame, by its status."""
        if status in BREAK_STATUSES:
            self.resync()
        self.confirmation.reported(status, self.confirm_setting)

    def judge(self, fmt, bits, *, spw_check=None, spw_tolerance=1, commit=True,
              received_ok=None):
        """Verdict for a frame whose received bits are ``bits`` ([Start, CDS, words...]).

        ``received_ok``: per word, False if the line corrupted that word on the way (the core
        saw a CRC error there) although ``bits`` is what the encoder sent.
        """
        parsed = frames.parse_frame(fmt, bits)
        words = parsed["words"]
        crc_ok = tuple(w["crc_ok"] and (received_ok is None or bool(received_ok[i]))
                       for i, w in enumerate(words))
        # The SPW plausibility check belongs to BiSS Safety (two words, not a chain).
        two = fmt.is_safety
        if spw_check is None:
            spw_check = two
        v = Verdict(STATUS["OK"], crc_ok, parsed=parsed)

        lc_word = next((i for i, w in enumerate(fmt.words) if w.lc), None)
        if lc_word is not None and crc_ok[lc_word]:
            lc = words[lc_word]["lc"]
            if lc == 0:
                v.lc_zero = 1
            elif self.last_lc is not None and lc == self.last_lc:
                v.lc_repeat = 1
            elif self.last_lc is not None and lc != lc_successor(self.last_lc):
                v.lc_skip = 1
            if commit and lc != 0:
                self.last_lc = lc

        if two and spw_check and all(crc_ok):
            bits_spw = fmt.words[1].data_bits
            cpw_top = words[0]["position"] >> (fmt.words[0].data_bits - bits_spw)
            spw = words[1]["position"]
            ahead = (cpw_top - spw) % (1 << bits_spw)
            behind = (spw - cpw_top) % (1 << bits_spw)
            v.spw_mismatch = int(min(ahead, behind) > spw_tolerance)

        crc_error = crc_status(crc_ok)      # word 0, any later word, or both
        if crc_error:
            v.status = STATUS[crc_error]
        elif v.lc_repeat or v.lc_skip or v.lc_zero:
            v.status = STATUS["SIGN_OF_LIFE"]
        elif v.spw_mismatch:
            v.status = STATUS["SPW_MISMATCH"]
        elif self.confirmation.pending(self.confirm_setting):
            v.status = STATUS["UNCONFIRMED"]
        return v


# -- Configuration rules (docs/ports.md, "Configuration") -------------------------------------
CRC_KIND = {code: kind for kind, code in CRC_CODE.items()}


def config_valid(cfg, *, max_data_bits=(55, 40), word_crcs=((1, 2), (1, 2)),
                 max_line_delay=4095, custom_crc=True):
    """Is a dict of ``cfg_*`` values valid for a core built with these parameters? A custom
    CRC (code 3) needs a build with them and a width of 1..CRC_MAX_WIDTH."""
    def word_ok(w):
        crc = cfg[f"cfg_w{w}_crc"]
        custom = (custom_crc and crc == CRC_CODE["custom"]
                  and 1 <= cfg.get(f"cfg_w{w}_crc_width", 0) <= CRC_MAX_WIDTH)
        return (1 <= cfg[f"cfg_w{w}_data_bits"] <= max_data_bits[w]
                and (crc == 0 or crc in word_crcs[w] or custom))

    ok = cfg["cfg_ma_half_period"] >= MA_HALF_PERIOD_MIN and word_ok(0)
    ok = ok and cfg["cfg_delay_limit"] <= max_line_delay
    n = len(max_data_bits)
    if n >= 2:
        # Word N is in the frame when enabled; an enabled word needs its predecessor enabled;
        # one LC per frame (docs/ports.md; issue 26's chains for N >= 2).
        on = [True] + [bool(cfg.get(f"cfg_w{w}_enable", 0)) for w in range(1, n)]
        for w in range(1, n):
            ok = ok and (not on[w] or (on[w - 1] and word_ok(w)))
        ok = ok and sum(bool(on[w] and cfg[f"cfg_w{w}_lc"]) for w in range(n)) <= 1
        if cfg["cfg_spw_check"]:
            ok = ok and on[1] and cfg["cfg_w1_data_bits"] <= cfg["cfg_w0_data_bits"] \
                and cfg["cfg_w1_crc"] != 0
    return bool(ok)


def _crc_of(cfg, w):
    """The encoder model's CRC for word ``w`` of a valid configuration: a named kind, or a
    CustomCrc whose polynomial and start are the ports' low ``width`` bits (the master reads
    no bit above the width: docs/ports.md)."""
    code = cfg[f"cfg_w{w}_crc"]
    if code != CRC_CODE["custom"]:
        return CRC_KIND[code]
    width = cfg[f"cfg_w{w}_crc_width"]
    mask = (1 << width) - 1
    return frames.CustomCrc(width, cfg[f"cfg_w{w}_crc_poly"] & mask,
                            cfg[f"cfg_w{w}_crc_start"] & mask, bool(cfg[f"cfg_w{w}_crc_inverted"]))


def format_of(cfg, words=2):
    """The frame format a valid configuration describes (what the encoder must send) in a
    build of ``words`` words: word 0 and the enabled words after it."""
    n = 1
    while n < words and cfg.get(f"cfg_w{n}_enable", 0):
        n += 1
    ws = []
    for w in range(n):
        ws.append(frames.WordFormat(cfg[f"cfg_w{w}_data_bits"], nenw=bool(cfg[f"cfg_w{w}_nenw"]),
                                    lc=bool(cfg[f"cfg_w{w}_lc"]), crc=_crc_of(cfg, w),
                                    gray=bool(cfg.get(f"cfg_w{w}_gray", 0)),
                                    signed=bool(cfg.get(f"cfg_w{w}_signed", 0))))
    return _LooseFormat("fuzz", tuple(ws))


class _LooseFormat(frames.FrameFormat):
    """A FrameFormat for fuzzed configurations: the SPW may be longer than the CPW when the
    plausibility check is off (the core does not care then)."""

    def __post_init__(self):
        object.__setattr__(self, "words", tuple(self.words))

    @property
    def spw_shift(self):
        return max(0, self.words[0].data_bits - self.words[1].data_bits) if self.is_safety else 0


# -- SSI mode (docs/ports.md, "SSI mode"; master_contract's SSI facts) ------------------------
def ssi_verdict(fmt, levels, *, double):
    """``(status name, reading)`` of one SSI cycle whose line, as the master reads it, showed
    ``levels`` after its MA rising edges 1 .. N + 1 (2 N + 2 with double transmission): the word
    (``fmt``: an encoder_model.ssi.SsiFormat), with ``double`` a separator and the second copy,
    then the bit after the word that must be 0. ``reading``: copy 1 parsed
    (encoder_model.ssi.parse_ssi), what the position and flags report whatever the status
    (master_contract.SSI_DOUBLE_REPORTS). The rules, in order:

    * the bit after the word (after copy 2) is 1: NO_STOP, whatever cfg_end_check says; it
      replaces the frame's verdict (the frame is not reported);
    * copy 1's CRC (extended SSI) fails: CRC_ERROR_WORD0 (it comes before SPW_MISMATCH);
    * double transmission: a separator of 1, or copy 2 differing from copy 1 in any bit:
      SPW_MISMATCH;
    * else OK (the caller applies the line checks and the confirmation rule, which judge the
      line, not the bits).
    An active error bit or nE / nW never changes the status."""
    from encoder_model.ssi import parse_ssi       # the test side's SSI model
    n = fmt.total_bits
    levels = list(levels)
    assert len(levels) == (2 * n + 2 if double else n + 1), (len(levels), n, double)
    reading = parse_ssi(fmt, levels[:n])
    if levels[-1]:
        return "NO_STOP", reading
    if reading.crc_ok is False:
        return "CRC_ERROR_WORD0", reading
    if double and (levels[n] or levels[n + 1:2 * n + 1] != levels[:n]):
        return "SPW_MISMATCH", reading
    return "OK", reading
