"""SignOfLife on Amaranth's simulator: the LC rule (1..63, then 1; 0 never valid).

The master builds ``SignOfLife(early=True)``: the frame decoder shifts the LC in bit by bit
(``lc_next`` with ``load``), the block compares every loaded value and registers the result,
and the master strobes ``check`` some clocks after the LC's last bit. Every scenario runs in
that mode, driven as the master drives it, and in the default ``early=False`` mode (``lc`` and
``check`` in one clock, combinational verdict), which the class still offers.

Cycle conventions and where expected values come from: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.sign_of_life import SignOfLife
from encoder_model.frames import SignOfLife as ModelSignOfLife

from testkit.block_sim import simulate

#: The LC field is 6 bits, sent MSB first (docs/protocol.md, 5.2).
LC_BITS = 6
LC_MASK = (1 << LC_BITS) - 1

#: Both modes of the block: ``early=True`` is the one in the master.
MODES = pytest.mark.parametrize("early", (True, False), ids=("early", "comb"))


class RefSignOfLife:
    """The LC rule of docs/protocol.md (5.2), independently: 1..63 then 1; 0 never valid."""

    def __init__(self):
        self.last = None        # None = not synced

    def judge(self, lc):
        """(repeat, skip, zero) for lc."""
        if lc == 0:
            return (0, 0, 1)
        if self.last is None:
            return (0, 0, 0)
        expected = 1 if self.last == 63 else self.last + 1
        return (int(lc == self.last), int(lc not in (self.last, expected)), 0)

    def check(self, lc):
        verdict = self.judge(lc)
        if lc != 0:
            self.last = lc
        return verdict


def _sol_sim(ops, *, early, seed=0, gaps=True):
    """ops: ("check", lc) | ("peek", lc) (verdict without check) | ("resync",).
    Returns [(repeat, skip, zero, synced_before)] for check/peek ops, read in the clock of the
    (possible) check.

    ``early=True`` drives the block as the master does. The LC register (``lc``; the decoder's,
    cleared between cycles) takes the LC MSB first, one bit per clock with ``load``, the bits
    0..1 clocks apart; ``lc_next`` is that register shifted left with the new bit, and junk in
    the clocks without ``load``. ``check`` (or the peek) comes 0..2 clocks after the clock that
    follows the last bit; the verdict must already be there in that first clock, and must not
    change until the check. ``gaps=False``: no clocks between the bits, the check right after
    (the fastest the block can be used). ``early=False``: ``lc`` and ``check`` in one clock.
    """
    rng = random.Random(seed)
    dut = SignOfLife(early=early)
    out = []

    async def tb(ctx):
        def quiet():
            ctx.set(dut.check, 0)
            ctx.set(dut.resync, 0)
            if early:
                ctx.set(dut.load, 0)
                ctx.set(dut.lc_next, rng.randrange(1 << LC_BITS))

        def verdict():
            return (ctx.get(dut.repeat), ctx.get(dut.skip), ctx.get(dut.zero),
                    ctx.get(dut.synced))

        for op in ops:
            quiet()
            if op[0] == "resync":
                ctx.set(dut.resync, 1)
                await ctx.tick()
                continue
            kind, lc = op
            if early:
                reg = 0
                ctx.set(dut.lc, reg)
                for i in reversed(range(LC_BITS)):
                    for _ in range(rng.randrange(2) if gaps else 0):
                        await ctx.tick()
                        quiet()
                    reg = ((reg << 1) | (lc >> i) & 1) & LC_MASK
                    ctx.set(dut.lc_next, reg)
                    ctx.set(dut.load, 1)
                    await ctx.tick()
                    ctx.set(dut.lc, reg)
                    quiet()
                first = verdict()           # the clock after the last bit
                for _ in range(rng.randrange(3) if gaps else 0):
                    await ctx.tick()
                    quiet()
                    assert verdict() == first, f"verdict for LC {lc} changed before the check"
            ctx.set(dut.lc, lc)
            ctx.set(dut.check, int(kind == "check"))
            out.append(verdict())
            await ctx.tick()

    simulate(dut, tb)
    return out


def _sol_expected(ops):
    ref = RefSignOfLife()
    out = []
    for op in ops:
        if op[0] == "resync":
            ref.last = None
        else:
            synced = int(ref.last is not None)
            verdict = ref.check(op[1]) if op[0] == "check" else ref.judge(op[1])
            out.append(verdict + (synced,))
    return out



@MODES
def test_sign_of_life_normal_sequence_wraps_63_to_1(early):
    model = ModelSignOfLife()
    values = [model.next() for _ in range(63 * 2 + 5)]
    assert values[62:65] == [63, 1, 2]
    got = _sol_sim([("check", v) for v in values], early=early)
    assert got[0] == (0, 0, 0, 0)                      # first frame after reset: accepted
    assert got[1:] == [(0, 0, 0, 1)] * (len(values) - 1)


@MODES
def test_sign_of_life_repeat_skip_zero_by_hand(early):
    ops = [("check", 5), ("check", 5), ("check", 6), ("check", 8), ("check", 0), ("check", 10),
           ("check", 0), ("check", 11), ("check", 63), ("check", 63), ("check", 1),
           ("check", 62), ("check", 1)]
    # 5 first: ok | 5 repeat | 6 ok | 8 skip | 0 zero | 10 vs 8: skip | 0 zero | 11 vs 10: ok |
    # 63 skip | 63 repeat | 1 ok (wrap) | 62 skip | 1 skip (62 -> 63 expected)
    assert _sol_sim(ops, early=early) == [
        (0, 0, 0, 0), (1, 0, 0, 1), (0, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1), (0, 1, 0, 1),
        (0, 0, 1, 1), (0, 0, 0, 1), (0, 1, 0, 1), (1, 0, 0, 1), (0, 0, 0, 1), (0, 1, 0, 1),
        (0, 1, 0, 1)]


@MODES
def test_sign_of_life_frame_after_zero_judged_against_last_good(early):
    ops = [("check", 20), ("check", 0), ("check", 21), ("check", 0), ("check", 0),
           ("check", 21), ("check", 0), ("check", 23)]
    # 21 after (20, 0): ok. 21 after (21, 0, 0): repeat. 23 after (21, 0): skip.
    assert _sol_sim(ops, early=early) == [(0, 0, 0, 0), (0, 0, 1, 1), (0, 0, 0, 1), (0, 0, 1, 1),
                             (0, 0, 1, 1), (1, 0, 0, 1), (0, 0, 1, 1), (0, 1, 0, 1)]


@MODES
def test_sign_of_life_every_value_after_every_value(early):
    # From each stored value 1..63, every LC 0..63 peeked (verdict, no store). (Back to back:
    # the other tests cover the spacing, this one the values.)
    ops = []
    for last in range(1, 64):
        ops.append(("check", last))
        ops += [("peek", lc) for lc in range(64)]
    got = _sol_sim(ops, early=early, gaps=False)
    assert got == _sol_expected(ops)
    # Spot checks that the reference itself agrees with the protocol text.
    per = 65
    assert got[per * 62 + 1 + 1] == (0, 0, 0, 1)       # stored 63, peek 1: the wrap is fine
    assert got[per * 62 + 1 + 63] == (1, 0, 0, 1)      # stored 63, peek 63: repeat
    assert got[per * 62 + 1 + 0] == (0, 0, 1, 1)       # zero
    assert sum(v[1] for v in got[1:per]) == 61         # stored 1: 61 values skip (not 0, 1, 2)


@MODES
def test_sign_of_life_skips_of_1_to_62_values(early):
    # The encoder model loses n values, then sends the next one. Losing 62 of a 63-value cycle
    # brings back the same value: that is a repeat, not a skip.
    for start in (1, 40, 63):
        ops = []
        for n in range(1, 63):
            model = ModelSignOfLife(start)
            ops += [("resync",), ("check", model.next()), ("check", model.skip(n))]
        got = _sol_sim(ops, early=early)
        assert got == _sol_expected(ops)
        assert [v[:3] for v in got[1::2]] == [(0, 1, 0)] * 61 + [(1, 0, 0)], start


@MODES
def test_sign_of_life_resync_accepts_next_value_and_first_after_reset(early):
    ops = [("check", 0), ("check", 17), ("check", 18), ("resync",), ("check", 40), ("check", 41),
           ("resync",), ("check", 0), ("check", 41), ("peek", 9), ("check", 42)]
    got = _sol_sim(ops, early=early)
    assert got == [
        (0, 0, 1, 0),       # zero first after reset: flagged, not stored, still unsynced
        (0, 0, 0, 0),       # 17 first value: accepted
        (0, 0, 0, 1),
        (0, 0, 0, 0),       # 40 after resync: accepted
        (0, 0, 0, 1),
        (0, 0, 1, 0),       # zero after resync: flagged, does not sync
        (0, 0, 0, 0),       # 41 (equal to the old stored value) accepted: no repeat after resync
        (0, 1, 0, 1),       # peek 9: would be a skip, but is not stored
        (0, 0, 0, 1),       # 42 follows 41
    ]
    assert got == _sol_expected(ops)


@MODES
def test_sign_of_life_random_sequences_against_reference(early):
    rng = random.Random(4000)
    model = ModelSignOfLife()
    ops = []
    sent = False                        # model.repeat() needs a value sent before
    for _ in range(600):
        r = rng.random()
        if r < 0.6 or (r < 0.7 and not sent):
            ops.append(("check", model.next()))
            sent = True
        elif r < 0.7:
            ops.append(("check", model.repeat()))
        elif r < 0.8:
            ops.append(("check", model.skip(rng.randint(1, 62))))
            sent = True
        elif r < 0.87:
            ops.append(("check", model.zero()))
        elif r < 0.93:
            ops.append(("peek", rng.randrange(64)))
        else:
            ops.append(("resync",))
    got = _sol_sim(ops, early=early)
    assert got == _sol_expected(ops)
    assert sum(v[0] for v in got) > 10 and sum(v[1] for v in got) > 10
    assert sum(v[2] for v in got) > 10




def test_sign_of_life_early_compares_each_loaded_value_one_clock_later():
    # Stored 10 (expected next 11). 11 = 0b001011 shifted in MSB first passes through the partial
    # values 0, 0, 1, 2, 5, 11: each is compared when loaded, and its verdict shows from the next
    # clock on. So in the clock of the last bit the flags still judge 5 (a skip), and from the
    # clock after it they judge 11 (in order); clocks without ``load`` change nothing.
    dut = SignOfLife(early=True)
    got = []

    async def tb(ctx):
        def flags():
            return (ctx.get(dut.repeat), ctx.get(dut.skip), ctx.get(dut.zero))

        ctx.set(dut.lc, 10)
        ctx.set(dut.lc_next, 10)
        ctx.set(dut.load, 1)
        await ctx.tick()
        ctx.set(dut.load, 0)
        ctx.set(dut.check, 1)                   # stores 10 (first value: accepted)
        await ctx.tick()
        ctx.set(dut.check, 0)
        reg = 0
        for i in reversed(range(LC_BITS)):
            reg = (reg << 1) | (11 >> i) & 1
            ctx.set(dut.lc_next, reg)
            ctx.set(dut.load, 1)
            got.append(flags())                 # the clock in which this bit is loaded
            await ctx.tick()
            ctx.set(dut.lc, reg)
        ctx.set(dut.load, 0)
        for junk in (0, 10, 63, 12):            # lc_next changes, no load
            ctx.set(dut.lc_next, junk)
            got.append(flags())
            await ctx.tick()

    simulate(dut, tb)
    zero, skip, ok = (0, 0, 1), (0, 1, 0), (0, 0, 0)
    # First: the clock after the check. The store is registered, so 10 is stored only at the
    # end of this clock: not synced yet, nothing flagged (the flags are stale here anyway, as
    # documented: the master checks once per frame, after the LC).
    assert got == [ok, zero, zero, skip, skip, skip] + [ok] * 4


@pytest.mark.parametrize("same_clock", (True, False), ids=("resync_with_check", "resync_after"))
def test_sign_of_life_early_resync_around_the_registered_store(same_clock):
    # A resync in the clock of a check, or in the clock after it, leaves the block unsynced:
    # the next LC, even the same value again, is accepted as it is (no repeat).
    dut = SignOfLife(early=True)
    got = []

    async def tb(ctx):
        async def shift_in(lc):
            reg = 0
            for i in reversed(range(LC_BITS)):
                reg = (reg << 1) | (lc >> i) & 1
                ctx.set(dut.lc_next, reg)
                ctx.set(dut.load, 1)
                await ctx.tick()
            ctx.set(dut.load, 0)
            ctx.set(dut.lc, lc)

        for lc in (20, 21):                     # synced on 21
            await shift_in(lc)
            ctx.set(dut.check, 1)
            await ctx.tick()
            ctx.set(dut.check, 0)
        await shift_in(22)
        ctx.set(dut.check, 1)
        ctx.set(dut.resync, int(same_clock))
        await ctx.tick()
        ctx.set(dut.check, 0)
        ctx.set(dut.resync, int(not same_clock))
        await ctx.tick()
        ctx.set(dut.resync, 0)
        got.append(ctx.get(dut.synced))
        await shift_in(22)
        got.append((ctx.get(dut.repeat), ctx.get(dut.skip), ctx.get(dut.zero)))

    simulate(dut, tb)
    assert got == [0, (0, 0, 0)]
