/*
 * Bare-metal C driver for the BiSS master bus tops (biss_master_axil, biss_master_wb).
 *
 * Portable C99: needs <stdint.h>, <stdbool.h>, <stddef.h> and nothing else of the C library.
 * Every register offset and field mask comes from the generated biss_master_regs.h
 * (`make regmap`, from rtl/regmap/biss_master.rdl); this driver holds none of its own.
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
 * Not here yet: register access over the control channel (BiSS C CDM/CDS). The bus tops
 * reserve its window (channel + 0x100 .. + 0x1FF, docs/bus.md) but do not implement it; the
 * functions for it come with the register map that has the engine's registers.
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
    BISS_ERR_CRC = -9,              /* CRC kind not NONE, CRC6 or CRC16 */
    BISS_ERR_LC = -10,              /* both words carry the LC */
    BISS_ERR_WORD1 = -11,           /* word 1 enabled on a one-word channel */
    BISS_ERR_SPW_CHECK = -12,       /* SPW check without word 1, word 1 wider than word 0, or
                                       word 1 without CRC */
    BISS_ERR_TIME_RANGE = -13,      /* a time setting wider than the channel's timers */
    BISS_ERR_DELAY_LIMIT = -14,     /* delay limit wider than its field */
    BISS_ERR_RUNNING = -15,         /* configure while periodic requests run: stop first */
    BISS_ERR_REFUSED = -16,         /* written, but the core reports state.config_error */
    BISS_ERR_TIMEOUT = -17          /* the polls ran out before the event */
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

typedef struct {
    biss_bus_t bus;                 /* a copy of the bus */
    uintptr_t base;                 /* this channel's register block */
    uint8_t index;                  /* channel number */
    uint8_t max_data_bits[2];       /* caps: longest word 0 / word 1 (0: one-word build) */
    uint8_t timer_width;            /* caps: bits of the time settings */
    bool has_counters;              /* caps: error counters built */
    bool has_timestamp;             /* caps: timestamp built */
} biss_channel_t;

/* Probe the bus (biss_probe), check the index, read the channel's capabilities. */
biss_err_t biss_channel_init(biss_channel_t *ch, const biss_bus_t *bus, unsigned index);

/* -- Configuration ---------------------------------------------------------------------- */

typedef enum { BISS_CRC_NONE = 0, BISS_CRC6 = 1, BISS_CRC16 = 2 } biss_crc_t;

typedef struct {
    uint8_t data_bits;              /* position / data bits, 1 .. caps */
    uint8_t crc;                    /* biss_crc_t */
    bool nenw;                      /* the word ends with nE, nW */
    bool lc;                        /* the word carries the 6-bit LC (sign of life) */
} biss_word_format_t;

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
    BISS_STATUS_NO_STOP = 12
} biss_status_t;

/* The name of a status code without the prefix ("NO_ACK"), "?" for an unknown one. */
const char *biss_status_name(unsigned status);

typedef struct {
    uint64_t word0;                 /* word 0 data (up to 55 bits) */
    uint64_t word1;                 /* word 1 data (up to 40 bits) */
    uint32_t timestamp;             /* clock count at the frame's first MA rising edge */
    uint16_t seq;                   /* ended request cycles since reset, wrapping */
    uint16_t line_delay;            /* measured round trip, clocks */
    uint8_t status;                 /* biss_status_t */
    uint8_t lc;                     /* the LC (sign of life) */
    bool cds;
    bool w0_ne, w0_nw, w0_crc_ok;   /* nE, nW: 1 = no error / no warning */
    bool w1_ne, w1_nw, w1_crc_ok;
    bool lc_repeat, lc_skip, lc_zero, spw_mismatch;
} biss_result_t;

/* The last result, all of one frame: result.status is read first (it takes the snapshot,
 * docs/bus.md), then the rest. The frame fields keep the last decoded frame after a fault. */
biss_err_t biss_read_result(biss_channel_t *ch, biss_result_t *res);

/* Error counters, 16 bits each, saturating (docs/ports.md, Counters). */
typedef struct {
    uint16_t crc_word0, crc_word1, no_ack, no_start, delay_range, slo_stuck_low;
    uint16_t lc_repeat, lc_skip, lc_zero, spw_mismatch, overrun, aborted, no_stop;
} biss_counters_t;

biss_err_t biss_read_counters(biss_channel_t *ch, biss_counters_t *cnt);

/* -- Interrupts ------------------------------------------------------------------------- */

/* Causes (irq_status / irq_enable bits): a cycle ended; it ended with a status other than OK.
 * (access_done is reserved for the register-access engine.) */
#define BISS_IRQ_DONE BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__DONE_bm
#define BISS_IRQ_ERROR BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__ERROR_bm

biss_err_t biss_irq_enable(biss_channel_t *ch, uint32_t causes);    /* exactly these causes */
uint32_t biss_irq_status(biss_channel_t *ch);                       /* sticky causes set */
biss_err_t biss_irq_clear(biss_channel_t *ch, uint32_t causes);     /* write 1 to clear */

#ifdef __cplusplus
}
#endif

#endif /* BISS_MASTER_H */
