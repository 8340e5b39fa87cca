"""BiSS protocol facts, in one place.

Every number here comes from ``docs/protocol.md`` (the protocol facts in our words, with their
sources; the section numbers below are its sections), except ``MA_HALF_PERIOD_MIN`` and
``MA_HALF_PERIOD_MAX``, which are limits of the core's port (docs/ports.md). This module is pure
Python with no imports beyond the standard library, so that both the RTL and the
independent encoder model can name the same *facts* without sharing any *logic*.
"""

# -- MA clock (section 3, 9) -----------------------------------------------------------------
MA_FREQ_MIN_HZ = 80e3           # protocol-wide minimum (BiSS C protocol description)
MA_FREQ_MAX_HZ = 10e6
MA_HALF_PERIOD_MIN = 2          # system clocks; below this MA cannot have a 1:1 duty cycle
MA_HALF_PERIOD_MAX = 65535      # system clocks (16-bit runtime setting)

# -- Encoder timing (section 2, 3) -----------------------------------------------------------
SAMPLING_MOMENT_S = 3.250e-6        # typ; position latched this long after the 1st MA rise
SAMPLING_MOMENT_MIN_S = 3.225e-6
SAMPLING_MOMENT_MAX_S = 3.275e-6
ENCODER_INTERNAL_DELAY_S = 42.5e-9  # MA to SLO inside the encoder (max)
CABLE_ROUND_TRIP_S_PER_M = 10e-9    # master -> encoder -> master
MIN_CYCLE_PERIOD_S = 31.25e-6       # 32 kHz maximum request rate (start-to-start)
ACK_MAX_RESOLUTE_S = 16e-6
ACK_MAX_EVOLUTE_S = 20e-6

# -- Protocol-wide limits (section 9) --------------------------------------------------------
PROCESSING_TIME_MAX_S = 40e-6       # latch edge to Start bit
LINE_DELAY_MAX_S = 40e-6
BREAK_TIME_S = 40e-6                # MA held high after power-on, an error or an abort
SLAVE_TIMEOUT_MAX_S = 40e-6         # static slave timeout is 12.5 .. 40 us

# -- Line checks of this master (not protocol facts: docs/ports.md, Noise) --------------------
QUIET_TIME_S = 1e-6             # default time SLO must be high before MA starts
DELAY_TOLERANCE_DEFAULT = 2     # clocks a frame's round trip may leave the settled one
DELAY_SETTLE_FRAMES = 4         # clean frames that agree settle (or move) the round trip

# -- Frame (section 5) -----------------------------------------------------------------------
START_BIT = 1
ACK_LEVEL = 0
NE_NW_BITS = 2                  # nE, nW: active-low error and warning
LC_BITS = 6                     # BiSS Safety sign-of-life counter
LC_FIRST = 1                    # first value after power-on
LC_MAX = 63                     # wraps to LC_FIRST; 0 is never sent
BP3_POSITION_BITS_MAX = 55      # DL_POS = 1 .. 55

# -- CRCs (section 6). Register polynomials without the top term; start 0; sent inverted. -----
CRC6_WIDTH = 6
CRC6_POLY = 0x03                # x^6 + x + 1 (0x43 with the top term)
CRC6_XOR_OUT = 0x3F
CRC16_WIDTH = 16
CRC16_POLY = 0x90D9             # x^16+x^15+x^12+x^7+x^6+x^4+x^3+1 (0x190D9)
CRC16_XOR_OUT = 0xFFFF
CRC_INIT = 0

# -- Control communication (section 10) ------------------------------------------------------
CRC4_WIDTH = 4
CRC4_POLY = 0x03                # x^4 + x + 1 (0x13 with the top term); start 0, sent inverted
CRC4_XOR_OUT = 0x0F
CONTROL_ID_BITS = 3             # slave ID: position in the chain, 0 for a single encoder
CONTROL_ADDRESS_BITS = 7        # register address 0x00 .. 0x7F
REGISTER_BITS = 8
BANK_BYTES = 64                 # registers 0x00..0x3F show the selected bank
REG_BANK_SELECT = 0x40          # R/W: the bank that 0x00..0x3F shows
REG_EDS_BANK = 0x41             # read only: the bank where the EDS starts
EDS_BANK_NONE = (0x00, 0xFF)    # EDS pointer values that mean "no EDS"
REG_PROFILE_ID = 0x42           # 0x42 profile ID, 0x43 data length (BP3, section 7)
CDM_IDLE_FRAMES = 14            # CDM = 0 frames before a control frame; as many cancel one

# -- BP3 Standard Encoder Profile (section 7) ------------------------------------------------
BP3_PROFILE_ID = 0b0110         # register 0x42 bits 7:4
BP3_VERSION = 1                 # register 0x42 bits 3:1 (0 not allowed, 2..7 reserved)
BP3_DL_MIN = 0x02               # register 0x43 DL: data length without CRC
BP3_DL_MAX_SEPARATE_CRC = 0x39  # C = 0: DL = DL_POS + nE + nW
BP3_DL_MAX_SAFETY = 0x3F        # C = 1
