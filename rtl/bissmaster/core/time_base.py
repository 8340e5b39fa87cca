"""Free-running time base behind the ``timestamp`` result."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class TimeBase(wiring.Component):
    """A free-running clock counter, captured at the cycle's first MA rise.

    The encoder latches its position a fixed time after the first MA rising edge (its sampling
    moment), so that edge timestamps the position. The counter wraps.

    Parameters
    ----------
    width : int
    external : bool
        Capture the input ``now`` (a time base shared by several cores) instead of a counter
        of this block's own.

    Attributes
    ----------
    now : In(width)
        Only with ``external``: the time to capture.
    first_rise : In(1)
        The cycle's first MA rising edge (MaClock).
    first_rise_time : Out(width)
        The counter (or ``now``) at the last ``first_rise``.
    """

    def __init__(self, width, external=False):
        self._external = external
        super().__init__({**({"now": In(width)} if external else {}),
                          "first_rise": In(1), "first_rise_time": Out(width)})

    def elaborate(self, platform):
        m = Module()
        if self._external:
            now = self.now
        else:
            now = Signal(len(self.first_rise_time))
            m.d.sync += now.eq(now + 1)
        with m.If(self.first_rise):
            m.d.sync += self.first_rise_time.eq(now)
        return m
