/*
 * Bare-metal C driver for the BiSS master bus tops (biss_master_axil, biss_master_wb).
 *
 * Portable C99: needs <stdint.h>, <stdbool.h>, <stddef.h> and nothing else of the C library.
 * Every register offset and field mask comes from the generated biss_master_regs.h
 * (`make regmap`, from rtl/bissmaster/bus/biss_master.rdl); this driver holds none of its own.
 *
 * The driver never touches the bus itself: it calls the two hooks of a biss_bus_t (a 32-bit
 * read and a 32-bit write of a byte address) with the bus's context pointer, so the same code
 * runs on memory-mapped registers (biss_mmio_read32 / biss_mmio_write32 below), through an
 * SoC bridge, or against a simulation. Hooks cannot fail; a bus that can must report its
 * errors on its own.
 *
 * Functions that can fail return a biss_err_t (BISS_OK = 0, errors < 0). None of them keeps
 * state beyond the handles the caller owns, so handles of different channels may be used from
 * different contexts (an ISR and the main loop) as long as one channel is not.
 *
 * Register access over the control channel (BiSS C CDM/CDS, the `ca` block at channel + 0x100,
 * docs/bus.md) and BP3 identification with its EDS (docs/control.md, Host side) are
 * blocking, polled calls: each waits for its access with a poll limit and never hangs.
 *
 * Documentation with an example: docs/driver.md.
 */
#ifndef BISS_MASTER_H
#define BISS_MASTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "biss_master_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* -- Errors ----------------------------------------------------------------------------- */

typedef enum {
    BISS_OK = 0,
    BISS_ERR_ARG = -1,              /* a NULL handle, pointer or hook */
    BISS_ERR_NO_DEVICE = -2,        /* the id register does not read "BiSS" */
    BISS_ERR_VERSION = -3,          /* the map's major version is not this driver's */
    BISS_ERR_CHANNEL = -4,          /* channel index >= the build's channel count */
    BISS_ERR_UNKNOWN_PRESET = -5,   /* no encoder preset of that name */
    BISS_ERR_MA_RATE = -6,          /* MA rate outside 80 kHz .. 10 MHz, or clock 0 */
    BISS_ERR_MA_HALF_PERIOD = -7,   /* MA half period < 2 clocks or wider than its field */
    BISS_ERR_DATA_BITS = -8,        /* a word's data bits 0 or above what the channel has */
    BISS_ERR_CRC = -9,              /* CRC kind above CUSTOM, or a custom CRC of width 0 or
                                       above 16, or a polynomial / start value wider than it */
    BISS_ERR_LC = -10,              /* both words carry the LC */
    BISS_ERR_WORD1 = -11,           /* word 1 enabled on a one-word channel */
    BISS_ERR_SPW_CHECK = -12,       /* SPW check without word 1, word 1 wider than word 0, or
                                       word 1 without CRC */
    BISS_ERR_TIME_RANGE = -13,      /* a time setting wider than the channel's timers */
    BISS_ERR_DELAY_LIMIT = -14,     /* delay limit wider than its field */
    BISS_ERR_RUNNING = -15,         /* configure while periodic requests run: stop first */
    BISS_ERR_REFUSED = -16,         /* written, but the core reports state.config_error */
    BISS_ERR_TIMEOUT = -17,         /* the polls ran out before the event (a register access
                                       still running is then aborted) */
    /* Register access (biss_reg_read / biss_reg_write), checked before anything is sent */
    BISS_ERR_NO_REGISTER_ACCESS = -18, /* caps.register_access is 0: the build has no engine */
    BISS_ERR_SLAVE_ID = -19,        /* slave ID above 7 */
    BISS_ERR_ADDRESS = -20,         /* address above 0x7F, or the last register above 0x7F */
    BISS_ERR_COUNT = -21,           /* count 0 or above 64 */
    BISS_ERR_BUSY = -22,            /* an access is still running (ca.state.busy) */
    /* ... and the engine's status of an access that ran (ca.state.status) */
    BISS_ERR_CA_CRC4 = -23,         /* CRC4_ERROR: a byte (or a write's echo) failed the CRC-4 */
    BISS_ERR_CA_NO_ANSWER = -24,    /* NO_ANSWER: no IDL0, no control side (unidirectional) */
    BISS_ERR_CA_REFUSED = -25,      /* REFUSED: no echo / no start bit (read only, wrong ID) */
    BISS_ERR_CA_ABORTED = -26,      /* ABORTED: biss_reg_abort (or the poll limit) */
    BISS_ERR_CA_DATA_FAULT = -27,   /* DATA_FAULT: a data-channel cycle did not end OK */
    BISS_ERR_CA_BAD_REQUEST = -28,  /* BAD_REQUEST: the engine refused the request */
    /* BP3 (biss_bp3_*) */
    BISS_ERR_NOT_BP3 = -29,         /* profile ID (0x42 / BP_ID bits 7:4) is not 0b0110 */
    BISS_ERR_BP3_FIELD = -30,       /* a field outside what the profile allows (VER, DL, ...) */
    BISS_ERR_NO_EDS = -31,          /* EDS pointer (0x41) is 0x00 or 0xFF */
    BISS_ERR_EDS_CHECKSUM = -32,    /* CHKSUM is not the sum of bytes 0x00..0x3E mod 256 */
    BISS_ERR_EDS_MISMATCH = -33,    /* BP_ID / DL differ from registers 0x42 / 0x43 */
    BISS_ERR_BANK_SELECT = -34,     /* the bank select reads back another bank */
    BISS_ERR_UNSUPPORTED = -35,     /* a valid BP3 encoder the core cannot read from its EDS */
    BISS_ERR_CA_SHORT = -36,        /* the engine said OK with fewer bytes done than asked: a
                                       broken or foreign register window; no byte is trusted */
    BISS_ERR_LINE_CHECK = -37,      /* quiet time, noise limit or delay tolerance wider than
                                       its field */
    BISS_ERR_SSI = -38,             /* SSI asked of a build without it (caps.ssi = 0), with a
                                       word option SSI cannot have (LC, word 1, chain words,
                                       the SPW check, the error bit with nE/nW), or a delay
                                       wider than its field */
    /* Chains (words 2..7, docs/frames.md) */
    BISS_ERR_CHAIN = -39,           /* chain words the build lacks (beyond caps.words), or
                                       chain words without word 1 */
    BISS_ERR_TORN = -40             /* biss_read_result: a new frame ended during every one of
                                       BISS_READ_RETRIES reads; *res holds the last (mixed) */
} biss_err_t;

