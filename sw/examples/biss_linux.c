/*
 * biss_linux: the C driver on Linux, from user space (docs/driver.md, "On Linux: the example
 * program"). Built and linked against libbissmaster.a by `make driver`.
 *
 * Maps the bus top's register window through UIO (/dev/uioN, map 0) or /dev/mem (a physical
 * address), gives the driver volatile 32-bit hooks on it, checks that the window is this core
 * (id "BiSS", the map's major version), configures the channels from encoder presets (or,
 * with --identify, from a BP3 encoder's EDS), then triggers (or runs periodic requests) and
 * prints every frame: status, position, nE / nW, CRC, line delay, seq, timestamp; at the end
 * the error counters.
 *
 * Exit codes: 0 every frame OK; 2 bad arguments (or arguments this build cannot do);
 * 3 the device cannot be opened or mapped; 4 the window is not this core; 5 encoder errors or
 * timeouts (a frame not OK, no frame at all, a BP3 access that failed); 130 interrupted;
 * 1 an internal error. Every failure prints one line on stderr.
 */
/* POSIX (mmap, clock_nanosleep, sigaction, strtok_r) in this file only: the driver itself is
 * plain C99. 64-bit off_t: physical addresses above 4 GiB on 32-bit systems. */
#define _POSIX_C_SOURCE 200809L
#define _FILE_OFFSET_BITS 64

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "biss_master.h"

#define PROG "biss_linux"

enum {
    EXIT_OK = 0,
    EXIT_INTERNAL = 1,
    EXIT_ARGS = 2,
    EXIT_DEVICE = 3,
    EXIT_NOT_CORE = 4,
    EXIT_ENCODER = 5,
    EXIT_INTERRUPTED = 130
};

/* -- The register map, from the generated header -------------------------------------------- */

#define GLOBAL_OFF(member) ((size_t)offsetof(biss_master_regs_t, member))
#define CH0_OFF ((size_t)offsetof(biss_master_regs_t, channel[0]))
#define CH_STRIDE ((size_t)(offsetof(biss_master_regs_t, channel[1]) - CH0_OFF))
#define CH_SLOTS \
    (sizeof(((biss_master_regs_t *)0)->channel) / sizeof(((biss_master_regs_t *)0)->channel[0]))
#define MAP_BYTES sizeof(biss_master_regs_t)
#define FIELD(word, F) (((uint32_t)(word) & (uint32_t)F##_bm) >> F##_bp)

/* The bytes of the window that channel `n` (and the global registers before it) needs. */
static size_t window_needed(unsigned n)
{
    return CH0_OFF + ((size_t)n + 1u) * CH_STRIDE;
}

static const char *crc_name(unsigned crc)
{
    return crc == BISS_CRC6 ? "CRC-6" : crc == BISS_CRC16 ? "CRC-16" : "no CRC";
}

/* -- Options ------------------------------------------------------------------------------- */

typedef struct {
    const char *uio;                /* --uio /dev/uioN */
    const char *file;               /* --file PATH (tests, dry runs) */
    bool mem;                       /* --mem given */
    uint64_t mem_addr;
    unsigned channel[CH_SLOTS];
    unsigned channels;
    const char *preset[CH_SLOTS];
    unsigned presets;
    uint32_t clock_hz, ma_hz;
    unsigned long count;            /* 0: until interrupted */
    unsigned long period_us;
    unsigned long timeout_ms;
    bool periodic, identify, trace;
    unsigned slave, eds_offset;
} options_t;

static void usage(FILE *out)
{
    fputs(
"usage: " PROG " (--uio /dev/uioN | --mem ADDR) [options]\n"
"       " PROG " --list-presets | --help\n"
"\n"
"Maps the register window of a BiSS master bus top (biss_master_axil / biss_master_wb),\n"
"checks it is this core, configures channels and prints their frames (docs/driver.md).\n"
"\n"
"The register window (one of):\n"
"  --uio /dev/uioN       a UIO device (generic-uio), its map 0; size from\n"
"                        /sys/class/uio/uioN/maps/map0/size\n"
"  --mem ADDR            /dev/mem at physical address ADDR (e.g. 0x43C00000; root)\n"
"  --file PATH           a regular file as the window (tests, dry runs: nothing answers,\n"
"                        the writes land in the file); with --mem ADDR the file stands in\n"
"                        for /dev/mem and the window starts at byte ADDR of it\n"
"\n"
"Channels and encoders:\n"
"  --channel N[,N...]    channels to use, 0..7 (default 0; may be repeated)\n"
"  --preset NAME[,...]   encoder preset: one for all channels or one per channel\n"
"                        (--list-presets); optional with --identify\n"
"  --clock-hz HZ         the bus top's clock (default 100000000)\n"
"  --ma-hz HZ            MA rate, at most this (80000..10000000, default 1000000)\n"
"  --identify            BP3: read the profile ID and the EDS of each channel's encoder\n"
"                        and print them; without --preset, configure from the EDS\n"
"  --slave N             BP3 slave ID, 0..7 (default 0)\n"
"  --eds-offset N        the BP3 bank is the EDS pointer + N, 0 or 1 (default 1)\n"
"\n"
"Reading:\n"
"  --count N             frames per channel (default 10; 0: until Ctrl-C)\n"
"  --period-us US        time between frames (default 100000)\n"
"  --periodic            the core requests every --period-us itself (default: a software\n"
"                        trigger every --period-us starts all channels in the same clock)\n"
"  --timeout-ms MS       longest wait for a frame to end (default 100)\n"
"  --trace               print every register access on stderr\n"
"\n"
"Exit codes: 0 all frames OK, 2 bad arguments, 3 cannot open or map the device,\n"
"4 the window is not this core, 5 encoder errors or timeouts, 130 interrupted.\n",
        out);
}

