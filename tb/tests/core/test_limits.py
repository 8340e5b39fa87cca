"""Issue 11, "limits to the clock": every limit of ``biss_master`` probed at its boundary.

Each test drives the stimulus (or, for NO_START, the setting) to the documented limit - 1, the
limit and the limit + 1, and checks both sides against docs/ports.md and docs/timing.md
("Limits to the clock"): status, the clock of ``done``, the counter, MA activity, and when the
controller is ready again. The test ids name the probe and the outcome expected there.

Clock references (all seen on the ports, see limits_bench.py for the cycle convention):
  s   the 2nd MA rise: the first clock with MA high after the 2nd rising edge;
  m   MA stopped: the last rise + hp, the clock in which MA would have fallen again;
  ld  ``line_delay``; slot k is centred in clock s + ld + 1 + hp + 2*hp*k and decided v clocks
      later, v = hp // 2 the vote spacing (0 at hp = 2; ports.md, "Noise immunity").

Status codes and counter names come from tb/master_contract.py, protocol times from docs/protocol.md
(40 us at the bench's 1 MHz clock), frames from tb/encoder_model: nothing from rtl/.
"""

from dataclasses import replace

import pytest

from encoder_model.frames import (CRC6, FrameFaults, FrameFormat, WordFormat, WordValue,
                                  build_frame)
from testkit.limits_bench import (FRAME, MAX_LINE_DELAY, PARAMS, POSITION, WIDE_PARAMS, WORD,
                                  Encoder, base_config, clocks, simulate, simulate_frames)
from master_contract import STATUS

HP = 2
BREAK = 3                           # cfg_break_time of every test that is not about it
FRAME_BITS = WORD.total_bits        # data + nE/nW + CRC: 12
DEFAULT_BREAK = clocks(40e-6)       # docs/protocol.md, section 9: the master pauses 40 us after an error
DEFAULT_ACK = clocks(40e-6)         # docs/protocol.md, section 9: processing time and line delay <= 40 us
DEFAULT_TIMEOUT = 2 * clocks(40e-6)  # ports.md: twice the longest static slave timeout (40 us)


def vote_spacing(hp):
    """Clocks between the three votes of a slot (ports.md): a quarter bit, none at hp = 2."""
    return hp // 2 if hp >= 3 else 0


def sample_clock(s, ld, k, hp=HP):
    """The clock in which slot k is decided (timing.md): its third vote, v after its centre."""
    return s + ld + 1 + hp + 2 * hp * k + vote_spacing(hp)


def target_rises(ack_slots):
    """MA rising edges of a whole frame (ports.md): Ack slots + frame bits + 4."""
    return ack_slots + FRAME_BITS + 4


def busy_falls(run):
    return [t for t in range(1, len(run.trace))
            if not run.trace[t]["busy"] and run.trace[t - 1]["busy"]]


def cycle_starts(run, hp=HP):
    """The first MA fall of every cycle."""
    return [f for i, f in enumerate(run.falls) if i == 0 or f - run.falls[i - 1] > 2 * hp]


def start_at(*clocks_):
    return lambda t, run: {"start": int(t in clocks_)}


def assert_frame(run, s, ld, ack_slots, *, end_check_done=None, hp=HP):
    """One frame, reported OK, at the documented clock (3 clocks after the last CRC bit's
    decision: the decoder reads it one clock after the decision); MA made exactly the frame's
    rises."""
    done = end_check_done or sample_clock(s, ld, ack_slots + FRAME_BITS + 1, hp) + 3
    assert run.dones == [(done, STATUS["OK"])]
    assert run.trace[-1]["word0_position"] == POSITION
    assert run.cycles("valid") == [run.dones[0][0]]
    assert run.trace[-1]["line_delay"] == ld
    assert len(run.rises) == target_rises(ack_slots)
    assert not any(run.counts.values())


def assert_fault(run, status, done, counter, hp=HP):
    """One fault at ``done``, counted once; MA stops (no fall after done) and then stays high;
    the break ends cfg_break_time + 1 clocks after BREAK's first clock with MA stopped."""
    assert run.dones == [(done, STATUS[status])]
    assert not run.cycles("valid")
    assert {k: v for k, v in run.counts.items() if v} == {counter: 1}
    assert all(f <= done for f in run.falls)
    m = max(run.rises[-1] + hp, done)
    assert all(x["ma"] for x in run.trace[m:])
    assert busy_falls(run)[-1] == m + BREAK + 1