/* The name of an error code ("BISS_ERR_CRC"), "?" for an unknown one. */
const char *biss_error_name(int err);

/* -- The bus: base address and hooks ---------------------------------------------------- */

typedef uint32_t (*biss_read32_fn)(void *ctx, uintptr_t addr);
typedef void (*biss_write32_fn)(void *ctx, uintptr_t addr, uint32_t value);

typedef struct {
    uintptr_t base;                 /* byte address of the map (the bus top's register 0) */
    biss_read32_fn read32;          /* 32-bit read of the byte address addr (4-aligned) */
    biss_write32_fn write32;        /* 32-bit write, all four byte lanes */
    void *ctx;                      /* handed to both hooks unchanged */
} biss_bus_t;

/* Hooks for memory-mapped registers (volatile 32-bit accesses; ctx unused). */
static inline uint32_t biss_mmio_read32(void *ctx, uintptr_t addr)
{
    (void)ctx;
    return *(volatile const uint32_t *)addr;
}

static inline void biss_mmio_write32(void *ctx, uintptr_t addr, uint32_t value)
{
    (void)ctx;
    *(volatile uint32_t *)addr = value;
}

/* Check the id and the map's major version; *channels (may be NULL) gets the channel count. */
biss_err_t biss_probe(const biss_bus_t *bus, unsigned *channels);

/* Start every channel whose trigger is enabled (biss_set_trigger_enable) in the same clock:
 * the synchronous sample. The bus top's `trigger` input does the same in hardware. */
biss_err_t biss_trigger(const biss_bus_t *bus);

/* Per channel (bit n: channel n), some interrupt cause set and enabled: what `irq` is the OR of. */
uint32_t biss_irq_pending(const biss_bus_t *bus);

