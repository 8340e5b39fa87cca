"""RegisterAccess on Amaranth's simulator: register reads and writes over the control channel,
frame by frame, against a small slave written from docs/protocol.md (section 10) in
tb/testkit/control_slave.py.

Cycle conventions: ``block_sim.py``. The bench plays the master's side of the frame interface:
a request cycle every few clocks, which takes the engine's ``cdm`` while "idle" (like the
controller's copy) and reports the frame a few clocks later (``frame_end`` with the frame's
CDS, its status OK or not, and the CDM bit it carried). The slave answers the CDM of frame n in
the CDS of frame n + 1. Status codes are the test side's own table (docs/control.md);
nothing is imported from the RTL but the block under test.
"""

import pytest

from bissmaster.control.register_access import RegisterAccess

from testkit.block_sim import simulate
from testkit.control_slave import (ABORTED, BAD_REQUEST, CRC4_ERROR, DATA_FAULT, IDLE_FRAMES,
                                    NO_ANSWER, OK, REFUSED, START_WAIT, Slave, bits_of, crc4)


def test_crc4_reference_detects_single_bit_errors():
    data = bits_of(0x5A, 8)
    sent = crc4(data)
    for i in range(8):
        flipped = list(data)
        flipped[i] ^= 1
        assert crc4(flipped) != sent


FRAME_CLOCKS = 5        # one request cycle of the bench: accept, 3 clocks, report


