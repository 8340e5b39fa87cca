"""What the documentation promises about ``biss_master``'s ports, as the test side's own table.

Written from docs/ports.md, never imported from ``rtl/``: a renumbered status code or a renamed
counter in the RTL must show up as a failing test, not be followed silently. Every test,
testbench, campaign and tool on the test side takes these facts from here and nowhere else:
status codes, CRC codes, counters, the encoder presets the regression and the coverage name,
the system clock the simulations run at, and the shortest MA half period the core accepts. The
protocol's own numbers are in tb/protocol_facts.py.
"""

#: ``status`` codes (docs/ports.md, "Status codes").
STATUS = {
    "OK": 0, "CRC_ERROR_WORD0": 1, "CRC_ERROR_WORD1": 2, "CRC_ERROR_BOTH": 3,
    "SIGN_OF_LIFE": 4, "SPW_MISMATCH": 5, "NO_ACK": 6, "NO_START": 7, "DELAY_RANGE": 8,
    "SLO_STUCK_LOW": 9, "ABORTED": 10, "BAD_CONFIG": 11, "NO_STOP": 12,
    # Issue 28's line checks (docs/ports.md, "Noise: the line checks"): more noise events than
    # cfg_noise_limit, and a round trip off the settled one by more than the tolerance.
    "NOISY_LINE": 13, "DELAY_JUMP": 14,
    # A frame that passed every check, within cfg_confirm_frames frames of a cycle that did not
    # end OK (docs/ports.md, "Confirmation after a fault").
    "UNCONFIRMED": 15,
}
STATUS_NAME = {code: name for name, code in STATUS.items()}
#: The line checks' statuses (docs/ports.md, "Noise: the line checks"): a clean line never
#: gives them.
NOISE_STATUSES = ("NOISY_LINE", "DELAY_JUMP")

#: Words a core may be built for (docs: ``MasterParams.max_data_bits`` has one entry per word,
#: 1..8): word N's ports are ``cfg_wN_*`` and ``wordN_*``, ``cfg_wN_enable`` for N >= 1.
MAX_WORDS = 8


def crc_status(crc_ok):
    """The status of a frame whose words' CRC verdicts are ``crc_ok`` (word 0 first, the enabled
    words only; None if every CRC is good): CRC_ERROR_WORD0 when word 0 fails and no later word,
    CRC_ERROR_WORD1 when word 0 passes and any later word fails (a chain's word 2 too: the
    ``wordN_crc_ok`` ports say which), CRC_ERROR_BOTH when word 0 and any later word fail."""
    first_bad = not crc_ok[0]
    later_bad = not all(crc_ok[1:])
    if first_bad and later_bad:
        return "CRC_ERROR_BOTH"
    if first_bad:
        return "CRC_ERROR_WORD0"
    if later_bad:
        return "CRC_ERROR_WORD1"
    return None


def crc_counters(crc_ok):
    """The CRC counters a frame with these verdicts advances: ``crc_word<N>`` for each word N
    that failed (docs/ports.md, Counters: one counter per word)."""
    return tuple(f"crc_word{w}" for w, ok in enumerate(crc_ok) if not ok)


#: Statuses that judge a received frame (the frame fields are new with them).
FRAME_STATUSES = ("OK", "CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH",
                  "SIGN_OF_LIFE", "SPW_MISMATCH", "NOISY_LINE", "DELAY_JUMP", "UNCONFIRMED")

#: ``cfg_wN_crc`` codes, keyed by the encoder model's CRC kinds (frames.CRC_NONE, CRC6, CRC16);
#: "custom": the word's own CRC from its ``cfg_wN_crc_width/_poly/_start/_inverted`` ports.
CRC_CODE = {"none": 0, "crc6": 1, "crc16": 2, "custom": 3}
#: The widest CRC a word may have (docs/ports.md, ``cfg_w0_crc_width``).
CRC_MAX_WIDTH = 16

#: The ``count_<name>`` outputs of the default build, in port order.
COUNTERS = ("crc_word0", "crc_word1", "no_ack", "no_start", "delay_range", "slo_stuck_low",
            "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch", "overrun", "aborted",
            "no_stop", "noisy_line", "delay_jump", "noise_event")