/* -- Messages, and what has to be undone on the way out ---------------------------------------- */

static biss_channel_t g_ch[CH_SLOTS];
static bool g_periodic_started[CH_SLOTS];
static unsigned g_used;
static volatile sig_atomic_t g_stop;

static void undo(void)
{
    unsigned i;
    for (i = 0; i < g_used; i++)
        if (g_periodic_started[i]) {
            g_periodic_started[i] = false;
            biss_set_periodic(&g_ch[i], false, 0);
        }
}

/* One line on stderr, then exit with `code` (periodic requests stopped first). */
static void fail(int code, const char *fmt, ...)
{
    va_list ap;
    fflush(stdout);                 /* what was printed before comes first */
    fputs(PROG ": ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    undo();
    exit(code);
}

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static void on_bus_error(int sig)
{
    static const char msg[] = PROG ": bus error in the register window: nothing answers there "
                              "(wrong address, or the bitstream is not loaded)\n";
    (void)sig;
    if (write(STDERR_FILENO, msg, sizeof msg - 1u) < 0) {
        /* nothing left to tell */
    }
    _exit(EXIT_DEVICE);
}

/* -- Numbers -------------------------------------------------------------------------------- */

static bool parse_u64(const char *s, uint64_t *value)
{
    char *end;
    unsigned long long v;
    if (s == NULL || *s == '\0' || *s == '-' || *s == '+' || *s == ' ')
        return false;
    errno = 0;
    v = strtoull(s, &end, 0);
    if (errno != 0 || *end != '\0')
        return false;
    *value = (uint64_t)v;
    return true;
}

static uint64_t number(const char *opt, const char *s, uint64_t min, uint64_t max)
{
    uint64_t v;
    if (!parse_u64(s, &v))
        fail(EXIT_ARGS, "%s: '%s' is not a number", opt, s);
    if (v < min || v > max)
        fail(EXIT_ARGS, "%s: %s is outside %" PRIu64 "..%" PRIu64, opt, s, min, max);
    return v;
}

/* -- Command line --------------------------------------------------------------------------- */

static void add_channels(options_t *o, const char *list)
{
    char buf[128], *tok, *save = NULL;
    unsigned i, n;
    if (strlen(list) >= sizeof buf)
        fail(EXIT_ARGS, "--channel: list too long");
    strcpy(buf, list);
    for (tok = strtok_r(buf, ",", &save); tok != NULL; tok = strtok_r(NULL, ",", &save)) {
        n = (unsigned)number("--channel", tok, 0, CH_SLOTS - 1u);
        for (i = 0; i < o->channels; i++)
            if (o->channel[i] == n)
                fail(EXIT_ARGS, "--channel: channel %u given twice", n);
        o->channel[o->channels++] = n;
    }
    if (o->channels == 0)
        fail(EXIT_ARGS, "--channel: no channel in '%s'", list);
}

static void add_presets(options_t *o, char *list)
{
    char *tok, *save = NULL;
    for (tok = strtok_r(list, ",", &save); tok != NULL; tok = strtok_r(NULL, ",", &save)) {
        if (o->presets == CH_SLOTS)
            fail(EXIT_ARGS, "--preset: more than %u names", (unsigned)CH_SLOTS);
        if (biss_preset_find(tok) == NULL)
            fail(EXIT_ARGS, "--preset: no preset '%s' (--list-presets)", tok);
        o->preset[o->presets++] = tok;
    }
    if (o->presets == 0)
        fail(EXIT_ARGS, "--preset: no name given");
}

static void list_presets(void)
{
    unsigned i, w;
    for (i = 0; i < biss_preset_count(); i++) {
        const biss_preset_t *p = biss_preset_at(i);
        bool safety = p->words == 2;
        printf("%-18s %-12s", p->name, safety ? "BiSS Safety" : "BiSS C");
        for (w = 0; w < p->words && w < 2u; w++) {
            const biss_word_format_t *f = &p->word[w];
            printf("%s%s: %u bits %s%s%s", w ? "; " : "", safety ? (w ? "SPW" : "CPW")
                   : "word 0", (unsigned)f->data_bits, crc_name(f->crc),
                   f->nenw ? " nE nW" : "", f->lc ? " LC" : "");
        }
        if (p->spw_check)
            printf("; SPW check (tolerance %u)", (unsigned)p->spw_tolerance);
        putchar('\n');
    }
}

/* "--name=value" or "--name value"; NULL if `arg` is not option `name`. */
static char *value_of(const char *name, int argc, char **argv, int *i)
{
    size_t len = strlen(name);
    char *arg = argv[*i];
    if (strncmp(arg, name, len) != 0)
        return NULL;
    if (arg[len] == '=')
        return arg + len + 1;
    if (arg[len] != '\0')
        return NULL;
    if (*i + 1 >= argc)
        fail(EXIT_ARGS, "%s needs a value (--help)", name);
    return argv[++*i];
}

static void parse_args(options_t *o, int argc, char **argv)
{
    int i;
    char *v;
    unsigned k;
    biss_config_t cfg;
    biss_err_t err;

    memset(o, 0, sizeof *o);
    o->clock_hz = 100000000u;
    o->ma_hz = 1000000u;
    o->count = 10;
    o->period_us = 100000;
    o->timeout_ms = 100;
    o->eds_offset = 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            exit(EXIT_OK);
        } else if (strcmp(a, "--list-presets") == 0) {
            list_presets();
            exit(EXIT_OK);
        } else if ((v = value_of("--uio", argc, argv, &i)) != NULL) {
            o->uio = v;
        } else if ((v = value_of("--mem", argc, argv, &i)) != NULL) {
            o->mem = true;
            o->mem_addr = number("--mem", v, 0, UINT64_MAX);
        } else if ((v = value_of("--file", argc, argv, &i)) != NULL) {
            o->file = v;
        } else if ((v = value_of("--channel", argc, argv, &i)) != NULL) {
            add_channels(o, v);
        } else if ((v = value_of("--preset", argc, argv, &i)) != NULL) {
            add_presets(o, v);          /* the names stay in argv */
        } else if ((v = value_of("--clock-hz", argc, argv, &i)) != NULL) {
            o->clock_hz = (uint32_t)number("--clock-hz", v, 1, UINT32_MAX);
        } else if ((v = value_of("--ma-hz", argc, argv, &i)) != NULL) {
            o->ma_hz = (uint32_t)number("--ma-hz", v, 1, UINT32_MAX);
        } else if ((v = value_of("--count", argc, argv, &i)) != NULL) {
            o->count = (unsigned long)number("--count", v, 0, 1000000000u);
        } else if ((v = value_of("--period-us", argc, argv, &i)) != NULL) {
            o->period_us = (unsigned long)number("--period-us", v, 0, 3600000000u);
        } else if ((v = value_of("--timeout-ms", argc, argv, &i)) != NULL) {
            o->timeout_ms = (unsigned long)number("--timeout-ms", v, 1, 3600000u);
        } else if ((v = value_of("--slave", argc, argv, &i)) != NULL) {
            o->slave = (unsigned)number("--slave", v, 0, 7);
        } else if ((v = value_of("--eds-offset", argc, argv, &i)) != NULL) {
            o->eds_offset = (unsigned)number("--eds-offset", v, 0, 1);
        } else if (strcmp(a, "--periodic") == 0) {
            o->periodic = true;
        } else if (strcmp(a, "--identify") == 0) {
            o->identify = true;
        } else if (strcmp(a, "--trace") == 0) {
            o->trace = true;
        } else if (a[0] == '-') {
            fail(EXIT_ARGS, "unknown option '%s' (--help lists them)", a);
        } else {
            fail(EXIT_ARGS, "unexpected argument '%s' (--help)", a);
        }
    }
    if (o->uio != NULL && (o->mem || o->file != NULL))
        fail(EXIT_ARGS, "give one register window: --uio, or --mem (--file for tests)");
    if (o->uio == NULL && !o->mem && o->file == NULL)
        fail(EXIT_ARGS, "no register window: give --uio /dev/uioN or --mem ADDR (--help)");
    if (o->mem && o->mem_addr % 4u != 0)
        fail(EXIT_ARGS, "--mem: 0x%" PRIx64 " is not 4-byte aligned", o->mem_addr);
    if (o->channels == 0)
        o->channel[o->channels++] = 0;
    if (o->presets == 0 && !o->identify)
        fail(EXIT_ARGS, "give --preset NAME (--list-presets) or --identify");
    if (o->presets > 1 && o->presets != o->channels)
        fail(EXIT_ARGS, "--preset: %u names for %u channels (give one, or one per channel)",
             o->presets, o->channels);
    /* The MA rate against the clock, before any device is touched. */
    for (k = 0; k < (o->presets ? o->presets : 1u); k++) {
        err = biss_config_from_preset(&cfg, o->presets ? o->preset[k]
                                      : biss_preset_at(0)->name, o->clock_hz, o->ma_hz);
        if (err == BISS_ERR_MA_RATE)
            fail(EXIT_ARGS, "--ma-hz: %" PRIu32 " Hz is outside BiSS C's 80 kHz .. 10 MHz",
                 o->ma_hz);
        if (err != BISS_OK)
            fail(EXIT_ARGS, "--ma-hz %" PRIu32 " at --clock-hz %" PRIu32 ": %s (the MA half "
                 "period must be 2..65535 clocks)", o->ma_hz, o->clock_hz,
                 biss_error_name(err));
    }
}

