"""The cycle's CDM bit and the hold of MA low after its frame (the control channel)."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out


class CdmHold(wiring.Component):
    """Copies the CDM bit for the cycle and asks MaClock to hold MA low after a CDM = 1 frame.

    ``cdm_cycle`` takes ``cdm`` in every clock with ``idle`` high (the controller's, like the
    configuration), so a cycle carries the bit of its accepted request.

    ``ma_hold`` (to :class:`~bissmaster.core.ma_clock.MaClock`'s ``hold``), combinational:

    - while ``framing`` (CLOCK, TAIL): ``cdm_cycle`` and no ``abort``. MaClock reads it only at
      the end of the last high phase, so only a frame that clocked out every rise is followed
      by a hold;
    - while ``holding`` (END, CONFIRM, PAUSE): ``cdm_cycle``, until the first clock with SLO
      high (the encoder's timeout ended), ``slo_stuck`` (SLO low for the timeout limit: it
      never ends) or ``abort``; in that clock and after it, low (the release);
    - otherwise low (a fault or an abort goes to BREAK, which never holds).

    Attributes
    ----------
    idle : In(1)
        The controller is idle: take ``cdm`` as the cycle's bit in this clock.
    cdm : In(1)
        The CDM bit for the next cycle (from the register-access engine).
    framing, holding : In(1)
        The controller's state: the frame is clocked out; the frame is over.
    slo, slo_stuck, abort : In(1)
        Synchronized SLO; SLO low for the latched timeout limit; ``abort_cycle``.
    cdm_cycle : Out(1)
        The CDM bit this cycle carries.
    ma_hold : Out(1)
        Hold MA low after the frame.
    """

    def __init__(self):
        super().__init__({
            "idle": In(1),
            "cdm": In(1),
            "framing": In(1),
            "holding": In(1),
            "slo": In(1),
            "slo_stuck": In(1),
            "abort": In(1),
            "cdm_cycle": Out(1),
            "ma_hold": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        # The cycle's CDM bit, copied while idle like the configuration.
        with m.If(self.idle):
            m.d.sync += self.cdm_cycle.eq(self.cdm)
        # Release the hold: the encoder's timeout ended (SLO high), it never ends (the
        # timeout limit), or an abort.
        release = self.slo | self.slo_stuck | self.abort
        with m.If(self.framing):
            m.d.comb += self.ma_hold.eq(self.cdm_cycle & ~self.abort)
        with m.Elif(self.holding):
            m.d.comb += self.ma_hold.eq(self.cdm_cycle & ~release)
        return m
