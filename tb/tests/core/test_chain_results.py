"""ChainResults on Amaranth's simulator: the data of a chain's words 2..7 in a memory of two
pages, against a reference of its documented contract (the class docstring; docs/ports.md,
Chains), written here:

- a chain word's data, present on ``data`` from the clock after its ``word_end`` until the
  next word's first bit (4 clocks at least), is what a read of that word returns once the
  frame is published;
- ``publish`` makes the frame's words readable from the next clock on (the clock the result
  registers change in); words the published frame did not have read 0, and so does every
  word before the first publication, also after a reset;
- a frame that is never published (a fault) is never seen: reads keep the last published
  frame's words while the next frame's are written;
- a read takes its address with ``read_en``; from the next clock ``read_data`` is that word
  as it is in each clock (so a frame published meanwhile shows from the clock after its
  ``publish``), bits 31..0 at address 2 (W - 2), bits 63..32 at 2 (W - 2) + 1.

Random frames of random word counts, a random sprinkling of unpublished frames, reads of
every address between and across publications, for a 4-word build (words of up to 64 and 16
bits) and an 8-word one (64-bit words).
"""

import random

import pytest

from bissmaster.core.chain_results import ChainResults
from testkit.block_sim import simulate_with_reset

#: Words of the register map's read address: words 2..7, two 32-bit halves each.
ADDRESSES = 12
FIRST = 2           # the first chain word


def expected(frame, address):
    """What address ``address`` reads for the published ``frame`` (``{word: data}``, the
    words it had), or 0."""
    word, half = FIRST + address // 2, address % 2
    return (frame.get(word, 0) >> (32 * half)) & 0xFFFF_FFFF


def run(words, data_bits, frames, seed, reset_at=None):
    """Send ``frames`` (each ``(published, {word: data})``, its words 2.. in order), reading
    between every step; ``reset_at``: frame index before which the design is reset. Returns the
    number of checked reads."""
    dut = ChainResults(words, data_bits)
    rng = random.Random(seed)
    checked = [0]

    async def bench(ctx, rst):
        shown = {}                          # the published frame as a reader must see it

        async def tick(new_shown=None):
            """One clock with a read issued in it (a random address); in the next clock the
            read's word must be that of the frame shown then (``new_shown``: published in
            this clock)."""
            nonlocal shown
            address = rng.randrange(ADDRESSES)
            ctx.set(dut.read_en, 1)
            ctx.set(dut.read_addr, address)
            await ctx.tick()
            ctx.set(dut.read_en, 0)
            if new_shown is not None:
                shown = new_shown
            got = ctx.get(dut.read_data)
            assert got == expected(shown, address), \
                f"address {address}: {got:#x}, expected {expected(shown, address):#x}"
            checked[0] += 1

        for n, (publish, frame) in enumerate(frames):
            if n == reset_at:
                ctx.set(rst, 1)
                await ctx.tick()
                ctx.set(rst, 0)
                shown = {}
            for k, (word, value) in enumerate(sorted(frame.items())):
                # The word's last bit: word_end; its data from the next clock for 4 clocks,
                # garbage before and after (the next word shifting in).
                ctx.set(dut.data, rng.getrandbits(data_bits))
                ctx.set(dut.index, word - FIRST)
                ctx.set(dut.word_end, 1)
                await tick()
                ctx.set(dut.word_end, 0)
                ctx.set(dut.index, rng.randrange(words - FIRST))
                ctx.set(dut.data, value)
                for _ in range(4):
                    await tick()
                ctx.set(dut.data, rng.getrandbits(data_bits))
            # The frame ends: published (or not) two clocks after its last word's end.
            await tick()
            if publish:
                ctx.set(dut.words_published, FIRST + len(frame))
                ctx.set(dut.publish, 1)
                await tick(new_shown=dict(frame))       # shown from the clock after publish
                ctx.set(dut.publish, 0)
                ctx.set(dut.words_published, rng.randrange(words + 1))
            for _ in range(rng.randrange(1, 6)):
                await tick()
        # Every address once more, and a word held: the address stays what read_en took.
        for address in range(ADDRESSES):
            ctx.set(dut.read_en, 1)
            ctx.set(dut.read_addr, address)
            await ctx.tick()
            ctx.set(dut.read_en, 0)
            ctx.set(dut.read_addr, (address + 5) % ADDRESSES)
            for _ in range(2):
                assert ctx.get(dut.read_data) == expected(shown, address), address
                checked[0] += 1
                await ctx.tick()

    simulate_with_reset(dut, bench)
    return checked[0]


def random_frames(words, data_bits, count, seed):
    rng = random.Random(seed)
    longest = {w: (data_bits if w == FIRST else min(data_bits, 16)) for w in range(FIRST, words)}
    frames = []
    for _ in range(count):
        n = rng.randrange(0, words - FIRST + 1)         # the frame's chain words
        frame = {w: rng.getrandbits(longest[w]) for w in range(FIRST, FIRST + n)}
        frames.append((rng.random() < 0.8, frame))
    return frames


@pytest.mark.parametrize("words, data_bits", [(4, 64), (8, 64), (3, 32), (5, 20)])
def test_published_frames_read_back_and_others_never(words, data_bits):
    frames = random_frames(words, data_bits, 40, seed=words * 100 + data_bits)
    assert any(not p for p, _ in frames) and any(len(f) == words - FIRST for _, f in frames)
    assert run(words, data_bits, frames, seed=7) > 200


def test_nothing_before_the_first_publication_and_after_a_reset():
    """Reads are 0 before any frame is published, also for frames written but not published,
    and again after a reset (the memory keeps its contents; the reads must not show them)."""
    frames = [(False, {2: 0xDEAD_BEEF_0123_4567, 3: 0x1234}),
              (True, {2: 0x1111_2222_3333_4444, 3: 0x5678}),
              (True, {2: 0x5555_6666_7777_8888}),
              (False, {2: 0x9999_AAAA_BBBB_CCCC, 3: 0x9ABC})]
    assert run(4, 64, frames, seed=1, reset_at=2) > 50


def test_the_page_read_is_never_the_page_written():
    """A frame written while the previous one is read: every read between its first word
    and its publication returns the previous frame, word for word (one 64-bit word 2 written
    in two halves while both halves are read)."""
    frames = [(True, {2: 2**64 - 1, 3: 0xFFFF}), (True, {2: 0, 3: 0}),
              (True, {2: 0x8000_0000_0000_0001}), (False, {2: 0x7FFF_FFFF_FFFF_FFFE, 3: 1})]
    assert run(4, 64, frames * 5, seed=3) > 200


@pytest.mark.filterwarnings("ignore::amaranth.hdl.UnusedElaboratable")
@pytest.mark.parametrize("words, data_bits", [(2, 32), (9, 32), (4, 0), (4, 65)])
def test_a_build_it_cannot_be_is_refused(words, data_bits):
    with pytest.raises(ValueError):
        ChainResults(words, data_bits)
