"""The sampler's noise judgement: the vote patterns and edges between slot centres that no
clean line gives (issue 28)."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class SlotNoise(wiring.Component):
    """Judges each decided slot of :class:`~bissmaster.core.slo_sampler.SloSampler` by its three
    votes and by the edges since the centre vote of the slot before.

    A clean line changes at most once between two slot centres, near their boundary: however
    far a jittered edge moves towards a slot, its first vote can differ from the decision only
    when the slot before was decided the other way (a change at the slot's start), its third
    only when the slot after is (a change at its end), and its centre never differs from both.
    A slot is **odd** for each pattern no clean line gives:

    - the centre vote against the two outer ones;
    - the first vote against the decision while the slot before was decided the same;
    - the third vote against the decision while the slot after is decided the same (judged
      with the slot after's decision);
    - two edges between two slot centres: from the clock after one slot's centre vote (after
      the Ack edge, ``clear``, for slot 0) up to and including the next slot's centre vote
      (the vote sees the new level), judged there and reported with that slot's decision.
      Jitter moves an edge anywhere between the centres without a report: the check tolerates
      what the votes do.

    One disturbance, one report: a glitch across a slot centre breaks that slot's votes and may
    crowd the next span too (its second edge beside a data edge), so a slot is not reported when
    the slot before was (a run of n odd slots gives ceil(n / 2) reports). A noise edge that
    lands in a span without a data edge and off the votes is not seen: it looks like data.

    Attributes
    ----------
    level : In(1)
        Synchronized SLO (the sampler's ``level``): the third vote in the clock of ``decided``,
        the centre vote in the clock of ``centre``.
    edge : In(1)
        ``level`` differs from its value in the clock before.
    clear : In(1)
        An Ack edge is taken: slot 0's span starts in the next clock, the slot before counts as
        decided low (the Ack is low from the edge on; high with ``clear_high``) and as not
        reported. Wins over the others.
    clear_high : In(1)
        With ``clear``: the slot before slot 0 counts as decided high (an SSI frame: the idle
        line before the first bit).
    centre : In(1)
        The centre vote of a slot is taken in this clock (never at a half period of 2).
    decided : In(1)
        A slot is decided from three votes in this clock (never at a half period of 2).
    vote1, vote2 : In(1)
        The slot's first and centre votes.
    majority : In(1)
        The decision of the three votes (``vote1``, ``vote2``, ``level``).
    odd : Out(1)
        Strobe with ``decided``: the slot is odd and the slot before was not reported.
    """

    def __init__(self):
        super().__init__({
            "level": In(1),
            "edge": In(1),
            "clear": In(1),
            "clear_high": In(1),
            "centre": In(1),
            "decided": In(1),
            "vote1": In(1),
            "vote2": In(1),
            "majority": In(1),
            "odd": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        level, majority = self.level, self.majority

        # ``last`` is the slot before's decision (``clear_high`` for slot 0), ``tail_odd`` its third vote
        # against it, to be judged with this slot's decision.
        last = Signal()
        tail_odd = Signal()
        centre_odd = (self.vote1 == level) & (self.vote2 != level)
        head_odd = (self.vote1 != majority) & (last == majority)
        tail_late = tail_odd & (last == majority)
        # ``one_edge`` / ``two_edges``: one / two edges in the span so far; ``crowded``: the
        # span that ended at the last centre vote had two.
        one_edge = Signal()
        two_edges = Signal()
        crowded = Signal()
        strobed = Signal()                          # the last decided slot was reported
        odd_slot = centre_odd | head_odd | tail_late | crowded

        with m.If(self.clear):
            m.d.sync += [last.eq(self.clear_high), tail_odd.eq(0), one_edge.eq(0), two_edges.eq(0),
                         crowded.eq(0), strobed.eq(0)]
        with m.Else():
            with m.If(self.centre):
                m.d.sync += [one_edge.eq(0), two_edges.eq(0),
                             crowded.eq(two_edges | one_edge & self.edge)]
            with m.Else():
                m.d.sync += [one_edge.eq(one_edge | self.edge),
                             two_edges.eq(two_edges | one_edge & self.edge)]
            with m.If(self.decided):
                m.d.sync += [last.eq(majority), tail_odd.eq(level != majority),
                             strobed.eq(odd_slot & ~strobed)]
        m.d.comb += self.odd.eq(self.decided & odd_slot & ~strobed)
        return m