#: The counters that count a cycle by its status (docs/ports.md, "Counters"): one each per
#: cycle ended with that status (CRC_ERROR_BOTH counts in both CRC counters); BAD_CONFIG, OK,
#: SIGN_OF_LIFE, SPW_MISMATCH and UNCONFIRMED in none of these.
STATUS_COUNTERS = {"CRC_ERROR_WORD0": ("crc_word0",), "CRC_ERROR_WORD1": ("crc_word1",),
                   "CRC_ERROR_BOTH": ("crc_word0", "crc_word1"), "NO_ACK": ("no_ack",),
                   "NO_START": ("no_start",), "DELAY_RANGE": ("delay_range",),
                   "SLO_STUCK_LOW": ("slo_stuck_low",), "ABORTED": ("aborted",),
                   "NO_STOP": ("no_stop",), "NOISY_LINE": ("noisy_line",),
                   "DELAY_JUMP": ("delay_jump",)}
#: In SSI mode (no LC, docs/ports.md "SPW check"): ``spw_mismatch``, and so
#: ``count_spw_mismatch``, is set exactly with status SPW_MISMATCH (a double transmission's
#: copies differ).
SSI_STATUS_COUNTERS = {**STATUS_COUNTERS, "SPW_MISMATCH": ("spw_mismatch",)}
#: Counters a one-word build does not have.
WORD1_COUNTERS = ("crc_word1", "spw_mismatch")
#: The counters of issue 28's noise defences (a core with ``count_noisy_line``): one per
#: NOISY_LINE, one per DELAY_JUMP, and the noise events seen.
NOISE_COUNTERS = ("noisy_line", "delay_jump", "noise_event")


#: The line checks' configuration ports (docs/ports.md) at their defaults: every one 0 (any
#: noise event rejects the frame, SLO high for 1 us before MA starts, the round-trip tolerance
#: the half period + 2 clocks), whatever the clock.
NOISE_CONFIG_DEFAULTS = {"cfg_noise_limit": 0, "cfg_quiet_time": 0, "cfg_delay_tolerance": 0,
                         "cfg_confirm_frames": 0}


#: ``cfg_noise_limit`` and ``cfg_delay_tolerance`` value that turns the check off (the noise
#: count saturates at 15; 15 also forgets the settled round trip).
CHECK_OFF = 15


#: The noise defences' result ports (issue 28): events in the cycle (saturating), whether the
#: round trip has settled, the settled round trip and its spread (clocks).
NOISE_FIELDS = ("noise_events", "delay_settled", "settled_delay", "delay_spread")

#: The named encoder presets of the issue (keys of tb/encoder_model/frames.PRESETS): BiSS
#: Safety, EVOLUTE and RESOLUTE BiSS C. BP3 lengths are named ``bp3_N`` and chosen per use.
ENCODER_PRESETS = ("resolute_fs_lmm", "resolute_fs_rsm", "resolute_fs_rsh", "fortis_fs_rsh",
                   "evolute_26", "evolute_32", "evolute_36",
                   "resolute_c_18", "resolute_c_26", "resolute_c_32", "resolute_c_36")

#: System clock of the simulations (Hz); the default build's core parameters assume the same.
SYS_CLK_HZ = 100_000_000

#: Shortest ``cfg_ma_half_period`` the core accepts (docs/ports.md, "Configuration": "Must be
#: >= 2; otherwise the configuration is invalid"). A fact of the ports, not of the protocol.
MA_HALF_PERIOD_MIN = 2

#: The line checks' defaults (docs/ports.md, "Noise: the line checks"): SLO high for 1 us before
#: MA starts (``cfg_quiet_time`` = 0), a tolerance of 2 clocks (``cfg_delay_tolerance`` = 0),
#: 4 clean frames that agree settle (or move) the round trip.
QUIET_TIME_S = 1e-6
#: Confirmation after a fault (docs/ports.md): ``cfg_confirm_frames`` = 0 stands for 1 frame;
#: statuses after which it does not apply (they say nothing about the line).
CONFIRM_FRAMES_DEFAULT = 1
CONFIRM_NEUTRAL = ("OK", "ABORTED", "BAD_CONFIG", "UNCONFIRMED")


