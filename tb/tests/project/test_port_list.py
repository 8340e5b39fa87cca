"""The generated Verilog keeps its port list: names, order, directions and widths, for every
generator preset. The reference lists in ``data/ports_<preset>.txt`` were taken from the
Verilog before the master was split into components (issue 11); a change to a port is a change
to every user's instantiation and must be made on purpose (regenerate with ``--update``)."""

import re
import sys
from pathlib import Path

import pytest

from bissmaster.generate import PRESETS, main

from testkit import DATA, REPO


def port_list(verilog, module="biss_master"):
    """``direction width name`` per port of ``module``, in header order."""
    body = verilog[verilog.index(f"module {module}("):]
    header = body[body.index("(") + 1:body.index(")")]
    order = [name.strip() for name in header.split(",")]
    decl = dict((m.group(3), (m.group(1), m.group(2) or "[0:0]"))
                for m in re.finditer(r"^\s*(input|output)\s+(?:wire\s+|reg\s+)?(\[\d+:\d+\])?\s*(\w+);",
                                     body[:body.index("endmodule")], re.M))
    return [f"{decl[n][0]} {decl[n][1]} {n}" for n in order]


def generated_ports(preset, tmp_path):
    out = tmp_path / f"{preset}.v"
    main(["--preset", preset, "-o", str(out)])
    return port_list(out.read_text())


@pytest.mark.parametrize("preset", PRESETS)
def test_port_list_unchanged(preset, tmp_path):
    want = (DATA / f"ports_{preset}.txt").read_text().splitlines()
    got = generated_ports(preset, tmp_path)
    assert got == want, (f"preset {preset}: the port list changed; if on purpose, run "
                         f"`PYTHONPATH=rtl .venv/bin/python tb/tests/project/test_port_list.py --update`")



def test_readme_instantiation_ties_every_input():
    """The README's Verilog instantiation of the default build connects every input port: a
    user who copies it leaves no input floating (X in simulation) when a port is added. (Its
    outputs are left to the user: "remaining outputs as needed".)"""
    text = (REPO / "README.md").read_text()
    block = text[text.index("biss_master u_biss ("):]
    block = block[:block.index(");")]
    connected = set(re.findall(r"\.(\w+)\(", block))
    inputs = {line.split()[-1] for line in (DATA / "ports_default.txt").read_text().splitlines()
              if line.startswith("input")}
    assert not inputs - connected, f"README instantiation leaves inputs open: {sorted(inputs - connected)}"
    assert not connected - inputs - {line.split()[-1] for line in
                                      (DATA / "ports_default.txt").read_text().splitlines()}, \
        "README instantiation names a port the default build does not have"

if __name__ == "__main__" and "--update" in sys.argv:
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        for preset in PRESETS:
            (DATA / f"ports_{preset}.txt").write_text(
                "\n".join(generated_ports(preset, Path(d))) + "\n")
