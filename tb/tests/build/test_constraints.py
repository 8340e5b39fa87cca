"""The registers the constraint files name exist in the committed Verilog under those names:
a renamed block or register must fail here, not silently drop a false path in a user's flow."""

import re
from pathlib import Path

import pytest

from testkit import REPO as ROOT
VERILOG = (ROOT / "rtl" / "generated" / "biss_master.v").read_text()


def _register_exists(path):
    """``a/b/r``: register ``r`` in the module of instance ``b`` inside instance ``a``."""
    *instances, reg = path
    module = ".".join(["biss_master", *instances])
    body = VERILOG.split(f"module \\{module} (" if instances else "module biss_master(", 1)
    assert len(body) == 2, f"no module {module} in the Verilog"
    body = body[1].split("endmodule", 1)[0]
    return re.search(rf"^\s*reg (\[\d+:\d+\] )?{re.escape(reg)}\b", body, re.M) is not None


def _paths(file, pattern, sep):
    text = (ROOT / "constraints" / file).read_text()
    code = "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))
    return sorted({tuple(m.split(sep)) for m in re.findall(pattern, code)})


XDC = _paths("biss_master.xdc", r"\$biss_inst/([\w/]+?)_reg\b", "/")
SDC = _paths("biss_master.sdc", r"\$\{biss_inst\}\|([\w|]+)", "|")


@pytest.mark.parametrize("path", XDC + SDC, ids=lambda p: "/".join(p))
def test_constrained_register_exists(path):
    assert _register_exists(path), f"constraints name {'/'.join(path)}, not in the Verilog"


def test_constraints_name_the_synchronizer_and_ma():
    assert ("sampler", "sync", "stage0") in XDC and ("ma_clock", "ma") in XDC
    assert ("sampler", "sync", "stage0") in SDC
