"""SLO receiver with line-delay compensation."""

from types import SimpleNamespace

from amaranth.hdl import *
from amaranth.lib import cdc, wiring
from amaranth.lib.wiring import In, Out

from ..params import HALF_PERIOD_WIDTH
from .const_compare import above, at_most
from .slot_noise import SlotNoise


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
    for the next one. SLO high again before slot 0's first vote (within ``u = half_period - v``
    clocks of the fall; at a half period of 2: before its only sample) may mean a glitch was
    taken for the edge: the sampler waits for the next fall, and if that comes within ``v``
    clocks of the rise (one glitch right at the real edge, either a short low before it or a
    short high after it: the two cannot be told apart), it takes the edge halfway between the
    two falls, at most ``v`` clocks from the true one, and the votes keep every decision right.
    Later high blips in slot 0 are votes like any other. So the delay is exact (``true <= delay
    < true + 1``) unless a glitch starts within ``u`` clocks after the edge or ends within ``v``
    clocks before it; then it is off by at most ``v`` clocks.

    **Noise (``noise``).** The votes also tell a noisy line from a clean one. A clean line
    changes at most once between two slot centres, near their boundary: however far a jittered
    edge moves towards a slot, its first vote can differ from the decision only when the slot
    before was decided the other way (a change at the slot's start), its third only when the
    slot after is (a change at its end), and its centre never differs from both. ``noise``
    strobes for each pattern no clean line gives: the centre vote against the two outer ones;
    the first vote against the decision while the slot before was decided the same; the third
    vote against the decision while the slot after is decided the same (strobed with the slot
    after's decision); two edges between two slot centres (after one slot's centre vote, or
    after the Ack edge, up to and including the next slot's centre vote: a clean line read
    right changes at most once there, however far jitter moves its edges; strobed with that
    slot's decision); and an edge the sampler dropped (slot 0 decided high, or SLO high again
    before slot 0's first vote). A slot's pattern strobes only if the slot before did not
    strobe: one glitch across a slot centre can break that slot's votes and crowd the next
    span, and counts once (a run of n odd slots strobes ceil(n / 2) times). A noise edge that
    lands in a span without a data edge and off the votes gives no strobe: it looks like data.
    ``noise`` sees part of the noise, never a clean line. No vote or edge strobes at a half
    period of 2 (one sample per slot). The patterns and the spans are judged by
    :class:`~bissmaster.core.slot_noise.SlotNoise`, the dropped edges here.

    **Area.** The slot timer only counts down to zero and reloads, from four values (edge to
    first vote, vote to vote, third vote to the next slot's first, and the halfway edge),
    reset-less registers or wiring from them: no comparator on the timer's width anywhere.

    SLO is asynchronous: it passes a two-flop synchronizer
    (:class:`amaranth.lib.cdc.FFSynchronizer`) first, whose flops are reset-less, so the
    master's reset between cycles (``ResetInserter``) does not touch them; ``level`` is the
    synchronized line for the rest of the master. The measured delay is compensated for the
    synchronizer's latency (:data:`SYNC_EXTRA_LATENCY`). ``synchronizer=False`` leaves the
    flops out for block tests and formal harnesses of the sampler alone: they drive ``slo`` as
    the output of such a synchronizer (the compensation stays).

    **A set round trip (SSI).** Built with ``fixed=True``, the sampler also takes the round trip
    from ``fixed_delay`` when ``fixed`` is high (an SSI frame has no Ack edge to measure it on):
    the edge is then taken ``fixed_delay`` clocks after ``arm`` by the same measure as a
    measured one (the clock in which a fall with that delay would have been seen), ``delay``
    reports ``fixed_delay``, ``early`` stays low, and slot 0 is data, not an Ack: its decision is
    the first ``sample``, ``locked`` rises with the edge, and the slot before it counts as
    decided high (the idle line) for the noise judgement. Nothing is dropped or waited for.

    ``half_period_width`` (``MasterParams.half_period_width``, 16 by default) is the width of
    ``half_period``, of the slot timer and of its reload values.

    Attributes
    ----------
    slo : In(1)
        The SLO pin (with ``synchronizer=False``: the output of a two-flop synchronizer).
    level : Out(1)
        SLO after the synchronizer.
    half_period : In(half_period_width)
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
    noise : Out(1)
        Strobe: a vote pattern or edges no clean line gives (see *Noise*).
    fixed : In(1)
        ``fixed=True`` builds: take the round trip from ``fixed_delay`` (constant during the
        cycle), not from an Ack edge.
    fixed_delay : In(bits)
        ``fixed=True`` builds: the round trip to use, in the same measure as ``delay``.
    """

    def __init__(self, delay_width, *, synchronizer=True, fixed=False,
                 half_period_width=HALF_PERIOD_WIDTH):
        self._delay_width = delay_width
        self._hp_width = half_period_width
        self._synchronizer = bool(synchronizer)
        self._fixed = bool(fixed)
        super().__init__({
            "slo": In(1, init=1),
            "level": Out(1, init=1),
            "half_period": In(half_period_width),
            "arm": In(1),
            "delay": Out(delay_width),
            "early": Out(1),
            "locked": Out(1),
            "sample": Out(1),
            "bit": Out(1),
            "noise": Out(1),
            **({"fixed": In(1), "fixed_delay": In(delay_width)} if fixed else {}),
        })

    def elaborate(self, platform):
        m = Module()
        # What the parts below share: the line, the slot timing, the votes and the decision.
        s = SimpleNamespace()
        if self._synchronizer:
            m.submodules.sync = cdc.FFSynchronizer(self.slo, self.level, init=1, stages=2)
        else:
            m.d.comb += self.level.eq(self.slo)
        s.slo = slo = self.level

        s.slo_prev = Signal(init=1, name="slo_prev")
        m.d.sync += s.slo_prev.eq(slo)
        s.fell = s.slo_prev & ~slo

        self._slot_timing(m, s)
        self._midpoint(m, s)

        s.elapsed = Signal(self._delay_width, name="elapsed")   # clocks since arm
        # clocks to the slot's next event, minus one
        s.slot_left = Signal(self._hp_width + 1, name="slot_left")
        # ``slot_left == 0`` kept as a register, written wherever ``slot_left`` is, from the
        # value written: the event strobe needs no wide compare.
        s.slot_zero = Signal(init=1, name="slot_zero")
        s.phase = Signal(2, name="phase")           # next event: 0 first vote, 1 centre, 2 third
        s.first_slot = Signal(name="first_slot")    # slot 0 (inside the Ack) not decided yet
        s.vote1 = Signal(name="vote1")              # the slot's first vote
        s.vote2 = Signal(name="vote2")              # its centre
        # After SLO went high again right after the edge: the next fall within ``v`` clocks is
        # ambiguous (the slot timer counts the window down).
        s.gap = Signal(name="gap")

        s.majority = (s.vote1 & s.vote2) | (s.vote1 & slo) | (s.vote2 & slo)
        s.decided = Signal(name="decided")          # a slot's decision in this clock
        s.decision = Mux(s.single, slo, s.majority)
        m.d.comb += [self.sample.eq(s.decided & ~s.first_slot), self.bit.eq(s.decision)]

        self._noise(m, s)
        self._fsm(m, s)
        return m

    def _slot_timing(self, m, s):
        """The vote spacing ``v`` and the slot timer's reload values (``s.vote``, ``s.single``,
        ``s.first_load``, ``s.vote_load``, ``s.vote_one``, ``s.period_load``)."""
        hp = self.half_period
        # The vote spacing ``v`` and the slot timer's reload values, from the cycle's half
        # period (constant within a cycle): reset-less registers that follow it in every clock,
        # valid a few clocks after the configuration latch, long before the first edge. With
        # ``u = hp - v``, a slot's events are: first vote ``u`` clocks after its start, the
        # centre ``v`` later, the third vote (the decision) ``v`` later again, and the next
        # slot's first vote ``2 * u`` after that (``2 * u + 2 * v`` = one MA period). The timer
        # only ever counts down to zero and reloads: no wide compare anywhere.
        # ``v`` is a register (it keeps the compare and select of the half period out of the
        # subtracter in front of ``first_load``: the core's critical path without it); ``2u - 1``
        # is wiring (``u - 1`` with a 1 below it).
        vw = self._hp_width - 1
        s.vote = vote = Signal(vw, reset_less=True, name="vote")
        # one sample per slot (hp = 2)
        s.single = Signal(reset_less=True, name="single")
        # u - 1: edge to first vote
        s.first_load = Signal(self._hp_width, reset_less=True, name="first_load")
        s.vote_load = Signal(vw, reset_less=True, name="vote_load")      # v - 1: vote to vote
        s.vote_one = Signal(reset_less=True, name="vote_one")            # v == 1: vote_load is 0
        s.period_load = Cat(C(1, 1), s.first_load)                       # 2u - 1: third to first
        m.d.sync += [
            vote.eq(Mux(above(hp, 2), hp[1:], 0)),
            s.single.eq(at_most(hp, 2)),
            s.first_load.eq(hp - vote - 1),
            s.vote_load.eq(vote - 1),
            s.vote_one.eq(vote == 1),
        ]

    def _midpoint(self, m, s):
        """The edge halfway between the last fall and now (``s.mid_slot``, ``s.mid_delay``,
        ``s.odd``)."""
        # The edge halfway between the last fall and now, kept up to date clock by clock (so
        # that no arithmetic sits between the fall and the registers it loads): with ``span``
        # clocks since that fall, ``mid_slot`` = hp - 1 - ceil(span / 2) (the timer to the
        # slot's centre had the edge been halfway) and ``mid_delay`` = its delay + floor(span /
        # 2); ``odd`` = span % 2.
        s.mid_slot = Signal(self._hp_width + 1, name="mid_slot")
        s.mid_delay = Signal(self._delay_width, name="mid_delay")
        s.odd = Signal(name="odd")
        with m.If(s.odd):
            m.d.sync += s.mid_delay.eq(s.mid_delay + 1)
        with m.Else():
            m.d.sync += s.mid_slot.eq(s.mid_slot - 1)
        m.d.sync += s.odd.eq(~s.odd)

    def _noise(self, m, s):
        """The vote patterns and edges a clean line cannot give (see the docstring), judged by
        SlotNoise at each decision; an edge the sampler drops is noise too (``s.dropped``,
        ``s.centre``, ``s.clear``: set by the state machine)."""
        m.submodules.slot_noise = slot_noise = SlotNoise()
        s.dropped = Signal(name="dropped")          # an edge dropped in this clock
        s.centre = Signal(name="centre")            # the centre vote is taken in this clock
        s.clear = Signal(name="clear")              # an Ack edge is taken in this clock
        m.d.comb += [
            slot_noise.level.eq(s.slo),
            slot_noise.edge.eq(s.slo != s.slo_prev),
            slot_noise.clear.eq(s.clear),
            slot_noise.clear_high.eq(self.fixed if self._fixed else 0),
            slot_noise.centre.eq(s.centre),
            slot_noise.decided.eq(s.decided & ~s.single),
            slot_noise.vote1.eq(s.vote1),
            slot_noise.vote2.eq(s.vote2),
            slot_noise.majority.eq(s.majority),
            self.noise.eq(s.dropped | slot_noise.odd),
        ]

    def _fsm(self, m, s):
        """IDLE -> MEASURE (the Ack edge, the round trip) -> SAMPLE (the slots), or FIXED (SSI:
        the configured round trip) -> SAMPLE."""
        hp = self.half_period
        slo, fell, elapsed = s.slo, s.fell, s.elapsed
        slot_left, slot_zero, phase, first_slot = s.slot_left, s.slot_zero, s.phase, s.first_slot
        vote1, vote2, gap, decided, decision = s.vote1, s.vote2, s.gap, s.decided, s.decision
        mid_slot, mid_delay, odd = s.mid_slot, s.mid_delay, s.odd
        first_load, vote_load, vote_one = s.first_load, s.vote_load, s.vote_one
        period_load, single = s.period_load, s.single
        dropped, centre, clear = s.dropped, s.centre, s.clear
        delay_max = (1 << self._delay_width) - 1

        def load(value, zero):
            m.d.sync += [slot_left.eq(value), slot_zero.eq(zero)]

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
                    if self._fixed:
                        with m.If(self.fixed):
                            m.d.sync += self.early.eq(0)
                            m.next = "FIXED"
            if self._fixed:
                # The clock in which a fall with ``fixed_delay`` would be seen (reset-less: it
                # follows the cycle's constant setting long before ``arm``).
                fixed_at = Signal(self._delay_width, reset_less=True)
                m.d.sync += fixed_at.eq(self.fixed_delay + SYNC_EXTRA_LATENCY)
                with m.State("FIXED"):
                    m.d.sync += elapsed.eq(elapsed + 1)     # stops at fixed_at, below its max
                    with m.If(elapsed == fixed_at):
                        # As a measured edge (MEASURE, no gap), but slot 0 is data.
                        m.d.sync += [
                            self.delay.eq(self.fixed_delay),
                            self.locked.eq(1),
                            vote1.eq(0),
                            vote2.eq(0),
                            first_slot.eq(0),
                            phase.eq(0),
                        ]
                        m.d.comb += clear.eq(1)
                        load(first_load, 0)                 # u >= 2
                        m.next = "SAMPLE"
            with m.State("MEASURE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                with m.If(gap):
                    # The ambiguity window after a rise right after the edge.
                    load(slot_left - 1, slot_left == 1)
                    with m.If(slot_zero):
                        m.d.sync += gap.eq(0)
                with m.If(fell):
                    # The edge entered the second flop ``elapsed - 1`` clocks after the MA edge.
                    # A saturated count stays saturated: above every limit.
                    delay = Mux(elapsed == delay_max, delay_max, elapsed - SYNC_EXTRA_LATENCY)
                    m.d.sync += [
                        vote1.eq(0),
                        vote2.eq(0),
                        first_slot.eq(1),
                        gap.eq(0),
                    ]
                    m.d.comb += clear.eq(1)
                    with m.If(gap):
                        # One glitch right at the edge, a short low before it or a short high
                        # after it (the two cannot be told apart): the edge is halfway between
                        # the two falls. Its first vote is now or later: SLO is low, so the
                        # vote is taken now and the timer runs to the centre.
                        m.d.sync += [
                            self.delay.eq(Mux(elapsed == delay_max, delay_max, mid_delay)),
                            phase.eq(1),
                        ]
                        load(mid_slot, mid_slot == 0)
                    with m.Else():
                        m.d.sync += [
                            self.delay.eq(delay),
                            phase.eq(0),
                            # Halfway values for a fall in the next clock (span 1).
                            mid_slot.eq(hp - 2),
                            mid_delay.eq(delay),
                            odd.eq(1),
                        ]
                        load(first_load, 0)                 # u >= 2
                    m.next = "SAMPLE"
            with m.State("SAMPLE"):
                with m.If(elapsed != delay_max):
                    m.d.sync += elapsed.eq(elapsed + 1)
                load(slot_left - 1, slot_left == 1)
                with m.If(first_slot & (phase == 0) & slo):
                    # SLO high before slot 0's first vote (at a half period of 2: before its
                    # only sample): maybe a glitch was taken for the edge. Wait for the next
                    # fall; if it comes within ``v`` clocks, it and this edge are one glitch at
                    # the real edge.
                    m.d.sync += gap.eq(~single)
                    m.d.comb += dropped.eq(1)
                    load(vote_load, vote_one)
                    m.next = "MEASURE"
                with m.Elif(slot_zero):
                    with m.Switch(phase):
                        with m.Case(0):
                            with m.If(single):
                                m.d.comb += decided.eq(1)
                                load(period_load, 0)
                            with m.Else():
                                m.d.sync += [vote1.eq(slo), phase.eq(1)]
                                load(vote_load, vote_one)
                        with m.Case(1):
                            m.d.comb += centre.eq(~single)
                            m.d.sync += [vote2.eq(slo), phase.eq(2)]
                            load(vote_load, vote_one)
                        with m.Default():
                            m.d.comb += decided.eq(1)
                            m.d.sync += phase.eq(0)
                            load(period_load, 0)
                with m.If(decided & first_slot):
                    with m.If(decision):
                        # Slot 0 high: that was no Ack edge. Wait for the next one.
                        m.d.comb += dropped.eq(1)
                        m.next = "MEASURE"
                    with m.Else():
                        m.d.sync += [first_slot.eq(0), self.locked.eq(1)]
                        m.d.comb += self.sample.eq(1)
