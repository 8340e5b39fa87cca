"""BiSS Safety sign-of-life (LC) tracker."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .. import protocol


class SignOfLife(wiring.Component):
    """Checks that each frame's LC is the previous one plus 1, with 63 wrapping to 1.

    The verdict flags are combinational from ``lc`` and the stored value, for the frame being
    checked; ``check`` then stores the new value. 0 is never valid and is flagged as ``zero``;
    it does not replace the stored value, so the frame after it is judged against the last good
    LC. ``repeat`` (same value again: a stale frame) and ``skip`` (any other value: frames lost
    or out of order) are told apart. After ``resync`` (reset, abort, encoder reset) the next
    non-zero LC is accepted as it is.

    Attributes
    ----------
    lc : In(6)
    check : In(1)
        Strobe: ``lc`` belongs to a frame whose CRC was good; judge it and store it.
    resync : In(1)
        Forget the stored value.
    repeat, skip, zero : Out(1)
        Verdict for ``lc`` (only meaningful when ``check`` is high).
    synced : Out(1)

    With ``early=True`` two more inputs, ``lc_next`` and ``load``, give the LC while it is
    shifted in (``lc_next`` is the value ``lc`` will hold after a clock with ``load`` high). The
    three compares are then made on ``lc_next`` and registered, and ``repeat``, ``skip`` and
    ``zero`` come from those flip-flops: right from the clock after the LC's last bit on, for as
    long as neither the LC nor the stored value changes (the master checks once per frame, after
    the LC field). No compare then sits in front of the master's frame verdict.

    In that mode the store is registered as well: ``check`` (with ``lc``) is taken into a
    flip-flop and the new value is stored one clock later, so that the enable of the stored
    value and of ``synced`` comes from a flip-flop and not from the master's end-of-frame
    decision. The verdict of the checked frame is unchanged (it is read in the clock of
    ``check``); a ``resync`` in the clock of ``check`` cancels the store, one in the clock
    after wins over it, as it does without the register (``synced`` ends low, and the stored
    value does not matter until the next check). The next check can come at the earliest
    after the next LC has been shifted in (6 ``load`` clocks), long after the store.
    """

    def __init__(self, early=False):
        self._early = early
        members = {
            "lc": In(protocol.LC_BITS),
            "check": In(1),
            "resync": In(1),
            "repeat": Out(1),
            "skip": Out(1),
            "zero": Out(1),
            "synced": Out(1),
        }
        if early:
            members.update({"lc_next": In(protocol.LC_BITS), "load": In(1)})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()

        def successor(lc):
            return Mux(lc == protocol.LC_MAX, protocol.LC_FIRST, lc + 1)

        last = Signal(protocol.LC_BITS)
        # The successor of ``last``, stored with it (no incrementer in front of the compare).
        # Its reset value is the successor of last's reset value 0.
        expected = Signal(protocol.LC_BITS, init=1)

        if self._early:
            is_zero = Signal()
            is_last = Signal()
            is_expected = Signal()
            with m.If(self.load):
                m.d.sync += [
                    is_zero.eq(self.lc_next == 0),
                    is_last.eq(self.lc_next == last),
                    is_expected.eq(self.lc_next == expected),
                ]
        else:
            is_zero = self.lc == 0
            is_last = self.lc == last
            is_expected = self.lc == expected
        m.d.comb += [
            self.zero.eq(is_zero),
            self.repeat.eq(self.synced & ~is_zero & is_last),
            self.skip.eq(self.synced & ~is_zero & ~is_last & ~is_expected),
        ]
        if self._early:
            store = Signal()
            store_lc = Signal(protocol.LC_BITS)
            m.d.sync += [store.eq(self.check & ~self.zero & ~self.resync), store_lc.eq(self.lc)]
        else:
            store, store_lc = self.check & ~self.zero, self.lc
        with m.If(store):
            m.d.sync += [last.eq(store_lc), expected.eq(successor(store_lc)), self.synced.eq(1)]
        with m.If(self.resync):
            m.d.sync += self.synced.eq(0)

        return m
