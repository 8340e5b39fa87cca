"""SLO receiver with line-delay compensation."""

from amaranth.hdl import *
from amaranth.lib import cdc, wiring
from amaranth.lib.wiring import In, Out

from .params import HALF_PERIOD_WIDTH


#: Clocks between the SLO pin and the Ack-edge detector beyond the pin edge itself: the second
#: synchronizer flop. The first flop's sampling uncertainty (< 1 clock) stays in the measurement,
#: so the reported delay ``d`` satisfies ``true <= d < true + 1`` clock.
SYNC_EXTRA_LATENCY = 1


def vote_spacing(half_period):
    """Clocks between the three votes of a slot, for a half period of ``half_period`` clocks:
    a quarter bit (``half_period // 2``) where the eye allows it, none (a single sample) at
    ``half_period`` = 2. A Python model of the rule the hardware applies, for documentation and
    tools (tests derive the same rule themselves from docs/ports.md)."""
    return half_period // 2 if half_period >= 3 else 0


class SloSampler(wiring.Component):
    """Measures the round trip and decides every SLO bit from three votes around its centre.

    The round trip is counted from ``arm`` (the master's own second MA rising edge) to the
    falling edge of Ack on the synchronized SLO. Every bit the encoder sends after that edge
    arrives exactly one MA period after the previous one, shifted by the same round trip,
    whatever its length: so the sampler does not follow MA at all. It runs its own period
    timer, started at the Ack edge; the centre of slot ``k`` is ``half_period + 2 * half_period *
    k`` clocks after the edge. That works for round trips of any number of bit periods; slot
    ``k`` is the bit the encoder put on SLO at MA rising edge ``k + 2``.

    **Votes (noise immunity).** Each slot is decided by the majority of three samples: ``v``
    clocks before its centre, at its centre, and ``v`` clocks after it, with ``v`` =
    :func:`vote_spacing` (``half_period // 2``; 0, a single sample, at a half period of 2). The
    decision (``sample`` with ``bit``) comes with the third vote, ``v`` clocks after the centre.
    A glitch (the line inverted for a while) can change a decision only by inverting two votes,
    so one glitch shorter than ``v`` clocks never changes a decided bit, fakes a Start or ends an
    Ack early.

    **The Ack edge.** SLO must be low at slot 0 (it is inside the Ack), decided by the same
    votes; slot 0 high by the majority means the edge was not an Ack edge, and the sampler waits
    for the next one. SLO high again within ``v`` clocks of the edge (at a half period of 2:
    before the centre) may mean a glitch was taken for the edge: the sampler waits for the next
    fall, and if that comes within ``v`` clocks of the rise (one glitch right at the real edge,
    either a short low before it or a short high after it: the two cannot be told apart), it
    takes the edge halfway between the two falls, at most ``v`` clocks from the true one, and
    the votes keep every decision right. Later high blips in slot 0 are votes like any other.
    So the delay is exact (``true <= delay < true + 1``) unless a glitch shorter than ``v`` clocks
    touches the edge itself; then it is off by at most ``v`` clocks.

    SLO is asynchronous: it passes a two-flop synchronizer
    (:class:`amaranth.lib.cdc.FFSynchronizer`) first, whose flops are reset-less, so the
    master's reset between cycles (``ResetInserter``) does not touch them; ``level`` is the
    synchronized line for the rest of the master. The measured delay is compensated for the
    synchronizer's latency (:data:`SYNC_EXTRA_LATENCY`). ``synchronizer=False`` leaves the
    flops out for block tests and formal harnesses of the sampler alone: they drive ``slo`` as
    the output of such a synchronizer (the compensation stays).

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
        Slot 0 was decided low: the Ack edge is confirmed; decisions are being produced (from
        the clock after slot 0's decision).
    sample : Out(1)
        Strobe: ``bit`` is the decision of the next slot (``v`` clocks after its centre).
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
        hp = self.half_period

        if self._synchronizer:
            m.submodules.sync = cdc.FFSynchronizer(self.slo, self.level, init=1, stages=2)
        else:
            m.d.comb += self.level.eq(self.slo)
        slo = self.level

        slo_prev = Signal(init=1)
        m.d.sync += slo_prev.eq(slo)
        fell = slo_prev & ~slo

        # The vote spacing and the slot-timer values of the votes, from the cycle's half period
        # (constant within a cycle): reset-less registers that follow it in every clock, valid
        # a few clocks after the configuration latch, long before the first edge.
        vw = HALF_PERIOD_WIDTH - 1
        vote = Signal(vw, reset_less=True)
        single = Signal(reset_less=True)                        # one sample per slot
        pre_at = Signal(HALF_PERIOD_WIDTH + 1, reset_less=True)  # vote + 1
        post_at = Signal(HALF_PERIOD_WIDTH + 1, reset_less=True)  # 2 * hp - vote + 1
        m.d.sync += [
            vote.eq(Mux(hp >= 3, hp[1:], 0)),
            single.eq(hp < 3),
            pre_at.eq(vote + 1),
            post_at.eq(Cat(C(0, 1), hp) - vote + 1),
        ]

        elapsed = Signal(self._delay_width)        # clocks since arm
        delay_max = (1 << self._delay_width) - 1
        slot_left = Signal(HALF_PERIOD_WIDTH + 1)  # clocks to the next slot centre, minus one
        first_slot = Signal()                       # slot 0 (inside the Ack) not decided yet
        # ``slot_left == 0`` (the centre), ``== vote`` (the first vote) and ``== 2 * hp - vote``
        # (the third vote, after the centre's reload), kept as registers written wherever
        # ``slot_left`` is, from the value written: no wide compare in front of the strobes.
        slot_zero = Signal(init=1)
        pre_vote = Signal()
        post_vote = Signal()
        vote1 = Signal()                            # the first vote of the slot
        vote2 = Signal()                            # its centre
        # Slot 0: clocks left (after the edge) in which SLO high may mean a glitch was taken for
        # the edge; after such a rise, clocks left in which the next fall is ambiguous.
        grace = Signal(vw)
        gap = Signal(vw)
        # The edge halfway between the last fall and now, kept up to date clock by clock (so
        # that no arithmetic sits between the fall and the registers it loads): with ``span``
        # clocks since that fall, ``mid_slot`` = hp - 1 - ceil(span / 2) (the slot timer had the
        # edge been halfway) and ``mid_delay`` = its delay + floor(span / 2); ``odd`` = span % 2.
        mid_slot = Signal(HALF_PERIOD_WIDTH + 1)
        mid_delay = Signal(self._delay_width)
        odd = Signal()
        with m.If(odd):
            m.d.sync += mid_delay.eq(mid_delay + 1)
        with m.Else():
            m.d.sync += mid_slot.eq(mid_slot - 1)
        m.d.sync += odd.eq(~odd)

        def count_down(counter):
            with m.If(counter != 0):
                m.d.sync += counter.eq(counter - 1)

        majority = (vote1 & vote2) | (vote1 & slo) | (vote2 & slo)
        decided = Signal()                          # a slot's decision in this clock
        decision = Mux(single, slo, majority)
        m.d.comb += [self.sample.eq(decided & ~first_slot), self.bit.eq(decision)]

        with m.FSM(name="sampler_fsm"):
            with m.State("IDLE"):
                with m.If(self.arm):
                    m.d.sync += [
                        elapsed.eq(1),
                        self.early.eq(~slo),
                        self.locked.eq(0),
                        gap.eq(0),
                    ]
                    m.next = "MEASURE"
            with m.State("MEASURE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                count_down(gap)
                with m.If(fell):
                    # The edge entered the second flop ``elapsed - 1`` clocks after the MA edge.
                    # After a glitch at the edge, the edge is halfway between the two falls.
                    ambiguous = gap != 0
                    delay = Mux(elapsed == delay_max, delay_max, elapsed - SYNC_EXTRA_LATENCY)
                    # A saturated count stays saturated: above every limit.
                    m.d.sync += [
                        self.delay.eq(Mux(ambiguous & (elapsed != delay_max), mid_delay, delay)),
                        slot_left.eq(Mux(ambiguous, mid_slot, hp - 1)),
                        slot_zero.eq((hp == 1) & ~ambiguous),
                        pre_vote.eq(0),
                        post_vote.eq(0),
                        vote1.eq(0),
                        vote2.eq(0),
                        first_slot.eq(1),
                        grace.eq(Mux(ambiguous, 0, vote)),
                        gap.eq(0),
                    ]
                    with m.If(~ambiguous):
                        # Halfway values for a fall in the next clock (span 1).
                        m.d.sync += [mid_slot.eq(hp - 2), mid_delay.eq(delay), odd.eq(1)]
                    m.next = "SAMPLE"
            with m.State("SAMPLE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                count_down(grace)
                m.d.sync += [
                    slot_left.eq(slot_left - 1),
                    slot_zero.eq(slot_left == 1),
                    pre_vote.eq(slot_left == pre_at),
                    post_vote.eq(slot_left == post_at),
                ]
                with m.If(pre_vote):
                    m.d.sync += vote1.eq(slo)
                with m.If(first_slot & slo & (single | (grace != 0) & ~slot_zero)):
                    # SLO high right after the edge: maybe a glitch was taken for the edge.
                    # Wait for the next fall; if it comes within ``vote`` clocks, it and this
                    # edge are one glitch at the real edge.
                    m.d.sync += gap.eq(vote)
                    m.next = "MEASURE"
                with m.Elif(slot_zero):
                    # The slot's centre: the second vote; the timer runs on to the next centre.
                    m.d.sync += [
                        vote2.eq(slo),
                        slot_left.eq(Cat(C(0, 1), hp) - 1),    # one MA period
                        slot_zero.eq(0),                        # odd: never 0
                        pre_vote.eq(0),                         # 2 * hp - 1 > vote
                        post_vote.eq(vote == 1),                # 2 * hp - 1 == 2 * hp - vote
                    ]
                    m.d.comb += decided.eq(single)
                with m.Elif(post_vote):
                    m.d.comb += decided.eq(~single)
                with m.If(decided & first_slot):
                    with m.If(decision):
                        # Slot 0 high: that was no Ack edge. Wait for the next one.
                        m.next = "MEASURE"
                    with m.Else():
                        m.d.sync += [first_slot.eq(0), self.locked.eq(1)]
                        m.d.comb += self.sample.eq(1)

        return m
