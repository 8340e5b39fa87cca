"""What a board design puts on its pins, without the board: the UART bridge top with its
channels, the RS-422 transceiver enables and the status LEDs (:class:`BoardLogic`).

Everything here runs in the ``sync`` domain that the board's clocking makes
(:mod:`bissmaster.boards.clocking`); :class:`~bissmaster.boards.designs.BoardTop` connects it
to the board's pins. It has no pin of its own and no vendor primitive, so the Amaranth
simulator runs it as it is (tb/tests/board/).
"""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..bus.bus_top import BusTop

#: How long a status LED stays lit after a one-clock event (a frame), in seconds: a single
#: frame is seen, and frames at any rate above 1 / LED_HOLD_S keep it lit steadily.
LED_HOLD_S = 0.05
#: The heartbeat LED's period in seconds (it toggles every half period): the design runs and
#: its clock is the one expected.
HEARTBEAT_PERIOD_S = 1.0


def led_hold_clocks(sys_clk_hz):
    """:data:`LED_HOLD_S` in clocks."""
    return round(LED_HOLD_S * sys_clk_hz)


def heartbeat_half_clocks(sys_clk_hz):
    """Half of :data:`HEARTBEAT_PERIOD_S` in clocks (the heartbeat LED toggles after it)."""
    return round(HEARTBEAT_PERIOD_S / 2 * sys_clk_hz)


class PulseStretcher(Elaboratable):
    """``o`` is high for ``clocks`` clocks after each clock in which ``i`` is high."""

    def __init__(self, clocks):
        if clocks < 1:
            raise ValueError(f"clocks must be at least 1, not {clocks!r}")
        self.clocks = clocks
        self.i = Signal()
        self.o = Signal()

    def elaborate(self, platform):
        m = Module()
        left = Signal(range(self.clocks + 1))
        with m.If(self.i):
            m.d.sync += left.eq(self.clocks)
        with m.Elif(left != 0):
            m.d.sync += left.eq(left - 1)
        m.d.comb += self.o.eq(left != 0)
        return m


class BoardLogic(wiring.Component):
    """A board's design minus clocking and pins: :class:`~bissmaster.bus.bus_top.BusTop` with the
    UART bridge (``channels`` cores of ``params``, ``baud``), per channel the transceiver's driver
    and receiver enables, and the status LEDs.

    Parameters
    ----------
    channels : int
    params : MasterParams
        The cores' configuration; its ``sys_clk_hz`` is the clock this logic runs on (the UART
        divider, the LED times and the core's default times count it).
    baud : int
        The UART bridge's baud rate (8N1).

    Attributes
    ----------
    uart_rx : In(1)
        From the host (the USB-serial chip's TXD); asynchronous, idles high.
    uart_tx : Out(1)
        To the host.
    ch<n>_ma : Out(1)
        MA, to the transceiver's driver input (DI / D).
    ch<n>_slo : In(1)
        SLO, from the transceiver's receiver output (RO / R); asynchronous.
    ch<n>_de : Out(1)
        The driver enable: high once the design is out of reset (MA is then driven, idle high).
    ch<n>_re : Out(1)
        The receiver enable (the pin is the transceiver's active-low ``/RE``: the board inverts
        it): high once the design is out of reset.
    heartbeat : Out(1)
        Toggles every ``HEARTBEAT_PERIOD_S / 2``.
    ch<n>_valid_led, ch<n>_fault_led : Out(1)
        Lit for ``LED_HOLD_S`` after a cycle ended with a valid frame, or with any other status
        (CRC error, no start bit, timeout, ...).
    """

    def __init__(self, channels, params, baud=115200):
        self.channels, self.params, self.baud = channels, params, baud
        self.sys_clk_hz = params.sys_clk_hz
        # Built here so that a bad baud rate or channel count is refused at once.
        self._top = BusTop("uart", channels, params, status=True, baud=baud)
        members = {"uart_rx": In(1, init=1), "uart_tx": Out(1, init=1), "heartbeat": Out(1)}
        for n in range(channels):
            members.update({f"ch{n}_ma": Out(1, init=1), f"ch{n}_slo": In(1, init=1),
                            f"ch{n}_de": Out(1), f"ch{n}_re": Out(1),
                            f"ch{n}_valid_led": Out(1), f"ch{n}_fault_led": Out(1)})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        m.submodules.top = top = self._top
        m.d.comb += [top.uart_rx.eq(self.uart_rx), self.uart_tx.eq(top.uart_tx),
                     top.trigger.eq(0)]

        # Out of reset: the enables are flip-flops reset to 0 (the transceiver's driver stays off
        # while the design is held in reset, e.g. until the PLL locks).
        running = Signal()
        m.d.sync += running.eq(1)
        for n in range(self.channels):
            m.d.comb += [getattr(self, f"ch{n}_ma").eq(getattr(top, f"ch{n}_ma")),
                         getattr(top, f"ch{n}_slo").eq(getattr(self, f"ch{n}_slo")),
                         getattr(self, f"ch{n}_de").eq(running),
                         getattr(self, f"ch{n}_re").eq(running)]
            for event, led in (("frame_valid", "valid_led"), ("frame_error", "fault_led")):
                m.submodules[f"ch{n}_{led}"] = s = PulseStretcher(led_hold_clocks(self.sys_clk_hz))
                m.d.comb += [s.i.eq(getattr(top, f"ch{n}_{event}")),
                             getattr(self, f"ch{n}_{led}").eq(s.o)]

        beat = Signal(range(heartbeat_half_clocks(self.sys_clk_hz)))
        with m.If(beat == heartbeat_half_clocks(self.sys_clk_hz) - 1):
            m.d.sync += [beat.eq(0), self.heartbeat.eq(~self.heartbeat)]
        with m.Else():
            m.d.sync += beat.eq(beat + 1)
        return m