class ConfirmationAccount:
    """The confirmation rule as docs/ports.md states it, kept from the reported statuses: after
    a status outside CONFIRM_NEUTRAL, the next ``cfg_confirm_frames`` frames (0: 1; 15: none)
    that pass every check are UNCONFIRMED. The setting is read when a fault is reported and
    while frames are owed (15 ends the debt at once)."""

    def __init__(self):
        self.left = 0

    def pending(self, setting):
        """The next frame that passes every check is UNCONFIRMED."""
        return self.left > 0 and setting != CHECK_OFF

    def reported(self, status, setting):
        """Account for a reported cycle's status code."""
        name = STATUS_NAME[status]
        if name == "UNCONFIRMED":
            self.left -= 1
        elif name not in CONFIRM_NEUTRAL:
            self.left = 0 if setting == CHECK_OFF else setting or CONFIRM_FRAMES_DEFAULT
DELAY_TOLERANCE_DEFAULT = 2
DELAY_SETTLE_FRAMES = 4

# -- Register access (control channel), builds with the engine (the default build) ------------

#: ``ca_status`` codes (docs/ports.md, "Register access"; docs/control.md, "Statuses").
CA_STATUS = {
    "OK": 0, "CRC4_ERROR": 1, "NO_ANSWER": 2, "REFUSED": 3, "ABORTED": 4, "DATA_FAULT": 5,
    "BAD_REQUEST": 6,
}
CA_STATUS_NAME = {code: name for name, code in CA_STATUS.items()}

#: The ``count_<name>`` outputs of the engine, by the ``ca_status`` they count (docs/ports.md:
#: "one per ended access with that status"; OK and BAD_REQUEST have none).
CA_COUNTERS = {"CRC4_ERROR": "ca_crc4_error", "NO_ANSWER": "ca_no_answer",
               "REFUSED": "ca_refused", "ABORTED": "ca_aborted", "DATA_FAULT": "ca_data_fault"}

#: Registers one access reads or writes: 1 .. 64 (``ca_count``), the last at most 0x7F.
CA_COUNT_MAX = 64
CA_ADDRESS_MAX = 0x7F

#: ``start_wait_frames``: the longest wait for a read's late start bit, in frames (a generation
#: parameter; docs/control.md, "A late start bit": 16 by default).
CA_START_WAIT_FRAMES = 16


def ca_frame_bound(count, write, start_wait_frames=CA_START_WAIT_FRAMES):
    """The most request cycles one accepted access of ``count`` registers takes, ``ca_done``
    included (docs/control.md, "Bound: every access ends"): the cycles up to the last
    one that can carry CDM = 1, then a cancel's 14 zeros. 14 idle, 1 in flight at
    ``ca_start``, 18 header, the registers before the last (14 each for a write, 14 +
    start_wait_frames for a read), the last one up to its last CDM = 1 (13 for a write, 2 +
    start_wait_frames for a read), 14. With the default wait: a read 65 for one register,
    1,955 for 64; a write 60 and 942."""
    per_register = 14 if write else 14 + start_wait_frames
    last = 13 if write else 2 + start_wait_frames
    return 14 + 1 + 18 + (count - 1) * per_register + last + 14


#: The defaults of the time limits that 0 selects (docs/ports.md, "Configuration"): the break,
#: the Ack limit and the SLO-low (timeout) limit, in seconds.
DEFAULT_BREAK_S = 40e-6
DEFAULT_ACK_LIMIT_S = 40e-6
DEFAULT_TIMEOUT_LIMIT_S = 80e-6

#: The longest word 0 and word 1 of the default build, in data bits (docs/ports.md:
#: ``max_data_bits = [55, 40]``; ``cfg_w0_data_bits`` 1 .. 55, ``cfg_w1_data_bits`` 1 .. 40).
MAX_DATA_BITS = (55, 40)
#: The chain bus top the bus scenarios build (sim/shared/runner.py, ``axil_chain``): one channel
#: whose core decodes four words of up to these data bits (the register map's chain words,
#: docs/registers.md: words 2..7 at cfg_wN / chain.*; words 0, 1 and 2 as long as a word can
#: be, 64 bits: result.w0_hi, result.w1_hi and chain.w2_hi each hold 32 of them).
CHAIN_BUS_DATA_BITS = (64, 64, 64, 16)


