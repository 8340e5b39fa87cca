"""The registers the constraint files name exist in the committed Verilog under those names:
a renamed block or register must fail here, not silently drop a false path in a user's flow.

The core's files (biss_master.xdc, .sdc) are checked against rtl/generated/biss_master.v; the
bus tops' (biss_master_bus.xdc, .sdc) against biss_master_axil.v and biss_master_wb.v: every
channel's synchronizer and MA register, on the path ch<i>/core/..., and the channel's own pins
ch<i>_ma / ch<i>_slo, for every channel the committed bus tops have.
"""

import re

import pytest

from testkit import REPO as ROOT
CORE = "biss_master"
BUS_TOPS = ("biss_master_axil", "biss_master_wb", "biss_master_uart")
UART_TOP = "biss_master_uart"


def _verilog(top):
    return (ROOT / "rtl" / "generated" / f"{top}.v").read_text()


def _module_body(top, instances):
    """The text of the module of the instance path ``instances`` below ``top``."""
    verilog = _verilog(top)
    module = ".".join([top, *instances])
    body = verilog.split(f"module \\{module} (" if instances else f"module {top}(", 1)
    assert len(body) == 2, f"no module {module} in {top}.v"
    return body[1].split("endmodule", 1)[0]


def _register_exists(path, top=CORE):
    """``a/b/r``: register ``r`` in the module of instance ``b`` inside instance ``a``."""
    *instances, reg = path
    body = _module_body(top, instances)
    return re.search(rf"^\s*reg (\[\d+:\d+\] )?{re.escape(reg)}\b", body, re.M) is not None


def _ports(top, direction):
    """The one-bit ports of ``top`` declared with ``direction`` ("input", "output")."""
    return set(re.findall(rf"^\s*{direction} (\w+);", _module_body(top, []), re.M))


def _code(file):
    text = (ROOT / "constraints" / file).read_text()
    return "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))


def _paths(file, pattern, sep):
    return sorted({tuple(m.split(sep)) for m in re.findall(pattern, _code(file))})


XDC = _paths("biss_master.xdc", r"\$biss_inst/([\w/]+?)_reg\b", "/")
SDC = _paths("biss_master.sdc", r"\$\{biss_inst\}\|([\w|]+)", "|")
BUS_XDC = _paths("biss_master_bus.xdc", r"\$bus_inst/([\w/]+?)_reg\b", "/")
BUS_SDC = _paths("biss_master_bus.sdc", r"\$\{bus_inst\}\|([\w|]+)", "|")
UART_XDC = _paths("biss_master_uart.xdc", r"\$bus_inst/([\w/]+?)_reg\b", "/")
UART_SDC = _paths("biss_master_uart.sdc", r"\$\{bus_inst\}\|([\w|]+)", "|")


@pytest.mark.parametrize("path", XDC + SDC, ids=lambda p: "/".join(p))
def test_constrained_register_exists(path):
    assert _register_exists(path), f"constraints name {'/'.join(path)}, not in the Verilog"


def test_constraints_name_the_synchronizer_and_ma():
    assert ("sampler", "sync", "stage0") in XDC and ("ma_clock", "ma") in XDC
    assert ("sampler", "sync", "stage0") in SDC


# -- The bus tops -------------------------------------------------------------------------------

def _channels(top):
    """The channel indices of a committed bus top, from its ch<i>_ma ports."""
    return sorted(int(n) for n in re.findall(r"ch(\d+)_ma", " ".join(_ports(top, "output"))))


@pytest.mark.parametrize("top", BUS_TOPS)
@pytest.mark.parametrize("path", BUS_XDC + BUS_SDC, ids=lambda p: "/".join(p))
def test_bus_constrained_register_exists(top, path):
    assert _register_exists(path, top), f"constraints name {'/'.join(path)}, not in {top}.v"


@pytest.mark.parametrize("top", BUS_TOPS)
def test_bus_constraints_cover_every_channel(top):
    channels = _channels(top)
    assert channels == list(range(len(channels))) and len(channels) >= 2
    for i in channels:
        core = (f"ch{i}", "core")
        assert (*core, "sampler", "sync", "stage0") in BUS_XDC, f"ch{i} synchronizer (xdc)"
        assert (*core, "sampler", "sync", "stage1") in BUS_XDC, f"ch{i} ASYNC_REG (xdc)"
        assert (*core, "ma_clock", "ma") in BUS_XDC, f"ch{i} MA register (xdc)"
        assert (*core, "sampler", "sync", "stage0") in BUS_SDC, f"ch{i} synchronizer (sdc)"
    constrained = {p[0] for p in BUS_XDC + BUS_SDC}
    assert constrained == {f"ch{i}" for i in channels}, "a channel the bus tops do not have"


@pytest.mark.parametrize("file", ["biss_master_bus.xdc", "biss_master_bus.sdc"])
@pytest.mark.parametrize("top", BUS_TOPS)
def test_bus_pins_are_the_channels_ports(file, top):
    """Each channel's pin variables default to its own ports of the bus top, and every
    constraint that names a pin and a register names those of one channel."""
    code = _code(file)
    pins = dict(re.findall(r"^set (ch\d+_(?:ma|slo)_port)\s+(\w+)", code, re.M))
    for i in _channels(top):
        assert pins[f"ch{i}_ma_port"] == f"ch{i}_ma" in _ports(top, "output")
        assert pins[f"ch{i}_slo_port"] == f"ch{i}_slo" in _ports(top, "input")
    for line in code.splitlines():
        indices = set(re.findall(r"\$\{?(?:bus_inst\}?[/|])?ch(\d+)", line))
        assert len(indices) <= 1, f"{file}: one line, two channels: {line}"
    used = set(re.findall(r"\$(ch\d+_(?:ma|slo)_port)", code))
    assert used == set(pins), f"{file}: a pin set but not constrained, or the reverse"


# -- The UART-bridge top's host link -------------------------------------------------------------

@pytest.mark.parametrize("path", UART_XDC + UART_SDC, ids=lambda p: "/".join(p))
def test_uart_constrained_register_exists(path):
    assert _register_exists(path, UART_TOP), f"constraints name {'/'.join(path)}, not in the Verilog"


def test_uart_constraints_name_the_rx_synchronizer():
    sync = ("bus", "receiver", "sync")
    assert {(*sync, "stage0"), (*sync, "stage1")} <= set(UART_XDC)
    assert (*sync, "stage0") in UART_SDC


@pytest.mark.parametrize("file", ["biss_master_uart.xdc", "biss_master_uart.sdc"])
def test_uart_pins_are_the_tops_ports(file):
    code = _code(file)
    pins = dict(re.findall(r"^set (uart_\w+_port)\s+(\w+)", code, re.M))
    assert pins == {"uart_rx_port": "uart_rx", "uart_tx_port": "uart_tx"}
    assert "uart_rx" in _ports(UART_TOP, "input") and "uart_tx" in _ports(UART_TOP, "output")
    assert set(re.findall(r"\$(uart_\w+_port)", code)) == set(pins)
