"""CycleController on Amaranth's simulator: its inputs driven directly, its state seen through
its outputs.

Cycle conventions and where expected values come from: ``block_sim.py``. The states and their
outputs are those of the block's docstring and docs/timing.md ("States", "Faults"): BREAK holds
the receiver in reset and resyncs the sign of life; IDLE is the only ``idle`` state; WAIT_READY
holds the receiver in reset; CLOCK is the only ``in_clock`` state and runs MA until it has made
enough rises; TAIL runs MA as well; END and CONFIRM drive nothing. Status codes come from
``tb/master_contract.py``; each fault's strobe in ``faults`` is named after its status.
"""

import pytest

from bissmaster.core.cycle_controller import CycleController
from master_contract import STATUS, STATUS_NAME

from testkit.block_sim import run_clocks

FAULT_NAMES = [name for name, code in STATUS.items()
               if STATUS["NO_ACK"] <= code <= STATUS["NO_STOP"]]
QUIET = {"request": 0, "abort": 0, "config_ok": 1, "end_check": 0, "slo": 1, "ma_busy": 0,
         "ma_arm": 0, "ma_enough": 0, "locked": 0, "early": 0, "frame_done": 0, "started": 0,
         "slots_full": 0, "stopped": 0, "stop_bit": 0, "break_over": 0, "ack_expired": 0,
         "no_start_expired": 0, "slo_stuck": 0, "slo_stuck_live": 0, "delay_over": 0,
         "quiet": 1, "quiet_live": 1,
         "frame_doubtful": 0, "ssi": 0, "timeout_over": 0}
SIGNALS = ["idle", "waiting", "first_clock", "receiver_clear", "resync", "timer_clear", "in_clock",
           "restart_timer", "ma_run", "report_frame", "report_delay", "fault", "fault_status"]
OUTPUTS = SIGNALS + [f"faults.{name.lower()}" for name in FAULT_NAMES]


def state(row):
    """The state as the outputs show it (TAIL only while MA must run on: ``ma_enough`` low)."""
    if row["resync"]:
        return "BREAK"
    if row["idle"]:
        return "IDLE"
    if row["in_clock"]:
        return "CLOCK"
    if row["receiver_clear"]:
        return "WAIT_READY"
    if row["ma_run"]:
        return "TAIL"
    return "END/CONFIRM"


def run(steps, *, end_check=0):
    """Run from reset; check in every clock that the ``faults`` strobes are one-hot with
    ``fault_status`` and that a fault and a frame report never coincide."""
    trace = run_clocks(CycleController(), steps, OUTPUTS, defaults={**QUIET, "end_check": end_check})
    for t, row in enumerate(trace):
        strobes = {name for name in FAULT_NAMES if row[f"faults.{name.lower()}"]}
        if row["fault"]:
            assert strobes == {STATUS_NAME[row["fault_status"]]}, t
            assert not row["report_frame"], t
        else:
            assert strobes == set(), t
        if row["report_frame"]:
            assert row["report_delay"], t
        row["state"] = state(row)
    return trace


def _outs(row, names):
    return tuple(row[n] for n in names)


# -- A good cycle ---------------------------------------------------------------------------------

