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


def test_external_time_base_captures_its_input():
    """``external``: the capture is the input ``now`` of the strobe's clock (a time base shared
    by several cores), held until the next strobe; no counter of its own."""
    rng = random.Random(7711)
    n = 300
    strobes = [int(rng.random() < 0.1) for _ in range(n)]
    times = [rng.getrandbits(16) for _ in range(n)]
    trace = run_clocks(TimeBase(16, external=True),
                       [{"first_rise": s, "now": t} for s, t in zip(strobes, times)],
                       ["first_rise_time"])
    got = [x["first_rise_time"] for x in trace]
    last = 0
    for t in range(1, n):
        if strobes[t - 1]:
            last = times[t - 1]
        assert got[t] == last, t
    assert sum(strobes) > 15