/* -- A channel -------------------------------------------------------------------------- */

/* Words after word 1 a frame can have: a chain of slaves reads words 0..7 (docs/frames.md). */
#define BISS_CHAIN_WORDS 6

typedef struct {
    biss_bus_t bus;                 /* a copy of the bus */
    uintptr_t base;                 /* this channel's register block */
    uint8_t index;                  /* channel number */
    uint8_t max_data_bits[2];       /* caps: longest word 0 / word 1 (0: one-word build) */
    uint8_t timer_width;            /* caps: bits of the time settings */
    bool has_counters;              /* caps: error counters built */
    bool has_timestamp;             /* caps: timestamp built */
    bool has_register_access;       /* caps: the control channel's register-access engine */
    uint32_t max_polls;             /* polls of irq_status per register access before
                                       BISS_ERR_TIMEOUT; biss_channel_init sets
                                       BISS_REG_MAX_POLLS, the caller may change it */
    bool has_ssi;                   /* caps: SSI mode built (added last: older layouts hold) */
    /* Added with chains (words 2..7; a build of 1 or 2 words has words 1 or 2 and zeros): */
    uint8_t words;                  /* caps: data words the build decodes, 1..8 */
    uint8_t chain_data_bits[BISS_CHAIN_WORDS];  /* caps: longest word 2..7 (0: not built) */
    uint8_t chain_words;            /* chain words biss_read_result reads (words 2..): the
                                       build's (words - 2) from biss_channel_init, the
                                       configuration's from biss_configure; the caller may
                                       lower it */
} biss_channel_t;

/* The default poll limit of a register access: the longest access (64 registers) takes at
 * most 1,969 request cycles (docs/control.md, Bound); this allows 1,000 polls per
 * cycle. Set ch->max_polls for the bus speed and MA rate at hand. */
#define BISS_REG_MAX_POLLS 2000000u

/* Probe the bus (biss_probe), check the index, read the channel's capabilities. */
biss_err_t biss_channel_init(biss_channel_t *ch, const biss_bus_t *bus, unsigned index);

/* -- Configuration ---------------------------------------------------------------------- */

/* A word's CRC: none, BiSS's CRC-6 (0x43) or CRC-16 (0x190D9), or the word's own (custom:
 * crc_width, crc_poly, crc_start, crc_inverted; docs/ports.md, "Custom CRCs"). */
typedef enum { BISS_CRC_NONE = 0, BISS_CRC6 = 1, BISS_CRC16 = 2, BISS_CRC_CUSTOM = 3 } biss_crc_t;

typedef struct {
    uint8_t data_bits;              /* position / data bits, 1 .. caps */
    uint8_t crc;                    /* biss_crc_t */
    bool nenw;                      /* the word ends with nE, nW */
    bool lc;                        /* the word carries the 6-bit LC (sign of life) */
    /* Added with custom CRCs and Gray (0 = as before, so older initializers keep working): */
    bool gray;                      /* the data field is Gray-coded on the line (read in binary) */
    bool crc_inverted;              /* BISS_CRC_CUSTOM: the CRC is sent complemented */
    uint8_t crc_width;              /* BISS_CRC_CUSTOM: 1 .. 16 bits */
    uint16_t crc_poly;              /* BISS_CRC_CUSTOM: register polynomial, top term dropped */
    uint16_t crc_start;             /* BISS_CRC_CUSTOM: register value before the first bit */
    /* Added with signed positions (0 = unsigned, as before): */
    bool is_signed;                 /* the data field is two's complement: the core sign-extends
                                       it to its register's width (biss_signed_data) */
} biss_word_format_t;

/* Set `w`'s CRC to the one iC-MB4 names by its length (3: 0xB, 4: 0x13, 5: 0x25, 6: 0x43,
 * 7: 0x89, 8: 0x12F, 16: 0x190D9; start 0, sent inverted) as a custom CRC; BISS_ERR_CRC for
 * another width or a NULL `w`. */
biss_err_t biss_crc_named(biss_word_format_t *w, unsigned width);

/* Every runtime setting of a channel (docs/ports.md, Configuration). Times are in clocks of
 * the bus top's clock; 0 selects the core's default where docs/ports.md gives one. */