#: (step, state seen, (receiver_clear, resync, timer_clear, in_clock, restart_timer, ma_run,
#: report_frame, first_clock))
GOOD_CYCLE = [
    ({}, "BREAK", (1, 1, 0, 0, 0, 0, 0, 0)),
    ({"ma_busy": 1}, "BREAK", (1, 1, 1, 0, 0, 0, 0, 0)),      # MA still finishing: restart
    ({"abort": 1}, "BREAK", (1, 1, 1, 0, 0, 0, 0, 0)),        # abort held: restart
    ({"break_over": 1}, "BREAK", (1, 1, 0, 0, 0, 0, 0, 0)),
    ({}, "IDLE", (1, 0, 1, 0, 0, 0, 0, 0)),
    ({"request": 1}, "IDLE", (1, 0, 1, 0, 0, 0, 0, 1)),       # first_clock: IDLE before
    ({"slo": 0}, "WAIT_READY", (1, 0, 1, 0, 0, 0, 0, 1)),     # encoder not ready yet
    ({"slo": 0}, "WAIT_READY", (1, 0, 1, 0, 0, 0, 0, 0)),
    ({"slo": 1}, "WAIT_READY", (1, 0, 1, 0, 0, 0, 0, 0)),
    ({}, "CLOCK", (0, 0, 0, 1, 0, 1, 0, 0)),
    ({"ma_arm": 1}, "CLOCK", (0, 0, 1, 1, 1, 1, 0, 0)),       # 2nd rise: timer restarts
    ({}, "CLOCK", (0, 0, 0, 1, 0, 1, 0, 0)),
    ({"locked": 1}, "CLOCK", (0, 0, 1, 1, 1, 1, 0, 0)),       # Ack found: timer restarts
    ({"locked": 1}, "CLOCK", (0, 0, 0, 1, 0, 1, 0, 0)),       # ... once
    ({"locked": 1, "started": 1}, "CLOCK", (0, 0, 0, 1, 0, 1, 0, 0)),
    ({"locked": 1, "started": 1, "ma_enough": 1}, "CLOCK", (0, 0, 0, 1, 0, 0, 0, 0)),
    ({"locked": 1, "started": 1, "frame_done": 1}, "CLOCK", (0, 0, 0, 1, 0, 1, 1, 0)),
    ({}, "TAIL", (0, 0, 0, 0, 0, 1, 0, 0)),
    ({"ma_enough": 1}, "END/CONFIRM", (0, 0, 0, 0, 0, 0, 0, 0)),   # TAIL, MA told to stop
    ({"stopped": 1}, "TAIL", (0, 0, 0, 0, 0, 1, 0, 0)),
    ({"ma_busy": 1}, "END/CONFIRM", (0, 0, 0, 0, 0, 0, 0, 0)),     # END: MA's last high phase
    ({"ma_busy": 0}, "END/CONFIRM", (0, 0, 0, 0, 0, 0, 0, 0)),
    ({}, "IDLE", (1, 0, 1, 0, 0, 0, 0, 0)),
]
COLUMNS = ("receiver_clear", "resync", "timer_clear", "in_clock", "restart_timer", "ma_run",
           "report_frame", "first_clock")


def test_cycle_controller_good_cycle_states_and_outputs():
    trace = run([s for s, _, _ in GOOD_CYCLE])
    for t, ((step, seen, outs), row) in enumerate(zip(GOOD_CYCLE, trace)):
        assert row["state"] == seen, (t, step)
        assert _outs(row, COLUMNS) == outs, (t, step)
        assert row["idle"] == int(seen == "IDLE"), t
        # The noise watch: only while MA is stopped and the encoder may only raise SLO.
        assert row["waiting"] == int(seen in ("IDLE", "WAIT_READY")), t
        assert not row["fault"], t
    # The frame is reported in the clock of ``frame_done``, with its line delay, and only there.
    assert [t for t, x in enumerate(trace) if x["report_frame"]] == [16]
    assert [t for t, x in enumerate(trace) if x["report_delay"]] == [16]


def test_cycle_controller_good_cycle_with_end_check_reports_in_confirm():
    steps = [s for s, _, _ in GOOD_CYCLE[:17]] + [
        {},                                         # 17 TAIL: frame not reported yet
        {"stopped": 1, "stop_bit": 0},              # 18 stop bit low: CONFIRM
        {"ma_busy": 1, "slo": 1},                   # 19 CONFIRM: MA not stopped yet
        {"slo": 0, "slo_stuck_live": 1},            # 20 encoder timeout running (live flag ignored)
        {"slo": 0},                                 # 21
        {"slo": 1},                                 # 22 SLO back high, MA stopped: report
        {},                                         # 23 IDLE
    ]
    trace = run(steps, end_check=1)
    assert [x["state"] for x in trace[16:]] == ["CLOCK", "TAIL", "TAIL"] + ["END/CONFIRM"] * 4 \
        + ["IDLE"]
    assert [t for t, x in enumerate(trace) if x["report_frame"]] == [22]
    assert [t for t, x in enumerate(trace) if x["report_delay"]] == [22]
    assert not any(x["fault"] for x in trace)


