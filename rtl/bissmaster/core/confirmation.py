"""Confirmation after a fault: the frames after a cycle that did not end OK must earn ``valid``."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import LINE_CHECK_WIDTH, Status


class Confirmation(wiring.Component):
    """Withholds ``valid`` from the first frames after a fault (issue 28; docs/ports.md,
    *Confirmation after a fault*).

    A cycle that ends with any status but OK, ABORTED, BAD_CONFIG or UNCONFIRMED is evidence
    that the line (or the encoder) was wrong in that cycle: a CRC error, a noise event, a lost
    Ack or stop bit. The noise that corrupted that cycle is likely still there in the next,
    where a corruption the line checks cannot see (a pulse whose edges fall where data edges
    may) passes a CRC-6 one time in 64. So the next ``frames`` frames that pass every check
    are reported as UNCONFIRMED (not valid, no pause: they are clean) before a frame is OK
    again; any fault among them starts the count again. ABORTED and BAD_CONFIG say nothing
    about the line and leave the count as it is; so does a cycle's fault-free end.

    The count is a register, so the verdict's status stays one decode of registered inputs.

    Attributes
    ----------
    report : In(1)
        A cycle ends (the verdict's ``report``).
    status : In(Status)
        The status reported with it.
    setting : In(4)
        ``cfg_confirm_frames`` for the cycle: 0 the default (1 frame), 1..14 that many frames,
        15 off.
    pending : Out(1)
        The next frame that passes every check is UNCONFIRMED.
    """

    #: ``cfg_confirm_frames`` value that turns the confirmation off, and the count the value 0
    #: stands for.
    OFF = 2**LINE_CHECK_WIDTH - 1
    DEFAULT_FRAMES = 1

    def __init__(self):
        super().__init__({
            "report": In(1),
            "status": In(Status),
            "setting": In(LINE_CHECK_WIDTH),
            "pending": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        left = Signal(LINE_CHECK_WIDTH)
        frames = Mux(self.setting == 0, self.DEFAULT_FRAMES,
                     Mux(self.setting == self.OFF, 0, self.setting))
        neutral = Cat(self.status == s for s in (Status.OK, Status.ABORTED, Status.BAD_CONFIG,
                                                  Status.UNCONFIRMED)).any()
        # Statements, not a multiplexer: an `if` on a strobe that a simulator holds at X before
        # the first cycle is not taken, so the count cannot turn X (Icarus; docs/verification.md).
        with m.If(self.report & ~neutral):
            m.d.sync += left.eq(frames)
        with m.Elif(self.report & (self.status == Status.UNCONFIRMED)):
            m.d.sync += left.eq(left - 1)
        m.d.comb += self.pending.eq((left != 0) & (self.setting != self.OFF))
        return m
