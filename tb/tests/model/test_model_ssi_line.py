"""The cocotb SSI encoder's logic (encoder_model.cocotb_ssi.SsiLineLogic) against the pure SSI
model (encoder_model.ssi.SsiEncoder): the same clock trains give the same levels, latches,
positions and monoflop ends. Pure Python: the logic runs on integer times (1 ps steps) as it
does in the simulator; the trains are SsiEncoder's (50 % duty, whole nanoseconds)."""

import random

import pytest

from encoder_model.cocotb_ssi import SsiFaults, SsiLineLogic
from encoder_model.frames import CRC6
from encoder_model.ssi import SsiEncoder, SsiFormat, line_levels, ssi_bits

PS = 1e-12
US = 1e-6


def ps(t_s):
    return round(t_s / PS)


def drive(logic, train):
    """One train's edges into the logic, with the monoflop's end handled in time order.
    Returns (level between the first fall and the first rise, level after each rise)."""
    def upto(t):
        if logic.high_at is not None and logic.high_at < t:
            logic.expire(logic.high_at)

    upto(ps(train.t_first_fall_s))
    levels, before = [], None
    for k in range(1, train.n_clocks + 1):
        t_rise = train.rising_edge_s(k)
        t_fall = t_rise - train.period_s / 2
        upto(ps(t_fall))
        logic.fall(ps(t_fall))
        if k == 1:
            before = logic.level
        upto(ps(t_rise))
        logic.rise(ps(t_rise))
        levels.append(logic.level)
    return before, levels


def random_position(rng, bits):
    return lambda t: rng.getrandbits(bits)


FORMATS = [
    SsiFormat(13, gray=True),
    SsiFormat(25, error_bits=1, error_polarity=("low",)),
    SsiFormat(25, repeat="ring"),
    SsiFormat(9, nenw=True, crc=CRC6, repeat="ring", retrigger="any"),
    SsiFormat(6, error_bits=2, gray=True, gray_errors=True, retrigger="any", tm_s=5 * US),
]


@pytest.mark.parametrize("fmt", FORMATS, ids=lambda f: f"{f.data_bits}-{f.repeat}-{f.retrigger}")
def test_logic_follows_the_pure_model_over_random_trains(fmt):
    rng = random.Random(fmt.total_bits)
    values = random.Random(1)
    flags = lambda t: tuple(values.random() < 0.5 for _ in range(fmt.error_bits))
    nenw = (lambda t: (values.getrandbits(1), values.getrandbits(1))) if fmt.nenw else None
    # Both sides draw from their own copy of the same random streams, in latch order.
    model_pos, logic_pos = random.Random(2), random.Random(2)
    model = SsiEncoder(fmt, random_position(model_pos, fmt.data_bits), errors_at=flags,
                       nenw_at=nenw)
    values_logic = random.Random(1)
    logic = SsiLineLogic(
        fmt, random_position(logic_pos, fmt.data_bits),
        errors_at=lambda t: tuple(values_logic.random() < 0.5 for _ in range(fmt.error_bits)),
        nenw_at=(lambda t: (values_logic.getrandbits(1), values_logic.getrandbits(1)))
        if fmt.nenw else None, step_s=PS)
    t, latches, saw_repeat = 1 * US, 0, False
    for _ in range(40):
        period_ns = rng.choice((100, 200, 1000, 2000))
        n = rng.choice((fmt.clocks, fmt.clocks, 2 * fmt.clocks, rng.randint(1, 3 * fmt.clocks)))
        tr = model.train(t, n_clocks=n, period_s=period_ns * 1e-9)
        before, levels = drive(logic, tr)
        latches += tr.new_latch
        saw_repeat |= not tr.new_latch
        assert len(logic.records) == latches
        rec = logic.records[-1]
        assert (rec.position, rec.errors, rec.nenw, rec.word) == \
            (tr.position, tr.errors, tr.nenw, tr.word)
        assert ps(rec.t_latch_s) == ps(tr.t_latch_s)
        assert before == tr.level_before
        assert levels == tr.levels
        assert ps(logic.high_at * PS) == ps(tr.line_high_s)
        # next train: within tm (a repeat), or after it, never within 1 ns of the boundary
        gap = rng.choice((0.3, 0.7, 1.3, 2.5)) * fmt.tm_s
        t = round((tr.t_last_rise_s + gap) * 1e9) * 1e-9
    assert saw_repeat and latches > 5
    # the last transmission ends when the monoflop runs out: the line goes high
    end = logic.high_at
    assert logic.expire(end - 1) is None
    logic.expire(end)
    assert logic.level == 1 and logic.records[-1].ended
    assert ps(logic.records[-1].t_line_high_s) == end


def test_record_counts_edges_and_ends_at_tm():
    fmt = SsiFormat(13, gray=True)
    logic = SsiLineLogic(fmt, lambda t: 5000, step_s=PS)
    tr = SsiEncoder(fmt, lambda t: 5000).train(0.0, period_s=1 * US)
    drive(logic, tr)
    rec = logic.records[0]
    assert (rec.ma_falls, rec.ma_rises) == (14, 14) and rec.levels == line_levels(fmt, 5000)
    assert not rec.ended
    assert logic.expire(ps(33 * US)) == 1
    assert rec.ended and rec.t_line_high_s == pytest.approx(33 * US)
    # a fall exactly when the line goes high latches anew (ssi.py, model choice 5)
    logic2 = SsiLineLogic(fmt, lambda t: round(t / US), step_s=PS)
    drive(logic2, tr)
    logic2.fall(ps(33 * US))
    assert len(logic2.records) == 2 and logic2.records[0].ended
    assert logic2.records[1].position == 33


def test_faults_flip_the_second_copy_or_force_the_separator():
    fmt = SsiFormat(8, repeat="ring")
    word = ssi_bits(fmt, 0xA5)
    tr = SsiEncoder(fmt, lambda t: 0xA5).train(0.0, n_clocks=2 * fmt.clocks, period_s=1 * US)
    for faults, want in (
            (SsiFaults(), word + [0] + word + [0]),
            (SsiFaults(flip_copy2=(3,)), word + [0] + word[:3] + [1 - word[3]] + word[4:] + [0]),
            (SsiFaults(separator=1), word + [1] + word + [0]),
            (SsiFaults(flip=(7,)), 2 * (word[:7] + [1 - word[7]] + [0])),
            (SsiFaults(force=((17, 1), (0, 1 - word[0]))),
             [1 - word[0]] + word[1:] + [0] + word + [1])):
        logic = SsiLineLogic(fmt, lambda t: 0xA5, step_s=PS)
        logic.plan.append(faults)
        assert drive(logic, tr)[1] == want
        assert logic.records[0].word == word       # the record keeps the model's word


def test_same_value_is_refused():
    with pytest.raises(ValueError):
        SsiLineLogic(SsiFormat(8, repeat="same_value"), lambda t: 0)
