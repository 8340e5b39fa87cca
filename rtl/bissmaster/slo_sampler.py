"""SLO receiver with line-delay compensation."""

from amaranth.hdl import *
from amaranth.lib import cdc, wiring
from amaranth.lib.wiring import In, Out

from .params import HALF_PERIOD_WIDTH


#: Clocks between the SLO pin and the Ack-edge detector beyond the pin edge itself: the second
#: synchronizer flop. The first flop's sampling uncertainty (< 1 clock) stays in the measurement,
#: so the reported delay ``d`` satisfies ``true <= d < true + 1`` clock.
SYNC_EXTRA_LATENCY = 1


class SloSampler(wiring.Component):
    """Measures the round trip and samples every SLO bit in the middle of its eye.

    The round trip is counted from ``arm`` (the master's own second MA rising edge) to the
    falling edge of Ack on the synchronized SLO. Every bit the encoder sends after that edge
    arrives exactly one MA period after the previous one, shifted by the same round trip,
    whatever its length: so the sampler does not follow MA at all. It runs its own period
    timer, started at the Ack edge, and samples ``half_period`` clocks into every slot. That
    works for round trips of any number of bit periods; slot ``k`` is the bit the encoder put on
    SLO at MA rising edge ``k + 2``.

    SLO is asynchronous: it passes a two-flop synchronizer
    (:class:`amaranth.lib.cdc.FFSynchronizer`) first, whose flops are reset-less, so the
    master's reset between cycles (``ResetInserter``) does not touch them; ``level`` is the
    synchronized line for the rest of the master. The measured delay is compensated for the
    synchronizer's latency (:data:`SYNC_EXTRA_LATENCY`). ``synchronizer=False`` leaves the
    flops out for block tests and formal harnesses of the sampler alone: they drive ``slo`` as
    the output of such a synchronizer (the compensation stays).

    SLO must stay low from the edge to the slot-0 sample (it is inside the Ack): if it goes high
    before, the edge was a glitch, and the sampler goes back to waiting for the Ack edge.

    Attributes
    ----------
    slo : In(1)
        The SLO pin (with ``synchronizer=False``: the output of a two-flop synchronizer).
    level : Out(1)
        SLO after the synchronizer.
    half_period : In(16)
        MA half period in system clocks (constant during the cycle).
    arm : In(1)
        Strobe on the master's second MA rising edge: start measuring.
    delay : Out(bits)
        Round trip in system clocks, compensated for the synchronizer. Saturates.
    early : Out(1)
        SLO was already low when armed: it fell before the second MA rise could have caused it.
    locked : Out(1)
        The Ack edge was found; samples are being produced.
    sample : Out(1)
        Strobe: ``bit`` holds the middle of the next slot.
    bit : Out(1)
    """

    def __init__(self, delay_width, *, synchronizer=True):
        self._delay_width = delay_width
        self._synchronizer = bool(synchronizer)
        super().__init__({
            "slo": In(1, init=1),
            "level": Out(1, init=1),
            "half_period": In(HALF_PERIOD_WIDTH),
            "arm": In(1),
            "delay": Out(delay_width),
            "early": Out(1),
            "locked": Out(1),
            "sample": Out(1),
            "bit": Out(1),
        })

    def elaborate(self, platform):
        m = Module()

        if self._synchronizer:
            m.submodules.sync = cdc.FFSynchronizer(self.slo, self.level, init=1, stages=2)
        else:
            m.d.comb += self.level.eq(self.slo)
        slo = self.level

        slo_prev = Signal(init=1)
        m.d.sync += slo_prev.eq(slo)
        fell = slo_prev & ~slo

        elapsed = Signal(self._delay_width)        # clocks since arm
        delay_max = (1 << self._delay_width) - 1
        slot_left = Signal(HALF_PERIOD_WIDTH + 1)                     # clocks to the next sample, minus one
        first_slot = Signal()                       # the next sample is slot 0 (inside the Ack)
        # ``slot_left == 0``, kept as a register: written wherever ``slot_left`` is, from the
        # value written. The sample strobe then needs no wide compare.
        slot_zero = Signal(init=1)

        m.d.comb += self.bit.eq(slo)

        with m.FSM(name="sampler_fsm"):
            with m.State("IDLE"):
                with m.If(self.arm):
                    m.d.sync += [
                        elapsed.eq(1),
                        self.early.eq(~slo),
                        self.locked.eq(0),
                    ]
                    m.next = "MEASURE"
            with m.State("MEASURE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                with m.If(fell):
                    # The edge entered the second flop ``elapsed - 1`` clocks after the MA edge.
                    # A saturated count stays saturated: above every limit.
                    m.d.sync += [
                        self.delay.eq(Mux(elapsed == delay_max, delay_max,
                                          elapsed - SYNC_EXTRA_LATENCY)),
                        slot_left.eq(self.half_period - 1),
                        slot_zero.eq(self.half_period == 1),
                        first_slot.eq(1),
                    ]
                    m.next = "SAMPLE"
            with m.State("SAMPLE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                m.d.sync += [slot_left.eq(slot_left - 1), slot_zero.eq(slot_left == 1)]
                with m.If(first_slot & slo):
                    # SLO high again inside the first Ack slot: the edge was a glitch (or a
                    # bounce before the real edge). Keep waiting for the real Ack edge.
                    m.next = "MEASURE"
                with m.Elif(slot_zero):
                    m.d.sync += [
                        slot_left.eq(Cat(C(0, 1), self.half_period) - 1),   # one MA period
                        slot_zero.eq(0),                                    # odd: never 0
                        first_slot.eq(0),
                        self.locked.eq(1),
                    ]
                    m.d.comb += self.sample.eq(1)

        return m
