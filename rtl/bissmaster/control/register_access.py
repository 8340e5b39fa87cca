"""The register-access engine: BiSS C control communication (CDM/CDS) for the host."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .. import protocol
from .access_buffers import AccessBuffers
from .access_sequencer import HEADER_FRAMES, REGISTER_FRAMES, AccessSequencer
from .cdm_sender import CdmSender
from .cds_checker import CdsChecker
from .idle_count import IdleCount
from ..layouts import (BUFFER_LANES, BUFFER_WORD_BITS, access_request_layout,
                      access_result_layout, buffer_write_layout)

__all__ = ["HEADER_FRAMES", "REGISTER_FRAMES", "RegisterAccess", "frame_bound"]

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

    **Frames** (docs/protocol.md, section 10; f = 0 is the frame that carries S). Before S, CDM = 0 until 14
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

    **Inside**: :class:`~bissmaster.control.access_sequencer.AccessSequencer` leads the access frame by
    frame and decides how it ends; :class:`~bissmaster.control.cdm_sender.CdmSender` holds the bits
    sent (header, write byte, their CRC-4) and puts the one due on ``cdm``;
    :class:`~bissmaster.control.cds_checker.CdsChecker` collects a register's CDS bits and checks their
    CRC-4 and a write's echo; :class:`~bissmaster.control.idle_count.IdleCount` counts the CDM = 0
    frames; :class:`~bissmaster.control.access_buffers.AccessBuffers` holds the bytes.

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
        ... with a frame that passed every check, status OK or UNCONFIRMED (the verdict's
        ``passed``) ...
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
        m.submodules.sequencer = sequencer = AccessSequencer(self._start_wait)
        m.submodules.sender = sender = CdmSender()
        m.submodules.checker = checker = CdsChecker()
        m.submodules.idle = idle = IdleCount()
        m.submodules.buffers = buffers = AccessBuffers()

        # The host: the request and its strobes in, the result out; the buffers' word ports.
        m.d.comb += [
            sequencer.request.eq(self.request), sequencer.start.eq(self.start),
            sequencer.abort.eq(self.abort),
            self.busy.eq(sequencer.busy), self.frames.eq(sequencer.busy),
            self.done.eq(sequencer.done), self.result.eq(sequencer.result),
            sender.request.eq(self.request),
            buffers.wbuf.eq(self.wbuf), buffers.rbuf_addr.eq(self.rbuf_addr),
            buffers.rbuf_en.eq(self.rbuf_en), self.rbuf_data.eq(buffers.rbuf_data),
        ]

        # The frames: each ended one reported to the sequencer and the idle count.
        for block in (sequencer, idle):
            m.d.comb += [block.frame_end.eq(self.frame_end), block.frame_ok.eq(self.frame_ok),
                         block.frame_cdm.eq(self.frame_cdm)]
        m.d.comb += [sequencer.frame_cds.eq(self.frame_cds),
                     sequencer.run_enough.eq(idle.run_enough),
                     sequencer.seen_enough.eq(idle.seen_enough)]

        # CDM out: the sequencer says which bit, the sender holds it (a write byte from the
        # write buffer).
        wiring.connect(m, sequencer.send, sender.control)
        m.d.comb += [sender.byte.eq(buffers.byte_to_send), self.cdm.eq(sender.cdm)]

        # CDS in: the checker takes the bits the sequencer names; a read's byte goes to the
        # read buffer.
        wiring.connect(m, sequencer.check, checker.control)
        m.d.comb += [
            checker.cds.eq(self.frame_cds), checker.sent.eq(sender.sent),
            sequencer.crc_ok.eq(checker.crc_ok), sequencer.echo_ok.eq(checker.echo_ok),
            buffers.index.eq(sequencer.index), buffers.store.eq(sequencer.store),
            buffers.byte_received.eq(checker.byte),
        ]
        return m
