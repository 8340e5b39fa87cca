"""The BiSS protocol facts of the test side, written from ``docs/protocol.md``.

Never imported from ``rtl/``: the RTL has its own table (``bissmaster.protocol``), and the two
are written separately so that a wrong number in the RTL fails a test instead of hiding behind
an identical number in the checker. ``tb/tests/model/test_protocol_facts.py`` compares every name the
two share; when they disagree, the spec decides which side is wrong.

Only the facts the test side uses are here (the encoder model, its cocotb driver and self-checks,
the reference model of sim/, the model tests). The names are the RTL's, so that the comparison
can go by name. The one value the test side needs that the spec does not give, the shortest MA
half period the core accepts, is a fact of the core's ports (docs/ports.md), not of the
protocol: it is ``master_contract.MA_HALF_PERIOD_MIN``.
"""

# -- Encoder timing (section 2 "One request cycle", section 3 "Timing limits") ----------------
#: Sampling moment (typ): the encoder latches its position this long after the *first* MA rise
#: (min 3.225 us, max 3.275 us; the model uses the typical value).
SAMPLING_MOMENT_S = 3.250e-6
#: Encoder internal delay, MA to SLO (max).
ENCODER_INTERNAL_DELAY_S = 42.5e-9
#: Cable round-trip delay (typ), master -> encoder -> master, per metre.
CABLE_ROUND_TRIP_S_PER_M = 10e-9
#: RESOLUTE / FORTiS / EVOLUTE acquire at most every 31.25 us (32 kHz, start-to-start); SLO
#: stays low (timeout) until then when the frame ends earlier (section 2, step 7).
MIN_CYCLE_PERIOD_S = 31.25e-6

# -- Frame (section 2, steps 3 and 5; section 5 "Frame formats") ------------------------------
#: SLO level during Ack: the encoder pulls SLO low on the second MA rise.
ACK_LEVEL = 0
#: Start bit: always 1.
START_BIT = 1
#: nE and nW after the position (active low error and warning).
NE_NW_BITS = 2
#: BiSS Safety LC sign-of-life counter (section 5.2): 6 bits, first value 1, counts up to 63
#: (0x3F) and wraps to 1; 0 is never sent.
LC_BITS = 6
LC_FIRST = 1
LC_MAX = 63
#: BP3: DL_POS = 1 .. 55 position bits (sections 5.1 and 7).
BP3_POSITION_BITS_MAX = 55

# -- CRCs of the data words (section 6 "CRCs") ------------------------------------------------
# Register polynomials without their top term, start value 0, sent inverted (bitwise
# complement), MSB first.
#: CPW / BiSS C / BP3: x^6 + x + 1 (0x43 with the top term).
CRC6_WIDTH = 6
CRC6_POLY = 0x03
CRC6_XOR_OUT = 0x3F
#: SPW: x^16 + x^15 + x^12 + x^7 + x^6 + x^4 + x^3 + 1 (0x190D9 with the top term).
CRC16_WIDTH = 16
CRC16_POLY = 0x90D9
CRC16_XOR_OUT = 0xFFFF
#: Start value of every BiSS CRC: CRC-6 and CRC-16 (section 6), CRC-4 (section 10).
CRC_INIT = 0

# -- Control communication (section 10, "CRC-4") ----------------------------------------------
#: x^4 + x + 1 (0x13 with the top term), start 0, MSB first, sent inverted.
CRC4_WIDTH = 4
CRC4_POLY = 0x03
CRC4_XOR_OUT = 0x0F