# -- NO_ACK: cfg_ack_limit ---------------------------------------------------------------------

def ack_round_trip_max(a, hp):
    """The largest accepted ``line_delay`` at Ack limit ``a`` (ports.md, ``cfg_ack_limit``):
    ``line_delay`` + hp + v + 1 <= A, v the vote spacing."""
    return a - hp - vote_spacing(hp) - 1


@pytest.mark.parametrize("hp,limit", ((2, 12), (2, 0), (3, 20), (5, 30), (50, 1000)),
                         ids=("hp2_cfg12", "hp2_cfg0_default40us", "hp3_cfg20", "hp5_cfg30",
                              "hp50_cfg1000"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("A-1_frame", "A_frame", "A+1_NO_ACK"))
def test_ack_limit_no_ack(hp, limit, offset):
    """The Ack's slot-0 decision (ld + hp + v + 1 clocks after s: the slot's centre half a
    period after the edge, decided v later) comes at most A clocks after s. So the last
    accepted round trip is ``line_delay`` = A - hp - v - 1 (hp 50, A 1000: 924, not the 949 of
    a formula without v); one clock more is NO_ACK."""
    a = limit or DEFAULT_ACK
    ld = ack_round_trip_max(a, hp) + offset          # slot-0 decision at s + a + offset
    params = WIDE_PARAMS if ld > MAX_LINE_DELAY else None
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=limit)
    run = simulate(cfg, Encoder(hp, FRAME, round_trip=ld - 1), 5 + a + 2 * hp * 24,
                   start_at(5), params=params)
    s = run.rises[1]
    assert sample_clock(s, ld, 0, hp) == s + a + offset
    if offset <= 0:
        assert_frame(run, s, ld, 1, hp=hp)
    else:
        assert_fault(run, "NO_ACK", s + a + 2, "no_ack", hp)
        assert run.trace[-1]["line_delay"] == 0          # not updated by NO_ACK


def test_ack_limit_counts_the_vote_spacing():
    """hp 50 (v 25), A 1000: a round trip of 941 clocks (940.5 at the pin) passes a limit
    without the votes (941 + 50 + 1 <= 1000) but not the real one (941 + 50 + 25 + 1 > 1000):
    NO_ACK in s + A + 2."""
    hp, a, ld = 50, 1000, 941
    assert ld + hp + 1 <= a < ld + hp + vote_spacing(hp) + 1
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=a)
    run = simulate(cfg, Encoder(hp, FRAME, round_trip=ld - 1), 5 + a + 2 * hp * 24,
                   start_at(5), params=WIDE_PARAMS)
    assert_fault(run, "NO_ACK", run.rises[1] + a + 2, "no_ack", hp)


def test_no_ack_without_encoder_fires_at_a_plus_two():
    """No encoder at all: NO_ACK in clock s + A + 2, like a late Ack."""
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_ack_limit=7)
    run = simulate(cfg, Encoder(HP, FRAME, present=False), 40, start_at(5))
    assert_fault(run, "NO_ACK", run.rises[1] + 7 + 2, "no_ack")


# -- NO_START: cfg_ack_limit + one MA period ---------------------------------------------------

@pytest.mark.parametrize("hp,ack_slots", ((2, 3), (3, 4)), ids=("hp2_acks3", "hp3_acks4"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("L-1_frame", "L_frame", "L+1_NO_START"))
def test_no_start_limit(hp, ack_slots, offset):
    """Start must be sampled at most A + 2*hp + 1 clocks after the Ack's slot-0 sample. The
    Start sample is 2*hp*acks after it, so the setting is the probe: that distance is put at
    the limit + offset."""
    a = 2 * hp * ack_slots - 2 * hp - 1 - offset
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=a)
    run = simulate(cfg, Encoder(hp, FRAME, ack_slots=ack_slots), 5 + 2 * hp * 40,
                   start_at(5))
    s, ld = run.rises[1], 1
    if offset <= 0:
        assert_frame(run, s, ld, ack_slots, hp=hp)
    else:
        assert_fault(run, "NO_START", sample_clock(s, ld, 0, hp) + a + 2 * hp + 4, "no_start", hp)
        assert len(run.rises) < target_rises(ack_slots)


# -- DELAY_RANGE: cfg_delay_limit --------------------------------------------------------------

