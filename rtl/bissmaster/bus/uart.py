"""An 8N1 UART: receiver, transmitter and the baud divider they share.

Written here because amaranth-stdio (Amaranth's own serial blocks) is not published on PyPI,
and the package depends only on what pip installs. The UART bridge
(:mod:`bissmaster.bus.uart_bridge`, docs/uart_bridge.md) is their one user.

Both halves count the same divider: one bit lasts ``divider`` system clocks (:func:`divider`
chooses it from the clock and the baud rate, and refuses a rate it cannot keep). 8N1: a start
bit (0), eight data bits LSB first, one stop bit (1), no parity; the line idles high.
"""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

#: The shortest bit in system clocks: the receiver samples in the middle of a bit, so it needs
#: a few clocks per bit to find that middle after its 2-flop synchronizer.
MIN_DIVIDER = 4
#: The largest difference between the baud rate asked for and the one the divider gives. Both
#: ends of a line may be off; 2 % here leaves the sender's share of the receiver's margin
#: (the middle of the stop bit, 9.5 bits after the start edge, must stay in the stop bit).
MAX_BAUD_ERROR = 0.02


def divider(sys_clk_hz, baud):
    """The system clocks per bit for ``baud`` at ``sys_clk_hz``: the nearest integer.

    Raises ValueError when it is below :data:`MIN_DIVIDER` (the clock is too slow for that
    rate) or when the rate it gives is more than :data:`MAX_BAUD_ERROR` away from ``baud``.
    """
    for name, value in (("sys_clk_hz", sys_clk_hz), ("baud", baud)):
        if not isinstance(value, int) or isinstance(value, bool) or value <= 0:
            raise ValueError(f"{name} must be a positive integer, not {value!r}")
    div = round(sys_clk_hz / baud)
    if div < MIN_DIVIDER:
        raise ValueError(f"baud {baud} at sys_clk_hz {sys_clk_hz}: the divider would be "
                         f"{sys_clk_hz / baud:.2f} clocks per bit, less than {MIN_DIVIDER} "
                         f"(at most {sys_clk_hz // MIN_DIVIDER} baud at this clock)")
    error = abs(sys_clk_hz / div - baud) / baud
    if error > MAX_BAUD_ERROR:
        raise ValueError(f"baud {baud} at sys_clk_hz {sys_clk_hz}: the divider {div} gives "
                         f"{sys_clk_hz / div:.0f} baud, {100 * error:.1f} % off (at most "
                         f"{100 * MAX_BAUD_ERROR:.0f} %); choose another baud rate or clock")
    return div


