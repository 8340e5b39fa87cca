"""The control channel through the whole ``BissMaster``: a register read over real request
cycles, and MA clock by clock around every CDM = 1 hold.

The encoder is the limits bench's (tb/testkit/limits_bench.py) with the control side of
the test side's slave (tb/testkit/control_slave.py): the CDS slot of every frame is the slave's answer, and the
slave reads the CDM as the inverted MA level in the clock its timeout ends (docs/protocol.md, section 10).
Expected timing from docs/timing.md ("CDM"): MA falls where the next period would have begun
(m = last rise + hp), rises 3 clocks after the SLO pin is high again (2 synchronizer clocks,
then the MaClock register), stays high one half period, and the next cycle's first fall comes
hp + 4 clocks after that rise at the earliest.
"""

from testkit.control_slave import OK, RELEASE, ROUND_TRIP, ControlEncoder, Slave
from testkit.limits_bench import FRAME, base_config, simulate

HP = 2


def _read(address, regs, clocks):
    slave = Slave(regs)
    enc = ControlEncoder(hp=HP, bits=list(FRAME), ack_slots=1, round_trip=ROUND_TRIP,
                         release=RELEASE, slave=slave)
    cfg = base_config(hp=HP, cfg_break_time=3)
    ca = {}

    def drive(t, run):
        if t == 60:                                     # after the power-up break
            return {"ca_address": address, "ca_count": 1, "ca_start": 1}
        if t == 61:
            return {"ca_start": 0}
        return {}

    from testkit import limits_bench
    old = limits_bench.TRACE
    limits_bench.TRACE = old + ("ca_busy", "ca_done", "ca_status", "slo")
    try:
        run = simulate(cfg, enc, clocks, drive)
    finally:
        limits_bench.TRACE = old
    return run, enc, slave


def _phases(ma):
    out, start = [], 0
    for t in range(1, len(ma) + 1):
        if t == len(ma) or ma[t] != ma[start]:
            out.append((ma[start], start, t - start))
            start = t
    return out


def test_register_read_through_the_master_and_ma_around_every_hold():
    run, enc, slave = _read(0x42, {0x42: 0x62}, 6500)
    tr = run.trace
    dones = [t for t, x in enumerate(tr) if x["ca_done"]]
    assert len(dones) == 1 and tr[dones[0]]["ca_status"] == OK
    # Every data frame still delivered and checked its position.
    assert all(s == 0 for _, s in run.dones)
    ma = [x["ma"] for x in tr]
    # No MA phase shorter than the half period; MA high whenever the master is idle.
    for level, start, length in _phases(ma)[1:-1]:
        assert length >= HP, (level, start, length)
    assert all(x["ma"] for x in tr if not x["busy"])
    # The slave read the header's CDM bits as the engine sent them: 14 zeros, then S, CTS, ...
    cdm = [1 - level for _, level in enc.timeout_ends]
    s0 = cdm.index(1)
    assert s0 >= 14 and cdm[s0:s0 + 2] == [1, 1]
    holds = [(start, length) for level, start, length in _phases(ma) if level == 0
             and length > HP]
    assert len(holds) == sum(cdm), "one hold per CDM = 1"
    rises = run.rises
    for start, length in holds:
        # MA falls where the next period would have begun: the last rise + hp.
        last_rise = max(r for r in rises if r < start)
        assert start == last_rise + HP
        # MA rises 3 clocks after the SLO pin is high again (the encoder's timeout ended).
        # (The frame's last bits may still be on the pin at m: the timeout's end is the
        # encoder's SLO rise, on the pin ROUND_TRIP clocks later.)
        rise = start + length
        ended = next(t for t, _ in enc.timeout_ends if t >= start - ROUND_TRIP)
        pin_high = ended + ROUND_TRIP
        assert all(tr[t]["slo"] == 0 for t in range(pin_high - 3, pin_high))
        assert tr[pin_high]["slo"] == 1
        assert rise == pin_high + 3
        # One half period high at least, and the next cycle's first fall hp + 4 after the rise.
        next_fall = next((t for t in range(rise, len(ma)) if not ma[t]), None)
        if next_fall is not None:
            assert next_fall - rise >= HP + 4
    # In this run the cycles follow as fast as the encoder allows: exactly hp + 4.
    gaps = [next(t for t in range(s + n, len(ma)) if not ma[t]) - (s + n)
            for s, n in holds[:-1]]
    assert set(gaps) == {HP + 4}
    assert slave.regs[0x42] == 0x62


def test_cdm0_frames_idle_high_after_the_frame():
    """Without an access every frame carries CDM = 0: MA high from m on (today's timing)."""
    slave = Slave()
    enc = ControlEncoder(hp=HP, bits=list(FRAME), ack_slots=1, round_trip=ROUND_TRIP,
                         release=RELEASE, slave=slave)
    cfg = base_config(hp=HP, cfg_break_time=3)
    run = simulate(cfg, enc, 1200, lambda t, r: {"periodic": int(t >= 60)})
    assert all(level == 1 for _, level in enc.timeout_ends) and len(enc.timeout_ends) >= 5
    ma = [x["ma"] for x in run.trace]
    for level, start, length in _phases(ma)[1:-1]:
        assert length == HP if level == 0 else length >= HP