@pytest.mark.parametrize("limit", (6, 0), ids=("cfg6", "cfg0_max_line_delay63"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("D-1_frame", "D_frame", "D+1_DELAY_RANGE"))
def test_delay_limit(limit, offset):
    """line_delay <= D is accepted, D + 1 is DELAY_RANGE (line_delay shows the value)."""
    d = limit or MAX_LINE_DELAY
    ld = d + offset
    hp = 3                  # a frame longer than the round trip: MA makes just the frame's rises
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_delay_limit=limit, cfg_ack_limit=200)
    run = simulate(cfg, Encoder(hp, FRAME, round_trip=ld - 1), 5 + ld + 130, start_at(5))
    s = run.rises[1]
    if offset <= 0:
        assert_frame(run, s, ld, 1, hp=hp)
    else:
        assert_fault(run, "DELAY_RANGE", sample_clock(s, ld, 0, hp) + 2, "delay_range", hp)
        assert run.trace[-1]["line_delay"] == ld


def shown_line_delay(ld, max_line_delay):
    """``line_delay`` as ports.md gives it: the port is wide enough for ``max_line_delay`` + 1
    and saturates at its all-ones value F, which every round trip of F - 1 clocks or more
    shows (F - 1 itself never shows)."""
    full = 2 ** (max_line_delay + 1).bit_length() - 1
    return ld if ld <= full - 2 else full


@pytest.mark.parametrize("params,ld", (
    (WIDE_PARAMS, 8189), (WIDE_PARAMS, 8190), (WIDE_PARAMS, 9001),
    (None, 125), (None, 126), (None, 200),
    # The longest round trip a 16-bit timer build can accept at hp 3: A = 2**16 - 1.
    (None, 2**16 - 1 - 3 - 1 - 1),
), ids=("w13_8189", "w13_8190_sat", "w13_9001_sat", "w7_125", "w7_126_sat", "w7_200_sat",
        "w7_65530_sat"))
def test_line_delay_saturates(params, ld):
    """A round trip beyond the port: DELAY_RANGE at the usual clock (the sampler still samples
    slot 0 at its real place), and ``line_delay`` saturated, never wrapped: 8191 on the 13-bit
    port of the default build's ``max_line_delay`` (4095) from 8190 clocks on, 127 on the
    bench's 7-bit port (63); the value below shows exactly."""
    hp = 3
    max_line_delay = (params or PARAMS).max_line_delay
    a = min(ld + hp + vote_spacing(hp) + 1 + 10, 2**16 - 1)
    assert ld <= ack_round_trip_max(a, hp)
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=a)
    run = simulate(cfg, Encoder(hp, FRAME, round_trip=ld - 1), 5 + ld + 130, start_at(5),
                   params=params)
    s = run.rises[1]
    assert_fault(run, "DELAY_RANGE", sample_clock(s, ld, 0, hp) + 2, "delay_range", hp)
    assert run.trace[-1]["line_delay"] == shown_line_delay(ld, max_line_delay)


# -- MA rising edges of a frame near the 65535-slot limit --------------------------------------

#: BiSS C with 36 position bits, nE/nW and CRC-6: 44 frame bits (ports.md's example).
WORD36 = WordFormat(36, nenw=True, crc=CRC6)
POSITION36 = 0x9_8765_4321
FRAME36 = build_frame(FrameFormat("biss-c-36", (WORD36,)), [WordValue(POSITION36)])
#: A 36-bit build with 24-bit timers (an Ack limit for 65535 slots); no counters and no
#: register-access engine: a quarter faster.
PARAMS36 = replace(WIDE_PARAMS, max_data_bits=(36,), counter_width=0, register_access=False)
RISES_MAX = 2**16 - 1           # ports.md: MA's rising-edge count saturates at 65535