class UartRx(wiring.Component):
    """8N1 receiver.

    ``rx`` is asynchronous: it goes through a 2-flop synchronizer
    (:class:`~amaranth.lib.cdc.FFSynchronizer`, reset value 1, the idle line). A byte begins
    with the first clock in which the synchronized line is low while the receiver is idle; the
    start bit is sampled ``divider // 2`` clocks later (its middle) and, when it reads 1 there,
    was a glitch and is forgotten. Then each data bit and the stop bit is sampled ``divider``
    clocks after the one before, in its middle. At the stop bit's sample the byte ends: with
    the stop bit 1, ``valid`` is high for one clock with ``data``; with the stop bit 0,
    ``frame_error`` is high for one clock instead (``data`` holds the bits as sampled) and the
    receiver waits for the line to be high again before it looks for the next start bit, so a
    line held low (a break, an unplugged cable) gives one framing error, not a byte per
    ten bit times. From the stop bit's sample on it watches for the next start bit at once: a
    sender up to half a bit per byte fast is followed.

    ``data`` holds its value from one byte's end to the next; ``valid`` and ``frame_error``
    come from flip-flops, the clock after the stop bit's sample. ``busy`` is high from the
    clock a start bit is seen up to the stop bit's sample, and while the line stays low after a
    framing error: it is low exactly while the receiver sees a quiet (high) line.

    Parameters
    ----------
    divider : int
        System clocks per bit (:func:`divider`), at least :data:`MIN_DIVIDER`.

    Attributes
    ----------
    rx : In(1)
        The line (idle 1), asynchronous.
    data : Out(8)
    valid : Out(1)
    frame_error : Out(1)
    busy : Out(1)
    """

    def __init__(self, divider):
        if not isinstance(divider, int) or divider < MIN_DIVIDER:
            raise ValueError(f"divider must be an integer of at least {MIN_DIVIDER}, "
                             f"not {divider!r}")
        self.divider = divider
        super().__init__({"rx": In(1, init=1), "data": Out(8), "valid": Out(1),
                          "frame_error": Out(1), "busy": Out(1)})

    def elaborate(self, platform):
        m = Module()
        div = self.divider
        line = Signal(init=1)
        m.submodules.sync = FFSynchronizer(self.rx, line, init=1)

        count = Signal(range(div))          # clocks to the next sample, minus one
        bit = Signal(range(8))              # the data bit sampled next
        shift = Signal(8)
        m.d.sync += [self.valid.eq(0), self.frame_error.eq(0)]
        with m.FSM(name="rx_fsm") as fsm:
            with m.State("IDLE"):
                with m.If(~line):
                    m.d.sync += count.eq(div // 2 - 1)
                    m.next = "START"
            with m.State("START"):
                with m.If(count != 0):
                    m.d.sync += count.eq(count - 1)
                with m.Elif(line):
                    m.next = "IDLE"                 # shorter than half a bit: a glitch
                with m.Else():
                    m.d.sync += [count.eq(div - 1), bit.eq(0)]
                    m.next = "DATA"
            with m.State("DATA"):
                with m.If(count != 0):
                    m.d.sync += count.eq(count - 1)
                with m.Else():
                    m.d.sync += [shift.eq(Cat(shift[1:], line)), count.eq(div - 1),
                                 bit.eq(bit + 1)]
                    with m.If(bit == 7):
                        m.next = "STOP"
            with m.State("STOP"):
                with m.If(count != 0):
                    m.d.sync += count.eq(count - 1)
                with m.Else():
                    m.d.sync += self.data.eq(shift)
                    with m.If(line):
                        m.d.sync += self.valid.eq(1)
                        m.next = "IDLE"
                    with m.Else():
                        m.d.sync += self.frame_error.eq(1)
                        m.next = "WAIT_HIGH"
            with m.State("WAIT_HIGH"):
                with m.If(line):
                    m.next = "IDLE"
        m.d.comb += self.busy.eq(~fsm.ongoing("IDLE"))
        return m


class UartTx(wiring.Component):
    """8N1 transmitter.

    ``ready`` is high when a byte can be taken: while idle, and in the last clock of a stop
    bit. A byte is taken in a clock with ``valid`` and ``ready``; ``tx`` (a flip-flop) gives its
    start bit from the next clock, then the eight data bits LSB first and the stop bit,
    ``divider`` clocks each. Bytes given as soon as ``ready`` allows follow each other without
    a gap: one byte per ``10 * divider`` clocks.

    Parameters
    ----------
    divider : int
        System clocks per bit (:func:`divider`), at least :data:`MIN_DIVIDER`.

    Attributes
    ----------
    data : In(8)
    valid : In(1)
    ready : Out(1)
    tx : Out(1)
        The line, idle 1.
    """

    def __init__(self, divider):
        if not isinstance(divider, int) or divider < MIN_DIVIDER:
            raise ValueError(f"divider must be an integer of at least {MIN_DIVIDER}, "
                             f"not {divider!r}")
        self.divider = divider
        super().__init__({"data": In(8), "valid": In(1), "ready": Out(1),
                          "tx": Out(1, init=1)})

    def elaborate(self, platform):
        m = Module()
        div = self.divider
        count = Signal(range(div))          # clocks left in the bit on the line, minus one
        left = Signal(range(11))            # bits on the line or still to come (0: idle)
        shift = Signal(9)                   # the data bits, then the stop bit
        m.d.comb += self.ready.eq((left == 0) | ((left == 1) & (count == 0)))
        with m.If(self.valid & self.ready):
            m.d.sync += [self.tx.eq(0), shift.eq(Cat(self.data, 1)), left.eq(10),
                         count.eq(div - 1)]
        with m.Elif(left != 0):
            with m.If(count != 0):
                m.d.sync += count.eq(count - 1)
            with m.Else():
                m.d.sync += [self.tx.eq(Mux(left == 1, 1, shift[0])),
                             shift.eq(Cat(shift[1:], 1)), left.eq(left - 1),
                             count.eq(div - 1)]
        return m
