"""TimeBase on Amaranth's simulator: a free-running clock count, captured at the first MA rise.

Cycle conventions and where expected values come from: ``block_sim.py``. The contract (the
block's docstring, docs/ports.md ``timestamp``): the capture is new the clock after the
``first_rise`` strobe and held until the next one; two captures differ by the clocks between
their strobes, modulo 2**width (the counter wraps and never stops).
"""

import random

import pytest

from bissmaster.core.time_base import TimeBase

from testkit.block_sim import run_clocks


@pytest.mark.parametrize("width", (4, 16, 32))
def test_time_base_captures_differ_by_the_clocks_between_strobes(width):
    rng = random.Random(7700 + width)
    n = 600
    strobes = [0] * 3 + [int(rng.random() < 0.08) for _ in range(n - 5)] + [0, 0]
    strobes[3] = strobes[4] = 1                       # back to back: one clock apart
    trace = run_clocks(TimeBase(width), [{"first_rise": s} for s in strobes],
                       ["first_rise_time"])
    got = [x["first_rise_time"] for x in trace]
    at = [t for t, s in enumerate(strobes) if s]
    for a, b in zip(at, at[1:]):
        assert (got[b + 1] - got[a + 1]) % 2**width == (b - a) % 2**width, (a, b)
    # Held between strobes: changes only the clock after a strobe.
    for t in range(1, n):
        if not strobes[t - 1]:
            assert got[t] == got[t - 1], t
    assert len(at) > 20


def test_time_base_wraps():
    width = 4
    strobes = [int(t % 7 == 2) for t in range(60)]
    trace = run_clocks(TimeBase(width), [{"first_rise": s} for s in strobes],
                       ["first_rise_time"])
    captures = [trace[t + 1]["first_rise_time"] for t, s in enumerate(strobes[:-1]) if s]
    assert [(b - a) % 16 for a, b in zip(captures, captures[1:])] == [7] * (len(captures) - 1)
    assert any(b < a for a, b in zip(captures, captures[1:]))          # it did wrap