def frame_rises(start_slot, frame_bits, ld, hp):
    """MA rising edges of a frame (ports.md, "Number of MA rising edges per frame"): the target
    start slot + frame bits + 4; a target above 65535 cannot be counted, and MA stops after the
    stop bit's decision instead: ceil((line_delay + v + 5) / (2 hp)) edges more."""
    target = start_slot + frame_bits + 4
    if target <= RISES_MAX:
        return target
    return target + -(-(ld + vote_spacing(hp) + 5) // (2 * hp))


# About a minute each: the exact limit runs in make test, the two beyond it in make unit.
@pytest.mark.parametrize("start_slot,round_trip", (
    (65487, 0), pytest.param(65495, 0, marks=pytest.mark.long),
    pytest.param(65520, 3, marks=pytest.mark.long)),
    ids=("S65487_target65535", "S65495_target65543_ld1", "S65520_target65568_ld4"))
def test_ma_rises_near_the_slot_limit(start_slot, round_trip):
    """Start in slot 65487 of a 44-bit frame: the target is 65535, MA makes exactly that many
    rises. Beyond (65495, 65520), the target cannot be counted; MA makes the documented number
    of rises, all after the stop bit's rise, the frame is reported OK at the usual clock (3
    after the last CRC bit's decision), the master goes idle, and the next frame (1 Ack slot)
    is a normal one. About 45 s each: 262k clocks."""
    hp, ld, bits = 2, round_trip + 1, WORD36.total_bits
    a = 2 * hp * start_slot + 100
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=a, cfg_w0_data_bits=36)
    frames = simulate_frames(cfg, (start_slot, 1), round_trip, timeout=2 * hp + 4,
                             params=PARAMS36, bits=FRAME36)
    for f in frames:
        s = f.second_rise
        assert (f.status, f.position, f.line_delay) == (STATUS["OK"], POSITION36, ld)
        assert f.done == sample_clock(s, ld, f.ack_slots + bits + 1, hp) + 3
        assert f.rises == frame_rises(f.ack_slots, bits, ld, hp)
        assert f.last_rise < f.idle
    assert frames[1].rises == 1 + bits + 4


# -- SLO_STUCK_LOW before a cycle: cfg_timeout_limit -------------------------------------------

def _second_request_when_idle(t, run):
    """Start at clock 5, and again in the first idle clock after the first done."""
    if t == 5:
        return {"start": 1}
    if run.dones and t > run.dones[0][0] and not run.trace[-1]["busy"] \
            and "again" not in run.counts:
        run.counts["again"] = t
        return {"start": 1}
    return {"start": 0}


@pytest.mark.parametrize("limit", (12, 0), ids=("cfg12", "cfg0_default80us"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("T-1_starts", "T_starts", "T+1_SLO_STUCK_LOW"))
def test_timeout_limit_before_cycle(limit, offset):
    """After a frame, the next request waits for SLO. SLO seen low (after the synchronizer,
    i.e. the pin 2 clocks earlier) for T clocks from MA stopped: the cycle starts; for T + 1:
    SLO_STUCK_LOW in clock m + T, done at m + T + 1, MA never moves."""
    t_lim = limit or DEFAULT_TIMEOUT
    low = t_lim + offset                      # clocks the master sees SLO low after m
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_timeout_limit=limit)
    run = simulate(cfg, Encoder(HP, FRAME, release=low - 2), 5 + 80 + t_lim + 30,
                   _second_request_when_idle)
    again = run.counts.pop("again")
    first_rises = run.rises[:target_rises(1)]
    m = first_rises[-1] + HP
    # Idle again in m + ld + 5 (ld = 1); the bench sees that one clock late.
    assert again == m + 1 + 5 + 1
    assert run.dones[0][1] == STATUS["OK"]
    if offset <= 0:
        # SLO seen high in clock m + low: CLOCK next, MA falls one clock later.
        assert [f for f in run.falls if f > m][0] == m + low + 2
        assert [s for _, s in run.dones] == [STATUS["OK"]] * len(run.dones)
        assert run.counts["slo_stuck_low"] == 0
    else:
        assert run.dones[1:] == [(m + t_lim + 1, STATUS["SLO_STUCK_LOW"])]
        assert run.counts["slo_stuck_low"] == 1
        assert not [f for f in run.falls if f > m]
        assert busy_falls(run)[-1] == m + t_lim + 1 + BREAK + 1


# -- End check: SLO_STUCK_LOW in CONFIRM, and the confirm wait ---------------------------------

@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("T-1_frame", "T_frame", "T+1_SLO_STUCK_LOW"))
def test_timeout_limit_end_check(offset):
    """With the end check, the frame is reported 1 clock after SLO is seen high (the pin + 3)
    if that is within T clocks of MA stopping; otherwise SLO_STUCK_LOW at m + T + 1."""
    t_lim = 12
    low = t_lim + offset
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_timeout_limit=t_lim, cfg_end_check=1)
    run = simulate(cfg, Encoder(HP, FRAME, release=low - 2), 5 + 80 + t_lim + 15, start_at(5))
    m = run.rises[-1] + HP
    if offset <= 0:
        assert_frame(run, run.rises[1], 1, 1, end_check_done=m + low + 1)
        assert busy_falls(run)[-1] == m + low + 1         # IDLE with done, no break
    else:
        assert_fault(run, "SLO_STUCK_LOW", m + t_lim + 1, "slo_stuck_low")
        assert run.cycles("valid") == []


