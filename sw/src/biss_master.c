/*
 * Bare-metal C driver for the BiSS master bus tops: see biss_master.h and docs/driver.md.
 *
 * Every address and field comes from the generated biss_master_regs.h: offsets through
 * offsetof() on its biss_master_regs_t, fields through its _bm / _bp macros.
 */
#include "biss_master.h"

/* -- Addresses and fields, from the generated header ------------------------------------ */

#define GLOBAL_OFF(member) ((uintptr_t)offsetof(biss_master_regs_t, member))
#define CHANNEL_OFF(member) \
    ((uintptr_t)(offsetof(biss_master_regs_t, channel[0].member) - \
                 offsetof(biss_master_regs_t, channel[0])))
#define CHANNEL_STRIDE \
    ((uintptr_t)(offsetof(biss_master_regs_t, channel[1]) - \
                 offsetof(biss_master_regs_t, channel[0])))
#define CHANNEL_BASE(n) ((uintptr_t)offsetof(biss_master_regs_t, channel[0]) + \
                         (uintptr_t)(n) * CHANNEL_STRIDE)
#define CHANNEL_SLOTS \
    (sizeof(((biss_master_regs_t *)0)->channel) / sizeof(((biss_master_regs_t *)0)->channel[0]))

/* F is a field's macro prefix, e.g. CH(CFG_MA__MA_HALF_PERIOD); two levels so that CH()
 * expands before the pasting. */
#define G(f) BISS_MASTER_REGS__##f
#define CH(f) BISS_MASTER_REGS__CHANNELX__##f
#define GET(word, F) GET_(word, F)
#define GET_(word, F) (((uint32_t)(word) & (uint32_t)F##_bm) >> F##_bp)
#define PUT(value, F) PUT_(value, F)
#define PUT_(value, F) (((uint32_t)(value) << F##_bp) & (uint32_t)F##_bm)
#define MAX(F) MAX_(F)
#define MAX_(F) ((uint32_t)F##_bm >> F##_bp)

/* The protocol's MA rate range (BiSS C: 80 kHz .. 10 MHz). */
#define MA_HZ_MIN 80000u
#define MA_HZ_MAX 10000000u

/* -- Words 2..7 of a chain: their registers, from the generated header ------------------ */

/* A field of a register given by offset, mask and position (the chain words' registers differ
 * per word; the fields of one role have one layout, checked below). */
typedef struct {
    uintptr_t off;
    uint32_t bm;
    uint8_t bp;
} field_t;

typedef struct {
    uintptr_t cfg, crc, crc_start, lo, hi;      /* cfg_wW, cfg_wW_crc, _crc_start, chain.wW_* */
    uint32_t ne_bm, nw_bm, crc_ok_bm;           /* chain.flags */
    field_t caps, count;                        /* caps_chain*, count_chain* */
} chain_word_t;