# -- Faults ---------------------------------------------------------------------------------------

PREFIX = {"idle": [{}, {"break_over": 1}]}
PREFIX["wait_first"] = PREFIX["idle"] + [{"request": 1}]
PREFIX["wait_later"] = PREFIX["wait_first"] + [{"slo": 0}]
PREFIX["clock"] = PREFIX["wait_first"] + [{"slo": 1}]
PREFIX["armed"] = PREFIX["clock"] + [{"ma_arm": 1}]
PREFIX["locked"] = PREFIX["armed"] + [{"locked": 1}]
PREFIX["tail"] = PREFIX["locked"] + [{"locked": 1, "started": 1, "frame_done": 1}]
PREFIX["after_tail"] = PREFIX["tail"] + [{"stopped": 1}]      # END, or CONFIRM with the end check

# (case id, end check, prefix, the clock's inputs, status or None, state the clock after,
#  report_delay, timer_clear in that clock or None = not checked)
FAULTS = [
    ("bad_config", 0, "wait_first", {"config_ok": 0}, "BAD_CONFIG", "IDLE", 0, 1),
    ("bad_config_with_abort", 0, "wait_first", {"config_ok": 0, "abort": 1}, "BAD_CONFIG",
     "BREAK", 0, 1),
    ("bad_config_over_slo_stuck", 0, "wait_first", {"config_ok": 0, "slo": 0,
                                                    "slo_stuck_live": 1}, "BAD_CONFIG", "IDLE", 0, 1),
    ("config_ok_read_only_in_first_clock", 0, "wait_later", {"config_ok": 0, "slo": 0}, None,
     "WAIT_READY", 0, 1),
    ("aborted_in_wait_ready", 0, "wait_later", {"abort": 1, "slo": 0}, "ABORTED", "BREAK", 0, 1),
    ("aborted_in_clock", 0, "locked", {"abort": 1, "locked": 1}, "ABORTED", "BREAK", 0, 1),
    ("aborted_over_frame_done", 0, "locked", {"abort": 1, "locked": 1, "frame_done": 1},
     "ABORTED", "BREAK", 0, 1),
    ("aborted_in_tail_end_check", 1, "tail", {"abort": 1}, "ABORTED", "BREAK", 0, 1),
    ("abort_in_tail_no_report", 0, "tail", {"abort": 1}, None, "BREAK", 0, 1),
    ("aborted_in_confirm", 1, "after_tail", {"abort": 1, "slo": 0}, "ABORTED", "BREAK", 0, 1),
    ("abort_in_idle_no_report", 0, "idle", {"abort": 1, "request": 1}, None, "BREAK", 0, 1),
    ("abort_in_end_ignored", 0, "after_tail", {"abort": 1, "ma_busy": 1}, None, "END/CONFIRM",
     0, 0),
    ("slo_stuck_live_in_first_clock", 0, "wait_first", {"slo": 0, "slo_stuck_live": 1},
     "SLO_STUCK_LOW", "BREAK", 0, 1),
    ("slo_stuck_latched_ignored_in_first_clock", 0, "wait_first", {"slo": 0, "slo_stuck": 1},
     None, "WAIT_READY", 0, 1),
    ("slo_stuck_after_first_clock", 0, "wait_later", {"slo": 0, "slo_stuck": 1},
     "SLO_STUCK_LOW", "BREAK", 0, 1),
    ("slo_stuck_live_ignored_after_first_clock", 0, "wait_later", {"slo": 0, "slo_stuck_live": 1},
     None, "WAIT_READY", 0, 1),
    ("slo_high_wins_over_stuck", 0, "wait_later", {"slo": 1, "slo_stuck": 1}, None, "CLOCK", 0, 1),
    # SLO high, but not yet for the quiet time: wait on (and never stuck: SLO is high).
    ("slo_high_not_quiet_waits", 0, "wait_later", {"slo": 1, "quiet": 0, "slo_stuck": 1}, None,
     "WAIT_READY", 0, 1),
    ("quiet_live_read_in_first_clock", 0, "wait_first", {"slo": 1, "quiet": 1, "quiet_live": 0},
     None, "WAIT_READY", 0, 1),
    ("quiet_latched_ignored_in_first_clock", 0, "wait_first", {"slo": 1, "quiet": 0,
                                                                "quiet_live": 1}, None, "CLOCK", 0, 1),
    ("delay_range_early", 0, "armed", {"early": 1}, "DELAY_RANGE", "BREAK", 0, 0),
    ("early_before_arm_ignored", 0, "clock", {"early": 1}, None, "CLOCK", 0, 0),
    ("delay_range_on_lock", 0, "armed", {"locked": 1, "delay_over": 1}, "DELAY_RANGE", "BREAK",
     1, 1),
    ("delay_over_after_lock_ignored", 0, "locked", {"locked": 1, "delay_over": 1}, None, "CLOCK",
     0, 0),
    ("early_over_no_ack", 0, "armed", {"early": 1, "ack_expired": 1}, "DELAY_RANGE", "BREAK", 0, 0),
    ("no_ack", 0, "armed", {"ack_expired": 1}, "NO_ACK", "BREAK", 0, 0),
    ("ack_expired_before_arm_ignored", 0, "clock", {"ack_expired": 1}, None, "CLOCK", 0, 0),
    ("ack_expired_in_lock_clock_ignored", 0, "armed", {"locked": 1, "ack_expired": 1}, None,
     "CLOCK", 0, 1),
    ("no_ack_over_no_start", 0, "armed", {"ack_expired": 1, "no_start_expired": 1}, "NO_ACK",
     "BREAK", 0, 0),
    ("no_start_expired", 0, "locked", {"locked": 1, "no_start_expired": 1}, "NO_START", "BREAK",
     0, 0),
    ("no_start_slots_full", 0, "locked", {"locked": 1, "slots_full": 1}, "NO_START", "BREAK", 0, 0),
    ("no_start_in_lock_clock_ignored", 0, "armed", {"locked": 1, "no_start_expired": 1}, None,
     "CLOCK", 0, 1),
    ("no_start_after_started_ignored", 0, "locked",
     {"locked": 1, "started": 1, "no_start_expired": 1, "slots_full": 1}, None, "CLOCK", 0, 0),
    ("frame_done_over_line_faults", 0, "locked",
     {"locked": 1, "frame_done": 1, "no_start_expired": 1, "ack_expired": 1}, None, "TAIL", 1, 0),
    ("no_stop", 1, "tail", {"stopped": 1, "stop_bit": 1}, "NO_STOP", "BREAK", 0, 1),
    ("stop_bit_high_without_end_check", 0, "tail", {"stopped": 1, "stop_bit": 1}, None,
     "END/CONFIRM", 0, 0),
    ("slo_stuck_in_confirm", 1, "after_tail", {"slo": 0, "slo_stuck": 1}, "SLO_STUCK_LOW",
     "BREAK", 0, 1),
    ("slo_stuck_live_ignored_in_confirm", 1, "after_tail", {"slo": 0, "slo_stuck_live": 1}, None,
     "END/CONFIRM", 0, 0),
]