typedef struct {
    uint16_t ma_half_period;        /* MA = f_clk / (2 * value), >= 2 */
    uint16_t delay_limit;           /* largest accepted round trip; 0: the build's maximum */
    uint32_t request_period;        /* periodic mode: clocks request to request; 0: at once */
    uint32_t break_time;            /* 0: 40 us */
    uint32_t ack_limit;             /* 0: 40 us */
    uint32_t timeout_limit;         /* 0: 80 us */
    biss_word_format_t word[2];     /* word 0 (CPW / BiSS C position), word 1 (SPW) */
    bool word1_enable;              /* a second word follows (BiSS Safety) */
    bool end_check;                 /* report a frame only after its stop bit and timeout */
    bool spw_check;                 /* check the SPW against the CPW */
    uint8_t spw_tolerance;          /* largest accepted SPW/CPW distance, SPW LSBs */
    /* The line checks (docs/ports.md, "Noise: the line checks"); 0 is each one's default. */
    uint16_t quiet_time;            /* clocks SLO high before MA starts; 0: 1 us; 1: off */
    uint8_t noise_limit;            /* noise events a valid frame may have; 0: none; 15: off */
    uint8_t delay_tolerance;        /* clocks beyond the half period; 0: 2; 15: off */
    uint8_t confirm_frames;         /* clean frames after a fault before one is valid (status
                                       UNCONFIRMED until then); 0: 1; 15: off */
    /* SSI mode (docs/ports.md, "SSI mode"; 0 = BiSS, as before): word[0] is clocked out with
     * no Ack, Start or CDS. */
    bool ssi;                       /* read an SSI encoder */
    bool ssi_error;                 /* one error bit follows the position (result w0_ne = 0:
                                       active) */
    bool ssi_error_low;             /* that bit is active low */
    bool ssi_double;                /* the encoder sends the word twice; a difference is
                                       status SPW_MISMATCH */
    uint16_t ssi_delay;             /* round trip, system clocks (MA rise to SLO change) */
    /* A chain of slaves (docs/frames.md; 0 = two words at most, as before): words 2..7 after
     * word 0 and word 1, in the frame in order. */
    uint8_t chain_words;            /* words after word 1, 0 .. caps.words - 2 (word1_enable
                                       needed when above 0) */
    biss_word_format_t chain[BISS_CHAIN_WORDS];     /* chain[i]: word i + 2 */
} biss_config_t;

/* A named encoder: its frame format. */
typedef struct {
    const char *name;               /* "resolute_c_26", "resolute_fs_rsh", ... */
    uint8_t words;                  /* 1: BiSS C, 2: BiSS Safety (CPW + SPW) */
    biss_word_format_t word[2];
    bool spw_check;
    uint8_t spw_tolerance;
} biss_preset_t;

/* The presets: count, the i-th (NULL past the end), by name (NULL if unknown). */
unsigned biss_preset_count(void);
const biss_preset_t *biss_preset_at(unsigned i);
const biss_preset_t *biss_preset_find(const char *name);

/* A complete configuration for preset `name` at the MA rate `ma_hz` on a clock of `clk_hz`:
 * the half period rounds up (the MA rate is at most ma_hz), every other time is the core's
 * default. The caller may change fields before biss_configure. */
biss_err_t biss_config_from_preset(biss_config_t *cfg, const char *name, uint32_t clk_hz,
                                   uint32_t ma_hz);

/* Validate cfg against the core's rules and this channel's capabilities; writes nothing. */
biss_err_t biss_config_check(const biss_channel_t *ch, const biss_config_t *cfg);

/* Validate, write every configuration register, and read back that the core accepts it.
 * Refused while periodic requests run (BISS_ERR_RUNNING): a frame must not start on half a
 * configuration. */
biss_err_t biss_configure(biss_channel_t *ch, const biss_config_t *cfg);

/* Forget the settled round trip (the round-trip check settles again on the next 4 good
 * frames): after changing the cable or the encoder on purpose (docs/ports.md, "Noise: the
 * line checks"). Writes cfg_checks.delay_tolerance = 15, then the setting back. */
biss_err_t biss_rearm_delay_check(biss_channel_t *ch);

