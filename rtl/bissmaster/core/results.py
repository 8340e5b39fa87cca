"""The result registers: what the last cycle reported, held until the next ``done``."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..layouts import result_layout


class ResultRegisters(wiring.Component):
    """Registers a cycle's result when the verdict reports it.

    ``done`` and ``valid`` are one-clock strobes one clock after ``report``; in the same clock
    the fields are new: ``status`` with every report, ``line_delay`` with ``report_delay`` (a
    frame, or its DELAY_RANGE fault), every other field with ``report_frame`` only. After a
    fault the frame fields keep the last decoded frame.

    Parameters
    ----------
    params : MasterParams

    Attributes
    ----------
    frame : In(result_layout)
        The result being reported (status from the verdict, fields from the decoder, the
        sampler and the time base).
    report, report_frame, report_delay, valid : In(1)
    done : Out(1)
    valid_out : Out(1)
        ``valid`` registered with ``done``.
    result : Out(result_layout)
    """

    def __init__(self, params):
        layout = result_layout(params)
        super().__init__({
            "frame": In(layout),
            "report": In(1),
            "report_frame": In(1),
            "report_delay": In(1),
            "valid": In(1),
            "done": Out(1),
            "valid_out": Out(1),
            "result": Out(layout),
        })

    def elaborate(self, platform):
        m = Module()
        frame, result = self.frame, self.result
        m.d.sync += [self.done.eq(self.report), self.valid_out.eq(self.valid)]
        with m.If(self.report):
            m.d.sync += result.status.eq(frame.status)
        with m.If(self.report_delay):
            m.d.sync += result.line_delay.eq(frame.line_delay)
        with m.If(self.report_frame):
            for name, _ in result.shape():
                if name not in ("status", "line_delay"):
                    m.d.sync += result[name].eq(frame[name])
        return m