@pytest.mark.parametrize("end_check, prefix, step, status, after, report_delay, timer_clear",
                         [c[1:] for c in FAULTS], ids=[c[0] for c in FAULTS])
def test_cycle_controller_fault(end_check, prefix, step, status, after, report_delay, timer_clear):
    steps = PREFIX[prefix] + [step, {"slo": 0, "ma_busy": 1}]
    trace = run(steps, end_check=end_check)
    row = trace[-2]
    assert row["fault"] == int(status is not None)
    if status is not None:
        assert row["fault_status"] == STATUS[status]
    assert row["report_frame"] == int(status is None and prefix == "locked"
                                      and bool(step.get("frame_done")) and not end_check)
    assert row["report_delay"] == report_delay
    if timer_clear is not None:
        assert row["timer_clear"] == timer_clear
    assert trace[-1]["state"] == after
    # No fault before the clock under test (the prefixes through TAIL report their frame).
    assert not any(x["fault"] for x in trace[:-2])


@pytest.mark.parametrize("name", ["ABORTED", "SLO_STUCK_LOW", "NO_STOP", "DELAY_RANGE"])
def test_cycle_controller_break_after_fault_waits_for_break_over(name):
    case = {"ABORTED": ("locked", {"abort": 1, "locked": 1}, 0),
            "SLO_STUCK_LOW": ("wait_later", {"slo": 0, "slo_stuck": 1}, 0),
            "NO_STOP": ("tail", {"stopped": 1, "stop_bit": 1}, 1),
            "DELAY_RANGE": ("armed", {"early": 1}, 0)}[name]
    prefix, step, end_check = case
    steps = PREFIX[prefix] + [step, {"ma_busy": 1}, {}, {}, {"break_over": 1}, {}]
    trace = run(steps, end_check=end_check)
    assert [x["state"] for x in trace[-5:]] == ["BREAK"] * 4 + ["IDLE"]
    assert trace[-5]["timer_clear"] == 1            # MA still running: the break restarts
    # The receiver is held and the sign of life resyncs in BREAK.
    assert all(x["receiver_clear"] and x["resync"] for x in trace[-5:-1])