#define CHAIN_FIELD(reg, f) { CHANNEL_OFF(reg), CH(f##_bm), CH(f##_bp) }
#define CHAIN_WORD(n, caps_reg, caps_f, count_reg, count_f) \
    { CHANNEL_OFF(cfg_w##n), CHANNEL_OFF(cfg_w##n##_crc), CHANNEL_OFF(cfg_w##n##_crc_start), \
      CHANNEL_OFF(chain.w##n##_lo), CHANNEL_OFF(chain.w##n##_hi), \
      CH(CHAIN__FLAGS__W##n##_NE_bm), CH(CHAIN__FLAGS__W##n##_NW_bm), \
      CH(CHAIN__FLAGS__W##n##_CRC_OK_bm), \
      CHAIN_FIELD(caps_reg, caps_f), CHAIN_FIELD(count_reg, count_f) }

static const chain_word_t chain_regs[BISS_CHAIN_WORDS] = {
    CHAIN_WORD(2, caps_chain, CAPS_CHAIN__DATA_BITS_A, count_chain, COUNT_CHAIN__CRC_A),
    CHAIN_WORD(3, caps_chain, CAPS_CHAIN__DATA_BITS_B, count_chain, COUNT_CHAIN__CRC_B),
    CHAIN_WORD(4, caps_chain, CAPS_CHAIN__DATA_BITS_C, count_chain2, COUNT_CHAIN2__CRC_A),
    CHAIN_WORD(5, caps_chain, CAPS_CHAIN__DATA_BITS_D, count_chain2, COUNT_CHAIN2__CRC_B),
    CHAIN_WORD(6, caps_chain2, CAPS_CHAIN2__DATA_BITS_A, count_chain3, COUNT_CHAIN3__CRC_A),
    CHAIN_WORD(7, caps_chain2, CAPS_CHAIN2__DATA_BITS_B, count_chain3, COUNT_CHAIN3__CRC_B),
};

/* The fields of cfg_wW, cfg_wW_crc, cfg_wW_crc_start and chain.wW_lo / _hi are put and read
 * with word 2's macros: every word's must be the same (a compile error otherwise). */
#define SAME_BM(w, reg, f) (CH(CFG_W##w##reg##__##f##_bm) == CH(CFG_W2##reg##__##f##_bm))
#define SAME_CFG(w) (SAME_BM(w, , DATA_BITS) && SAME_BM(w, , NENW) && SAME_BM(w, , LC) && \
                     SAME_BM(w, , CRC) && SAME_BM(w, , GRAY) && SAME_BM(w, , IS_SIGNED) && \
                     SAME_BM(w, , ENABLE) && SAME_BM(w, _CRC, CRC_POLY) && \
                     SAME_BM(w, _CRC, CRC_WIDTH) && SAME_BM(w, _CRC, CRC_INVERTED) && \
                     SAME_BM(w, _CRC_START, CRC_START) && \
                     CH(CHAIN__W##w##_LO__DATA_bm) == CH(CHAIN__W2_LO__DATA_bm) && \
                     CH(CHAIN__W##w##_HI__DATA_bm) == CH(CHAIN__W2_HI__DATA_bm))
typedef char chain_layouts_agree[(SAME_CFG(3) && SAME_CFG(4) && SAME_CFG(5) && SAME_CFG(6) &&
                                  SAME_CFG(7)) ? 1 : -1];

static uint32_t rd(const biss_bus_t *bus, uintptr_t off)
{
    return bus->read32(bus->ctx, bus->base + off);
}

static void wr(const biss_bus_t *bus, uintptr_t off, uint32_t value)
{
    bus->write32(bus->ctx, bus->base + off, value);
}

static uint32_t ch_rd(const biss_channel_t *ch, uintptr_t off)
{
    return ch->bus.read32(ch->bus.ctx, ch->base + off);
}

static void ch_wr(const biss_channel_t *ch, uintptr_t off, uint32_t value)
{
    ch->bus.write32(ch->bus.ctx, ch->base + off, value);
}

static bool bus_ok(const biss_bus_t *bus)
{
    return bus != NULL && bus->read32 != NULL && bus->write32 != NULL;
}

static bool channel_ok(const biss_channel_t *ch)
{
    return ch != NULL && bus_ok(&ch->bus);
}

/* -- Names ------------------------------------------------------------------------------ */

const char *biss_error_name(int err)
{
    static const char *const names[] = {
        "BISS_OK", "BISS_ERR_ARG", "BISS_ERR_NO_DEVICE", "BISS_ERR_VERSION",
        "BISS_ERR_CHANNEL", "BISS_ERR_UNKNOWN_PRESET", "BISS_ERR_MA_RATE",
        "BISS_ERR_MA_HALF_PERIOD", "BISS_ERR_DATA_BITS", "BISS_ERR_CRC", "BISS_ERR_LC",
        "BISS_ERR_WORD1", "BISS_ERR_SPW_CHECK", "BISS_ERR_TIME_RANGE", "BISS_ERR_DELAY_LIMIT",
        "BISS_ERR_RUNNING", "BISS_ERR_REFUSED", "BISS_ERR_TIMEOUT",
        "BISS_ERR_NO_REGISTER_ACCESS", "BISS_ERR_SLAVE_ID", "BISS_ERR_ADDRESS", "BISS_ERR_COUNT",
        "BISS_ERR_BUSY", "BISS_ERR_CA_CRC4", "BISS_ERR_CA_NO_ANSWER", "BISS_ERR_CA_REFUSED",
        "BISS_ERR_CA_ABORTED", "BISS_ERR_CA_DATA_FAULT", "BISS_ERR_CA_BAD_REQUEST",
        "BISS_ERR_NOT_BP3", "BISS_ERR_BP3_FIELD", "BISS_ERR_NO_EDS", "BISS_ERR_EDS_CHECKSUM",
        "BISS_ERR_EDS_MISMATCH", "BISS_ERR_BANK_SELECT", "BISS_ERR_UNSUPPORTED",
        "BISS_ERR_CA_SHORT", "BISS_ERR_LINE_CHECK", "BISS_ERR_SSI", "BISS_ERR_CHAIN",
        "BISS_ERR_TORN",
    };
    if (err > 0 || (unsigned)-err >= sizeof names / sizeof names[0])
        return "?";
    return names[-err];
}

int64_t biss_signed_data(const biss_channel_t *ch, unsigned word, uint64_t data)
{
    unsigned bits = 0;
    uint64_t sign;

    if (ch != NULL && word < 2)
        bits = ch->max_data_bits[word];
    else if (ch != NULL && word < 2 + BISS_CHAIN_WORDS)
        bits = ch->chain_data_bits[word - 2];

    if (bits == 0 || bits >= 64)
        return (int64_t)data;
    sign = (uint64_t)1 << (bits - 1);
    data &= (sign << 1) - 1;
    /* Two's complement from bit `bits - 1`, without a shift into the sign bit (portable C). */
    return (int64_t)(data ^ sign) - (int64_t)sign;
}

const char *biss_status_name(unsigned status)
{
    static const char *const names[] = {
        "OK", "CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH", "SIGN_OF_LIFE",
        "SPW_MISMATCH", "NO_ACK", "NO_START", "DELAY_RANGE", "SLO_STUCK_LOW", "ABORTED",
        "BAD_CONFIG", "NO_STOP", "NOISY_LINE", "DELAY_JUMP", "UNCONFIRMED",
    };
    return status < sizeof names / sizeof names[0] ? names[status] : "?";
}

/* -- Device ------------------------------------------------------------------------------ */

biss_err_t biss_probe(const biss_bus_t *bus, unsigned *channels)
{
    uint32_t version;
    if (!bus_ok(bus))
        return BISS_ERR_ARG;
    if (GET(rd(bus, GLOBAL_OFF(id)), G(ID__ID)) != G(ID__ID_reset))
        return BISS_ERR_NO_DEVICE;
    version = rd(bus, GLOBAL_OFF(version));
    if (GET(version, G(VERSION__MAJOR)) != G(VERSION__MAJOR_reset))
        return BISS_ERR_VERSION;
    if (channels != NULL)
        *channels = GET(rd(bus, GLOBAL_OFF(channels)), G(CHANNELS__COUNT));
    return BISS_OK;
}

biss_err_t biss_trigger(const biss_bus_t *bus)
{
    if (!bus_ok(bus))
        return BISS_ERR_ARG;
    wr(bus, GLOBAL_OFF(trigger), PUT(1, G(TRIGGER__START)));
    return BISS_OK;
}

uint32_t biss_irq_pending(const biss_bus_t *bus)
{
    if (!bus_ok(bus))
        return 0;
    return GET(rd(bus, GLOBAL_OFF(irq_pending)), G(IRQ_PENDING__CHANNEL));
}

biss_err_t biss_channel_init(biss_channel_t *ch, const biss_bus_t *bus, unsigned index)
{
    unsigned channels, i;
    uint32_t caps;
    biss_err_t err;
    if (ch == NULL || !bus_ok(bus))
        return BISS_ERR_ARG;
    err = biss_probe(bus, &channels);
    if (err != BISS_OK)
        return err;
    if (index >= channels || index >= CHANNEL_SLOTS)
        return BISS_ERR_CHANNEL;
    ch->bus = *bus;
    ch->index = (uint8_t)index;
    ch->base = bus->base + CHANNEL_BASE(index);
    caps = ch_rd(ch, CHANNEL_OFF(caps));
    ch->max_data_bits[0] = (uint8_t)GET(caps, CH(CAPS__DATA_BITS_W0));
    ch->max_data_bits[1] = (uint8_t)GET(caps, CH(CAPS__DATA_BITS_W1));
    ch->timer_width = (uint8_t)GET(caps, CH(CAPS__TIMER_WIDTH));
    ch->has_counters = GET(caps, CH(CAPS__COUNTERS)) != 0;
    ch->has_timestamp = GET(caps, CH(CAPS__TIMESTAMP)) != 0;
    ch->has_register_access = GET(caps, CH(CAPS__REGISTER_ACCESS)) != 0;
    ch->has_ssi = GET(caps, CH(CAPS__SSI)) != 0;
    ch->max_polls = BISS_REG_MAX_POLLS;
    /* caps.words; a map without it (0) is a build of one or two words. */
    ch->words = (uint8_t)GET(caps, CH(CAPS__WORDS));
    if (ch->words == 0)
        ch->words = ch->max_data_bits[1] != 0 ? 2 : 1;
    /* caps_chain, caps_chain2: each read once, and only for words the build has. */
    ch->chain_words = 0;
    for (i = 0; i < BISS_CHAIN_WORDS; i++) {
        const field_t *f = &chain_regs[i].caps;
        ch->chain_data_bits[i] = 0;
        if (i + 2u >= ch->words)
            continue;
        if (i == 0 || f->off != chain_regs[i - 1].caps.off)
            caps = ch_rd(ch, f->off);
        ch->chain_data_bits[i] = (uint8_t)((caps & f->bm) >> f->bp);
        ch->chain_words = (uint8_t)(i + 1u);
    }
    return BISS_OK;
}

/* -- Presets ----------------------------------------------------------------------------- */

/* Word 0 of every preset: position, nE nW, CRC-6. BiSS Safety's SPW: nE nW, LC, CRC-16. */
#define CPW(bits) { (bits), BISS_CRC6, true, false, false, false, 0, 0, 0, false }
#define SPW(bits) { (bits), BISS_CRC16, true, true, false, false, 0, 0, 0, false }
#define NO_WORD { 0, BISS_CRC_NONE, false, false, false, false, 0, 0, 0, false }
#define BISS_C(name, bits) { name, 1, { CPW(bits), NO_WORD }, false, 0 }
/* The SPW check accepts one SPW LSB of distance: CPW and SPW are separate conversions. */
#define SAFETY(name, cpw, spw) { name, 2, { CPW(cpw), SPW(spw) }, true, 1 }

static const biss_preset_t presets[] = {
    /* BiSS Safety (RESOLUTE FS, FORTiS FS): CPW + SPW */
    SAFETY("resolute_fs_lmm", 32, 32),
    SAFETY("resolute_fs_rsm", 28, 24),
    SAFETY("resolute_fs_rsh", 36, 28),
    SAFETY("fortis_fs_rsh", 36, 28),
    /* BiSS C, one word */
    BISS_C("evolute_26", 26),
    BISS_C("evolute_32", 32),
    BISS_C("evolute_36", 36),
    BISS_C("resolute_c_18", 18),
    BISS_C("resolute_c_26", 26),
    BISS_C("resolute_c_32", 32),
    BISS_C("resolute_c_36", 36),
};

unsigned biss_preset_count(void)
{
    return (unsigned)(sizeof presets / sizeof presets[0]);
}

const biss_preset_t *biss_preset_at(unsigned i)
{
    return i < biss_preset_count() ? &presets[i] : NULL;
}

static bool same_name(const char *a, const char *b)
{
    while (*a != '\0' && *a == *b) {
        a++;
        b++;
    }
    return *a == *b;
}

const biss_preset_t *biss_preset_find(const char *name)
{
    unsigned i;
    if (name == NULL)
        return NULL;
    for (i = 0; i < biss_preset_count(); i++)
        if (same_name(presets[i].name, name))
            return &presets[i];
    return NULL;
}

biss_err_t biss_config_from_preset(biss_config_t *cfg, const char *name, uint32_t clk_hz,
                                   uint32_t ma_hz)
{
    static const biss_config_t zero;
    const biss_preset_t *p;
    uint64_t half;
    if (cfg == NULL || name == NULL)
        return BISS_ERR_ARG;
    p = biss_preset_find(name);
    if (p == NULL)
        return BISS_ERR_UNKNOWN_PRESET;
    if (clk_hz == 0 || ma_hz < MA_HZ_MIN || ma_hz > MA_HZ_MAX)
        return BISS_ERR_MA_RATE;
    /* Rounded up: the MA rate is at most ma_hz. */
    half = ((uint64_t)clk_hz + 2u * (uint64_t)ma_hz - 1u) / (2u * (uint64_t)ma_hz);
    if (half < 2 || half > MAX(CH(CFG_MA__MA_HALF_PERIOD)))
        return BISS_ERR_MA_HALF_PERIOD;
    *cfg = zero;
    cfg->ma_half_period = (uint16_t)half;
    cfg->word[0] = p->word[0];
    cfg->word1_enable = p->words == 2;
    if (cfg->word1_enable)
        cfg->word[1] = p->word[1];
    cfg->spw_check = p->spw_check;
    cfg->spw_tolerance = p->spw_tolerance;
    return BISS_OK;
}

/* -- Configuration ------------------------------------------------------------------------ */

/* A function, not a comparison in place: a field as wide as its C type would give a
 * comparison that is always true (-Wtype-limits), and the map may widen or narrow it. */
static bool fits(uint32_t value, uint32_t max)
{
    return value <= max;
}

static biss_err_t check_word(const biss_word_format_t *w, unsigned max_bits, unsigned field_max)
{
    if (w->data_bits == 0 || !fits(w->data_bits, max_bits) || !fits(w->data_bits, field_max))
        return BISS_ERR_DATA_BITS;
    if (!fits(w->crc, BISS_CRC_CUSTOM))
        return BISS_ERR_CRC;
    if (w->crc == BISS_CRC_CUSTOM
        && (w->crc_width == 0 || !fits(w->crc_width, MAX(CH(CFG_CRC0__W0_CRC_WIDTH)))
            || !fits(w->crc_width, 16u)
            || (uint32_t)w->crc_poly >> w->crc_width != 0
            || (uint32_t)w->crc_start >> w->crc_width != 0))
        return BISS_ERR_CRC;
    return BISS_OK;
}

biss_err_t biss_crc_named(biss_word_format_t *w, unsigned width)
{
    /* iC-MB4's CRCs by length, with their top term (docs/protocol.md, section 6). */
    static const uint32_t named[17] = { 0, 0, 0, 0xBu, 0x13u, 0x25u, 0x43u, 0x89u, 0x12Fu,
                                        0, 0, 0, 0, 0, 0, 0, 0x190D9u };
    if (w == NULL || width > 16 || named[width] == 0)
        return BISS_ERR_CRC;
    w->crc = BISS_CRC_CUSTOM;
    w->crc_width = (uint8_t)width;
    w->crc_poly = (uint16_t)(named[width] & ((1u << width) - 1u));
    w->crc_start = 0;
    w->crc_inverted = true;
    return BISS_OK;
}

/* A word's custom CRC registers (cfg_crcN, cfg_crcN_start, and a chain word's cfg_wW_crc,
 * cfg_wW_crc_start, whose fields sit where word 0's do: a compile error otherwise): 0 when
 * the word has another CRC. */
typedef char chain_crc_layout_agrees[
    (CH(CFG_CRC0__W0_CRC_POLY_bm) == CH(CFG_W2_CRC__CRC_POLY_bm)
     && CH(CFG_CRC0__W0_CRC_WIDTH_bm) == CH(CFG_W2_CRC__CRC_WIDTH_bm)
     && CH(CFG_CRC0__W0_CRC_INVERTED_bm) == CH(CFG_W2_CRC__CRC_INVERTED_bm)
     && CH(CFG_CRC0_START__W0_CRC_START_bm) == CH(CFG_W2_CRC_START__CRC_START_bm)) ? 1 : -1];

static uint32_t crc_reg(const biss_word_format_t *w)
{
    if (w->crc != BISS_CRC_CUSTOM)
        return 0;
    return PUT(w->crc_poly, CH(CFG_CRC0__W0_CRC_POLY)) | PUT(w->crc_width, CH(CFG_CRC0__W0_CRC_WIDTH))
         | PUT(w->crc_inverted, CH(CFG_CRC0__W0_CRC_INVERTED));
}

static uint32_t crc_start_reg(const biss_word_format_t *w)
{
    return w->crc == BISS_CRC_CUSTOM ? PUT(w->crc_start, CH(CFG_CRC0_START__W0_CRC_START)) : 0;
}

static bool time_fits(const biss_channel_t *ch, uint32_t value, uint32_t field_max)
{
    if (!fits(value, field_max))
        return false;
    return ch->timer_width >= 32 || (value >> ch->timer_width) == 0;
}

biss_err_t biss_config_check(const biss_channel_t *ch, const biss_config_t *cfg)
{
    unsigned i, lcs;
    biss_err_t err;
    if (!channel_ok(ch) || cfg == NULL)
        return BISS_ERR_ARG;
    if (cfg->ma_half_period < 2 || !fits(cfg->ma_half_period, MAX(CH(CFG_MA__MA_HALF_PERIOD))))
        return BISS_ERR_MA_HALF_PERIOD;
    if (!fits(cfg->delay_limit, MAX(CH(CFG_MA__DELAY_LIMIT))))
        return BISS_ERR_DELAY_LIMIT;
    if (!time_fits(ch, cfg->request_period, MAX(CH(CFG_PERIOD__REQUEST_PERIOD))) ||
        !time_fits(ch, cfg->break_time, MAX(CH(CFG_BREAK__BREAK_TIME))) ||
        !time_fits(ch, cfg->ack_limit, MAX(CH(CFG_ACK__ACK_LIMIT))) ||
        !time_fits(ch, cfg->timeout_limit, MAX(CH(CFG_TIMEOUT__TIMEOUT_LIMIT))))
        return BISS_ERR_TIME_RANGE;
    err = check_word(&cfg->word[0], ch->max_data_bits[0], MAX(CH(CFG_WORDS__W0_DATA_BITS)));
    if (err != BISS_OK)
        return err;
    if (cfg->word1_enable) {
        if (ch->max_data_bits[1] == 0)
            return BISS_ERR_WORD1;
        err = check_word(&cfg->word[1], ch->max_data_bits[1],
                         MAX(CH(CFG_WORDS__W1_DATA_BITS)));
        if (err != BISS_OK)
            return err;
    }
    /* Chain words: built, after word 1, each a word as words 0 and 1; one LC per frame. */
    if (cfg->chain_words > 0 && (!cfg->word1_enable || !fits(cfg->chain_words, BISS_CHAIN_WORDS)
                                 || cfg->chain_words + 2u > ch->words))
        return BISS_ERR_CHAIN;
    lcs = cfg->word[0].lc ? 1u : 0u;
    if (cfg->word1_enable && cfg->word[1].lc)
        lcs++;
    for (i = 0; i < cfg->chain_words; i++) {
        err = check_word(&cfg->chain[i], ch->chain_data_bits[i], MAX(CH(CFG_W2__DATA_BITS)));
        if (err != BISS_OK)
            return err;
        if (cfg->chain[i].lc)
            lcs++;
    }
    if (lcs > 1)
        return BISS_ERR_LC;
    if (cfg->spw_check && (!cfg->word1_enable || cfg->word[1].data_bits > cfg->word[0].data_bits
                           || cfg->word[1].crc == BISS_CRC_NONE))
        return BISS_ERR_SPW_CHECK;
    if (!fits(cfg->spw_tolerance, MAX(CH(CFG_CHECKS__SPW_TOLERANCE))))
        return BISS_ERR_SPW_CHECK;
    if (!fits(cfg->quiet_time, MAX(CH(CFG_QUIET__QUIET_TIME)))
        || !fits(cfg->noise_limit, MAX(CH(CFG_CHECKS__NOISE_LIMIT)))
        || !fits(cfg->delay_tolerance, MAX(CH(CFG_CHECKS__DELAY_TOLERANCE)))
        || !fits(cfg->confirm_frames, MAX(CH(CFG_CHECKS__CONFIRM_FRAMES))))
        return BISS_ERR_LINE_CHECK;
    /* SSI: one word without LC; the error bit or nE/nW, not both (docs/ports.md, SSI mode). */
    if (cfg->ssi && (!ch->has_ssi || cfg->word1_enable || cfg->chain_words > 0
                     || cfg->spw_check || cfg->word[0].lc
                     || (cfg->ssi_error && cfg->word[0].nenw)
                     || !fits(cfg->ssi_delay, MAX(CH(CFG_SSI__SSI_DELAY)))))
        return BISS_ERR_SSI;
    return BISS_OK;
}

biss_err_t biss_configure(biss_channel_t *ch, const biss_config_t *cfg)
{
    const biss_word_format_t *w0, *w1;
    uint32_t words;
    unsigned i;
    biss_err_t err = biss_config_check(ch, cfg);
    if (err != BISS_OK)
        return err;
    if (GET(ch_rd(ch, CHANNEL_OFF(ctrl)), CH(CTRL__PERIODIC)))
        return BISS_ERR_RUNNING;
    w0 = &cfg->word[0];
    w1 = &cfg->word[1];
    ch_wr(ch, CHANNEL_OFF(cfg_ma), PUT(cfg->ma_half_period, CH(CFG_MA__MA_HALF_PERIOD)) |
                                   PUT(cfg->delay_limit, CH(CFG_MA__DELAY_LIMIT)));
    ch_wr(ch, CHANNEL_OFF(cfg_period), PUT(cfg->request_period, CH(CFG_PERIOD__REQUEST_PERIOD)));
    ch_wr(ch, CHANNEL_OFF(cfg_break), PUT(cfg->break_time, CH(CFG_BREAK__BREAK_TIME)));
    ch_wr(ch, CHANNEL_OFF(cfg_ack), PUT(cfg->ack_limit, CH(CFG_ACK__ACK_LIMIT)));
    ch_wr(ch, CHANNEL_OFF(cfg_timeout), PUT(cfg->timeout_limit, CH(CFG_TIMEOUT__TIMEOUT_LIMIT)));
    words = PUT(w0->data_bits, CH(CFG_WORDS__W0_DATA_BITS)) | PUT(w0->nenw, CH(CFG_WORDS__W0_NENW))
          | PUT(w0->lc, CH(CFG_WORDS__W0_LC)) | PUT(w0->crc, CH(CFG_WORDS__W0_CRC))
          | PUT(w0->gray, CH(CFG_WORDS__W0_GRAY)) | PUT(w0->is_signed, CH(CFG_WORDS__W0_SIGNED));
    if (cfg->word1_enable)
        words |= PUT(1, CH(CFG_WORDS__W1_ENABLE))
               | PUT(w1->data_bits, CH(CFG_WORDS__W1_DATA_BITS))
               | PUT(w1->nenw, CH(CFG_WORDS__W1_NENW)) | PUT(w1->lc, CH(CFG_WORDS__W1_LC))
               | PUT(w1->crc, CH(CFG_WORDS__W1_CRC)) | PUT(w1->gray, CH(CFG_WORDS__W1_GRAY))
               | PUT(w1->is_signed, CH(CFG_WORDS__W1_SIGNED));
    /* The custom CRCs first: the core latches every setting when a cycle starts. */
    ch_wr(ch, CHANNEL_OFF(cfg_crc0), crc_reg(w0));
    ch_wr(ch, CHANNEL_OFF(cfg_crc0_start), crc_start_reg(w0));
    ch_wr(ch, CHANNEL_OFF(cfg_crc1), cfg->word1_enable ? crc_reg(w1) : 0);
    ch_wr(ch, CHANNEL_OFF(cfg_crc1_start), cfg->word1_enable ? crc_start_reg(w1) : 0);
    for (i = 0; i + 2u < ch->words && i < BISS_CHAIN_WORDS; i++) {
        const biss_word_format_t *w = &cfg->chain[i];
        bool on = i < cfg->chain_words;
        ch_wr(ch, chain_regs[i].crc, on ? crc_reg(w) : 0);
        ch_wr(ch, chain_regs[i].crc_start, on ? crc_start_reg(w) : 0);
    }
    ch_wr(ch, CHANNEL_OFF(cfg_words), words);
    /* Every chain word the build has: the enabled ones in order after word 1, the others
     * written 0 (disabled). */
    for (i = 0; i + 2u < ch->words && i < BISS_CHAIN_WORDS; i++) {
        const biss_word_format_t *w = &cfg->chain[i];
        uint32_t reg = 0;
        if (i < cfg->chain_words)
            reg = PUT(1, CH(CFG_W2__ENABLE)) | PUT(w->data_bits, CH(CFG_W2__DATA_BITS))
                | PUT(w->nenw, CH(CFG_W2__NENW)) | PUT(w->lc, CH(CFG_W2__LC))
                | PUT(w->crc, CH(CFG_W2__CRC)) | PUT(w->gray, CH(CFG_W2__GRAY))
                | PUT(w->is_signed, CH(CFG_W2__IS_SIGNED));
        ch_wr(ch, chain_regs[i].cfg, reg);
    }
    ch->chain_words = cfg->chain_words;
    ch_wr(ch, CHANNEL_OFF(cfg_checks), PUT(cfg->end_check, CH(CFG_CHECKS__END_CHECK))
                                     | PUT(cfg->spw_check, CH(CFG_CHECKS__SPW_CHECK))
                                     | PUT(cfg->spw_tolerance, CH(CFG_CHECKS__SPW_TOLERANCE))
                                     | PUT(cfg->noise_limit, CH(CFG_CHECKS__NOISE_LIMIT))
                                     | PUT(cfg->delay_tolerance,
                                           CH(CFG_CHECKS__DELAY_TOLERANCE))
                                     | PUT(cfg->confirm_frames,
                                           CH(CFG_CHECKS__CONFIRM_FRAMES)));
    ch_wr(ch, CHANNEL_OFF(cfg_quiet), PUT(cfg->quiet_time, CH(CFG_QUIET__QUIET_TIME)));
    ch_wr(ch, CHANNEL_OFF(cfg_ssi), PUT(cfg->ssi, CH(CFG_SSI__SSI))
                                  | PUT(cfg->ssi_error, CH(CFG_SSI__SSI_ERROR))
                                  | PUT(cfg->ssi_error_low, CH(CFG_SSI__SSI_ERROR_LOW))
                                  | PUT(cfg->ssi_double, CH(CFG_SSI__SSI_DOUBLE))
                                  | PUT(cfg->ssi_delay, CH(CFG_SSI__SSI_DELAY)));
    if (GET(ch_rd(ch, CHANNEL_OFF(state)), CH(STATE__CONFIG_ERROR)))
        return BISS_ERR_REFUSED;
    return BISS_OK;
}

biss_err_t biss_rearm_delay_check(biss_channel_t *ch)
{
    uint32_t checks;
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    /* Tolerance 15 forgets the settled round trip in the clock it is written (docs/ports.md);
     * the next write restores the setting. */
    checks = ch_rd(ch, CHANNEL_OFF(cfg_checks));
    ch_wr(ch, CHANNEL_OFF(cfg_checks), (checks & ~(uint32_t)CH(CFG_CHECKS__DELAY_TOLERANCE_bm))
                                     | PUT(MAX(CH(CFG_CHECKS__DELAY_TOLERANCE)),
                                           CH(CFG_CHECKS__DELAY_TOLERANCE)));
    ch_wr(ch, CHANNEL_OFF(cfg_checks), checks);
    return BISS_OK;
}

biss_err_t biss_configure_preset(biss_channel_t *ch, const char *name, uint32_t clk_hz,
                                 uint32_t ma_hz)
{
    biss_config_t cfg;
    biss_err_t err = biss_config_from_preset(&cfg, name, clk_hz, ma_hz);
    return err != BISS_OK ? err : biss_configure(ch, &cfg);
}

/* -- Control ----------------------------------------------------------------------------- */

/* ctrl's stored fields (periodic, trigger_enable) with some pulse bits added: a write of ctrl
 * must keep the stored ones, and its pulses read 0. */
static biss_err_t ctrl_pulse(biss_channel_t *ch, uint32_t pulses)
{
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    ch_wr(ch, CHANNEL_OFF(ctrl), ch_rd(ch, CHANNEL_OFF(ctrl)) | pulses);
    return BISS_OK;
}

biss_err_t biss_start(biss_channel_t *ch)
{
    return ctrl_pulse(ch, PUT(1, CH(CTRL__START)));
}

biss_err_t biss_abort(biss_channel_t *ch)
{
    return ctrl_pulse(ch, PUT(1, CH(CTRL__ABORT)));
}

biss_err_t biss_clear_counters(biss_channel_t *ch)
{
    return ctrl_pulse(ch, PUT(1, CH(CTRL__CLEAR_COUNTERS)));
}

biss_err_t biss_set_periodic(biss_channel_t *ch, bool enable, uint32_t period_clocks)
{
    uint32_t ctrl;
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    if (!time_fits(ch, period_clocks, MAX(CH(CFG_PERIOD__REQUEST_PERIOD))))
        return BISS_ERR_TIME_RANGE;
    ctrl = ch_rd(ch, CHANNEL_OFF(ctrl)) & ~(uint32_t)CH(CTRL__PERIODIC_bm);
    if (enable)
        ch_wr(ch, CHANNEL_OFF(cfg_period), PUT(period_clocks, CH(CFG_PERIOD__REQUEST_PERIOD)));
    ch_wr(ch, CHANNEL_OFF(ctrl), ctrl | PUT(enable, CH(CTRL__PERIODIC)));
    return BISS_OK;
}

biss_err_t biss_set_trigger_enable(biss_channel_t *ch, bool enable)
{
    uint32_t ctrl;
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    ctrl = ch_rd(ch, CHANNEL_OFF(ctrl)) & ~(uint32_t)CH(CTRL__TRIGGER_ENABLE_bm);
    ch_wr(ch, CHANNEL_OFF(ctrl), ctrl | PUT(enable, CH(CTRL__TRIGGER_ENABLE)));
    return BISS_OK;
}

biss_err_t biss_read_state(biss_channel_t *ch, biss_state_t *state)
{
    uint32_t s, c;
    if (!channel_ok(ch) || state == NULL)
        return BISS_ERR_ARG;
    s = ch_rd(ch, CHANNEL_OFF(state));
    c = ch_rd(ch, CHANNEL_OFF(ctrl));
    state->busy = GET(s, CH(STATE__BUSY)) != 0;
    state->config_error = GET(s, CH(STATE__CONFIG_ERROR)) != 0;
    state->periodic = GET(c, CH(CTRL__PERIODIC)) != 0;
    state->trigger_enable = GET(c, CH(CTRL__TRIGGER_ENABLE)) != 0;
    return BISS_OK;
}

biss_err_t biss_wait_done(biss_channel_t *ch, uint32_t max_polls)
{
    uint32_t i;
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    for (i = 0; i < max_polls; i++) {
        if (ch_rd(ch, CHANNEL_OFF(irq_status)) & BISS_IRQ_DONE) {
            ch_wr(ch, CHANNEL_OFF(irq_status), BISS_IRQ_DONE);
            return BISS_OK;
        }
    }
    return BISS_ERR_TIMEOUT;
}

/* -- Results ------------------------------------------------------------------------------ */

/* The first n chain words' flags and data (read live) into res->chain, the others 0; no bus
 * access for n = 0. */
static void read_chain_words(const biss_channel_t *ch, unsigned n, biss_result_t *res)
{
    static const biss_word_result_t none;
    uint32_t flags = n > 0 ? ch_rd(ch, CHANNEL_OFF(chain.flags)) : 0, lo, hi;
    unsigned i;
    for (i = 0; i < BISS_CHAIN_WORDS; i++) {
        const chain_word_t *r = &chain_regs[i];
        biss_word_result_t *w = &res->chain[i];
        *w = none;
        if (i >= n)
            continue;
        lo = GET(ch_rd(ch, r->lo), CH(CHAIN__W2_LO__DATA));
        hi = GET(ch_rd(ch, r->hi), CH(CHAIN__W2_HI__DATA));
        w->data = (uint64_t)hi << CH(CHAIN__W2_LO__DATA_bw) | lo;
        w->ne = (flags & r->ne_bm) != 0;
        w->nw = (flags & r->nw_bm) != 0;
        w->crc_ok = (flags & r->crc_ok_bm) != 0;
    }
}

biss_err_t biss_read_result(biss_channel_t *ch, biss_result_t *res)
{
    uint32_t s, seq, lo, hi, line, before, after = 0;
    unsigned n, tries = 0;
    biss_err_t err = BISS_OK;
    if (!channel_ok(ch) || res == NULL)
        return BISS_ERR_ARG;
    n = ch->chain_words;
    if (n > BISS_CHAIN_WORDS)
        n = BISS_CHAIN_WORDS;
    if (n + 2u > ch->words)
        n = ch->words > 2 ? ch->words - 2u : 0;
    res->chain_words = (uint8_t)n;
    /* result.status first: reading it takes the snapshot the other registers return. The
     * chain words are live: they and the snapshot are of one frame when chain.updates reads
     * the same before and after them (it counts the core's result updates, and changes in the
     * clock after the results: a frame ending between the reads shows). The snapshot's other
     * registers are read after the window: they no longer change. */
    if (n == 0) {
        s = ch_rd(ch, CHANNEL_OFF(result.status));
        read_chain_words(ch, 0, res);
    } else {
        before = GET(ch_rd(ch, CHANNEL_OFF(chain.updates)), CH(CHAIN__UPDATES__UPDATES));
        for (;;) {
            s = ch_rd(ch, CHANNEL_OFF(result.status));
            read_chain_words(ch, n, res);
            after = GET(ch_rd(ch, CHANNEL_OFF(chain.updates)), CH(CHAIN__UPDATES__UPDATES));
            if (after == before)
                break;
            if (++tries >= BISS_READ_RETRIES) {
                err = BISS_ERR_TORN;
                break;
            }
            before = after;
        }
    }
    res->status = (uint8_t)GET(s, CH(RESULT__STATUS__STATUS));
    res->cds = GET(s, CH(RESULT__STATUS__CDS)) != 0;
    res->w0_ne = GET(s, CH(RESULT__STATUS__W0_NE)) != 0;
    res->w0_nw = GET(s, CH(RESULT__STATUS__W0_NW)) != 0;
    res->w0_crc_ok = GET(s, CH(RESULT__STATUS__W0_CRC_OK)) != 0;
    res->w1_ne = GET(s, CH(RESULT__STATUS__W1_NE)) != 0;
    res->w1_nw = GET(s, CH(RESULT__STATUS__W1_NW)) != 0;
    res->w1_crc_ok = GET(s, CH(RESULT__STATUS__W1_CRC_OK)) != 0;
    res->lc_repeat = GET(s, CH(RESULT__STATUS__LC_REPEAT)) != 0;
    res->lc_skip = GET(s, CH(RESULT__STATUS__LC_SKIP)) != 0;
    res->lc_zero = GET(s, CH(RESULT__STATUS__LC_ZERO)) != 0;
    res->spw_mismatch = GET(s, CH(RESULT__STATUS__SPW_MISMATCH)) != 0;
    res->lc = (uint8_t)GET(s, CH(RESULT__STATUS__LC));
    seq = ch_rd(ch, CHANNEL_OFF(result.seq));
    res->seq = (uint16_t)GET(seq, CH(RESULT__SEQ__SEQ));
    res->line_delay = (uint16_t)GET(seq, CH(RESULT__SEQ__LINE_DELAY));
    lo = GET(ch_rd(ch, CHANNEL_OFF(result.w0_lo)), CH(RESULT__W0_LO__DATA));
    hi = GET(ch_rd(ch, CHANNEL_OFF(result.w0_hi)), CH(RESULT__W0_HI__DATA));
    res->word0 = (uint64_t)hi << CH(RESULT__W0_LO__DATA_bw) | lo;
    lo = GET(ch_rd(ch, CHANNEL_OFF(result.w1_lo)), CH(RESULT__W1_LO__DATA));
    hi = GET(ch_rd(ch, CHANNEL_OFF(result.w1_hi)), CH(RESULT__W1_HI__DATA));
    res->word1 = (uint64_t)hi << CH(RESULT__W1_LO__DATA_bw) | lo;
    res->timestamp = GET(ch_rd(ch, CHANNEL_OFF(result.timestamp)), CH(RESULT__TIMESTAMP__TIME));
    line = ch_rd(ch, CHANNEL_OFF(result.line));
    res->noise_events = (uint8_t)GET(line, CH(RESULT__LINE__NOISE_EVENTS));
    res->delay_settled = GET(line, CH(RESULT__LINE__DELAY_SETTLED)) != 0;
    res->settled_delay = (uint16_t)GET(line, CH(RESULT__LINE__SETTLED_DELAY));
    res->delay_spread = (uint8_t)GET(line, CH(RESULT__LINE__DELAY_SPREAD));
    return err;
}

biss_err_t biss_read_counters(biss_channel_t *ch, biss_counters_t *cnt)
{
    uint32_t w;
    unsigned i;
    if (!channel_ok(ch) || cnt == NULL)
        return BISS_ERR_ARG;
    w = ch_rd(ch, CHANNEL_OFF(count_crc));
    cnt->crc_word0 = (uint16_t)GET(w, CH(COUNT_CRC__CRC_WORD0));
    cnt->crc_word1 = (uint16_t)GET(w, CH(COUNT_CRC__CRC_WORD1));
    w = ch_rd(ch, CHANNEL_OFF(count_ack));
    cnt->no_ack = (uint16_t)GET(w, CH(COUNT_ACK__NO_ACK));
    cnt->no_start = (uint16_t)GET(w, CH(COUNT_ACK__NO_START));
    w = ch_rd(ch, CHANNEL_OFF(count_line));
    cnt->delay_range = (uint16_t)GET(w, CH(COUNT_LINE__DELAY_RANGE));
    cnt->slo_stuck_low = (uint16_t)GET(w, CH(COUNT_LINE__SLO_STUCK_LOW));
    w = ch_rd(ch, CHANNEL_OFF(count_lc));
    cnt->lc_repeat = (uint16_t)GET(w, CH(COUNT_LC__LC_REPEAT));
    cnt->lc_skip = (uint16_t)GET(w, CH(COUNT_LC__LC_SKIP));
    w = ch_rd(ch, CHANNEL_OFF(count_check));
    cnt->lc_zero = (uint16_t)GET(w, CH(COUNT_CHECK__LC_ZERO));
    cnt->spw_mismatch = (uint16_t)GET(w, CH(COUNT_CHECK__SPW_MISMATCH));
    w = ch_rd(ch, CHANNEL_OFF(count_cycle));
    cnt->overrun = (uint16_t)GET(w, CH(COUNT_CYCLE__OVERRUN));
    cnt->aborted = (uint16_t)GET(w, CH(COUNT_CYCLE__ABORTED));
    w = ch_rd(ch, CHANNEL_OFF(count_stop));
    cnt->no_stop = (uint16_t)GET(w, CH(COUNT_STOP__NO_STOP));
    cnt->noisy_line = (uint16_t)GET(w, CH(COUNT_STOP__NOISY_LINE));
    w = ch_rd(ch, CHANNEL_OFF(count_noise));
    cnt->delay_jump = (uint16_t)GET(w, CH(COUNT_NOISE__DELAY_JUMP));
    cnt->noise_event = (uint16_t)GET(w, CH(COUNT_NOISE__NOISE_EVENT));
    /* Words 2..7: two counters a register, read once per register (only those built). */
    for (i = 0; i < BISS_CHAIN_WORDS; i++) {
        const field_t *f = &chain_regs[i].count;
        if (i + 2u >= ch->words) {
            cnt->crc_chain[i] = 0;
            continue;
        }
        if (i == 0 || f->off != chain_regs[i - 1].count.off)
            w = ch_rd(ch, f->off);
        cnt->crc_chain[i] = (uint16_t)((w & f->bm) >> f->bp);
    }
    return BISS_OK;
}

/* -- Interrupts ---------------------------------------------------------------------------- */

#define IRQ_ALL ((uint32_t)(BISS_IRQ_DONE | BISS_IRQ_ERROR | BISS_IRQ_ACCESS_DONE))

biss_err_t biss_irq_enable(biss_channel_t *ch, uint32_t causes)
{
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    ch_wr(ch, CHANNEL_OFF(irq_enable),
          PUT(GET(causes, CH(IRQ_STATUS__DONE)), CH(IRQ_ENABLE__DONE)) |
          PUT(GET(causes, CH(IRQ_STATUS__ERROR)), CH(IRQ_ENABLE__ERROR)) |
          PUT(GET(causes, CH(IRQ_STATUS__ACCESS_DONE)), CH(IRQ_ENABLE__ACCESS_DONE)));
    return BISS_OK;
}

uint32_t biss_irq_status(biss_channel_t *ch)
{
    if (!channel_ok(ch))
        return 0;
    return ch_rd(ch, CHANNEL_OFF(irq_status)) & IRQ_ALL;
}

biss_err_t biss_irq_clear(biss_channel_t *ch, uint32_t causes)
{
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    ch_wr(ch, CHANNEL_OFF(irq_status), causes & IRQ_ALL);
    return BISS_OK;
}


/* -- Register access over the control channel ------------------------------------------- */

#define CA_BUF_WORDS \
    (sizeof(((biss_master_regs_t *)0)->channel[0].ca.wbuf) / \
     sizeof(((biss_master_regs_t *)0)->channel[0].ca.wbuf[0]))
#define CA_WORD_OFF(buf, i) (CHANNEL_OFF(ca.buf) + (uintptr_t)(i) * sizeof(uint32_t))
#define CA_MAX_BYTES (CA_BUF_WORDS * sizeof(uint32_t))
/* The byte lane of buffer byte i (docs/bus.md, Byte order): the field width of a lane. */
#define CA_LANE_BITS CH(CA__WBUFX__BYTE0_bw)

static biss_err_t ca_error(uint32_t status)
{
    switch (status) {
    case BISS_CA_OK: return BISS_OK;
    case BISS_CA_CRC4_ERROR: return BISS_ERR_CA_CRC4;
    case BISS_CA_NO_ANSWER: return BISS_ERR_CA_NO_ANSWER;
    case BISS_CA_REFUSED: return BISS_ERR_CA_REFUSED;
    case BISS_CA_ABORTED: return BISS_ERR_CA_ABORTED;
    case BISS_CA_DATA_FAULT: return BISS_ERR_CA_DATA_FAULT;
    default: return BISS_ERR_CA_BAD_REQUEST;
    }
}

static biss_err_t ca_check(const biss_channel_t *ch, unsigned slave_id, unsigned address,
                           const void *buf, unsigned count)
{
    if (!channel_ok(ch) || buf == NULL)
        return BISS_ERR_ARG;
    if (!ch->has_register_access)
        return BISS_ERR_NO_REGISTER_ACCESS;
    if (!fits(slave_id, MAX(CH(CA__REQUEST__SLAVE_ID))))
        return BISS_ERR_SLAVE_ID;
    if (count == 0 || count > CA_MAX_BYTES)
        return BISS_ERR_COUNT;
    if (!fits(address, MAX(CH(CA__REQUEST__ADDRESS))) ||
        !fits(address + count - 1u, MAX(CH(CA__REQUEST__ADDRESS))))
        return BISS_ERR_ADDRESS;
    if (GET(ch_rd(ch, CHANNEL_OFF(ca.state)), CH(CA__STATE__BUSY)))
        return BISS_ERR_BUSY;
    return BISS_OK;
}

/* Request, start, poll access_done; the status as an error code, *done_bytes the bytes done. */
static biss_err_t ca_run(biss_channel_t *ch, unsigned slave_id, unsigned address, unsigned count,
                         bool write, unsigned *done_bytes)
{
    uint32_t i, state;
    *done_bytes = 0;
    ch_wr(ch, CHANNEL_OFF(irq_status), BISS_IRQ_ACCESS_DONE);       /* a stale one: cleared */
    ch_wr(ch, CHANNEL_OFF(ca.request), PUT(slave_id, CH(CA__REQUEST__SLAVE_ID)) |
                                       PUT(address, CH(CA__REQUEST__ADDRESS)) |
                                       PUT(count, CH(CA__REQUEST__COUNT)) |
                                       PUT(write, CH(CA__REQUEST__WRITE)));
    ch_wr(ch, CHANNEL_OFF(ca.ctrl), PUT(1, CH(CA__CTRL__START)));
    for (i = 0; i < ch->max_polls; i++) {
        if (ch_rd(ch, CHANNEL_OFF(irq_status)) & BISS_IRQ_ACCESS_DONE) {
            ch_wr(ch, CHANNEL_OFF(irq_status), BISS_IRQ_ACCESS_DONE);
            state = ch_rd(ch, CHANNEL_OFF(ca.state));
            *done_bytes = GET(state, CH(CA__STATE__BYTES_DONE));
            return ca_error(GET(state, CH(CA__STATE__STATUS)));
        }
    }
    ch_wr(ch, CHANNEL_OFF(ca.ctrl), PUT(1, CH(CA__CTRL__ABORT)));
    return BISS_ERR_TIMEOUT;
}

biss_err_t biss_reg_read(biss_channel_t *ch, unsigned slave_id, unsigned address, uint8_t *buf,
                         unsigned count, unsigned *done)
{
    unsigned got, i;
    uint32_t word = 0;
    biss_err_t err = ca_check(ch, slave_id, address, buf, count);
    if (done != NULL)
        *done = 0;
    if (err != BISS_OK)
        return err;
    err = ca_run(ch, slave_id, address, count, false, &got);
    if (got > count)
        got = count;
    if (err == BISS_OK && got < count)
        return BISS_ERR_CA_SHORT;   /* the engine's contract: OK means every byte (*done 0) */
    for (i = 0; i < got; i++) {
        if (i % sizeof(uint32_t) == 0)
            word = ch_rd(ch, CA_WORD_OFF(rbuf, i / sizeof(uint32_t)));
        buf[i] = (uint8_t)(word >> (CA_LANE_BITS * (i % sizeof(uint32_t))));
    }
    if (done != NULL)
        *done = got;
    return err;
}

biss_err_t biss_reg_write(biss_channel_t *ch, unsigned slave_id, unsigned address,
                          const uint8_t *data, unsigned count, unsigned *done)
{
    unsigned got, i;
    uint32_t word = 0;
    biss_err_t err = ca_check(ch, slave_id, address, data, count);
    if (done != NULL)
        *done = 0;
    if (err != BISS_OK)
        return err;
    for (i = 0; i < count; i++) {
        word |= (uint32_t)data[i] << (CA_LANE_BITS * (i % sizeof(uint32_t)));
        if (i % sizeof(uint32_t) == sizeof(uint32_t) - 1u || i == count - 1u) {
            ch_wr(ch, CA_WORD_OFF(wbuf, i / sizeof(uint32_t)), word);
            word = 0;
        }
    }
    err = ca_run(ch, slave_id, address, count, true, &got);
    if (err == BISS_OK && got < count)
        return BISS_ERR_CA_SHORT;   /* the engine's contract: OK means every byte (*done 0) */
    if (done != NULL)
        *done = got > count ? count : got;
    return err;
}

biss_err_t biss_reg_abort(biss_channel_t *ch)
{
    if (!channel_ok(ch))
        return BISS_ERR_ARG;
    if (!ch->has_register_access)
        return BISS_ERR_NO_REGISTER_ACCESS;
    ch_wr(ch, CHANNEL_OFF(ca.ctrl), PUT(1, CH(CA__CTRL__ABORT)));
    return BISS_OK;
}

/* -- BP3: identification and EDS (spec digest, section 7) ------------------------------ */

#define BP3_ID 0x6u                 /* register 0x42 bits 7:4 */
#define BP3_VERSION 1u              /* bits 3:1: 1 (0 not allowed, 2..7 reserved) */
#define BP3_DL_MIN 0x02u
#define BP3_DL_MAX_C0 0x39u         /* C = 0: CRC separate */
#define BP3_DL_MAX_C1 0x3Fu         /* C = 1: BiSS Safety */
#define BP3_FEEDBACK_BITS 2u        /* nE, nW */
#define BP3_FB_NE 1u
#define BP3_FB_NW 2u
#define BP3_EDS_NONE_LO 0x00u       /* EDS pointer: no EDS */
#define BP3_EDS_NONE_HI 0xFFu
#define BP3_CHKSUM_AT 0x3Fu
/* The core's CRCs with their top and x^0 terms (digest, section 6), both starting at 0. */
#define POLY_CRC6 0x43u
#define POLY_CRC16 0x190D9u

biss_err_t biss_bp3_decode_id(uint8_t reg_0x42, uint8_t reg_0x43, biss_bp3_id_t *id)
{
    unsigned c, dl;
    if (id == NULL)
        return BISS_ERR_ARG;
    if ((unsigned)(reg_0x42 >> 4) != BP3_ID)
        return BISS_ERR_NOT_BP3;
    if (((unsigned)(reg_0x42 >> 1) & 0x7u) != BP3_VERSION)
        return BISS_ERR_BP3_FIELD;
    c = reg_0x42 & 1u;
    dl = reg_0x43;          /* bit 7 must be 0: a set bit 7 is above either DL maximum */
    if (dl < BP3_DL_MIN || dl > (c ? BP3_DL_MAX_C1 : BP3_DL_MAX_C0))
        return BISS_ERR_BP3_FIELD;
    id->version = BP3_VERSION;
    id->crc_mode = (uint8_t)c;
    id->data_length = (uint8_t)dl;
    id->position_bits = (uint8_t)(c ? 0u : dl - BP3_FEEDBACK_BITS);
    return BISS_OK;
}

biss_err_t biss_bp3_identify(biss_channel_t *ch, unsigned slave_id, biss_bp3_id_t *id)
{
    uint8_t r[2];
    biss_err_t err;
    if (id == NULL)
        return BISS_ERR_ARG;
    err = biss_reg_read(ch, slave_id, BISS_BP3_REG_PROFILE_ID, r, 2, NULL);
    return err != BISS_OK ? err : biss_bp3_decode_id(r[0], r[1], id);
}

static uint16_t be16(const uint8_t *p)
{
    return (uint16_t)((unsigned)p[0] << 8 | p[1]);
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

biss_err_t biss_bp3_decode_eds(const uint8_t bank[BISS_BP3_EDS_BYTES], biss_bp3_eds_t *eds)
{
    unsigned i, sum = 0;
    biss_bp3_id_t id;
    biss_err_t err;
    if (bank == NULL || eds == NULL)
        return BISS_ERR_ARG;
    for (i = 0; i < BP3_CHKSUM_AT; i++)
        sum += bank[i];
    if ((sum & 0xFFu) != bank[BP3_CHKSUM_AT])
        return BISS_ERR_EDS_CHECKSUM;
    err = biss_bp3_decode_id(bank[0x02], bank[0x03], &id);
    if (err != BISS_OK)
        return err;
    eds->bp_ver = bank[0x00];
    eds->bp_len = bank[0x01];
    eds->bp_id = bank[0x02];
    eds->dl = bank[0x03];
    eds->fb1 = bank[0x04];
    eds->fb2 = bank[0x05];
    eds->pon_pdl = bank[0x06];
    eds->en_typ = bank[0x08];
    eds->pos_num = bank[0x09];
    eds->mt_len = bank[0x0A];
    eds->mt_fmt = bank[0x0B];
    eds->co_len = bank[0x0C];
    eds->co_fmt = bank[0x0D];
    eds->fi_len = bank[0x0E];
    eds->fi_fmt = bank[0x0F];
    eds->mt_cnt = be32(&bank[0x10]);
    eds->sip_cnt = be32(&bank[0x14]);
    eds->sip_res = be32(&bank[0x18]);
    eds->cpoly = be32(&bank[0x1C]);
    eds->cstart = be32(&bank[0x20]);
    eds->abs_acu = be16(&bank[0x24]);
    eds->rel_acu = be16(&bank[0x26]);
    eds->spd_acu = be16(&bank[0x28]);
    eds->hyst = be16(&bank[0x2A]);
    eds->spd_max = be16(&bank[0x2C]);
    eds->acc_max = be16(&bank[0x2E]);
    eds->tmp_min = be16(&bank[0x30]);
    eds->tmp_max = be16(&bank[0x32]);
    eds->vlt_min = be16(&bank[0x34]);
    eds->vlt_max = be16(&bank[0x36]);
    eds->cur_max = be16(&bank[0x38]);
    eds->chksum = bank[BP3_CHKSUM_AT];
    eds->eds_bank = 0;
    eds->profile_bank = 0;
    if (eds->bp_ver != 1u || eds->bp_len != 1u || eds->pon_pdl < 1u || eds->pon_pdl > 254u ||
        eds->pos_num > 2u || eds->en_typ > 1u || eds->mt_fmt > 1u ||
        (eds->fb1 != BP3_FB_NE && eds->fb1 != BP3_FB_NW) ||
        (eds->fb2 != BP3_FB_NE && eds->fb2 != BP3_FB_NW))
        return BISS_ERR_BP3_FIELD;
    return BISS_OK;
}

biss_err_t biss_bp3_read_eds(biss_channel_t *ch, unsigned slave_id, unsigned profile_bank_offset,
                             biss_bp3_eds_t *eds)
{
    uint8_t regs[4], bank[BISS_BP3_EDS_BYTES], sel;
    unsigned profile;
    biss_bp3_id_t id;
    biss_err_t err, restore;
    if (eds == NULL)
        return BISS_ERR_ARG;
    /* 0x40 bank select, 0x41 EDS pointer, 0x42 / 0x43 profile ID: one access. */
    err = biss_reg_read(ch, slave_id, BISS_BP3_REG_BANK_SELECT, regs, 4, NULL);
    if (err == BISS_OK)
        err = biss_bp3_decode_id(regs[2], regs[3], &id);
    if (err != BISS_OK)
        return err;
    if (regs[1] == BP3_EDS_NONE_LO || regs[1] == BP3_EDS_NONE_HI)
        return BISS_ERR_NO_EDS;
    profile = regs[1] + profile_bank_offset;
    if (profile_bank_offset > 0xFFu || profile > 0xFFu)
        return BISS_ERR_BP3_FIELD;
    if (profile == regs[0]) {
        err = biss_reg_read(ch, slave_id, 0x00, bank, BISS_BP3_EDS_BYTES, NULL);
    } else {
        sel = (uint8_t)profile;
        err = biss_reg_write(ch, slave_id, BISS_BP3_REG_BANK_SELECT, &sel, 1, NULL);
        if (err == BISS_OK)
            err = biss_reg_read(ch, slave_id, BISS_BP3_REG_BANK_SELECT, &sel, 1, NULL);
        if (err == BISS_OK && sel != profile)
            err = BISS_ERR_BANK_SELECT;
        if (err == BISS_OK)
            err = biss_reg_read(ch, slave_id, 0x00, bank, BISS_BP3_EDS_BYTES, NULL);
        /* Restore the previous bank whenever 0x40 may have been written. */
        restore = biss_reg_write(ch, slave_id, BISS_BP3_REG_BANK_SELECT, &regs[0], 1, NULL);
        if (err == BISS_OK)
            err = restore;
    }
    if (err != BISS_OK)
        return err;
    err = biss_bp3_decode_eds(bank, eds);
    if (err != BISS_OK)
        return err;
    if (eds->bp_id != regs[2] || eds->dl != regs[3])
        return BISS_ERR_EDS_MISMATCH;
    eds->eds_bank = regs[1];
    eds->profile_bank = (uint8_t)profile;
    return BISS_OK;
}

biss_err_t biss_bp3_config(const biss_bp3_eds_t *eds, biss_config_t *cfg)
{
    static const biss_word_format_t no_word;
    biss_bp3_id_t id;
    uint32_t poly;
    unsigned width;
    uint8_t crc;
    biss_err_t err;
    if (eds == NULL || cfg == NULL)
        return BISS_ERR_ARG;
    err = biss_bp3_decode_id(eds->bp_id, eds->dl, &id);
    if (err != BISS_OK)
        return err;
    if (id.crc_mode != 0 || eds->fb1 != BP3_FB_NE || eds->fb2 != BP3_FB_NW ||
        id.position_bits == 0 || eds->cpoly == 0)
        return BISS_ERR_UNSUPPORTED;
    /* CPOLY is the polynomial without x^0, shifted down one bit (docs/protocol.md, section 7):
     * degree 1 .. 16 and a start value that fits are a custom CRC; CRC-6 0x43 and CRC-16
     * 0x190D9 from 0 the named ones, as before custom CRCs. */
    if (eds->cpoly >= 0x10000u)
        return BISS_ERR_UNSUPPORTED;                    /* a CRC wider than 16 bits */
    poly = eds->cpoly << 1 | 1u;
    for (width = 16; (poly >> width) == 0; width--)
        ;
    if ((eds->cstart >> width) != 0)
        return BISS_ERR_UNSUPPORTED;
    cfg->word[0] = no_word;
    if (poly == POLY_CRC6 && eds->cstart == 0)
        crc = BISS_CRC6;
    else if (poly == POLY_CRC16 && eds->cstart == 0)
        crc = BISS_CRC16;
    else {
        crc = BISS_CRC_CUSTOM;
        cfg->word[0].crc_width = (uint8_t)width;
        cfg->word[0].crc_poly = (uint16_t)(poly & ((1u << width) - 1u));
        cfg->word[0].crc_start = (uint16_t)eds->cstart;
        cfg->word[0].crc_inverted = true;
    }
    cfg->word[0].data_bits = id.position_bits;
    cfg->word[0].crc = crc;
    cfg->word[0].nenw = true;
    cfg->word[0].lc = false;
    cfg->word[1] = no_word;
    cfg->word1_enable = false;
    cfg->spw_check = false;
    cfg->spw_tolerance = 0;
    return BISS_OK;
}