@pytest.mark.parametrize("round_trip", (0, 3), ids=("ld1", "ld4"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("E-1_NO_STOP", "E_NO_STOP", "E+1_frame"))
def test_end_check_stop_bit(round_trip, offset):
    """The stop bit is sampled in clock m + ld + 1 (the pin at m + ld - 1): SLO must still be
    low there. The encoder's timeout ending at the pin in clock m + ld - 1 + offset: 0 or
    earlier is NO_STOP (done at m + ld + 4: the decoder reads the decision one clock later), 1
    is a frame reported at m + ld + 5 (the earliest the confirm wait allows)."""
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_timeout_limit=20, cfg_end_check=1)
    run = simulate(cfg, Encoder(HP, FRAME, round_trip=round_trip, release=offset), 120,
                   start_at(5))
    m, ld = run.rises[-1] + HP, round_trip + 1
    if offset <= 0:
        assert_fault(run, "NO_STOP", m + ld + 4, "no_stop")
    else:
        assert_frame(run, run.rises[1], ld, 1, end_check_done=m + ld + 5)


# -- Break time: cfg_break_time -----------------------------------------------------------------

@pytest.mark.parametrize("limit", (6, 0), ids=("cfg6", "cfg0_default40us"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("B-1_overrun", "B_overrun", "B+1_accepted"))
def test_break_time_after_power_on(limit, offset):
    """Cycle 0 is BREAK's first clock (MA stopped, no abort). A request after B clocks of it
    (in clock B) is an overrun; in clock B + 1 the controller is idle and accepts it."""
    b = limit or DEFAULT_BREAK
    q = b + offset
    run = simulate(base_config(HP, cfg_break_time=limit), Encoder(HP, FRAME), q + 90,
                   start_at(q))
    assert busy_falls(run)[0] == b + 1
    if offset <= 0:
        assert run.cycles("overrun") == [q] and run.counts["overrun"] == 1
        assert not run.falls and not run.dones
    else:
        assert not run.cycles("overrun")
        assert run.falls[0] == q + 3
        assert run.dones and run.dones[0][1] == STATUS["OK"]


@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("B-1_overrun", "B_overrun", "B+1_accepted"))
def test_break_time_after_abort(offset):
    """abort_cycle in IDLE, held 3 clocks: the break counts from the first clock with
    abort_cycle low, B + 1 clocks to IDLE. No report."""
    b = 5
    q = 20 + b + offset                       # abort high in 17, 18, 19; low from 20

    def drive(t, run):
        return {"abort_cycle": int(17 <= t <= 19), "start": int(t == q)}

    run = simulate(base_config(HP, cfg_break_time=b), Encoder(HP, FRAME), q + 90, drive)
    assert busy_falls(run)[:2] == [b + 1, 20 + b + 1]
    assert run.counts["aborted"] == 0
    if offset <= 0:
        assert run.cycles("overrun") == [q] and not run.falls and not run.dones
    else:
        assert not run.cycles("overrun") and run.falls[0] == q + 3


# -- Request period and overrun -----------------------------------------------------------------

def cycle_length(ld=1, ack_slots=1):
    """Clocks from an accepted request to the first idle clock after its frame (no end check):
    MA falls 3 clocks after the request, makes the frame's rises, and the controller is idle
    again in m + ld + 5."""
    return 3 + 2 * HP * target_rises(ack_slots) + ld + 5


@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("C-1_overrun", "C_spacing_P", "C+1_spacing_P"))
def test_request_period(offset):
    """periodic = 1: ticks in the clock periodic rises and every P clocks after. A tick in an
    idle clock starts a cycle (MA falls 3 clocks later): start-to-start is exactly P. A tick
    while busy is an overrun, dropped; the next tick comes P later."""
    c = cycle_length()
    p = c + offset
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_request_period=p)
    run = simulate(cfg, Encoder(HP, FRAME, release=1), 10 + 2 * p + 15,
                   lambda t, run: {"periodic": int(t >= 10)})
    first_falls = cycle_starts(run)
    assert busy_falls(run)[1] == 10 + c
    if offset < 0:
        assert run.cycles("overrun") == [10 + p] and run.counts["overrun"] == 1
        assert first_falls == [13, 10 + 2 * p + 3]
    else:
        assert not run.cycles("overrun")
        assert first_falls == [13, 13 + p, 13 + 2 * p]
    assert all(s == STATUS["OK"] for _, s in run.dones)


