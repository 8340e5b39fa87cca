"""Noise on SLO: the events a clean line never gives, counted from one frame to the next."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import LINE_CHECK_WIDTH as NOISE_COUNT_WIDTH    # the counts saturate at 15


class LineNoise(wiring.Component):
    """Counts noise events and judges a frame by them (issue 28; docs/ports.md, *Noise*).

    A noise event is a strobe of ``sampler_noise`` (a vote pattern, two edges between two slot
    centres or an Ack edge no clean line gives: :class:`~bissmaster.core.slo_sampler.SloSampler`)
    or a fall of SLO while the master waits (``watch``: IDLE and WAIT_READY, with MA stopped
    and the encoder's timeout over or running: a clean encoder's SLO then only rises, once).
    The count runs from the end of the cycle before (its frame's end, ``close``, the decoder's
    ``done``; or its fault, ``restart``) to this frame's end: each frame is judged by the line since the cycle before
    it, so a fault (which has its own status) costs no second frame. It saturates at 15.

    At ``close`` the frame is ``noisy`` when its count (the events counted up to the clock
    before) is above ``limit``; ``noisy`` and ``events`` hold that frame's judgement and count from
    ``close`` (combinational in that clock, registered after it) to the next ``close``, so the
    verdict reads them in the clock of ``done`` (its ``doubtful``) and at the report (end check:
    later). The count starts again from 0 (or 1, for an event in the clock of ``close``).

    Attributes
    ----------
    watch : In(1)
        The master waits for a request or for the encoder (IDLE, WAIT_READY).
    level : In(1)
        Synchronized SLO.
    sampler_noise : In(1)
        The sampler's ``noise`` strobe.
    close : In(1)
        A frame ends: the decoder's ``done`` (BiSS), or its ``stopped`` (SSI: the frame ends
        with the bit after the word), both two clocks after the last bit's decision.
    restart : In(1)
        A cycle ended without a frame (the controller's ``fault``): the count starts again
        (an event in the same clock is dropped with it).
    limit : In(4)
        Events a frame may have and be judged clean (``cfg_noise_limit``; 15: never noisy),
        read in the clock of ``close``.
    noisy : Out(1)
        The frame's count is above ``limit``.
    events : Out(4)
        The frame's count.
    event : Out(1)
        Strobe: an event (for the counter), one clock after the input that makes it; it is
        counted in that clock (``close`` in the clock after an input strobe still counts it
        for the next frame).
    """

    def __init__(self):
        super().__init__({
            "watch": In(1),
            "level": In(1),
            "sampler_noise": In(1),
            "close": In(1),
            "restart": In(1),
            "limit": In(NOISE_COUNT_WIDTH),
            "noisy": Out(1),
            "events": Out(NOISE_COUNT_WIDTH),
            "event": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        level_prev = Signal(init=1)
        m.d.sync += level_prev.eq(self.level)
        # The event, registered: the sampler's vote decode stays out of the count's adder and
        # compare (the core's critical path otherwise). An event is counted one clock after
        # its strobe; the decoder's ``done`` comes two clocks after the last decision, so the
        # frame's last event is in by then.
        m.d.sync += self.event.eq(self.sampler_noise | self.watch & level_prev & ~self.level)

        top = 2**NOISE_COUNT_WIDTH - 1
        running = Signal(NOISE_COUNT_WIDTH)
        held_noisy = Signal()
        held_events = Signal(NOISE_COUNT_WIDTH)
        # Judged from the registered count alone (a 4-bit compare): the event input is already
        # a register, so no adder sits in front of the judgement.
        over = running > self.limit
        with m.If(self.close):
            m.d.sync += [held_noisy.eq(over), held_events.eq(running), running.eq(self.event)]
        with m.Elif(self.restart):
            m.d.sync += running.eq(0)
        with m.Elif(self.event & (running != top)):
            m.d.sync += running.eq(running + 1)
        m.d.comb += [self.noisy.eq(Mux(self.close, over, held_noisy)),
                     self.events.eq(Mux(self.close, running, held_events))]
        return m
