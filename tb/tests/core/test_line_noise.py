"""LineNoise on Amaranth's simulator: noise events counted from frame to frame, the judgement.

The contract (docs/ports.md, "Noise: the line checks"; the block's docstring): an event is the
sampler's ``noise`` strobe or a fall of SLO while the master waits, counted one clock after it; events are counted from the
end of the cycle before (a frame's end, ``close``, or a fault, ``restart``: the count starts
again, the event of that clock dropped) to this frame's end, saturating at 15; at a frame's end (``close``) the frame is noisy when
its count (events counted up to the clock before) is above the limit (read in that clock), and ``noisy`` / ``events`` hold
that judgement from ``close`` to the next ``close``. Cycle conventions: ``block_sim.py``.
"""

import random

import pytest

from bissmaster.core.line_noise import LineNoise

from testkit.block_sim import run_clocks

TOP = 15            # the counts saturate at 15 (4 bits, docs/ports.md)


class Reference:
    """The contract, clock by clock."""

    def __init__(self):
        self.level_before = 1
        self.running = 0
        self.held = (0, 0)          # (noisy, events) of the last closed frame
        self.event = 0              # the event of the clock before (registered)

    def step(self, watch, level, sampler_noise, close, restart, limit):
        event = self.event          # counted one clock after its input
        self.event = int(bool(sampler_noise or (watch and self.level_before and not level)))
        if close:
            noisy, events = int(self.running > limit), self.running
            self.held = (noisy, events)
            self.running = event
        elif restart:
            noisy, events = self.held
            self.running = 0
        else:
            noisy, events = self.held
            self.running = min(TOP, self.running + event)
        self.level_before = level
        return {"event": event, "noisy": noisy, "events": events}


INPUTS = ("watch", "level", "sampler_noise", "close", "restart", "limit")


def _run(steps):
    trace = run_clocks(LineNoise(), steps, ["event", "noisy", "events"])
    ref = Reference()
    for t, (step, row) in enumerate(zip(steps, trace)):
        want = ref.step(*(step[name] for name in INPUTS))
        assert {k: row[k] for k in want} == want, (t, step)
    return trace


def test_line_noise_random_sequences_against_the_contract():
    rng = random.Random(2820)
    steps = []
    limit = 0
    level = 1
    for t in range(20000):
        if rng.random() < 0.01:
            limit = rng.choice((0, 0, 1, 2, 5, 14, 15))
        if rng.random() < 0.2:
            level = 1 - level
        steps.append({"watch": int(rng.random() < 0.5), "level": level,
                      "sampler_noise": int(rng.random() < 0.08),
                      "close": int(rng.random() < 0.02), "restart": int(rng.random() < 0.01),
                      "limit": limit})
    trace = _run(steps)
    # Not vacuous: frames judged noisy and clean, saturated counts, both kinds of event.
    closes = [row for step, row in zip(steps, trace) if step["close"]]
    assert any(r["noisy"] for r in closes) and any(not r["noisy"] for r in closes)
    assert any(r["events"] == TOP for r in closes)


@pytest.mark.parametrize("limit", (0, 1, 3, 15))
def test_line_noise_limit_is_the_largest_clean_count(limit):
    """k events then a close: noisy exactly when k > limit; limit 15 never (the count
    saturates at 15)."""
    for k in range(0, 18):
        steps = [{"watch": 0, "level": 1, "sampler_noise": 0, "close": 1, "restart": 0, "limit": limit}]
        steps += [{"watch": 0, "level": 1, "sampler_noise": 1, "close": 0, "restart": 0, "limit": limit}] * k
        # One clock between the last event and the close, as in the master (the decoder's
        # ``done`` comes two clocks after the last decision): the event is counted a clock late.
        steps += [{"watch": 0, "level": 1, "sampler_noise": 0, "close": 0, "restart": 0, "limit": limit}]
        steps += [{"watch": 0, "level": 1, "sampler_noise": 0, "close": 1, "restart": 0, "limit": limit}]
        trace = _run(steps)
        assert trace[-1]["noisy"] == int(min(k, TOP) > limit), k
        assert trace[-1]["events"] == min(k, TOP)


def test_line_noise_only_falls_while_waiting_count():
    """A fall of SLO counts while ``watch`` is high, a rise never, a fall while not watching
    never (frames change SLO all the time)."""
    base = {"sampler_noise": 0, "close": 0, "restart": 0, "limit": 0}
    steps = [{**base, "watch": w, "level": lv}
             for w, lv in ((1, 1), (1, 0), (1, 1), (0, 0), (0, 1), (1, 1), (1, 0), (1, 0))]
    trace = _run(steps)
    assert [r["event"] for r in trace] == [0, 0, 1, 0, 0, 0, 0, 1]        # a clock later
