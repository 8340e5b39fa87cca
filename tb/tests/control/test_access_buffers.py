"""The register-access buffers (docs/control.md, "The buffers"; docs/ports.md, "Clock and reset"):
the read buffer holds the bytes a read stored, byte ``i`` in lane ``i % 4`` of word ``i // 4``,
and is cleared after every reset (a memory keeps its contents through a reset, and the
generated Verilog gives it no initial value), so a host never reads an undefined word."""

from bissmaster.control.access_buffers import AccessBuffers
from testkit.block_sim import simulate_with_reset

WORDS = 16            # 64 bytes (docs/control.md)
CLEAR_CLOCKS = WORDS  # a word per clock after reset; a read issued after them reads 0


def run(steps):
    """Each step: ``{"rst": 0/1, "store": (byte index, value) or None, "read": word or None}``.
    Returns, per step, the word the previous step's read returned (``rbuf_data`` in the clock
    after the read), or None."""
    dut = AccessBuffers()
    got = []

    async def tb(ctx, rst):
        pending = False
        for step in steps:
            ctx.set(rst, step.get("rst", 0))
            store = step.get("store")
            ctx.set(dut.store, store is not None)
            if store is not None:
                ctx.set(dut.index, store[0])
                ctx.set(dut.byte_received, store[1])
            read = step.get("read")
            ctx.set(dut.rbuf_en, read is not None)
            ctx.set(dut.rbuf_addr, read or 0)
            got.append(ctx.get(dut.rbuf_data) if pending else None)
            pending = read is not None
            await ctx.tick()

    simulate_with_reset(dut, tb)
    return got


def fill():
    """Steps storing byte i = 0xA0 ^ i for all 64 bytes, after the clear of the start."""
    return [{} for _ in range(CLEAR_CLOCKS)] + \
        [{"store": (i, 0xA0 ^ i)} for i in range(4 * WORDS)]


def word_of(i):
    return sum((0xA0 ^ (4 * i + k)) << 8 * k for k in range(4))


def test_stored_bytes_read_back_little_endian():
    steps = fill() + [{"read": w} for w in range(WORDS)] + [{}]
    got = [g for g in run(steps)[len(fill()) + 1:] if g is not None]
    assert got == [word_of(w) for w in range(WORDS)]


def test_a_reset_clears_every_word():
    """Full of bytes, then a one-clock reset: every word reads 0 once the clear is done, and a
    byte stored after it reads back with the rest of its word 0."""
    steps = fill() + [{"rst": 1}] + [{} for _ in range(CLEAR_CLOCKS)]
    steps += [{"read": w} for w in range(WORDS)] + [{}]
    steps += [{"store": (5, 0x3C)}, {"read": 1}, {}]
    got = run(steps)
    reads = [g for g in got[len(fill()) + 1 + CLEAR_CLOCKS:] if g is not None]
    assert reads[:WORDS] == [0] * WORDS
    assert reads[WORDS] == 0x3C << 8


def test_the_clear_goes_a_word_per_clock():
    """Word w is cleared in the w-th clock after the reset: a read of the last word issued in
    the clock its clear is written still sees its old bytes, one clock later 0."""
    base = fill() + [{"rst": 1}]
    last = WORDS - 1
    early = run(base + [{} for _ in range(last)] + [{"read": last}, {}])
    late = run(base + [{} for _ in range(last + 1)] + [{"read": last}, {}])
    assert early[-1] == word_of(last)
    assert late[-1] == 0