/* biss_config_from_preset + biss_configure. */
biss_err_t biss_configure_preset(biss_channel_t *ch, const char *name, uint32_t clk_hz,
                                 uint32_t ma_hz);

/* -- Control ---------------------------------------------------------------------------- */

biss_err_t biss_start(biss_channel_t *ch);          /* one request (an overrun if busy) */
biss_err_t biss_abort(biss_channel_t *ch);          /* abort the running cycle */
biss_err_t biss_clear_counters(biss_channel_t *ch);

/* Periodic requests every period_clocks (0: as fast as the encoder allows), or stop them. */
biss_err_t biss_set_periodic(biss_channel_t *ch, bool enable, uint32_t period_clocks);

/* Let biss_trigger (and the `trigger` input) start this channel, or not. */
biss_err_t biss_set_trigger_enable(biss_channel_t *ch, bool enable);

typedef struct {
    bool busy;                      /* a start now would be an overrun */
    bool config_error;              /* a request now would end with BAD_CONFIG */
    bool periodic;
    bool trigger_enable;
} biss_state_t;

biss_err_t biss_read_state(biss_channel_t *ch, biss_state_t *state);

/* Poll irq_status.done up to max_polls reads; when set, clear it (that bit only) and return
 * BISS_OK, else BISS_ERR_TIMEOUT. For polled use; an ISR uses biss_irq_status/clear. */
biss_err_t biss_wait_done(biss_channel_t *ch, uint32_t max_polls);

/* -- Results ---------------------------------------------------------------------------- */

/* result.status codes (docs/ports.md, Status codes). */
typedef enum {
    BISS_STATUS_OK = 0,
    BISS_STATUS_CRC_ERROR_WORD0 = 1,
    BISS_STATUS_CRC_ERROR_WORD1 = 2,
    BISS_STATUS_CRC_ERROR_BOTH = 3,
    BISS_STATUS_SIGN_OF_LIFE = 4,
    BISS_STATUS_SPW_MISMATCH = 5,
    BISS_STATUS_NO_ACK = 6,
    BISS_STATUS_NO_START = 7,
    BISS_STATUS_DELAY_RANGE = 8,
    BISS_STATUS_SLO_STUCK_LOW = 9,
    BISS_STATUS_ABORTED = 10,
    BISS_STATUS_BAD_CONFIG = 11,
    BISS_STATUS_NO_STOP = 12,
    BISS_STATUS_NOISY_LINE = 13,    /* more noise events than noise_limit (docs/ports.md) */
    BISS_STATUS_DELAY_JUMP = 14,    /* the round trip left the settled one */
    BISS_STATUS_UNCONFIRMED = 15    /* passed every check, within confirm_frames of a fault */
} biss_status_t;

/* The name of a status code without the prefix ("NO_ACK"), "?" for an unknown one. */
const char *biss_status_name(unsigned status);

/* A chain word's result (words 2..7): its data and flags. */
typedef struct {
    uint64_t data;                  /* up to 63 bits, sign-extended when set is_signed */
    bool ne, nw, crc_ok;            /* nE, nW: 1 = no error / no warning */
} biss_word_result_t;

typedef struct {
    uint64_t word0;                 /* word 0 data (up to 64 bits: caps.data_bits_w0) */
    uint64_t word1;                 /* word 1 data (up to 64 bits: caps.data_bits_w1) */
    uint32_t timestamp;             /* clock count at the frame's first MA rising edge */
    uint16_t seq;                   /* ended request cycles since reset, wrapping */
    uint16_t line_delay;            /* measured round trip, clocks */
    uint8_t status;                 /* biss_status_t */
    uint8_t lc;                     /* the LC (sign of life) */
    bool cds;
    bool w0_ne, w0_nw, w0_crc_ok;   /* nE, nW: 1 = no error / no warning */
    bool w1_ne, w1_nw, w1_crc_ok;
    bool lc_repeat, lc_skip, lc_zero, spw_mismatch;
    /* The line checks as the frame was judged (docs/ports.md, "Noise: the line checks"). */
    uint8_t noise_events;           /* since the frame before, saturating at 15 */
    bool delay_settled;             /* a round trip had settled: DELAY_JUMP judged */
    uint16_t settled_delay;         /* the settled round trip, clocks */
    uint8_t delay_spread;           /* largest accepted distance from it, saturating at 255 */
    /* Added with chains: words 2.. of the same frame (read live between two equal
     * chain.updates, see biss_read_result). */
    uint8_t chain_words;            /* chain[] entries read: ch->chain_words (the others 0) */
    biss_word_result_t chain[BISS_CHAIN_WORDS];     /* chain[i]: word i + 2 */
} biss_result_t;