/* -- The register window -------------------------------------------------------------------- */

typedef struct {
    volatile uint8_t *regs;         /* the bus top's register 0 */
    size_t size;                    /* bytes from regs */
    void *map;
    size_t map_len;
    bool trace;
    char what[320];                 /* for the messages */
} window_t;

static uint32_t win_read32(void *ctx, uintptr_t addr)
{
    window_t *w = ctx;
    uint32_t v;
    if (addr % 4u != 0 || addr + 4u > w->size)
        fail(EXIT_INTERNAL, "read of 0x%04lx outside the %zu-byte window",
             (unsigned long)addr, w->size);
    v = *(volatile const uint32_t *)(const volatile void *)(w->regs + addr);
    if (w->trace)
        fprintf(stderr, "trace: read  0x%04lx -> 0x%08" PRIx32 "\n", (unsigned long)addr, v);
    return v;
}

static void win_write32(void *ctx, uintptr_t addr, uint32_t value)
{
    window_t *w = ctx;
    if (addr % 4u != 0 || addr + 4u > w->size)
        fail(EXIT_INTERNAL, "write of 0x%04lx outside the %zu-byte window",
             (unsigned long)addr, w->size);
    if (w->trace)
        fprintf(stderr, "trace: write 0x%04lx <- 0x%08" PRIx32 "\n", (unsigned long)addr,
                value);
    *(volatile uint32_t *)(volatile void *)(w->regs + addr) = value;
}

