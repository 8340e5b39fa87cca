"""select_word on Amaranth's simulator: word k's value out of N, for plain values and views.

Cycle conventions: ``block_sim.py``. The expected values are the list itself, indexed in
Python.
"""

import random

import pytest
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import data, enum

from bissmaster.core.word_select import select_word

from testkit.block_sim import simulate


class _Code(enum.Enum, shape=2):
    A = 0
    B = 1
    C = 3


_LAYOUT = data.StructLayout({"bits": 7, "flag": 1, "code": _Code})


class _Picker(Elaboratable):
    def __init__(self, n):
        self.index = Signal(range(n + 2))       # two past the last word: reads 0
        self.plain = [Signal(5, name=f"plain{k}") for k in range(n)]
        self.views = [Signal(_LAYOUT, name=f"view{k}") for k in range(n)]
        self.codes = [Signal(_Code, name=f"code{k}") for k in range(n)]
        self.out_plain = Signal(5)
        self.out_view = Signal(_LAYOUT)
        self.out_code = Signal(_Code)

    def elaborate(self, platform):
        m = Module()
        view = select_word(self.index, self.views)
        code = select_word(self.index, self.codes)
        # The views come back as views of the same layout / enum: their members are usable.
        assert isinstance(view, data.View) and view.shape() is _LAYOUT
        m.d.comb += [self.out_plain.eq(select_word(self.index, self.plain)),
                     self.out_view.bits.eq(view.bits), self.out_view.flag.eq(view.flag),
                     self.out_view.code.eq(view.code), self.out_code.eq(code)]
        return m


@pytest.mark.parametrize("n", (1, 2, 3, 8))
def test_select_word_picks_word_index_and_zero_past_the_last(n):
    rng = random.Random(n)
    dut = _Picker(n)
    checks = []

    async def tb(ctx):
        for _ in range(40):
            plain = [rng.randrange(32) for _ in range(n)]
            views = [(rng.randrange(128), rng.randrange(2), rng.choice(list(_Code)))
                     for _ in range(n)]
            codes = [rng.choice(list(_Code)) for _ in range(n)]
            for k in range(n):
                ctx.set(dut.plain[k], plain[k])
                ctx.set(dut.views[k], {"bits": views[k][0], "flag": views[k][1],
                                       "code": views[k][2]})
                ctx.set(dut.codes[k], codes[k])
            for index in range(n + 2):
                ctx.set(dut.index, index)
                want = ((plain[index], views[index], codes[index]) if index < n
                        else (0, (0, 0, _Code.A), _Code.A))
                got = (ctx.get(dut.out_plain),
                       (ctx.get(dut.out_view.bits), ctx.get(dut.out_view.flag),
                        ctx.get(dut.out_view.code)),
                       ctx.get(dut.out_code))
                checks.append((got, want))
                await ctx.tick()

    simulate(dut, tb)
    assert len(checks) == 40 * (n + 2)
    assert all(got == want for got, want in checks), next(c for c in checks if c[0] != c[1])


def test_select_word_needs_a_value():
    with pytest.raises(ValueError):
        select_word(Signal(2), [])
