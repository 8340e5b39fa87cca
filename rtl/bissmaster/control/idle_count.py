"""The run of ended request cycles that carried CDM = 0, before S and in a cancel."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .. import protocol

_IDLE = protocol.CDM_IDLE_FRAMES


class IdleCount(wiring.Component):
    """Counts consecutive ended request cycles with CDM = 0, up to 14, all the time (also
    between accesses, so an access that follows another does not repeat them).

    ``idle_run`` counts every reported cycle (a cancel's 14 zeros: best effort, bounded even
    when the encoder stopped answering); ``idle_seen`` only cycles that delivered a good frame,
    so the encoder certainly saw their CDM = 0 (a NO_ACK cycle or a BAD_CONFIG report restarts
    it): S is sent only after 14 of those. A cycle that carried CDM = 1 restarts both.

    Attributes
    ----------
    frame_end : In(1)
        A request cycle ends in this clock ...
    frame_ok : In(1)
        ... with a frame and status OK ...
    frame_cdm : In(1)
        ... and the CDM bit that cycle carried.
    run_enough : Out(1)
        14 consecutive ended cycles carried CDM = 0, counting one that ends in this clock.
    seen_enough : Out(1)
        As ``run_enough``, of cycles that also delivered a good frame.
    """

    def __init__(self):
        super().__init__({
            "frame_end": In(1),
            "frame_ok": In(1),
            "frame_cdm": In(1),
            "run_enough": Out(1),
            "seen_enough": Out(1),
        })

    def elaborate(self, platform):
        m = Module()

        def run_after(run, reset):
            return Mux(reset, 0, Mux(run == _IDLE, _IDLE, run + 1))

        idle_run = Signal(range(_IDLE + 1))
        idle_seen = Signal(range(_IDLE + 1))
        idle_after = run_after(idle_run, self.frame_cdm)
        seen_after = run_after(idle_seen, self.frame_cdm | ~self.frame_ok)
        with m.If(self.frame_end):
            m.d.sync += [idle_run.eq(idle_after), idle_seen.eq(seen_after)]
        # The counts including a cycle that ends now: a decision need not wait a clock.
        m.d.comb += [
            self.run_enough.eq(Mux(self.frame_end, idle_after, idle_run) == _IDLE),
            self.seen_enough.eq(Mux(self.frame_end, seen_after, idle_seen) == _IDLE),
        ]
        return m