@pytest.mark.parametrize("end_check", (0, 1), ids=("end_check0", "end_check1"))
def test_cycle_controller_pause_after_a_doubtful_frame(end_check):
    """A frame that ends (``frame_done``) with ``frame_doubtful`` (its verdict will not be OK) is
    followed by PAUSE once reported: the
    receiver held, the sign of life kept (no resync), MA stopped, the timer cleared on the way in
    and while MA runs, IDLE only after ``break_over``. No fault is reported."""
    through_done = [s for s, _, _ in GOOD_CYCLE[:16]]
    done = {"locked": 1, "started": 1, "frame_done": 1, "frame_doubtful": 1}
    if end_check:
        tail = [{}, {"stopped": 1, "stop_bit": 0}, {"slo": 1}]
    else:
        tail = [{}, {"stopped": 1}]
    pause = [{"ma_busy": 1}, {}, {}, {"break_over": 1}, {}]
    trace = run(through_done + [done] + tail + pause, end_check=end_check)
    entry = len(through_done) + 1 + len(tail) - 1     # the clock that leaves for PAUSE
    assert trace[entry]["timer_clear"] == 1
    assert [t for t, x in enumerate(trace) if x["report_frame"]] == \
        [entry if end_check else len(through_done)]
    in_pause = trace[entry + 1:entry + 5]
    assert all(x["receiver_clear"] and not x["resync"] and not x["idle"] and not x["ma_run"]
               and not x["in_clock"] for x in in_pause)
    assert in_pause[0]["timer_clear"] == 1          # MA still running: the pause restarts
    assert trace[entry + 5]["idle"] == 1
    assert not any(x["fault"] for x in trace)


def test_cycle_controller_good_frame_does_not_pause():
    trace = run([s for s, _, _ in GOOD_CYCLE])
    assert trace[-1]["idle"] == 1 and not any(x["resync"] for x in trace[5:])


# -- CDM (control channel): the cycle's bit, the hold after the frame, its release ----------------

CDM_OUTPUTS = OUTPUTS + ["ma_hold", "cdm_cycle"]


def run_cdm(steps, *, end_check=0):
    trace = run_clocks(CycleController(cdm=True), steps, CDM_OUTPUTS,
                       defaults={**QUIET, "end_check": end_check, "cdm": 0, "ma_held": 0})
    for row in trace:
        row["state"] = state(row)
    return trace


def _good_cycle_with_cdm(cdm):
    """GOOD_CYCLE up to the stop bit, the engine's bit ``cdm`` offered while idle (and changed
    to the other value right after the request: the cycle keeps the bit it was accepted with)."""
    steps = [dict(s) for s, _, _ in GOOD_CYCLE[:20]]
    for t, s in enumerate(steps):
        s["cdm"] = cdm if t <= 5 else 1 - cdm
    return steps