/* Word `word`'s data (biss_result_t.word0 / word1, chain[word - 2].data for words 2..7) of a
 * word set is_signed, as a signed number: the core has sign-extended it to its register's
 * width (the channel's max_data_bits[word], chain_data_bits[word - 2]); this extends it on to
 * 64 bits. A word the build lacks: the data as it is. */
int64_t biss_signed_data(const biss_channel_t *ch, unsigned word, uint64_t data);

/* The last result, all of one frame: result.status is read first (it takes the snapshot,
 * docs/bus.md), then the rest. The frame fields keep the last decoded frame after a fault.
 * With chain words to read (ch->chain_words > 0), which the core shows live, not in the
 * snapshot: chain.updates, then result.status, chain.flags and the chain words, then
 * chain.updates again; equal counts mean every read between is of one frame, else the
 * status and chain words are read again (one more read of chain.updates each time), up to
 * BISS_READ_RETRIES times in all: then BISS_ERR_TORN. Without chain words the reads are
 * those of a two-word build (no chain.updates). */
#define BISS_READ_RETRIES 8
biss_err_t biss_read_result(biss_channel_t *ch, biss_result_t *res);

/* Error counters, 16 bits each, saturating (docs/ports.md, Counters). */
typedef struct {
    uint16_t crc_word0, crc_word1, no_ack, no_start, delay_range, slo_stuck_low;
    uint16_t lc_repeat, lc_skip, lc_zero, spw_mismatch, overrun, aborted, no_stop;
    uint16_t noisy_line, delay_jump, noise_event;   /* the line checks' statuses, events */
    uint16_t crc_chain[BISS_CHAIN_WORDS];   /* words 2..7's CRC errors (added last; 0 for a
                                               word the build lacks) */
} biss_counters_t;

biss_err_t biss_read_counters(biss_channel_t *ch, biss_counters_t *cnt);

/* -- Interrupts ------------------------------------------------------------------------- */

/* Causes (irq_status / irq_enable bits): a cycle ended; it ended with a status other than OK;
 * a register access ended (whatever its status). biss_reg_read / biss_reg_write poll and clear
 * BISS_IRQ_ACCESS_DONE themselves: an ISR must leave it alone while they run. */
#define BISS_IRQ_DONE BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__DONE_bm
#define BISS_IRQ_ERROR BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__ERROR_bm
#define BISS_IRQ_ACCESS_DONE BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__ACCESS_DONE_bm

biss_err_t biss_irq_enable(biss_channel_t *ch, uint32_t causes);    /* exactly these causes */
uint32_t biss_irq_status(biss_channel_t *ch);                       /* sticky causes set */
biss_err_t biss_irq_clear(biss_channel_t *ch, uint32_t causes);     /* write 1 to clear */

/* -- Register access over the control channel (BiSS C CDM / CDS) ------------------------ */

/* The engine's ca.state.status codes (docs/control.md, Statuses). */
typedef enum {
    BISS_CA_OK = 0,
    BISS_CA_CRC4_ERROR = 1,
    BISS_CA_NO_ANSWER = 2,
    BISS_CA_REFUSED = 3,
    BISS_CA_ABORTED = 4,
    BISS_CA_DATA_FAULT = 5,
    BISS_CA_BAD_REQUEST = 6
} biss_ca_status_t;