/* The first line of a sysfs file as a number. */
static bool read_sysfs_number(const char *path, uint64_t *value)
{
    char line[64];
    FILE *f = fopen(path, "r");
    bool ok;
    if (f == NULL)
        return false;
    ok = fgets(line, sizeof line, f) != NULL;
    fclose(f);
    if (ok)
        line[strcspn(line, "\r\n")] = '\0';
    return ok && parse_u64(line, value);
}

static size_t page_size(void)
{
    long p = sysconf(_SC_PAGESIZE);
    return p > 0 ? (size_t)p : 4096u;
}

/* mmap `len` bytes of fd at `offset` (page aligned), shared, read and write. */
static void *map_shared(int fd, size_t len, uint64_t offset, const char *what)
{
    void *p;
    if ((uint64_t)(off_t)offset != offset || (off_t)offset < 0)
        fail(EXIT_ARGS, "%s: offset 0x%" PRIx64 " does not fit off_t", what, offset);
    p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_SHARED, fd, (off_t)offset);
    if (p == MAP_FAILED)
        fail(EXIT_DEVICE, "cannot map %s (%zu bytes at 0x%" PRIx64 "): %s", what, len, offset,
             strerror(errno));
    return p;
}

static int open_device(const char *path, const char *hint)
{
    int fd = open(path, O_RDWR | O_SYNC);
    if (fd < 0)
        fail(EXIT_DEVICE, "cannot open %s: %s%s", path, strerror(errno),
             errno == EACCES || errno == EPERM ? hint : "");
    return fd;
}

/* UIO: map 0 of /dev/uioN, its size (and offset inside the page) from sysfs. BISS_UIO_SYSFS
 * replaces /sys/class/uio (tests). */
static void open_uio(window_t *w, const char *arg)
{
    const char *name = strrchr(arg, '/') ? strrchr(arg, '/') + 1 : arg;
    const char *sysfs = getenv("BISS_UIO_SYSFS") ? getenv("BISS_UIO_SYSFS") : "/sys/class/uio";
    char path[512], dev[256];
    uint64_t size, offset = 0;
    size_t page = page_size(), len;
    int fd;
    /* "uio0" is /dev/uio0 */
    snprintf(dev, sizeof dev, "%s%s", strchr(arg, '/') ? "" : "/dev/", arg);
    fd = open_device(dev, " (root, or a udev rule giving access to it)");
    snprintf(path, sizeof path, "%s/%s/maps/map0/size", sysfs, name);
    if (!read_sysfs_number(path, &size) || size == 0 || size > SIZE_MAX / 2u)
        fail(EXIT_DEVICE, "cannot read the size of %s's map 0 from %s: is it a UIO device "
             "with a memory map?", dev, path);
    snprintf(path, sizeof path, "%s/%s/maps/map0/offset", sysfs, name);
    if (!read_sysfs_number(path, &offset))
        offset = 0;                 /* older kernels: the map starts at the page */
    if (offset % 4u != 0 || offset >= page)
        fail(EXIT_DEVICE, "%s map 0: offset 0x%" PRIx64 " inside the page is not usable", dev,
             offset);
    len = (size_t)offset + (size_t)size;
    len = (len + page - 1u) / page * page;
    w->map = map_shared(fd, len, 0 * page, dev);       /* map N is at offset N pages */
    w->map_len = len;
    w->regs = (volatile uint8_t *)w->map + offset;
    w->size = (size_t)size;
    close(fd);
    snprintf(w->what, sizeof w->what, "%s (map 0, 0x%zx bytes)", dev, w->size);
}

/* /dev/mem (or a file standing in for it) at `addr`: the whole map. */
static void open_mem(window_t *w, const char *dev, uint64_t addr, uint64_t file_size)
{
    size_t page = page_size();
    uint64_t start = addr / page * page;
    size_t lead = (size_t)(addr - start);
    size_t len = (lead + MAP_BYTES + page - 1u) / page * page;
    int fd = open_device(dev, " (root: /dev/mem needs CAP_SYS_RAWIO; or use UIO)");
    if (file_size != 0 && (addr > file_size || file_size - addr < MAP_BYTES))
        fail(EXIT_DEVICE, "%s: %" PRIu64 " bytes, too short for the 0x%zx-byte map at 0x%"
             PRIx64, dev, file_size, (size_t)MAP_BYTES, addr);
    w->map = map_shared(fd, len, start, dev);
    w->map_len = len;
    w->regs = (volatile uint8_t *)w->map + lead;
    w->size = MAP_BYTES;
    close(fd);
    snprintf(w->what, sizeof w->what, "%s at 0x%" PRIx64 " (0x%zx bytes)", dev, addr, w->size);
}