def crc_config(crc):
    """A word's CRC as the master's configuration names it: ``(cfg_wN_crc code, {width, poly,
    start, inverted})`` for an encoder-model CRC (frames.CRC_NONE, CRC6, CRC16 or a
    frames.CustomCrc). A named CRC leaves the custom settings 0; a custom one is code 3 with
    its own settings (docs/ports.md, ``cfg_w0_crc_*``)."""
    if isinstance(crc, str):
        return CRC_CODE[crc], {"width": 0, "poly": 0, "start": 0, "inverted": 0}
    return CRC_CODE["custom"], {"width": crc.width, "poly": crc.poly, "start": crc.start,
                                "inverted": int(crc.inverted)}


def crc_settings(crc):
    """The CRC the master runs for a word (its code resolved): ``{width, poly, start,
    inverted}``; the named ones as docs/protocol.md section 6 gives them (start 0, sent
    inverted), width 0 for none."""
    import protocol_facts as facts
    named = {"none": (0, 0, 0, 0),
             "crc6": (facts.CRC6_WIDTH, facts.CRC6_POLY, facts.CRC_INIT, 1),
             "crc16": (facts.CRC16_WIDTH, facts.CRC16_POLY, facts.CRC_INIT, 1)}
    if isinstance(crc, str):
        width, poly, start, inverted = named[crc]
        return {"width": width, "poly": poly, "start": start, "inverted": inverted}
    return crc_config(crc)[1]


def port_position(word, field, width):
    """What ``wordN_position`` (``width`` bits) shows for a word's data field ``field`` (the
    value as the encoder model parses it: Gray already decoded) of frame format word ``word``:
    the field right-justified with zeros above it, or, for a signed word, its two's complement
    value sign-extended to the port's width (docs/ports.md, ``cfg_w0_signed``)."""
    if not word.signed or not field >> (word.data_bits - 1):
        return field
    return (field - (1 << word.data_bits)) % (1 << width)


# -- SSI channel mode (issue 26; docs/ports.md, "SSI") -----------------------------------------
# The channel runs SSI frames instead of BiSS when cfg_ssi = 1 (latched when the cycle starts,
# like every cfg_*). The word uses the word-0 ports: cfg_w0_data_bits (position bits),
# cfg_w0_gray (Gray on the line, reported binary), cfg_w0_signed, cfg_w0_nenw (nE nW after the
# position, active low: "extended SSI") and cfg_w0_crc with its custom-CRC ports (a CRC after
# the flags over the position and flag bits, exactly as a BiSS word's CRC).

#: The SSI configuration ports, in port order (the default build; the presets biss-c,
#: biss-c-lean, bp3 and safety have none of them).
SSI_PORTS = ("cfg_ssi", "cfg_ssi_delay", "cfg_ssi_error", "cfg_ssi_error_low", "cfg_ssi_double")
#: The builds with SSI: the default build only (bissmaster.generate presets have no cfg_ssi).
SSI_BUILDS = ("default",)
#: cfg_ssi_delay: the round trip in system clocks, from the master's MA rising edge at its ma
#: pin to the encoder's resulting change at the slo pin (cable both ways + encoder internal
#: delay: the measure BiSS reports on line_delay). 12 bits in the default build: 0 .. 4095,
#: longer than many MA periods is fine. In SSI mode line_delay reports cfg_ssi_delay.
SSI_DELAY_BITS = 12
SSI_DELAY_MAX = (1 << SSI_DELAY_BITS) - 1
#: cfg_ssi_error: ONE error bit right after the position bits; cfg_ssi_error_low: it is active
#: low (line 0 = error), else active high (line 1 = error).
SSI_ERROR_BITS = 1