@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("C-1_overrun", "C_accepted", "C+1_accepted"))
def test_overrun_at_end_of_cycle(offset):
    """A start in a busy clock is an overrun (counted, dropped); the cycle is busy for C clocks
    from its request, so a start C clocks after it is the first one accepted."""
    c = cycle_length()
    q = 10 + c + offset
    run = simulate(base_config(HP, cfg_break_time=BREAK), Encoder(HP, FRAME, release=1),
                   q + 90, start_at(10, q))
    assert busy_falls(run)[1] == 10 + c
    if offset < 0:
        assert run.cycles("overrun") == [q] and run.counts["overrun"] == 1
        assert len(run.dones) == 1
    else:
        assert not run.cycles("overrun")
        assert len(run.dones) == 2 and run.falls[target_rises(1)] == q + 3


def test_overrun_start_held_two_clocks():
    """The request clock itself goes to WAIT_READY: a start in the next clock is an overrun."""
    run = simulate(base_config(HP, cfg_break_time=BREAK), Encoder(HP, FRAME, release=1), 100,
                   start_at(10, 11))
    assert run.cycles("overrun") == [11] and run.counts["overrun"] == 1
    assert run.falls[0] == 13 and len(run.dones) == 1


def test_timeout_limit_late_request_reports_at_once():
    """A request that comes when SLO has already been seen low longer than T: SLO_STUCK_LOW in
    the request's next clock, done 2 clocks after the request."""
    t_lim = 12
    cfg = base_config(HP, cfg_break_time=BREAK, cfg_timeout_limit=t_lim)
    m = 5 + cycle_length() - 1 - 5            # first request at 5, ld = 1: idle in m + 6
    q = m + t_lim + 4
    run = simulate(cfg, Encoder(HP, FRAME, release=40), q + 10, start_at(5, q))
    assert run.rises[-1] + HP == m
    assert run.dones[1:] == [(q + 2, STATUS["SLO_STUCK_LOW"])]
    assert run.counts["slo_stuck_low"] == 1 and len(run.falls) == target_rises(1)


# -- The pause after a doubtful frame (issue 12) --------------------------------------------------

BAD_CRC_FRAME = build_frame(FrameFormat("limits", (WORD,)), [WordValue(POSITION)],
                            FrameFaults(crc_xor=(1,)))


@pytest.mark.parametrize("end_check", (0, 1), ids=("end_check0", "end_check1"))
@pytest.mark.parametrize("offset", (-1, 0, 1), ids=("I-1_overrun", "I_accepted", "I+1_accepted"))
def test_pause_after_a_crc_error(end_check, offset):
    """A frame with a CRC error is reported (done, CRC_ERROR_WORD0, counted), then the master
    pauses for cfg_break_time clocks with MA high before it is idle again, so that the encoder's
    timeout ends before the next cycle: idle (I) in m + ld + 5 + B without the end check (a good
    frame: m + ld + 5), in done + B + 1 with it (a good frame: done). A start before I is an
    overrun; the first one accepted starts a clean cycle."""
    ld = 1
    encoder = Encoder(HP, BAD_CRC_FRAME, release=1)
    probe = {}

    def idle_clock(run):
        first_done = run.dones[0][0]
        m = run.rises[target_rises(1) - 1] + HP
        return first_done + BREAK + 1 if end_check else m + ld + 5 + BREAK

    def drive(t, run):
        if run.dones and "q" not in probe:
            probe["q"] = idle_clock(run) + offset
        return {"start": int(t == 10 or t == probe.get("q"))}

    cfg = base_config(HP, cfg_break_time=BREAK, cfg_end_check=end_check)
    run = simulate(cfg, encoder, 260, drive)
    first_done, status = run.dones[0]
    assert status == STATUS["CRC_ERROR_WORD0"] and run.counts["crc_word0"] >= 1
    idle = idle_clock(run)
    assert [f for f in busy_falls(run) if f > first_done][0] == idle
    assert all(x["ma"] for x in run.trace[first_done:probe["q"] + 3])
    if offset < 0:
        assert run.cycles("overrun") == [probe["q"]] and len(run.dones) == 1
    else:
        assert not run.cycles("overrun") and len(run.dones) == 2
        assert run.falls[target_rises(1)] == probe["q"] + 3