def test_cycle_controller_cdm_bit_is_the_accepted_requests():
    trace = run_cdm(_good_cycle_with_cdm(1))
    # Accepted in clock 5 (IDLE with request): the bit of that clock, kept through the cycle.
    assert [x["cdm_cycle"] for x in trace[6:20]] == [1] * 14
    trace = run_cdm(_good_cycle_with_cdm(0))
    assert [x["cdm_cycle"] for x in trace[6:20]] == [0] * 14
    assert not any(x["ma_hold"] for x in trace)


def test_cycle_controller_cdm1_holds_until_slo_high_then_waits_for_ma():
    """CDM = 1: ``ma_hold`` high in CLOCK and TAIL (MaClock reads it when its last high phase
    ends) and in END while SLO (seen) is low; the first clock with SLO high releases; END goes
    to IDLE only when MaClock is idle (after its release phase)."""
    steps = _good_cycle_with_cdm(1) + [
        {"ma_busy": 1, "ma_held": 1, "slo": 0},     # 20 END: held, timeout running
        {"ma_busy": 1, "ma_held": 1, "slo": 0},     # 21
        {"ma_busy": 1, "ma_held": 1, "slo": 1},     # 22 SLO high: release
        {"ma_busy": 1, "slo": 1},                   # 23 MaClock's release phase (MA high)
        {"ma_busy": 0, "slo": 1},                   # 24 MaClock idle
        {},                                         # 25 IDLE
    ]
    trace = run_cdm(steps)
    assert all(x["ma_hold"] for x in trace[9:19] if x["state"] in ("CLOCK", "TAIL"))
    assert [x["ma_hold"] for x in trace[20:23]] == [1, 1, 0]
    assert [x["state"] for x in trace[20:26]] == ["END/CONFIRM"] * 5 + ["IDLE"]
    assert not any(x["fault"] for x in trace)


@pytest.mark.parametrize("why", ["slo_stuck", "abort"])
def test_cycle_controller_cdm1_hold_released_by_timeout_limit_or_abort(why):
    steps = _good_cycle_with_cdm(1) + [
        {"ma_busy": 1, "ma_held": 1, "slo": 0},
        {"ma_busy": 1, "ma_held": 1, "slo": 0, why: 1},
        {"ma_busy": 1, "slo": 0}, {"ma_busy": 0, "slo": 0}, {"slo": 0},
    ]
    trace = run_cdm(steps)
    assert [x["ma_hold"] for x in trace[20:22]] == [1, 0]
    # The timeout limit: no report here (the next cycle reports SLO_STUCK_LOW), IDLE once MA is
    # idle. An abort: BREAK (MA then stays high for the break time).
    after = "IDLE" if why == "slo_stuck" else "BREAK"
    assert trace[-1]["state"] == after
    assert not any(x["fault"] for x in trace)


def test_cycle_controller_cdm1_with_end_check_reports_while_held():
    steps = [dict(s, cdm=1 if t <= 5 else 0) for t, (s, _, _) in enumerate(GOOD_CYCLE[:17])] + [
        {},                                                   # 17 TAIL
        {"stopped": 1, "stop_bit": 0},                        # 18 CONFIRM next
        {"ma_busy": 1, "ma_held": 1, "slo": 0},               # 19 held, timeout running
        {"ma_busy": 1, "ma_held": 1, "slo": 1},               # 20 SLO high: report, release
        {"ma_busy": 1},                                       # 21 END: MaClock's release phase
        {"ma_busy": 0},                                       # 22
        {},                                                   # 23 IDLE
    ]
    trace = run_cdm(steps, end_check=1)
    assert [t for t, x in enumerate(trace) if x["report_frame"]] == [20]
    assert [x["ma_hold"] for x in trace[19:21]] == [1, 0]
    assert [x["state"] for x in trace[21:24]] == ["END/CONFIRM", "END/CONFIRM", "IDLE"]