/* A regular file as the window (tests, dry runs). */
static void open_file(window_t *w, const options_t *o)
{
    struct stat st;
    int fd;
    if (stat(o->file, &st) != 0)
        fail(EXIT_DEVICE, "cannot open %s: %s", o->file, strerror(errno));
    if (!S_ISREG(st.st_mode))
        fail(EXIT_DEVICE, "%s is not a regular file (--file is for tests and dry runs)",
             o->file);
    if (st.st_size < 4)
        fail(EXIT_DEVICE, "%s: %lld bytes, too short for a register window", o->file,
             (long long)st.st_size);
    if (o->mem) {
        open_mem(w, o->file, o->mem_addr, (uint64_t)st.st_size);
        return;
    }
    fd = open_device(o->file, "");
    w->size = (size_t)st.st_size & ~(size_t)3u;
    w->map = map_shared(fd, w->size, 0, o->file);
    w->map_len = w->size;
    w->regs = w->map;
    close(fd);
    snprintf(w->what, sizeof w->what, "%s (file, 0x%zx bytes)", o->file, w->size);
}

/* -- Time ----------------------------------------------------------------------------------- */

static int64_t now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static void sleep_until(int64_t t_ns)
{
    struct timespec t;
    t.tv_sec = (time_t)(t_ns / 1000000000);
    t.tv_nsec = (long)(t_ns % 1000000000);
    while (!g_stop && clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, NULL) == EINTR) {
    }
}

/* Wait for the channel's next `done` (biss_wait_done in slices), at most timeout_ns: BISS_OK,
 * BISS_ERR_TIMEOUT, or 1 when interrupted. Polls flat out for 2 ms, then every 100 us. */
static int wait_frame(biss_channel_t *ch, int64_t timeout_ns)
{
    int64_t t0 = now_ns(), waited;
    for (;;) {
        if (biss_wait_done(ch, 64) == BISS_OK)
            return BISS_OK;
        if (g_stop)
            return 1;
        waited = now_ns() - t0;
        if (waited > timeout_ns)
            return BISS_ERR_TIMEOUT;
        if (waited > 2000000)
            sleep_until(now_ns() + 100000);
    }
}

/* -- Channels ------------------------------------------------------------------------------- */

typedef struct {
    biss_config_t cfg;              /* as configured */
    const char *source;             /* the preset's name, or "EDS" */
} setup_t;

static void print_format(unsigned n, const setup_t *s, uint32_t clock_hz)
{
    const biss_config_t *c = &s->cfg;
    unsigned w;
    printf("ch %u: %s:", n, s->source);
    for (w = 0; w < (c->word1_enable ? 2u : 1u); w++)
        printf("%s word %u %u bits %s%s%s", w ? "," : "", w, (unsigned)c->word[w].data_bits,
               crc_name(c->word[w].crc), c->word[w].nenw ? " nE nW" : "",
               c->word[w].lc ? " LC" : "");
    if (c->spw_check)
        printf(", SPW check (tolerance %u)", (unsigned)c->spw_tolerance);
    printf("; MA %.0f Hz (half period %u clocks at %" PRIu32 " Hz)\n",
           (double)clock_hz / (2.0 * c->ma_half_period), (unsigned)c->ma_half_period, clock_hz);
}

/* Configure, or exit: a configuration the build cannot take is an argument error; the core
 * refusing what the driver accepts means the window is not the core it claims to be. */
static void configure(unsigned i, unsigned n, setup_t *s, uint32_t clock_hz)
{
    biss_err_t err = biss_configure(&g_ch[i], &s->cfg);
    if (err == BISS_ERR_REFUSED)
        fail(EXIT_NOT_CORE, "ch %u: the core refuses the configuration (state.config_error "
             "after %s)", n, s->source);
    if (err != BISS_OK)
        fail(EXIT_ARGS, "ch %u: %s does not fit this build: %s (caps: word 0 up to %u bits, "
             "word 1 up to %u, timers %u bits)", n, s->source, biss_error_name(err),
             (unsigned)g_ch[i].max_data_bits[0], (unsigned)g_ch[i].max_data_bits[1],
             (unsigned)g_ch[i].timer_width);
    print_format(n, s, clock_hz);
}

static const char *ca_hint(biss_err_t err)
{
    switch (err) {
    case BISS_ERR_CA_NO_ANSWER: return " (no control side: a unidirectional encoder?)";
    case BISS_ERR_CA_REFUSED: return " (wrong --slave, or the register is read only)";
    case BISS_ERR_CA_DATA_FAULT: return " (a data frame failed meanwhile: wiring, MA rate)";
    case BISS_ERR_CA_CRC4: return " (line noise, MA rate too high for the cable)";
    case BISS_ERR_TIMEOUT: return " (the access never ended)";
    case BISS_ERR_NOT_BP3: return " (not a BP3 Standard Encoder: give --preset)";
    case BISS_ERR_NO_EDS: return " (the encoder has no EDS: give --preset)";
    case BISS_ERR_BANK_SELECT: return " (try --eds-offset 0 or 1)";
    default: return "";
    }
}