def run_access(slave, requests, *, frames=160, faults=(), aborts=(), wbuf=None,
               start_wait=START_WAIT, read_back=64):
    """Frames one after the other; ``requests``: {frame index: request dict} (start strobed in
    the frame's first clock, or in its clock ``"clock"``); ``faults``: frame indices reported not OK; ``aborts``: frame
    indices whose second clock strobes ``abort``. Returns the done events (frame, status,
    bytes done), the CDM bit of every frame, the ``busy`` per frame, and the read buffer."""
    dut = RegisterAccess(start_wait)
    out = {"done": [], "cdm": [], "busy": [], "frames_out": [], "rbuf": []}

    async def tb(ctx):
        # One byte per write, its own lane enabled: the other lanes of the word keep theirs.
        for i, byte in enumerate(wbuf or []):
            ctx.set(dut.wbuf.addr, i // 4)
            ctx.set(dut.wbuf.data, (0xFFFFFFFF & ~(0xFF << 8 * (i % 4))) | byte << 8 * (i % 4))
            ctx.set(dut.wbuf.en, 1 << i % 4)
            await ctx.tick()
        ctx.set(dut.wbuf.en, 0)
        for n in range(frames):
            req = requests.get(n)
            cdm = None
            for c in range(FRAME_CLOCKS):
                start = req is not None and c == req.get("clock", 0)
                if start:
                    ctx.set(dut.request.slave_id, req.get("slave_id", 0))
                    ctx.set(dut.request.address, req["address"])
                    ctx.set(dut.request.count, req["count"])
                    ctx.set(dut.request.write, int(req.get("write", False)))
                ctx.set(dut.start, int(start))
                ctx.set(dut.abort, int(c == 1 and n in aborts))
                if c == 1:
                    cdm = ctx.get(dut.cdm)              # the controller's copy: accepted here
                    out["busy"].append(ctx.get(dut.busy))
                    out["frames_out"].append(ctx.get(dut.frames))
                report = c == FRAME_CLOCKS - 1
                ctx.set(dut.frame_end, int(report))
                ctx.set(dut.frame_ok, int(report and n not in faults))
                ctx.set(dut.frame_cds, int(report and slave.cds()))
                ctx.set(dut.frame_cdm, int(report and cdm))
                if ctx.get(dut.done):       # registered: in frame n's first clock from n - 1
                    out["done"].append((n - 1 if c == 0 else n, ctx.get(dut.result.status),
                                        ctx.get(dut.result.bytes_done)))
                await ctx.tick()
            out["cdm"].append(cdm)
            if n not in faults:
                slave.take(cdm)
            else:
                slave.take(0)           # a failed frame: MA high, the slave sees CDM = 0
        ctx.set(dut.frame_end, 0)
        # Words of 4 bytes, little endian (byte i in lane i % 4 of word i // 4).
        ctx.set(dut.rbuf_en, 1)
        for w in range(-(-read_back // 4)):
            ctx.set(dut.rbuf_addr, w)
            await ctx.tick()
            word = ctx.get(dut.rbuf_data)
            out["rbuf"] += [(word >> 8 * k) & 0xFF for k in range(4)][:read_back - 4 * w]

    simulate(dut, tb)
    return out


def _zeros_before_first_one(cdm):
    return cdm.index(1) if 1 in cdm else len(cdm)


# -- Reads and writes ----------------------------------------------------------------------------

def test_read_one_register_frame_layout_and_data():
    """A single read: 14 idle frames, then S, CTS, ID, ADR, CRC4, R, W, S, 12 zeros, P (spec
    section 10), the byte in the read buffer, OK after the frame that brings the echo of P."""
    slave = Slave({0x42: 0x62})
    out = run_access(slave, {0: {"address": 0x42, "count": 1}}, frames=60)
    assert out["done"] and out["done"][0][1:] == (OK, 1)
    cdm = out["cdm"]
    s0 = _zeros_before_first_one(cdm)
    assert s0 == IDLE_FRAMES
    header = [1, 1] + bits_of(0, 3) + bits_of(0x42, 7)
    expect = header + crc4(header[1:]) + [1, 0, 1] + [0] * 12 + [0]
    assert cdm[s0:s0 + 32] == expect
    # Done with the frame after P (s0 + 32): the echo of P.
    assert out["done"][0][0] == s0 + 32
    assert out["rbuf"][0] == 0x62


def test_write_one_register():
    slave = Slave({0x40: 0x00})
    out = run_access(slave, {0: {"address": 0x40, "count": 1, "write": True}}, frames=60,
                     wbuf=[0xA5])
    assert out["done"][0][1:] == (OK, 1)
    cdm = out["cdm"]
    s0 = _zeros_before_first_one(cdm)
    header = [1, 1] + bits_of(0, 3) + bits_of(0x40, 7)
    data = bits_of(0xA5, 8)
    assert cdm[s0:s0 + 32] == header + crc4(header[1:]) + [0, 1, 1] + data + crc4(data) + [0]
    assert slave.regs[0x40] == 0xA5


@pytest.mark.parametrize("count", (2, 64))
def test_sequential_read(count):
    """Sequential access: after P, S again for the next address, 14 frames per register."""
    regs = {i: (i * 37 + 5) & 0xFF for i in range(0x80)}
    address = 0x10 if count == 2 else 0x00
    slave = Slave(regs)
    frames = IDLE_FRAMES + 33 + 14 * (count - 1) + 4
    out = run_access(slave, {0: {"address": address, "count": count}}, frames=frames)
    assert out["done"][0][1:] == (OK, count)
    s0 = IDLE_FRAMES
    assert out["done"][0][0] == s0 + 32 + 14 * (count - 1)
    assert out["rbuf"][:count] == [regs[address + i] for i in range(count)]
    # Every register: S, 12 zeros, P.
    cdm = out["cdm"]
    for i in range(count):
        b = s0 + 18 + 14 * i
        assert cdm[b:b + 14] == [1] + [0] * 13, i


def test_sequential_write_two():
    slave = Slave({0x20: 0, 0x21: 0})
    out = run_access(slave, {0: {"address": 0x20, "count": 2, "write": True}}, frames=80,
                     wbuf=[0x12, 0xFE])
    assert out["done"][0][1:] == (OK, 2)
    assert slave.regs[0x20] == 0x12 and slave.regs[0x21] == 0xFE


def test_following_access_does_not_repeat_idle_frames():
    """The 14 idle frames are counted across accesses: a read ends with 13 zeros + the final
    frame, so the next read starts its S in the next frame."""
    slave = Slave({1: 0x11, 2: 0x22})
    out = run_access(slave, {0: {"address": 1, "count": 1}, 48: {"address": 2, "count": 1}},
                     frames=100)
    assert [d[1:] for d in out["done"]] == [(OK, 1), (OK, 1)]
    first_done = out["done"][0][0]
    assert first_done == IDLE_FRAMES + 32
    # Started in frame 48: S in frame 49 (the frame in flight at the start carries 0).
    assert out["cdm"][48] == 0 and out["cdm"][49] == 1
    assert out["rbuf"][0] == 0x22


def test_slave_id_is_sent():
    slave = Slave({5: 0x55}, slave_id=3)
    out = run_access(slave, {0: {"address": 5, "count": 1, "slave_id": 3}}, frames=60)
    assert out["done"][0][1:] == (OK, 1)
    s0 = IDLE_FRAMES
    assert out["cdm"][s0 + 2:s0 + 5] == [0, 1, 1]


# -- Faults ----------------------------------------------------------------------------------------

def _cancelled(out, status, *, frames_after=None):
    """Ended with ``status`` after a cancel: the last 14 frames before ``done`` carried CDM 0."""
    (n, got, _), = out["done"]
    assert got == status
    assert out["cdm"][n - IDLE_FRAMES + 1:n + 1] == [0] * IDLE_FRAMES
    return n


def test_no_answer_from_a_unidirectional_encoder():
    """CDS always 0 (RESOLUTE, EVOLUTE): no IDL0 in s0 + 1."""
    out = run_access(Slave(answers=False), {0: {"address": 0x42, "count": 1}}, frames=60)
    n = _cancelled(out, NO_ANSWER)
    assert n == IDLE_FRAMES + 1 + IDLE_FRAMES


def test_refused_write_to_read_only_register():
    out = run_access(Slave({0x41: 7}, read_only={0x41}),
                     {0: {"address": 0x41, "count": 1, "write": True}}, frames=80, wbuf=[1])
    _cancelled(out, REFUSED)


def test_refused_wrong_slave_id():
    out = run_access(Slave({0x41: 7}, slave_id=0), {0: {"address": 0x41, "count": 1,
                                                         "slave_id": 2}}, frames=80)
    _cancelled(out, REFUSED)


def test_refused_write_echoed_with_another_byte():
    """A slave that keeps its byte and echoes it (with its CRC-4) instead of the one sent: a
    consistent echo of another byte is REFUSED, not a CRC-4 error."""
    slave = Slave({0x30: 0x00}, echo_old=True)
    out = run_access(slave, {0: {"address": 0x30, "count": 1, "write": True}}, frames=80,
                     wbuf=[0x33])
    _cancelled(out, REFUSED)
    assert out["done"][0][2] == 0 and slave.regs[0x30] == 0


def test_crc4_error_on_a_read_byte():
    out = run_access(Slave({0x10: 0x99, 0x11: 0x98}, bad_crc_at=0x11),
                     {0: {"address": 0x10, "count": 2}}, frames=100)
    n = _cancelled(out, CRC4_ERROR)
    assert out["done"][0][2] == 1                   # the first byte was good
    assert out["rbuf"][0] == 0x99


@pytest.mark.parametrize("delay", (1, START_WAIT))
def test_read_with_a_late_start_bit(delay):
    """The slave's processing time: the start bit comes ``delay`` frames late; the engine keeps
    CDM = 1 from the frame after the expected start bit and reads on."""
    slave = Slave({0x43: 0x2A}, delay=delay)
    out = run_access(slave, {0: {"address": 0x43, "count": 1}}, frames=70)
    assert out["done"][0][1:] == (OK, 1)
    assert out["rbuf"][0] == 0x2A
    s0 = IDLE_FRAMES
    cdm = out["cdm"]
    # S (s0+18), 0 in s0+19 (the expected start bit's frame), then 1 until the start bit is seen.
    assert cdm[s0 + 18:s0 + 20] == [1, 0]
    assert cdm[s0 + 20:s0 + 20 + delay] == [1] * delay
    assert cdm[s0 + 20 + delay:s0 + 32 + delay] == [0] * 12
    assert out["done"][0][0] == s0 + 32 + delay


def test_frame_bound_start_bit_never_comes():
    """The start bit later than the wait: REFUSED, cancelled; the access takes the documented
    bound of a one-register read (docs/control.md: 14 idle, 1 in flight at the start,
    18 header, S, the expected start bit's frame and the wait, 14 zeros) but for the cycle in
    flight at the start, which this access has not: frames 0 .. n have ended."""
    slave = Slave({0x43: 0x2A}, delay=START_WAIT + 5)
    out = run_access(slave, {0: {"address": 0x43, "count": 1}}, frames=90)
    n = _cancelled(out, REFUSED)
    bound = IDLE_FRAMES + 1 + 18 + 2 + START_WAIT + IDLE_FRAMES
    assert n + 1 == bound - 1


def test_frame_bound_of_a_write_is_reached():
    """The write bound of docs/control.md, reached: 14 idle, 1 in flight at the start,
    18 header, 13 frames to the last CRC bit (a 1: the CRC-4 of byte 0 is sent as 1111), 14
    zeros. An access is aborted in the clock its S cycle is accepted: it ends at once (the 14
    frames before S carried 0) while S is on its way; a one-byte write starts in that ``done``
    clock, sees S end (its idle count starts again), sends 14 zeros and its frame, and its P
    frame fails: DATA_FAULT after 14 zeros from the last 1."""
    s0 = IDLE_FRAMES
    at = s0 + 1 + IDLE_FRAMES + 18 + 13   # the write's P frame
    out = run_access(Slave({0x40: 0}), {0: {"address": 0x42, "count": 1},
                                         s0: {"address": 0x40, "count": 1, "write": True,
                                              "clock": 3}},
                     aborts={s0}, faults={at}, frames=at + 20, wbuf=[0])
    assert out["cdm"][s0] == 1                                  # S of the first access
    assert [d[:2] for d in out["done"]] == [(s0, ABORTED), (at + IDLE_FRAMES - 1, DATA_FAULT)]
    assert out["cdm"][at - 1] == 1 and not any(out["cdm"][at:at + IDLE_FRAMES])
    ended = out["done"][1][0] - s0 + 1          # frames s0 (the S, ended after the start) ..
    assert ended == IDLE_FRAMES + 1 + 18 + 13 + IDLE_FRAMES == 60


def test_write_does_not_wait_for_a_late_start_bit():
    out = run_access(Slave({0x40: 0}, delay=1), {0: {"address": 0x40, "count": 1,
                                                      "write": True}}, frames=80, wbuf=[3])
    _cancelled(out, REFUSED)


@pytest.mark.parametrize("at", (IDLE_FRAMES + 5, IDLE_FRAMES + 25))
def test_abort_mid_frame_then_recovery(at):
    """``abort`` in the middle of a control frame: 14 frames of CDM = 0, ABORTED; the slave has
    cancelled, and the next read works."""
    slave = Slave({0x42: 0x62, 0x43: 0x05})
    out = run_access(slave, {0: {"address": 0x42, "count": 1}, at + 20: {"address": 0x43,
                                                                           "count": 1}},
                     aborts={at}, frames=at + 20 + 60)
    assert [d[1] for d in out["done"]] == [ABORTED, OK]
    n = out["done"][0][0]
    assert out["cdm"][n - IDLE_FRAMES + 1:n + 1] == [0] * IDLE_FRAMES
    assert out["rbuf"][0] == 0x05


def test_abort_before_s_ends_at_once():
    out = run_access(Slave(), {0: {"address": 0x42, "count": 1}}, aborts={3}, frames=10)
    assert out["done"] == [(3, ABORTED, 0)]
    assert 1 not in out["cdm"]


@pytest.mark.parametrize("at", (IDLE_FRAMES + 3, IDLE_FRAMES + 20))
def test_data_fault_cancels(at):
    """A frame carrying a control bit that does not end OK: DATA_FAULT once 14 consecutive
    frames with CDM = 0 have ended (in a read's zeros, those already sent count), and the
    slave is ready for the next access."""
    slave = Slave({0x42: 0x62, 0x43: 0x44})
    out = run_access(slave, {0: {"address": 0x42, "count": 1}, 90: {"address": 0x43, "count": 1}},
                     faults={at}, frames=140)
    assert [d[1] for d in out["done"]] == [DATA_FAULT, OK]
    n = out["done"][0][0]
    assert n >= at and out["cdm"][n - IDLE_FRAMES + 1:n + 1] == [0] * IDLE_FRAMES
    assert 1 not in out["cdm"][at + 1:n + 1]
    assert out["rbuf"][0] == 0x44


@pytest.mark.parametrize("address, count", [(0, 0), (0, 65), (0x7F, 2), (0x70, 17)])
def test_bad_request(address, count):
    out = run_access(Slave(), {0: {"address": address, "count": count}}, frames=4)
    assert out["done"] == [(0, BAD_REQUEST, 0)]
    assert out["busy"] == [0] * 4 and 1 not in out["cdm"]


def test_largest_good_request_is_accepted():
    out = run_access(Slave({0x7F: 9}), {0: {"address": 0x7F, "count": 1}}, frames=50)
    assert out["done"][0][1:] == (OK, 1) and out["rbuf"][0] == 9


def test_frames_wanted_while_busy():
    out = run_access(Slave({1: 1}), {0: {"address": 1, "count": 1}}, frames=50)
    n = out["done"][0][0]
    assert out["frames_out"] == out["busy"]
    assert out["busy"][1:n + 1] == [1] * n and out["busy"][n + 1:] == [0] * (49 - n)