#: The statuses an SSI cycle can end with: OK; CRC_ERROR_WORD0 (a bad CRC, extended SSI);
#: SPW_MISMATCH (the copies of a double transmission differ in any bit, or the separator bit
#: between them is 1); SLO_STUCK_LOW (SLO low longer than cfg_timeout_limit, 80 us by default,
#: before a cycle); ABORTED; BAD_CONFIG; NO_STOP (the bit after the word, after copy 2 with
#: double, is 1: line stuck high, an unplugged encoder behind a fail-safe receiver);
#: NOISY_LINE; UNCONFIRMED (the confirmation rule after a fault applies as in BiSS:
#: ConfirmationAccount).
SSI_STATUSES = ("OK", "CRC_ERROR_WORD0", "SPW_MISMATCH", "SLO_STUCK_LOW", "ABORTED",
                "BAD_CONFIG", "NO_STOP", "NOISY_LINE", "UNCONFIRMED")
#: BiSS-only statuses: never in SSI mode (no Ack, no Start, no measured round trip, no LC, no
#: second word).
SSI_NEVER = ("NO_ACK", "NO_START", "DELAY_RANGE", "DELAY_JUMP", "SIGN_OF_LIFE",
             "CRC_ERROR_WORD1", "CRC_ERROR_BOTH")
#: Statuses with which the SSI word's fields (position, nE, nW, crc_ok) are those received
#: (both copies alike where there are two).
SSI_FIELD_STATUSES = ("OK", "UNCONFIRMED", "CRC_ERROR_WORD0")

#: Double transmission: the position (and flags) reported are the first copy's, whatever the
#: status; an encoder that sends zeros after its word (no ring) fails every frame with
#: SPW_MISMATCH.
SSI_DOUBLE_REPORTS = "first copy"
#: Register access has no channel in SSI: no CDM hold is made (MA high after the pulses), and
#: an access started while the channel runs SSI ends with this ca_status at its first frame.
SSI_ACCESS_STATUS = "DATA_FAULT"
#: cfg_end_check = 1 also waits, in SSI, for SLO high again after the frame (the encoder's tm
#: over) before done; NO_STOP is checked in every SSI cycle, whatever cfg_end_check says.

#: Configurations SSI refuses (status BAD_CONFIG, config_error high, no MA edge at all), as
#: port overrides on a valid SSI configuration: an LC, a second word, the SPW check, and the
#: error bit together with nE nW.
SSI_BAD_CONFIGS = ({"cfg_w0_lc": 1}, {"cfg_w1_enable": 1}, {"cfg_spw_check": 1},
                   {"cfg_ssi_error": 1, "cfg_w0_nenw": 1})


def ssi_word_bits(data_bits, error, nenw, crc_width):
    """N, the bits of one SSI word on the line: the position, the error bit, nE nW, the CRC."""
    return data_bits + int(bool(error)) + 2 * int(bool(nenw)) + crc_width


def ssi_ma_pulses(word_bits, double):
    """MA clock pulses (fall then rise, the configured half period) of one SSI cycle: N + 1, the
    last one bringing the bit after the word that must be 0; with double transmission
    2N + 2 (word, separator 0, word, the 0 after it). MA idles high before and after."""
    return 2 * word_bits + 2 if double else word_bits + 1


def ssi_ne_nw(error_active=None, nenw=None):
    """``(word0_ne, word0_nw)`` of an SSI word: with the error bit (``error_active`` True or
    False), ne = 0 when it is active (either polarity) and 1 otherwise, nw = 1; with nE nW, the
    two line levels as in BiSS (``nenw``). An active error bit does not change the status (the
    frame stays OK). None for a word with neither: the contract says nothing then."""
    if nenw is not None:
        return tuple(nenw)
    if error_active is None:
        return None
    return (0 if error_active else 1), 1


def ssi_vote_margin(half_period):
    """The master decides bit k from votes at (MA rising edge k + 1) + cfg_ssi_delay + one half
    period, +/- half_period // 2 clocks: a configured delay off from the true round trip by
    less than about a quarter MA period still reads every bit right. The largest error in
    clocks, each way, that the test side relies on: half_period // 2 - 1."""
    return half_period // 2 - 1
