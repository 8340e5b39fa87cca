"""The register-access engine: BiSS C control communication (CDM/CDS) for the host."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from . import protocol
from .control_crc import CRC4
from .layouts import (BUFFER_ADDRESS_BITS, BUFFER_LANES, BUFFER_WORD_BITS, BUFFER_WORDS,
                      access_request_layout, access_result_layout, buffer_write_layout)
from .params import AccessStatus

#: The header's CDM bits after S: CTS, ID[2:0], ADR[6:0], CRC4[3:0], R, W (then S of register 0).
HEADER_FRAMES = 18
#: Frames of one register, from its S to its P: S, 8 data, 4 CRC, P (the slave start bit comes in
#: the CDS of the frame after S; a read may delay it).
REGISTER_FRAMES = 14
_IDLE = protocol.CDM_IDLE_FRAMES


def frame_bound(count, start_wait_frames, write):
    """The most frames (request cycles that end after the clock ``start`` was accepted in, up
    to ``done``) one accepted access of ``count`` registers takes.

    The frames up to the last one that can carry CDM = 1, then the 14 CDM = 0 frames of a
    cancel (an access that ends OK ends before that): 14 idle frames before S, plus one in
    flight when the access starts (an S still under way from an access aborted meanwhile), the
    header (18), the registers before the last one (14 each; a read's 14 plus its start-bit
    wait), the last register up to its last possible CDM = 1 (a write's last CRC bit: 13
    frames; a read's last wait frame: 2 + the wait), and 14. Exact: an access can take that
    many frames (tb/formal, ``access_ends_bound``).
    """
    last = REGISTER_FRAMES - 1 if write else 2 + start_wait_frames
    per_register = REGISTER_FRAMES + (0 if write else start_wait_frames)
    return _IDLE + 1 + HEADER_FRAMES + (count - 1) * per_register + last + _IDLE


class RegisterAccess(wiring.Component):
    """Reads or writes 1 .. 64 consecutive slave registers over the control channel.

    The host sets ``request`` (slave ID 0..7, start address 0..0x7F, byte count 1..64, read or
    write), fills the write buffer for a write (byte ``i`` goes to ``address + i``), and strobes
    ``start``. The engine then supplies one CDM bit per request cycle (``cdm``; the controller
    copies it while idle, so a cycle carries the bit it was accepted with) and takes the CDS bit
    of every reported frame (``frame_*``, in the clock the frame is reported). When the access
    ends, ``done`` strobes with ``result`` (status, bytes done) and the read buffer holds the
    bytes read (index ``i`` from ``address + i``).

    **The buffers** are 16 words of 4 bytes each, little endian: byte ``i`` is byte lane
    ``i % 4`` (bits ``8 (i % 4) + 7 .. 8 (i % 4)``) of word ``i // 4``. The write buffer is
    written a word at a time with a byte enable per lane (``wbuf``); the read buffer is read a
    word at a time through a registered port (``rbuf_addr``, ``rbuf_en`` -> ``rbuf_data``: in a
    clock with ``rbuf_en`` high the word at ``rbuf_addr`` is read, ``rbuf_data`` holds it from
    the next clock until the next read).

    **Frames** (spec section 10; f = 0 is the frame that carries S). Before S, CDM = 0 until 14
    consecutive cycles with CDM = 0 have delivered a good frame (so the encoder saw them: a
    cycle without an answer, NO_ACK, or a BAD_CONFIG report starts the count again; the count
    runs all the time, also between accesses, so an access that follows another does not
    repeat them). A cycle that fails before S ends the access with DATA_FAULT. Then, one CDM
    bit per frame:

    - header, f = 0 .. 17: S=1, CTS=1, ID[2:0], ADR[6:0], CRC4[3:0] (over CTS, ID, ADR), R, W;
    - register ``i`` (``b`` = 18 + 14 i, its S frame): S=1 in ``b``; a write sends DATA[7:0] in
      ``b+1 .. b+8`` and CRC4[3:0] (over DATA) in ``b+9 .. b+12``, a read sends 0 there; P=0 in
      ``b+13``. The next register's S follows in ``b+14`` (sequential access: the slave goes on at
      address + 1), or, after the last one, one more frame with CDM = 0 brings the echo of P.

    CDS checked, frame by frame: IDL0 = 1 in f = 1 (else NO_ANSWER; IDL1..7 and the zeros up to
    f = 16 are not checked: their meaning in chains is unconfirmed); the echo of R in f = 17 and
    of W in f = 18 (else REFUSED); per register the slave's start bit in ``b+1`` (else REFUSED),
    DATA[7:0] in ``b+2 .. b+9`` and CRC4 in ``b+10 .. b+13`` (a read: the bytes; a write: the
    echo of what was sent); the CRC-4 of those 12 bits (else CRC4_ERROR); for a write, the echo
    equal to the byte sent (else REFUSED); the echo of P (0) in the next S frame or the final
    frame (else REFUSED).

    A **read** may find its slave start bit late (the slave's processing time): the engine then
    sends CDM = 1 from the next frame on (it learns of a missing bit only after the frame that
    carried it, so the first frame after S carries 0 as in the standard layout) and waits up to
    ``start_wait_frames`` frames for it; the bytes follow the start bit wherever it comes. A
    **write** sends its DATA without waiting, as in the standard layout: a late start bit is
    REFUSED.

    **Ends**: OK after the final frame; every other outcome after S first cancels the control
    frame: CDM = 0 until 14 consecutive CDM = 0 frames have ended (those that ended before
    count). Before S (nothing sent yet) ``abort`` and a failed frame end at once. ``abort``
    cancels (ABORTED). A frame that carries a control bit and does not end OK (a frame status
    != OK, or a cycle fault) is DATA_FAULT: its CDS and its CDM are not trusted. A request with
    a byte count of 0 or above 64, or whose last address is beyond 0x7F (address wrap is
    unconfirmed), ends at once with BAD_REQUEST. An access takes at most
    :func:`frame_bound` frames. Commands (CTS = 0) are not supported.

    When ``done`` comes, the frames that carried this access's CDM = 1 bits have ended, with
    one exception: an ``abort`` while the frame carrying S is still under way (accepted, not
    yet ended) ends the access at once, since the 14 frames before S carried 0, and ``done``
    (ABORTED) comes before that frame ends. The slave then receives S after ``done``; the next
    access either takes it as its own S (when it is at its header's first frame by then) or,
    as that frame's CDM = 1 restarts the idle count, sends 14 CDM = 0 frames first. (Every
    later CDM = 1 of a frame follows another within 14 frames, so S is the only such case.)

    While ``busy`` (``frames``), the master starts request cycles itself if the host does not.

    Parameters
    ----------
    start_wait_frames : int
        The longest wait for a read's delayed slave start bit, in frames.

    Attributes
    ----------
    request : In(access_request_layout)
        Read when ``start`` is high.
    start, abort : In(1)
        Strobes; ``start`` is ignored while ``busy``.
    wbuf : In(buffer_write_layout)
        The host's write port of the write buffer (16 x 32, a byte enable per lane).
    rbuf_addr : In(4)
    rbuf_en : In(1)
    rbuf_data : Out(32)
        The host's read port of the read buffer (16 x 32), registered.
    busy : Out(1)
    done : Out(1)
        One-clock strobe: the access ended; ``result`` is new in the same clock.
    result : Out(access_result_layout)
        Status and the bytes done (read and checked, or written and echoed), held until the
        next ``done``.
    cdm : Out(1)
        The CDM bit for the next request cycle.
    frames : Out(1)
        The engine needs request cycles (it is busy).
    frame_end : In(1)
        A request cycle ends in this clock (the verdict's ``report``) ...
    frame_ok : In(1)
        ... with a frame and status OK (the verdict's ``valid``) ...
    frame_cds : In(1)
        ... the frame's CDS bit ...
    frame_cdm : In(1)
        ... and the CDM bit that cycle carried (the controller's ``cdm_cycle``).
    """

    def __init__(self, start_wait_frames=16):
        if not isinstance(start_wait_frames, int) or not 1 <= start_wait_frames <= 255:
            raise ValueError(f"start_wait_frames must be an integer from 1 to 255, "
                             f"not {start_wait_frames!r}")
        self._start_wait = start_wait_frames
        super().__init__({
            "request": In(access_request_layout()),
            "start": In(1),
            "abort": In(1),
            "wbuf": In(buffer_write_layout()),
            "rbuf_addr": In(BUFFER_WORD_BITS),
            "rbuf_en": In(1),
            "rbuf_data": Out(BUFFER_LANES * 8),
            "busy": Out(1),
            "done": Out(1),
            "result": Out(access_result_layout()),
            "cdm": Out(1),
            "frames": Out(1),
            "frame_end": In(1),
            "frame_ok": In(1),
            "frame_cds": In(1),
            "frame_cdm": In(1),
        })

    def elaborate(self, platform):
        m = Module()
        depth = protocol.BANK_BYTES

        # The buffers: the host writes bytes to send and reads bytes received, a word (4 byte
        # lanes) at a time; the engine takes and stores one byte (one lane) at a time.
        width = BUFFER_LANES * 8
        m.submodules.wbuf = wbuf = Memory(shape=width, depth=BUFFER_WORDS, init=[])
        host_write = wbuf.write_port(granularity=8)
        word_to_send = wbuf.read_port()
        m.submodules.rbuf = rbuf = Memory(shape=width, depth=BUFFER_WORDS, init=[])
        byte_received = rbuf.write_port(granularity=8)
        host_read = rbuf.read_port()
        m.d.comb += [
            host_write.addr.eq(self.wbuf.addr), host_write.data.eq(self.wbuf.data),
            host_write.en.eq(self.wbuf.en),
            host_read.addr.eq(self.rbuf_addr), host_read.en.eq(self.rbuf_en),
            self.rbuf_data.eq(host_read.data),
        ]

        # CRC-4 of the bits sent (header, write data) and of the bits received (data, echo).
        # The control channel's CRC-4 (control_crc.CRC4), bit-serial, one per direction.
        m.submodules.tx_crc = tx_crc = CRC4(data_width=1).create()
        m.submodules.rx_crc = rx_crc = CRC4(data_width=1).create()

        req = Signal(access_request_layout())
        index = Signal(BUFFER_ADDRESS_BITS)         # the register (byte) in progress
        step = Signal(range(HEADER_FRAMES))         # frame within the header or the register
        header = Signal(HEADER_FRAMES)              # the header's CDM bits, MSB first
        to_send = Signal(8)                         # the write byte, shifted out MSB first
        sent = Signal(8)                            # the write byte, kept for the echo
        got = Signal(8)                             # DATA bits received, MSB first
        got_crc = Signal(protocol.CRC4_WIDTH - 1)   # the first three CRC bits received
        waited = Signal(range(self._start_wait + 1))
        ending = Signal(AccessStatus)               # the status a cancel ends with
        lane = index[:2]                            # the byte's lane in its buffer word
        lane_enable = Cat(lane == k for k in range(BUFFER_LANES))
        m.d.comb += word_to_send.addr.eq(index[2:])
        byte_to_send = word_to_send.data.word_select(lane, 8)

        # Consecutive ended cycles with CDM = 0, up to 14: always counted. ``idle_run`` counts
        # every reported cycle (a cancel's 14 zeros: best effort, bounded even when the encoder
        # stopped answering); ``idle_seen`` only cycles that delivered a good frame, so the
        # encoder certainly saw their CDM = 0 (a NO_ACK cycle or a BAD_CONFIG report restarts
        # it): S is sent only after 14 of those.
        def run_after(run, reset):
            return Mux(reset, 0, Mux(run == _IDLE, _IDLE, run + 1))

        idle_run = Signal(range(_IDLE + 1))
        idle_seen = Signal(range(_IDLE + 1))
        idle_after = run_after(idle_run, self.frame_cdm)
        seen_after = run_after(idle_seen, self.frame_cdm | ~self.frame_ok)
        with m.If(self.frame_end):
            m.d.sync += [idle_run.eq(idle_after), idle_seen.eq(seen_after)]
        idle_enough = Mux(self.frame_end, idle_after, idle_run) == _IDLE
        seen_enough = Mux(self.frame_end, seen_after, idle_seen) == _IDLE

        frame = self.frame_end
        cds = self.frame_cds
        write = req.write
        # The CRC bit ``k`` (0 = first sent, the MSB) of the bits sent so far.
        def tx_crc_bit(k):
            return tx_crc.crc.bit_select(~k[:2], 1)

        m.d.sync += self.done.eq(0)

        def finish(status):
            m.d.sync += [self.done.eq(1), self.result.status.eq(status)]
            m.next = "IDLE"

        def cancel(status):
            m.d.sync += ending.eq(status)
            m.next = "CANCEL"

        # The request's bounds: 1 .. 64 bytes, the last address at most 0x7F.
        count = self.request.count
        last = self.request.address + count
        bad = (count == 0) | (count > depth) | (last > 2**protocol.CONTROL_ADDRESS_BITS)

        with m.FSM(name="access_fsm") as fsm:
            with m.State("IDLE"):
                with m.If(self.start):
                    with m.If(bad):
                        finish(AccessStatus.BAD_REQUEST)
                        m.d.sync += self.result.bytes_done.eq(0)
                    with m.Else():
                        m.d.sync += [
                            req.eq(self.request), index.eq(0), self.result.bytes_done.eq(0),
                            header.eq(Cat(self.request.write, ~self.request.write,
                                          C(0, protocol.CRC4_WIDTH), self.request.address,
                                          self.request.slave_id, C(1, 1), C(1, 1))),
                        ]
                        m.next = "LEAD"

            with m.State("LEAD"):
                # Idle frames before S; nothing sent yet, so an abort ends at once, and so does
                # a frame that failed (the data channel is not fit to carry the access).
                with m.If(self.abort):
                    finish(AccessStatus.ABORTED)
                with m.Elif(self.frame_end & ~self.frame_ok):
                    finish(AccessStatus.DATA_FAULT)
                with m.Elif(seen_enough):
                    m.d.sync += step.eq(0)
                    m.next = "HEADER"

            with m.State("HEADER"):
                m.d.comb += self.cdm.eq(Mux((step >= 12) & (step < 16), tx_crc_bit(step[:2]),
                                            header[-1]))
                with m.If(self.abort):
                    cancel(AccessStatus.ABORTED)
                with m.Elif(frame & (step == 0) & ~self.frame_cdm):
                    pass        # a cycle accepted before S was due: one more idle frame
                with m.Elif(frame & ~self.frame_ok):
                    cancel(AccessStatus.DATA_FAULT)
                with m.Elif(frame & (step == 1) & ~cds):
                    cancel(AccessStatus.NO_ANSWER)                  # no IDL0
                with m.Elif(frame & (step == HEADER_FRAMES - 1) & (cds == write)):
                    cancel(AccessStatus.REFUSED)                    # no echo of R
                with m.Elif(frame):
                    m.d.sync += [header.eq(header << 1), step.eq(step + 1)]
                    # The CRC-4 covers CTS, ID and ADR (frames 1 .. 11), not S.
                    m.d.comb += [tx_crc.start.eq(step == 0),
                                 tx_crc.valid.eq((step >= 1) & (step <= 11)),
                                 tx_crc.data.eq(header[-1])]
                    with m.If(step == HEADER_FRAMES - 1):
                        m.d.sync += step.eq(0)
                        m.next = "REGISTER"

            with m.State("REGISTER"):
                # step: 0 S, 1 .. 8 DATA, 9 .. 12 CRC4, 13 P. The CDS of step k + 1 answers
                # the CDM of step k: start bit in 1, DATA in 2 .. 9, CRC4 in 10 .. 13.
                with m.If(step == 0):
                    m.d.comb += self.cdm.eq(1)
                with m.Elif((step >= 1) & (step <= 8)):
                    m.d.comb += self.cdm.eq(write & to_send[-1])
                with m.Elif((step >= 9) & (step <= 12)):
                    m.d.comb += self.cdm.eq(write & tx_crc_bit(step - 9))
                # The write data's CRC-4, over DATA as sent (steps 1 .. 8).
                m.d.comb += [tx_crc.data.eq(to_send[-1]),
                             tx_crc.valid.eq(frame & (step >= 1) & (step <= 8))]
                crc_received = Cat(cds, got_crc)
                with m.If(self.abort):
                    cancel(AccessStatus.ABORTED)
                with m.Elif(frame & ~self.frame_ok):
                    cancel(AccessStatus.DATA_FAULT)
                with m.Elif(frame & (step == 0)):
                    # The echo of W (register 0) or of the previous register's P.
                    with m.If(cds != Mux(index == 0, write, 0)):
                        cancel(AccessStatus.REFUSED)
                    with m.Else():
                        m.d.sync += [to_send.eq(byte_to_send), sent.eq(byte_to_send),
                                     step.eq(1)]
                        m.d.comb += tx_crc.start.eq(1)
                with m.Elif(frame & (step == 1)):
                    m.d.sync += to_send.eq(to_send << 1)
                    with m.If(cds):
                        m.d.sync += step.eq(2)
                    with m.Elif(~write):
                        m.d.sync += waited.eq(0)
                        m.next = "WAIT"
                    with m.Else():
                        cancel(AccessStatus.REFUSED)                # no slave start bit
                with m.Elif(frame & (step < REGISTER_FRAMES - 1)):
                    m.d.sync += [to_send.eq(to_send << 1), step.eq(step + 1)]
                    with m.If(step <= 9):
                        m.d.sync += got.eq(Cat(cds, got))
                        m.d.comb += [rx_crc.start.eq(step == 2), rx_crc.valid.eq(1),
                                     rx_crc.data.eq(cds)]
                    with m.Else():
                        m.d.sync += got_crc.eq(Cat(cds, got_crc))
                with m.Elif(frame):
                    # The last CRC bit: check the byte (the P goes out with this frame).
                    with m.If(crc_received != rx_crc.crc):
                        cancel(AccessStatus.CRC4_ERROR)
                    with m.Elif(write & (got != sent)):
                        cancel(AccessStatus.REFUSED)                # the slave kept another byte
                    with m.Else():
                        m.d.comb += [byte_received.addr.eq(index[2:]),
                                     byte_received.data.eq(got.replicate(BUFFER_LANES)),
                                     byte_received.en.eq(Mux(write, 0, lane_enable))]
                        m.d.sync += [self.result.bytes_done.eq(index + 1), step.eq(0)]
                        with m.If(index + 1 == req.count):
                            m.next = "FINAL"
                        with m.Else():
                            m.d.sync += index.eq(index + 1)

            with m.State("WAIT"):
                # A read's slave start bit, late: CDM = 1 until it comes.
                m.d.comb += self.cdm.eq(1)
                with m.If(self.abort):
                    cancel(AccessStatus.ABORTED)
                with m.Elif(frame & ~self.frame_ok):
                    cancel(AccessStatus.DATA_FAULT)
                with m.Elif(frame & cds):
                    m.d.sync += step.eq(2)
                    m.next = "REGISTER"
                with m.Elif(frame):
                    m.d.sync += waited.eq(waited + 1)
                    with m.If(waited == self._start_wait - 1):
                        cancel(AccessStatus.REFUSED)

            with m.State("FINAL"):
                # CDM = 0; the CDS is the echo of the last P.
                with m.If(self.abort):
                    cancel(AccessStatus.ABORTED)
                with m.Elif(frame & ~self.frame_ok):
                    cancel(AccessStatus.DATA_FAULT)
                with m.Elif(frame & cds):
                    cancel(AccessStatus.REFUSED)
                with m.Elif(frame):
                    finish(AccessStatus.OK)

            with m.State("CANCEL"):
                # CDM = 0 until 14 consecutive CDM = 0 frames have ended.
                with m.If(idle_enough):
                    finish(ending)

        m.d.comb += [self.busy.eq(~fsm.ongoing("IDLE")), self.frames.eq(self.busy)]
        return m
