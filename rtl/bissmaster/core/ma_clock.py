"""MA clock generator."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import HALF_PERIOD_WIDTH, SLOT_WIDTH


class MaClock(wiring.Component):
    """Generates the MA clock: idle high, 1:1 duty, falling edge first.

    Every phase lasts exactly ``half_period`` system clocks, including the high phase after the
    last rising edge, so MA never shows a high or low phase shorter than the half period, even
    when ``run`` drops at an arbitrary moment (an abort): the clock then completes its current
    period and stays high.

    ``half_period`` is sampled at each edge; the master keeps it constant within a cycle.

    **CDM hold** (``cdm=True`` builds, for the control channel): when ``run`` is low at the end
    of a high phase and ``hold`` is high there, MA falls anyway, exactly when the next period
    would have begun, and stays low (state HOLD, ``held``) through the encoder's timeout: the
    encoder reads the inverted level as CDM = 1. The low phase lasts at least ``half_period``
    clocks, and until ``hold`` has been seen low in one clock (a release is remembered); MA then
    rises and stays high for exactly ``half_period`` clocks (RELEASE, busy) before the clock is
    idle. So the no-short-phase guarantee holds with the hold too, and MA is high whenever the
    clock is idle. ``hold`` is read only at the end of a high phase with ``run`` low, and in
    HOLD; the release rise is not a clock edge of a frame (no ``rise`` strobe, ``rises`` kept).

    Parameters
    ----------
    cdm : bool
        Build the CDM hold (the ``hold`` input, the ``held`` and ``clocking`` outputs).
    half_period_width : int
        Width of ``half_period`` and of the phase counter (``MasterParams.half_period_width``).

    Attributes
    ----------
    run : In(1)
        Keep clocking. Sampled at the end of every high phase: low there means stop, MA stays high.
    half_period : In(half_period_width)
        System clocks per MA phase, at least 2.
    ma : Out(1)
        The MA line, registered.
    rise : Out(1)
        High in the first system clock in which ``ma`` is high after a rising edge.
    rises : Out(16)
        Rising edges since the cycle's first falling edge (saturating).
    first_rise, second_rise : Out(1)
        ``rise`` for the first and for the second rising edge of the cycle (``rise`` and
        ``rises`` == 1 or 2), registered: no compare of ``rises`` behind them.
    busy : Out(1)
        A period is in progress (MA low, or in the high phase of a period; with the CDM hold
        also HOLD and RELEASE).
    hold : In(1)
        ``cdm`` builds: hold MA low after the last period (see above).
    held : Out(1)
        ``cdm`` builds: MA is held low for CDM = 1 (state HOLD).
    clocking : Out(1)
        ``cdm`` builds: a clock period is in progress (busy, but not in HOLD or RELEASE).
    """

    def __init__(self, cdm=False, half_period_width=HALF_PERIOD_WIDTH):
        self._cdm = bool(cdm)
        self._hp_width = half_period_width
        members = {
            "run": In(1),
            "half_period": In(half_period_width),
            "ma": Out(1, init=1),
            "rise": Out(1),
            "rises": Out(SLOT_WIDTH),
            "first_rise": Out(1),
            "second_rise": Out(1),
            "busy": Out(1),
        }
        if self._cdm:
            members.update({"hold": In(1), "held": Out(1), "clocking": Out(1)})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        cdm = self._cdm

        phase_left = Signal(self._hp_width)     # clocks left in the current phase, minus one
        # ``phase_left == 0``, kept as a register: written wherever ``phase_left`` is.
        last_clock = Signal(init=1)
        reload_last = self.half_period == 1      # phase_left <- half_period - 1 == 0

        if cdm:
            released = Signal()                 # CDM hold: ``hold`` was low in HOLD

        m.d.sync += [self.rise.eq(0), self.first_rise.eq(0), self.second_rise.eq(0)]
        with m.FSM(name="ma_fsm") as fsm:
            with m.State("IDLE"):
                with m.If(self.run):
                    m.d.sync += [
                        self.ma.eq(0),
                        phase_left.eq(self.half_period - 1),
                        last_clock.eq(reload_last),
                        self.rises.eq(0),
                    ]
                    m.next = "LOW"
            with m.State("LOW"):
                m.d.comb += self.busy.eq(1)
                m.d.sync += [phase_left.eq(phase_left - 1), last_clock.eq(phase_left == 1)]
                with m.If(last_clock):
                    m.d.sync += [
                        self.ma.eq(1),
                        self.rise.eq(1),
                        self.first_rise.eq(self.rises == 0),
                        self.second_rise.eq(self.rises == 1),
                        phase_left.eq(self.half_period - 1),
                        last_clock.eq(reload_last),
                    ]
                    with m.If(~self.rises.all()):
                        m.d.sync += self.rises.eq(self.rises + 1)
                    m.next = "HIGH"
            with m.State("HIGH"):
                m.d.comb += self.busy.eq(1)
                m.d.sync += [phase_left.eq(phase_left - 1), last_clock.eq(phase_left == 1)]
                with m.If(last_clock):
                    with m.If(self.run):
                        m.d.sync += [
                            self.ma.eq(0),
                            phase_left.eq(self.half_period - 1),
                            last_clock.eq(reload_last),
                        ]
                        m.next = "LOW"
                    if cdm:
                        with m.Elif(self.hold):
                            # CDM = 1: the fall the next period would have made, then low.
                            m.d.sync += [
                                self.ma.eq(0),
                                phase_left.eq(self.half_period - 1),
                                last_clock.eq(reload_last),
                                released.eq(0),
                            ]
                            m.next = "HOLD"
                    with m.Else():
                        m.next = "IDLE"
            if cdm:
                with m.State("HOLD"):
                    # At least one half period low, then low until ``hold`` has dropped once.
                    m.d.comb += [self.busy.eq(1), self.held.eq(1)]
                    with m.If(~last_clock):
                        m.d.sync += [phase_left.eq(phase_left - 1),
                                     last_clock.eq(phase_left == 1)]
                    with m.If(~self.hold):
                        m.d.sync += released.eq(1)
                    with m.If(last_clock & (released | ~self.hold)):
                        m.d.sync += [
                            self.ma.eq(1),
                            phase_left.eq(self.half_period - 1),
                            last_clock.eq(reload_last),
                        ]
                        m.next = "RELEASE"
                with m.State("RELEASE"):
                    # One full half period high before the clock is idle (and may fall again).
                    m.d.comb += self.busy.eq(1)
                    m.d.sync += [phase_left.eq(phase_left - 1), last_clock.eq(phase_left == 1)]
                    with m.If(last_clock):
                        m.next = "IDLE"

        if cdm:
            m.d.comb += self.clocking.eq(fsm.ongoing("LOW") | fsm.ongoing("HIGH"))
        return m