# -- Reset: rst for one clock ----------------------------------------------------------------------

RESET_MIN = 1           # ports.md, "Clock and reset": one clock edge with rst high
RESET_BREAK = 10


def run_from_reset(make_encoder, cfg, after, n_after, reset_at=None, n_rst=RESET_MIN,
                   before=None):
    """Power-up (``reset_at`` None): ``after(t)`` drives the inputs from cycle 0. Otherwise
    ``before(t)`` drives them, ``rst`` is high in clocks ``reset_at`` .. ``reset_at + n_rst - 1``
    (the edges ending them reset the core), and ``after(t - r0)`` drives them from the release
    r0 = ``reset_at + n_rst``: for the core, clock r0 is cycle 0 again. Every output recorded."""
    r0 = 0 if reset_at is None else reset_at + n_rst

    def drive(t, run):
        inputs = dict(after(t - r0) if t >= r0 else before(t))
        if reset_at is not None:
            inputs["rst"] = int(reset_at <= t < r0)
        return inputs

    return simulate(cfg, make_encoder(), r0 + n_after, drive, trace="outputs"), r0


def assert_as_after_power_up(run, r0, reset_at, power_up, ignore=()):
    """From the release on, every output as after power-up, clock for clock; in the clocks after
    a reset edge (rst still high or not), the power-up values of cycle 0."""
    def outputs(x):
        return {k: v for k, v in x.items() if k not in ignore}

    for t in range(reset_at + 1, r0 + 1):
        assert outputs(run.trace[t]) == outputs(power_up.trace[0]), t
    for t, x in enumerate(power_up.trace):
        assert outputs(run.trace[r0 + t]) == outputs(x), t


def _frame_encoder():
    # The encoder's timeout ends a frame cut by the reset (MA high 12 clocks), within the break.
    return Encoder(HP, FRAME, round_trip=3, release=2, timeout=12)


def _frame_at(q):
    return lambda t: {"start": int(t == q)}


@pytest.mark.parametrize("reset_at,n_rst,ma,busy", (
    (4, RESET_MIN, 1, 1), (40, RESET_MIN, 0, 1), (42, RESET_MIN, 1, 1), (97, RESET_MIN, 1, 1),
    (40, 7, 0, 1),
), ids=("in_break", "mid_frame_ma_low", "mid_frame_ma_high", "after_done", "ma_low_held7"))
def test_reset_mid_frame_is_power_up(reset_at, n_rst, ma, busy):
    """``rst`` for one clock (or held longer) in the power-up break, in a frame with MA low or
    high, or after the frame's done: from the release on the core behaves as after power-up,
    every output clock for clock: the break (busy until B + 1), then the next request's frame
    (MA falls 3 clocks after it, done OK). MA goes high in the clock after the first reset
    edge, even within a phase."""
    cfg = base_config(HP, cfg_break_time=RESET_BREAK)
    power_up, _ = run_from_reset(_frame_encoder, cfg, _frame_at(30), 130)
    assert busy_falls(power_up)[0] == RESET_BREAK + 1
    assert power_up.falls[0] == 33 and [s for _, s in power_up.dones] == [STATUS["OK"]]
    run, r0 = run_from_reset(_frame_encoder, cfg, _frame_at(30), 130, reset_at, n_rst,
                             before=_frame_at(20))
    assert (run.trace[reset_at]["ma"], run.trace[reset_at]["busy"]) == (ma, busy)
    assert [d for d, _ in run.dones if d < reset_at] == ([95] if reset_at > 95 else [])
    assert_as_after_power_up(run, r0, reset_at, power_up)


def _access_encoder():
    from testkit.control_slave import RELEASE, ROUND_TRIP, ControlEncoder, Slave
    return ControlEncoder(hp=HP, bits=list(FRAME), ack_slots=1, round_trip=ROUND_TRIP,
                          release=RELEASE, slave=Slave({0x42: 0x62}), timeout=20)


def _access_at(q):
    return lambda t: {"ca_address": 0x42, "ca_count": 1, "ca_start": int(t == q)}


@pytest.mark.parametrize("reset_at,held", ((1355, True), (3000, False)),
                         ids=("in_cdm_hold", "in_a_frame"))