/* Read `count` consecutive registers (1..64) of slave `slave_id` (0..7) from `address`
 * (0..0x7F, the last one at most 0x7F) into buf, one sequential access. The arguments and
 * caps.register_access are checked first (BISS_ERR_NO_REGISTER_ACCESS, _SLAVE_ID, _ADDRESS,
 * _COUNT; BISS_ERR_BUSY if an access runs). Then: request, start, poll irq_status.access_done
 * up to ch->max_polls times (clearing it), and the engine's status as BISS_OK or
 * BISS_ERR_CA_*. On the limit the access is aborted and BISS_ERR_TIMEOUT returned. On an error
 * the first *done (may be NULL) bytes of buf hold the registers checked before the fault; on
 * BISS_OK *done = count. The data channel keeps reading positions meanwhile, and every cycle
 * must end OK (docs/control.md, The data channel before identification). */
biss_err_t biss_reg_read(biss_channel_t *ch, unsigned slave_id, unsigned address, uint8_t *buf,
                         unsigned count, unsigned *done);

/* Write `count` bytes of data to consecutive registers from `address`; as biss_reg_read. */
biss_err_t biss_reg_write(biss_channel_t *ch, unsigned slave_id, unsigned address,
                          const uint8_t *data, unsigned count, unsigned *done);

/* Abort the running register access (ca.ctrl.abort); it ends with BISS_CA_ABORTED after the
 * cancel (docs/control.md). */
biss_err_t biss_reg_abort(biss_channel_t *ch);

/* -- BP3 Standard Encoder Profile: identification and EDS --------------------------------- */

/* BP3's registers (spec digest, sections 7 and 10). */
#define BISS_BP3_REG_BANK_SELECT 0x40u  /* R/W: the bank 0x00..0x3F shows */
#define BISS_BP3_REG_EDS_BANK 0x41u     /* read only: the bank where the EDS starts */
#define BISS_BP3_REG_PROFILE_ID 0x42u   /* ID 7:4 = 0b0110, VER 3:1 = 1, C 0 */
#define BISS_BP3_REG_DATA_LENGTH 0x43u  /* bit 7 = 0, DL 6:0 */
#define BISS_BP3_EDS_BYTES 64u

/* Registers 0x42 / 0x43, decoded and checked. */
typedef struct {
    uint8_t version;                /* VER: 1 */
    uint8_t crc_mode;               /* C: 0 CRC separate (Standard Encoder), 1 BiSS Safety */
    uint8_t data_length;            /* DL: data bits without CRC (2..0x39 C = 0, 2..0x3F C = 1) */
    uint8_t position_bits;          /* DL_POS = DL - 2 with C = 0; 0 with C = 1 */
} biss_bp3_id_t;

/* Check and decode 0x42 / 0x43: BISS_ERR_NOT_BP3 (ID not 0b0110), BISS_ERR_BP3_FIELD (VER
 * not 1, DL outside the range C allows, 0x43 bit 7 set). */
biss_err_t biss_bp3_decode_id(uint8_t reg_0x42, uint8_t reg_0x43, biss_bp3_id_t *id);

/* Read registers 0x42 / 0x43 of slave `slave_id` (one access) and decode them. */
biss_err_t biss_bp3_identify(biss_channel_t *ch, unsigned slave_id, biss_bp3_id_t *id);

/* The BP3 EDS bank, every field of the profile's table (digest section 7); U16 / U32 are big
 * endian in the bank. */
