"""How the end of a request cycle is reported: the frame, or a fault status and its strobe."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..layouts import fault_layout
from ..params import FAULTS, Status


class CycleReport(wiring.Component):
    """Turns the controller's decision into the report the verdict, the result registers and
    the counters take. Combinational: the report comes in the clock of the decision.

    - ``frame`` (the frame is reported): ``report_frame`` and ``report_delay``;
    - ``delay`` (DELAY_RANGE at the Ack edge): ``report_delay``, with the fault;
    - ``fail`` with ``status`` (one of ``FAULTS``): ``fault``, ``fault_status`` = ``status``
      and the one strobe of ``faults`` named after it.

    The controller sets ``status`` only with ``fail`` (OK otherwise), so ``fault_status`` is OK
    in every clock without a fault.

    Attributes
    ----------
    frame, delay : In(1)
        Report the frame (its verdict, fields and line delay); report the line delay.
    fail : In(1)
        The cycle ends with ``status``, without a frame.
    status : In(Status)
        The fault's status; OK without ``fail``.
    report_frame, report_delay : Out(1)
        To the verdict and the result registers.
    fault : Out(1)
        Report ``fault_status`` in this clock, without a frame.
    fault_status : Out(Status)
    faults : Out(fault_layout())
        One strobe per fault status.
    """

    def __init__(self):
        super().__init__({
            "frame": In(1),
            "delay": In(1),
            "fail": In(1),
            "status": In(Status),
            "report_frame": Out(1),
            "report_delay": Out(1),
            "fault": Out(1),
            "fault_status": Out(Status),
            "faults": Out(fault_layout()),
        })

    def elaborate(self, platform):
        m = Module()
        # The frame, and the delay measured for it or for its DELAY_RANGE fault.
        m.d.comb += [self.report_frame.eq(self.frame),
                     self.report_delay.eq(self.frame | self.delay)]
        # The fault, its status and its own strobe.
        m.d.comb += [self.fault.eq(self.fail), self.fault_status.eq(self.status)]
        m.d.comb += [self.faults[s.name.lower()].eq(self.fail & (self.status == s))
                     for s in FAULTS]
        return m