static void print_eds(unsigned n, const biss_bp3_eds_t *e)
{
    printf("ch %u: EDS bank 0x%02x (pointer 0x%02x): BP_VER %u BP_LEN %u BP_ID 0x%02x DL %u "
           "FB1 %u FB2 %u PON_PDL %u ms\n", n, (unsigned)e->profile_bank, (unsigned)e->eds_bank,
           (unsigned)e->bp_ver, (unsigned)e->bp_len, (unsigned)e->bp_id, (unsigned)e->dl,
           (unsigned)e->fb1, (unsigned)e->fb2, (unsigned)e->pon_pdl);
    printf("ch %u: EDS position: EN_TYP %u (%s) POS_NUM %u MT_LEN %u MT_FMT %u CO_LEN %u "
           "CO_FMT 0x%02x FI_LEN %u FI_FMT 0x%02x\n", n, (unsigned)e->en_typ,
           e->en_typ ? "linear" : "rotary", (unsigned)e->pos_num, (unsigned)e->mt_len,
           (unsigned)e->mt_fmt, (unsigned)e->co_len, (unsigned)e->co_fmt, (unsigned)e->fi_len,
           (unsigned)e->fi_fmt);
    printf("ch %u: EDS scale: MT_CNT %" PRIu32 " SIP_CNT %" PRIu32 " SIP_RES %" PRIu32
           " CPOLY 0x%08" PRIx32 " CSTART 0x%08" PRIx32 "\n", n, e->mt_cnt, e->sip_cnt,
           e->sip_res, e->cpoly, e->cstart);
    printf("ch %u: EDS accuracy: ABS_ACU %u REL_ACU %u SPD_ACU %u HYST %u SPD_MAX %u "
           "ACC_MAX %u\n", n, (unsigned)e->abs_acu, (unsigned)e->rel_acu, (unsigned)e->spd_acu,
           (unsigned)e->hyst, (unsigned)e->spd_max, (unsigned)e->acc_max);
    printf("ch %u: EDS ratings: TMP %u..%u K VLT %u..%u mV CUR_MAX %u mA CHKSUM 0x%02x\n", n,
           (unsigned)e->tmp_min, (unsigned)e->tmp_max, (unsigned)e->vlt_min,
           (unsigned)e->vlt_max, (unsigned)e->cur_max, (unsigned)e->chksum);
}

/* BP3: a frame long enough for any encoder (docs/control.md, The data channel before
 * identification), the profile ID, the EDS; then the data channel from the EDS unless a
 * preset is given. */
static void identify(unsigned i, unsigned n, const options_t *o, setup_t *s)
{
    biss_channel_t *ch = &g_ch[i];
    setup_t probe;
    biss_bp3_id_t id;
    biss_bp3_eds_t eds;
    biss_err_t err;

    probe.source = "identification frame";
    if (biss_config_from_preset(&probe.cfg, biss_preset_at(0)->name, o->clock_hz, o->ma_hz)
        != BISS_OK)
        fail(EXIT_INTERNAL, "no configuration for the identification frame");
    probe.cfg.word[0].data_bits = ch->max_data_bits[0];
    probe.cfg.word[0].crc = BISS_CRC_NONE;
    probe.cfg.word[0].nenw = true;
    probe.cfg.word[0].lc = false;
    probe.cfg.word1_enable = ch->max_data_bits[1] != 0;
    probe.cfg.word[1].data_bits = ch->max_data_bits[1];
    probe.cfg.word[1].crc = BISS_CRC_NONE;
    probe.cfg.word[1].nenw = probe.cfg.word1_enable;
    probe.cfg.word[1].lc = false;
    probe.cfg.spw_check = false;
    probe.cfg.spw_tolerance = 0;
    if (!ch->has_register_access)
        fail(EXIT_ARGS, "ch %u: --identify: this build has no register-access engine "
             "(caps.register_access 0)", n);
    configure(i, n, &probe, o->clock_hz);

    err = biss_bp3_identify(ch, o->slave, &id);
    if (err != BISS_OK)
        fail(EXIT_ENCODER, "ch %u: BP3 identify (slave %u): %s%s", n, o->slave,
             biss_error_name(err), ca_hint(err));
    printf("ch %u: BP3 profile ID: VER %u, C %u (%s), DL %u", n, (unsigned)id.version,
           (unsigned)id.crc_mode, id.crc_mode ? "BiSS Safety" : "CRC separate",
           (unsigned)id.data_length);
    if (id.crc_mode == 0)
        printf(": %u position bits", (unsigned)id.position_bits);
    putchar('\n');
    fflush(stdout);
    err = biss_bp3_read_eds(ch, o->slave, o->eds_offset, &eds);
    if (err != BISS_OK)
        fail(EXIT_ENCODER, "ch %u: BP3 EDS (slave %u, --eds-offset %u): %s%s", n, o->slave,
             o->eds_offset, biss_error_name(err), ca_hint(err));
    print_eds(n, &eds);
    if (s->source != NULL)
        return;                     /* a preset was given: it sets the data channel */
    s->cfg = probe.cfg;
    err = biss_bp3_config(&eds, &s->cfg);
    if (err != BISS_OK)
        fail(EXIT_ENCODER, "ch %u: the core cannot read this encoder from its EDS alone: %s "
             "(give --preset)", n, biss_error_name(err));
    s->source = "from the EDS";
}