typedef struct {
    uint8_t bp_ver;                 /* 0x00 profile version (1) */
    uint8_t bp_len;                 /* 0x01 length of the profile in banks (1) */
    uint8_t bp_id;                  /* 0x02 profile ID, as register 0x42 */
    uint8_t dl;                     /* 0x03 DL, as register 0x43 */
    uint8_t fb1;                    /* 0x04 feedback bit 1: 1 nE, 2 nW */
    uint8_t fb2;                    /* 0x05 feedback bit 2 */
    uint8_t pon_pdl;                /* 0x06 power-on delay, ms (1..254) */
    uint8_t en_typ;                 /* 0x08 0 rotary, 1 linear */
    uint8_t pos_num;                /* 0x09 position values: 0 undefined, 1, 2 */
    uint8_t mt_len;                 /* 0x0A multiturn bits */
    uint8_t mt_fmt;                 /* 0x0B 0 right-, 1 left-aligned */
    uint8_t co_len;                 /* 0x0C coarse length */
    uint8_t co_fmt;                 /* 0x0D coarse format (raw) */
    uint8_t fi_len;                 /* 0x0E fine length */
    uint8_t fi_fmt;                 /* 0x0F fine format (raw) */
    uint32_t mt_cnt;                /* 0x10 distinguishable revolutions / periods */
    uint32_t sip_cnt;               /* 0x14 signal periods per revolution, or period in nm */
    uint32_t sip_res;               /* 0x18 resolution per signal period */
    uint32_t cpoly;                 /* 0x1C CRC polynomial bits 32:1 (0x43 stored as 0x21) */
    uint32_t cstart;                /* 0x20 CRC start value */
    uint16_t abs_acu;               /* 0x24 absolute accuracy */
    uint16_t rel_acu;               /* 0x26 repeat accuracy */
    uint16_t spd_acu;               /* 0x28 speed-dependent accuracy */
    uint16_t hyst;                  /* 0x2A hysteresis */
    uint16_t spd_max;               /* 0x2C max speed, 1/min or m/min */
    uint16_t acc_max;               /* 0x2E max acceleration */
    uint16_t tmp_min, tmp_max;      /* 0x30 / 0x32 operating temperature, K */
    uint16_t vlt_min, vlt_max;      /* 0x34 / 0x36 operating voltage, mV */
    uint16_t cur_max;               /* 0x38 max current, mA */
    uint8_t chksum;                 /* 0x3F sum of bytes 0x00..0x3E mod 256 (checked) */
    uint8_t eds_bank;               /* register 0x41 as read (biss_bp3_read_eds only) */
    uint8_t profile_bank;           /* the bank read (biss_bp3_read_eds only) */
} biss_bp3_eds_t;

/* Check and decode a 64-byte BP3 EDS bank: BISS_ERR_EDS_CHECKSUM (first), BISS_ERR_NOT_BP3,
 * BISS_ERR_BP3_FIELD (BP_VER, BP_LEN, BP_ID's VER, DL, FB1, FB2, PON_PDL, EN_TYP, POS_NUM,
 * MT_FMT). eds_bank and profile_bank are set to 0. */
biss_err_t biss_bp3_decode_eds(const uint8_t bank[BISS_BP3_EDS_BYTES], biss_bp3_eds_t *eds);

/* Read and decode slave `slave_id`'s BP3 EDS bank. The accesses (as the Python host side,
 * bissmaster.bp3.identify): read 0x40..0x43 (bank select, EDS pointer, profile ID; checked as
 * biss_bp3_decode_id); BISS_ERR_NO_EDS if the pointer is 0x00 or 0xFF; the profile bank is
 * the pointer + profile_bank_offset (1: a common EDS part of one bank in front, 0: the pointer
 * names the BP3 bank; BISS_ERR_BP3_FIELD beyond 0xFF); unless selected already, write it to
 * 0x40 and read it back (BISS_ERR_BANK_SELECT); read 0x00..0x3F; restore 0x40 whenever it was
 * written, also after a failure (the first error is returned). Then biss_bp3_decode_eds and
 * BP_ID / DL against 0x42 / 0x43 (BISS_ERR_EDS_MISMATCH). */
biss_err_t biss_bp3_read_eds(biss_channel_t *ch, unsigned slave_id, unsigned profile_bank_offset,
                             biss_bp3_eds_t *eds);

/* The data-channel settings of a BP3 Standard Encoder (C = 0) from its EDS: word 0 with
 * DL - 2 position bits, nE / nW, no LC and the CRC that CPOLY / CSTART name (CRC-6 0x43 or
 * CRC-16 0x190D9 from 0: the named ones; any other polynomial of 1 .. 16 bits with a start
 * value that fits: BISS_CRC_CUSTOM, sent inverted); word 1 and the SPW check off. Only those
 * fields of cfg change: the MA rate and times stay as the caller set them (e.g.
 * biss_config_from_preset). Refused with BISS_ERR_UNSUPPORTED: C = 1, feedback bits other than
 * nE then nW, DL_POS 0, no CRC (CPOLY 0), a CRC wider than 16 bits, a start value wider than
 * the CRC. biss_configure checks DL_POS against the channel. */
biss_err_t biss_bp3_config(const biss_bp3_eds_t *eds, biss_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* BISS_MASTER_H */
