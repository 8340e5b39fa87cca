"""The line faults of a clocked frame before Start: NO_ACK, DELAY_RANGE, NO_START."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import Status


class LineFaults(wiring.Component):
    """Watches the Ack and Start of the frame being clocked, and restarts the cycle timer.

    It remembers two facts of the frame, both forgotten with ``clear`` (WAIT_READY) and
    learned only while ``watch`` is high (CLOCK): ``armed``, the cycle's second MA rise has been
    made (the sampler is armed), and ``locked_seen``, ``locked`` was high in an earlier clock.
    ``newly_locked`` is ``locked`` in a clock in which it was not seen yet: the Ack edge.

    ``restart_timer`` = ``ma_arm`` | ``newly_locked`` (in every state): the timer counts the Ack
    limit from the second rise and the NO_START limit from the Ack edge.

    ``fault`` with ``status`` (combinational, in every state; the controller takes it in CLOCK
    only, after ``abort`` and the frame's end): the first of

    1. armed and SLO was low when armed (``early``): DELAY_RANGE;
    2. armed, never locked, and the Ack limit expired: NO_ACK;
    3. the Ack edge now, with the round trip over its limit (``delay_over``): DELAY_RANGE, and
       ``delay`` high: the measured delay is reported with it;
    4. locked earlier, no Start, and the NO_START limit expired or the sampler took every slot
       it has (``slots_full``): NO_START.

    Without a fault ``status`` is OK and ``delay`` low.

    Attributes
    ----------
    clear : In(1)
        Forget ``armed`` and ``locked_seen``.
    watch : In(1)
        The frame is being clocked: learn ``armed`` and ``locked_seen``.
    ma_arm : In(1)
        The cycle's second MA rise.
    locked, early : In(1)
        The sampler found the Ack edge; SLO was low when armed.
    started, slots_full : In(1)
        From the decoder: Start seen; every slot taken.
    ack_expired, no_start_expired, delay_over : In(1)
        From the limit timers.
    restart_timer : Out(1)
        To the limit timers' ``restart``.
    fault : Out(1)
        A line fault ends the frame.
    status : Out(Status)
        Its status: DELAY_RANGE, NO_ACK or NO_START.
    delay : Out(1)
        Report the measured line delay with it.
    """

    def __init__(self):
        super().__init__({
            "clear": In(1),
            "watch": In(1),
            "ma_arm": In(1),
            "locked": In(1),
            "early": In(1),
            "started": In(1),
            "slots_full": In(1),
            "ack_expired": In(1),
            "no_start_expired": In(1),
            "delay_over": In(1),
            "restart_timer": Out(1),
            "fault": Out(1),
            "status": Out(Status),
            "delay": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        armed = Signal()            # the second MA rise has been made (the sampler is armed)
        locked_seen = Signal()      # ``locked`` was already high in an earlier clock
        newly_locked = self.locked & ~locked_seen

        # What the frame has shown so far.
        with m.If(self.clear):
            m.d.sync += [armed.eq(0), locked_seen.eq(0)]
        with m.If(self.watch & self.ma_arm):
            m.d.sync += armed.eq(1)
        with m.If(self.watch & newly_locked):
            m.d.sync += locked_seen.eq(1)

        # The timer restarts at the second rise and at the Ack edge.
        m.d.comb += self.restart_timer.eq(self.ma_arm | newly_locked)

        # The first fault that applies.
        with m.If(armed & self.early):
            m.d.comb += [self.fault.eq(1), self.status.eq(Status.DELAY_RANGE)]
        with m.Elif(armed & ~locked_seen & ~self.locked & self.ack_expired):
            m.d.comb += [self.fault.eq(1), self.status.eq(Status.NO_ACK)]
        with m.Elif(newly_locked & self.delay_over):
            m.d.comb += [self.fault.eq(1), self.status.eq(Status.DELAY_RANGE), self.delay.eq(1)]
        with m.Elif(locked_seen & ~self.started & (self.no_start_expired | self.slots_full)):
            m.d.comb += [self.fault.eq(1), self.status.eq(Status.NO_START)]
        return m