/* -- Frames --------------------------------------------------------------------------------- */

/* One line; the frame fields (position, flags, timestamp) only when the status says a frame
 * was decoded (statuses 0..5, docs/ports.md): after a fault they are the last frame's. */
static void print_frame(unsigned long frame, unsigned n, const biss_result_t *r,
                        const biss_config_t *c, uint32_t clock_hz)
{
    printf("frame %lu ch %u status %s", frame, n, biss_status_name(r->status));
    if (r->status <= BISS_STATUS_SPW_MISMATCH) {
        printf(" position %" PRIu64 " (0x%" PRIx64 ") nE %d nW %d crc %s", r->word0, r->word0,
               r->w0_ne, r->w0_nw, r->w0_crc_ok ? "ok" : "bad");
        if (c->word1_enable)
            printf(" word1 %" PRIu64 " (0x%" PRIx64 ") nE %d nW %d crc %s", r->word1,
                   r->word1, r->w1_ne, r->w1_nw, r->w1_crc_ok ? "ok" : "bad");
        if (c->word[0].lc || (c->word1_enable && c->word[1].lc))
            printf(" lc %u", (unsigned)r->lc);
    }
    if (r->status <= BISS_STATUS_SPW_MISMATCH || r->status == BISS_STATUS_DELAY_RANGE)
        printf(" line_delay %u (%.0f ns)", (unsigned)r->line_delay,
               (double)r->line_delay * 1e9 / (double)clock_hz);
    printf(" seq %u", (unsigned)r->seq);
    if (r->status <= BISS_STATUS_SPW_MISMATCH)
        printf(" timestamp %" PRIu32, r->timestamp);
    putchar('\n');
}

static void print_counters(unsigned n, biss_channel_t *ch)
{
    biss_counters_t c;
    if (!ch->has_counters || biss_read_counters(ch, &c) != BISS_OK) {
        printf("ch %u counters: not built\n", n);
        return;
    }
    printf("ch %u counters: crc_word0 %u crc_word1 %u no_ack %u no_start %u delay_range %u "
           "slo_stuck_low %u lc_repeat %u lc_skip %u lc_zero %u spw_mismatch %u overrun %u "
           "aborted %u no_stop %u\n", n, (unsigned)c.crc_word0, (unsigned)c.crc_word1,
           (unsigned)c.no_ack, (unsigned)c.no_start, (unsigned)c.delay_range,
           (unsigned)c.slo_stuck_low, (unsigned)c.lc_repeat, (unsigned)c.lc_skip,
           (unsigned)c.lc_zero, (unsigned)c.spw_mismatch, (unsigned)c.overrun,
           (unsigned)c.aborted, (unsigned)c.no_stop);
}

/* A `done` left from before: cleared, the causes set and no others (the ISR's rule). */
static void clear_stale_done(biss_channel_t *ch)
{
    uint32_t stale = biss_irq_status(ch) & (uint32_t)(BISS_IRQ_DONE | BISS_IRQ_ERROR);
    if (stale != 0)
        biss_irq_clear(ch, stale);
}