def test_cycle_controller_cdm1_no_hold_after_a_fault():
    """A fault goes to BREAK, which never holds MA (the frame did not end: CDM is not sent)."""
    steps = [dict(s, cdm=1) for s in PREFIX["locked"]] + [
        {"abort": 1, "locked": 1, "cdm": 1}, {"ma_busy": 1}, {"ma_busy": 1}]
    trace = run_cdm(steps)
    assert trace[-3]["fault"] and trace[-3]["ma_hold"] == 0
    assert trace[-1]["state"] == "BREAK" and not trace[-1]["ma_hold"]


# -- SSI (docs/ports.md, "SSI mode") ------------------------------------------------------------

#: An SSI cycle: no Ack or Start to wait for; the frame ends with the stop bit's decision
#: (``frame_done`` is the decoder's ``stopped`` in the master), checked there.
SSI_PREFIX = [{}, {"break_over": 1, "timeout_over": 1}, {}, {"request": 1}, {}, {}]   # CLOCK at 5


@pytest.mark.parametrize("end_check", (0, 1), ids=("end_check0", "end_check1"))
def test_cycle_controller_ssi_line_faults_ignored_stop_bit_low_reports(end_check):
    """No Ack, Start or delay fault in SSI (their flags are ignored in CLOCK); a stop bit of 0
    reports the frame (without the end check at once, with it after SLO is high again and MA
    stopped), TAIL does not wait for ``stopped`` again."""
    steps = SSI_PREFIX + [
        {"ack_expired": 1, "early": 1, "ma_arm": 1},                  # 6: would be faults
        {"locked": 1, "delay_over": 1, "no_start_expired": 1},        # 7
        {"ma_enough": 1},                                             # 8
        {"ma_enough": 1, "frame_done": 1, "stop_bit": 0, "slo": 0},   # 9: the stop bit, low
        {"ma_enough": 1, "slo": 0},                                   # 10
        {"ma_enough": 1, "slo": 1},                                   # 11: tm over
        {"ma_enough": 1},                                             # 12
    ]
    trace = run_clocks(CycleController(), steps, OUTPUTS,
                       defaults={**QUIET, "end_check": end_check, "ssi": 1})
    assert not any(x["fault"] for x in trace)
    reports = [t for t, x in enumerate(trace) if x["report_frame"]]
    assert reports == ([9] if not end_check else [11])
    assert trace[-1]["idle"] == 1


@pytest.mark.parametrize("end_check", (0, 1), ids=("end_check0", "end_check1"))
def test_cycle_controller_ssi_stop_bit_high_is_no_stop(end_check):
    """SSI: a stop bit of 1 is NO_STOP in CLOCK, with or without the end check; no report."""
    steps = SSI_PREFIX + [{"ma_enough": 1}, {"ma_enough": 1, "frame_done": 1, "stop_bit": 1},
                          {}]
    trace = run_clocks(CycleController(), steps, OUTPUTS,
                       defaults={**QUIET, "end_check": end_check, "ssi": 1})
    faults = [(t, STATUS_NAME[x["fault_status"]]) for t, x in enumerate(trace) if x["fault"]]
    assert faults == [(7, "NO_STOP")]
    assert not any(x["report_frame"] for x in trace)
    assert trace[7]["timer_clear"] == 1 and trace[8]["resync"] == 1       # to BREAK


def test_cycle_controller_ssi_break_waits_for_the_timeout_limit_too():
    """SSI: BREAK (after an abort here) ends only with both ``break_over`` and
    ``timeout_over``; BiSS: ``break_over`` alone."""
    for ssi in (0, 1):
        steps = SSI_PREFIX + [{"abort": 1}, {}, {"break_over": 1}, {"break_over": 1},
                              {"break_over": 1, "timeout_over": 1}, {}]
        trace = run_clocks(CycleController(), steps, OUTPUTS, defaults={**QUIET, "ssi": ssi})
        assert STATUS_NAME[trace[6]["fault_status"]] == "ABORTED" and trace[6]["fault"]
        states = [state(x) for x in trace[7:]]
        if ssi:
            assert states == ["BREAK"] * 4 + ["IDLE"]
        else:
            assert states == ["BREAK"] * 2 + ["IDLE"] * 3