def test_reset_mid_register_access_is_power_up(reset_at, held):
    """``rst`` for one clock during a register read (in a CDM = 1 hold, MA held low; in one of
    its frames): the access is dropped without ``ca_done``, and from the release on every output
    is as after power-up, the break and a whole new read (``ca_done`` OK, the byte) included,
    except ``cds``: that is the encoder's own answer, and the encoder may still be in the
    control frame the reset cut (until 14 frames of CDM = 0 cancel it), and
    the line checks' noise count: with this test's 3-clock break the encoder is still in the
    cut frame when the master is idle again, and its SLO falling there is, by docs/ports.md
    ("Noise"), a noise event (the protocol's 40 us break outlasts every frame and timeout), so
    the noise check is off here (``cfg_noise_limit`` 15) and the count not compared."""
    cfg = base_config(HP, cfg_break_time=3, cfg_noise_limit=15)
    power_up, _ = run_from_reset(_access_encoder, cfg, _access_at(60), 4000)
    ca_done = [t for t, x in enumerate(power_up.trace) if x["ca_done"]]
    assert len(ca_done) == 1 and power_up.trace[ca_done[0]]["ca_status"] == 0
    run, r0 = run_from_reset(_access_encoder, cfg, _access_at(60), 4000, reset_at,
                             before=_access_at(60))
    x = run.trace[reset_at]
    assert x["ca_busy"] and not x["ma"]
    assert all(not y["ma"] for y in run.trace[reset_at - HP - 1:reset_at + 1]) == held  # > hp low
    assert not any(y["ca_done"] for y in run.trace[:r0])
    assert_as_after_power_up(run, r0, reset_at, power_up, ignore=("cds", "count_noise_event", "noise_events"))


def test_reset_drops_requests():
    """``start`` held high through a reset of 4 clocks (from clock 60; a frame at 20, the
    start held from 50 and so overruns counted before): no request in the reset clocks
    (``overrun`` strobes, combinationally, but is not counted; the counters read 0 from the
    first reset edge on); from cycle 0 (64) on as after power-up: overruns counted in BREAK (the
    one of cycle 0 two clocks later), the held start accepted in the first idle clock, B + 1 =
    11 clocks after cycle 0, MA falling 3 clocks after that."""
    cfg = base_config(HP, cfg_break_time=RESET_BREAK)
    run = simulate(cfg, _frame_encoder(), 120,
                   lambda t, r: {"start": int(t == 20 or t >= 50), "rst": int(60 <= t < 64)},
                   trace="outputs")
    r0 = 64
    assert run.trace[60]["count_overrun"] > 0
    assert all(x["overrun"] for x in run.trace[60:r0 + RESET_BREAK + 1])
    assert [x["count_overrun"] for x in run.trace[61:r0 + 2]] == [0] * (r0 - 60 + 1)
    assert run.trace[r0 + 2]["count_overrun"] == 1
    assert busy_falls(run)[-1] == r0 + RESET_BREAK + 1
    assert [f for f in run.falls if f > 60][0] == r0 + RESET_BREAK + 1 + 3


# -- A build with a narrower half-period setting (half_period_width) -----------------------------

@pytest.mark.parametrize("hp", (2, 255), ids=("hp2_the_shortest", "hp255_the_longest"))
def test_an_8_bit_half_period_build_reads_frames_up_to_its_longest_half_period(hp):
    """MasterParams.half_period_width 8 (docs/ports.md, ``cfg_ma_half_period``): the setting
    holds half periods up to 2**8 - 1 = 255 clocks. A frame at the shortest and at the longest
    is read as in the default build: reported OK at the documented clock, with exactly the
    frame's MA rises, and MA's low phases exactly ``hp`` clocks long."""
    params = replace(PARAMS, half_period_width=8)
    ld = 7
    ack = ld + hp + vote_spacing(hp) + 1 + 10      # above ack_round_trip_max's bound
    cfg = base_config(hp, cfg_break_time=BREAK, cfg_ack_limit=ack)
    n = 5 + ld + 2 * hp * (target_rises(1) + 2) + 20
    run = simulate(cfg, Encoder(hp, FRAME, round_trip=ld - 1), n, start_at(5), params=params)
    s = run.rises[1]
    assert_frame(run, s, ld, 1, hp=hp)
    lows = [r - f for f, r in zip(run.falls, run.rises)]
    assert lows == [hp] * target_rises(1)