/* -- main ----------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    options_t o;
    window_t win;
    biss_bus_t bus;
    setup_t setup[CH_SLOTS];
    struct sigaction sa;
    uint32_t id, version;
    unsigned built, i, n;
    unsigned long frame, bad = 0, frames = 0;
    int64_t next, timeout_ns;
    biss_err_t err;

    parse_args(&o, argc, argv);
    if (o.trace)
        setvbuf(stdout, NULL, _IOLBF, 0);   /* the trace (stderr) and the frames in order */

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_bus_error;
    sigaction(SIGBUS, &sa, NULL);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    memset(&win, 0, sizeof win);
    win.trace = o.trace;
    if (o.uio != NULL)
        open_uio(&win, o.uio);
    else if (o.file != NULL)
        open_file(&win, &o);
    else
        open_mem(&win, "/dev/mem", o.mem_addr, 0);
    bus.base = 0;                   /* the hooks add the window's address */
    bus.read32 = win_read32;
    bus.write32 = win_write32;
    bus.ctx = &win;

    /* Is it this core? id, then the map's version, then the channel count. */
    if (win.size < GLOBAL_OFF(irq_pending) + 4u)
        fail(EXIT_DEVICE, "%s: too small for the global registers", win.what);
    id = win_read32(&win, GLOBAL_OFF(id));
    if (FIELD(id, BISS_MASTER_REGS__ID__ID) != BISS_MASTER_REGS__ID__ID_reset)
        fail(EXIT_NOT_CORE, "%s: id reads 0x%08" PRIx32 ", not 0x%08lx (\"BiSS\"): not a BiSS "
             "master register window (wrong address or device?)", win.what, id,
             (unsigned long)BISS_MASTER_REGS__ID__ID_reset);
    version = win_read32(&win, GLOBAL_OFF(version));
    if (FIELD(version, BISS_MASTER_REGS__VERSION__MAJOR) !=
        BISS_MASTER_REGS__VERSION__MAJOR_reset)
        fail(EXIT_NOT_CORE, "%s: register map version %" PRIu32 ".%" PRIu32 ", this program "
             "is built for major version %u", win.what,
             FIELD(version, BISS_MASTER_REGS__VERSION__MAJOR),
             FIELD(version, BISS_MASTER_REGS__VERSION__MINOR),
             (unsigned)BISS_MASTER_REGS__VERSION__MAJOR_reset);
    err = biss_probe(&bus, &built);
    if (err != BISS_OK)
        fail(EXIT_NOT_CORE, "%s: %s", win.what, biss_error_name(err));
    if (built < 1 || built > CH_SLOTS)
        fail(EXIT_NOT_CORE, "%s: the core reports %u channels (a build has 1..%u)", win.what,
             built, (unsigned)CH_SLOTS);
    printf("%s: BiSS master, register map %" PRIu32 ".%" PRIu32 ", %u channel%s\n", win.what,
           FIELD(version, BISS_MASTER_REGS__VERSION__MAJOR),
           FIELD(version, BISS_MASTER_REGS__VERSION__MINOR), built, built == 1 ? "" : "s");

    /* The channels: init, stop periodic requests left running, configure. */
    for (i = 0; i < o.channels; i++) {
        n = o.channel[i];
        if (n >= built)
            fail(EXIT_ARGS, "--channel %u: this build has %u channel%s (0..%u)", n, built,
                 built == 1 ? "" : "s", built - 1u);
        if (win.size < window_needed(n))
            fail(EXIT_DEVICE, "%s: channel %u needs a window of 0x%zx bytes (the whole map: "
                 "0x%zx)", win.what, n, window_needed(n), (size_t)MAP_BYTES);
        err = biss_channel_init(&g_ch[i], &bus, n);
        if (err != BISS_OK)
            fail(EXIT_NOT_CORE, "ch %u: %s", n, biss_error_name(err));
        g_used = i + 1u;
        printf("ch %u: caps: word 0 up to %u bits, word 1 up to %u, timers %u bits, counters "
               "%s, timestamp %s, register access %s\n", n, (unsigned)g_ch[i].max_data_bits[0],
               (unsigned)g_ch[i].max_data_bits[1], (unsigned)g_ch[i].timer_width,
               g_ch[i].has_counters ? "yes" : "no", g_ch[i].has_timestamp ? "yes" : "no",
               g_ch[i].has_register_access ? "yes" : "no");
        biss_set_periodic(&g_ch[i], false, 0);
        setup[i].source = NULL;
        if (o.presets != 0) {
            setup[i].source = o.preset[o.presets == 1 ? 0 : i];
            biss_config_from_preset(&setup[i].cfg, setup[i].source, o.clock_hz, o.ma_hz);
        }
        if (o.identify)
            identify(i, n, &o, &setup[i]);
        configure(i, n, &setup[i], o.clock_hz);
        biss_clear_counters(&g_ch[i]);
        biss_set_trigger_enable(&g_ch[i], !o.periodic);
        clear_stale_done(&g_ch[i]);
    }
    fflush(stdout);

    /* Frames: a trigger (all channels in one clock) or the core's own periodic requests. */
    timeout_ns = (int64_t)o.timeout_ms * 1000000;
    if (o.periodic) {
        timeout_ns += (int64_t)o.period_us * 1000;
        for (i = 0; i < o.channels; i++) {
            uint64_t clocks = (uint64_t)o.period_us * o.clock_hz / 1000000u;
            err = clocks > UINT32_MAX ? BISS_ERR_TIME_RANGE
                  : biss_set_periodic(&g_ch[i], true, (uint32_t)clocks);
            if (err != BISS_OK)
                fail(EXIT_ARGS, "--periodic --period-us %lu: %" PRIu64 " clocks do not fit "
                     "the %u-bit request period (%s)", o.period_us, clocks,
                     (unsigned)g_ch[i].timer_width, biss_error_name(err));
            g_periodic_started[i] = true;
        }
    }
    next = now_ns();
    for (frame = 1; (o.count == 0 || frame <= o.count) && !g_stop; frame++) {
        if (!o.periodic)
            biss_trigger(&bus);
        for (i = 0; i < o.channels && !g_stop; i++) {
            biss_result_t r;
            n = o.channel[i];
            err = wait_frame(&g_ch[i], timeout_ns);
            if (err == BISS_ERR_TIMEOUT)
                fail(EXIT_ENCODER, "ch %u: frame %lu: no frame ended within %" PRId64 " ms "
                     "(irq_status.done never set: is the core clocked and out of reset?)", n,
                     frame, timeout_ns / 1000000);
            if (err != BISS_OK)
                break;
            biss_read_result(&g_ch[i], &r);
            print_frame(frame, n, &r, &setup[i].cfg, o.clock_hz);
            frames++;
            if (r.status != BISS_STATUS_OK)
                bad++;
        }
        fflush(stdout);
        if (g_stop)
            break;
        if (!o.periodic && (o.count == 0 || frame < o.count)) {
            next += (int64_t)o.period_us * 1000;
            sleep_until(next);
        }
    }
    undo();
    for (i = 0; i < o.channels; i++)
        print_counters(o.channel[i], &g_ch[i]);
    fflush(stdout);
    munmap(win.map, win.map_len);
    if (g_stop) {
        fprintf(stderr, PROG ": interrupted after %lu frames, %lu not OK\n", frames, bad);
        return EXIT_INTERRUPTED;
    }
    if (bad != 0) {
        fprintf(stderr, PROG ": %lu of %lu frames not OK\n", bad, frames);
        return EXIT_ENCODER;
    }
    return EXIT_OK;
}
