"""The frame-by-frame course of a register access: the FSM of the control channel."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from .cdm_sender import SEND_CONTROL, CdmSource
from .cds_checker import CHECK_CONTROL
from ..layouts import BUFFER_ADDRESS_BITS, access_request_layout, access_result_layout
from ..params import AccessStatus

#: The header's CDM bits after S: CTS, ID[2:0], ADR[6:0], CRC4[3:0], R, W (then S of register 0).
HEADER_FRAMES = 18
#: Frames of one register, from its S to its P: S, 8 data, 4 CRC, P (the slave start bit comes in
#: the CDS of the frame after S; a read may delay it).
REGISTER_FRAMES = 14


class AccessSequencer(wiring.Component):
    """Leads one register access through its frames and decides how it ends.

    The frames, the checks and the ends are those of :class:`~bissmaster.control.register_access.
    RegisterAccess` (its docstring is the contract). This block owns the decisions: the state
    (``IDLE``, ``LEAD`` (idle frames before S), ``HEADER``, ``REGISTER``, ``WAIT`` (a read's
    late start bit), ``FINAL`` (the echo of the last P), ``CANCEL``), the frame within the
    header or the register (``step``), the register in progress (``index``), the request
    latched at ``start``, and the result. Every frame it tells the sender which bit to send
    next and what to load or shift (``send``), the checker which CDS bit to take (``check``),
    and the buffers which byte is due (``index``) and when to store the byte received
    (``store``, a read's byte that passed its checks). It reads the idle counts
    (``run_enough``, ``seen_enough``: :class:`~bissmaster.control.idle_count.IdleCount`) and the
    checker's verdict on the last CRC bit (``crc_ok``, ``echo_ok``).

    Parameters
    ----------
    start_wait_frames : int
        As :class:`~bissmaster.control.register_access.RegisterAccess` (checked there).

    Attributes
    ----------
    request, start, abort, frame_end, frame_ok, frame_cds, frame_cdm, busy, done, result
        The ports of the same names of :class:`~bissmaster.control.register_access.RegisterAccess`.
    run_enough, seen_enough : In(1)
    crc_ok, echo_ok : In(1)
    send : Out(SEND_CONTROL)
    check : Out(CHECK_CONTROL)
    index : Out(6)
    store : Out(1)
    """

    def __init__(self, start_wait_frames):
        self._start_wait = start_wait_frames
        super().__init__({
            "request": In(access_request_layout()),
            "start": In(1),
            "abort": In(1),
            "frame_end": In(1),
            "frame_ok": In(1),
            "frame_cds": In(1),
            "frame_cdm": In(1),
            "run_enough": In(1),
            "seen_enough": In(1),
            "crc_ok": In(1),
            "echo_ok": In(1),
            "busy": Out(1),
            "done": Out(1),
            "result": Out(access_result_layout()),
            "send": Out(SEND_CONTROL),
            "check": Out(CHECK_CONTROL),
            "index": Out(BUFFER_ADDRESS_BITS),
            "store": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        req = Signal(access_request_layout())
        index = self.index                          # the register (byte) in progress
        step = Signal(range(HEADER_FRAMES))         # frame within the header or the register
        waited = Signal(range(self._start_wait + 1))
        ending = Signal(AccessStatus)               # the status a cancel ends with
        frame = self.frame_end
        cds = self.frame_cds
        write = req.write
        send, check = self.send, self.check

        def source(value, crc_bit=None):
            m.d.comb += send.source.eq(value)
            if crc_bit is not None:
                m.d.comb += send.crc_bit.eq(crc_bit)

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
        bad = (count == 0) | (count > protocol.BANK_BYTES) \
            | (last > 2**protocol.CONTROL_ADDRESS_BITS)

        with m.FSM(name="access_fsm") as fsm:
            with m.State("IDLE"):
                with m.If(self.start):
                    with m.If(bad):
                        finish(AccessStatus.BAD_REQUEST)
                        m.d.sync += self.result.bytes_done.eq(0)
                    with m.Else():
                        m.d.sync += [req.eq(self.request), index.eq(0),
                                     self.result.bytes_done.eq(0)]
                        m.d.comb += send.load_header.eq(1)
                        m.next = "LEAD"

            with m.State("LEAD"):
                # Idle frames before S; nothing sent yet, so an abort ends at once, and so does
                # a frame that failed (the data channel is not fit to carry the access).
                with m.If(self.abort):
                    finish(AccessStatus.ABORTED)
                with m.Elif(self.frame_end & ~self.frame_ok):
                    finish(AccessStatus.DATA_FAULT)
                with m.Elif(self.seen_enough):
                    m.d.sync += step.eq(0)
                    m.next = "HEADER"

            with m.State("HEADER"):
                with m.If((step >= 12) & (step < 16)):
                    source(CdmSource.CRC, step[:2])
                with m.Else():
                    source(CdmSource.HEADER)
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
                    m.d.sync += step.eq(step + 1)
                    # The CRC-4 covers CTS, ID and ADR (frames 1 .. 11), not S.
                    m.d.comb += [send.shift_header.eq(1), send.crc_start.eq(step == 0),
                                 send.crc_valid.eq((step >= 1) & (step <= 11))]
                    with m.If(step == HEADER_FRAMES - 1):
                        m.d.sync += step.eq(0)
                        m.next = "REGISTER"

            with m.State("REGISTER"):
                # step: 0 S, 1 .. 8 DATA, 9 .. 12 CRC4, 13 P. The CDS of step k + 1 answers
                # the CDM of step k: start bit in 1, DATA in 2 .. 9, CRC4 in 10 .. 13.
                with m.If(step == 0):
                    source(CdmSource.ONE)
                with m.Elif((step >= 1) & (step <= 8) & write):
                    source(CdmSource.DATA)
                with m.Elif((step >= 9) & (step <= 12) & write):
                    source(CdmSource.CRC, step - 9)
                # The write data's CRC-4, over DATA as sent (steps 1 .. 8).
                m.d.comb += send.crc_valid.eq(frame & (step >= 1) & (step <= 8))
                with m.If(self.abort):
                    cancel(AccessStatus.ABORTED)
                with m.Elif(frame & ~self.frame_ok):
                    cancel(AccessStatus.DATA_FAULT)
                with m.Elif(frame & (step == 0)):
                    # The echo of W (register 0) or of the previous register's P.
                    with m.If(cds != Mux(index == 0, write, 0)):
                        cancel(AccessStatus.REFUSED)
                    with m.Else():
                        m.d.sync += step.eq(1)
                        m.d.comb += [send.load_byte.eq(1), send.crc_start.eq(1)]
                with m.Elif(frame & (step == 1)):
                    m.d.comb += send.shift_byte.eq(1)
                    with m.If(cds):
                        m.d.sync += step.eq(2)
                    with m.Elif(~write):
                        m.d.sync += waited.eq(0)
                        m.next = "WAIT"
                    with m.Else():
                        cancel(AccessStatus.REFUSED)                # no slave start bit
                with m.Elif(frame & (step < REGISTER_FRAMES - 1)):
                    m.d.sync += step.eq(step + 1)
                    m.d.comb += send.shift_byte.eq(1)
                    with m.If(step <= 9):
                        m.d.comb += [check.take_data.eq(1), check.first.eq(step == 2)]
                    with m.Else():
                        m.d.comb += check.take_crc.eq(1)
                with m.Elif(frame):
                    # The last CRC bit: check the byte (the P goes out with this frame).
                    with m.If(~self.crc_ok):
                        cancel(AccessStatus.CRC4_ERROR)
                    with m.Elif(write & ~self.echo_ok):
                        cancel(AccessStatus.REFUSED)                # the slave kept another byte
                    with m.Else():
                        m.d.comb += self.store.eq(~write)
                        m.d.sync += [self.result.bytes_done.eq(index + 1), step.eq(0)]
                        with m.If(index + 1 == req.count):
                            m.next = "FINAL"
                        with m.Else():
                            m.d.sync += index.eq(index + 1)

            with m.State("WAIT"):
                # A read's slave start bit, late: CDM = 1 until it comes.
                source(CdmSource.ONE)
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
                with m.If(self.run_enough):
                    finish(ending)

        m.d.comb += self.busy.eq(~fsm.ongoing("IDLE"))
        return m
