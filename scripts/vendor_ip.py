#!/usr/bin/env python3
"""`make vendor`: the AXI4-Lite bus top packaged for the vendors' IP tools (docs/vendor.md).

Writes into ``rtl/generated/vendor/biss_master_axil/``, from the committed
``rtl/generated/biss_master_axil.v`` (its module header and port declarations: the port list
is read, never written here, so the packages cannot drift from the Verilog):

* ``component.xml``: an IP-XACT component for Vivado's IP catalog, in the form Vivado's IP
  packager writes (IEEE 1685-2009, the ``spirit`` namespace, Xilinx vendor extensions): the
  ``xilinx.com:interface:aximm:1.0`` subordinate ``s_axil`` over the ``s_axil_*`` ports, the
  clock ``clk`` (``ASSOCIATED_BUSIF s_axil``), the reset ``rst`` (``POLARITY ACTIVE_HIGH``), the
  interrupt ``irq`` (``LEVEL_HIGH``), every port with its direction and width, the file sets
  (the Verilog, the IP's constraints) and the register map: PeakRDL's export of
  ``rtl/bissmaster/bus/biss_master.rdl`` (the source of ``rtl/generated/biss_master_regs.xml``)
  in the 2009 schema.
* ``biss_master_axil.xdc``: ``constraints/biss_master_bus.xdc`` as the IP's own, scoped,
  constraints: the instance prefix ``$bus_inst/`` dropped (an IP's XDC is applied inside the IP
  instance), the port names the IP's own.
* ``biss_master_axil_hw.tcl``: a Platform Designer (Quartus) component: the fileset, the clock
  and reset, the ``axi4lite`` subordinate, an interrupt sender, a conduit per channel (MA, SLO)
  and one for ``trigger``.

Nothing here has been run through Vivado or Quartus (docs/vendor.md says what was checked).
Deterministic: no dates, no checksums; ``tb/tests/project/test_vendor_ip.py`` regenerates every
file and compares.

    python scripts/vendor_ip.py
"""

import argparse
import os
import re
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
TOP = "biss_master_axil"
VERILOG = REPO / "rtl" / "generated" / f"{TOP}.v"
BUS_XDC = REPO / "constraints" / "biss_master_bus.xdc"
OUT = REPO / "rtl" / "generated" / "vendor" / TOP

COMPONENT = "component.xml"
XDC = f"{TOP}.xdc"
HW_TCL = f"{TOP}_hw.tcl"

#: The VLNV: FuseSoC's vendor and library (biss_master.core), Vivado's major.minor version.
VENDOR, LIBRARY = "bissmaster", "ip"

SPIRIT = "http://www.spiritconsortium.org/XMLSchema/SPIRIT/1685-2009"
XILINX = "http://www.xilinx.com"
XSI = "http://www.w3.org/2001/XMLSchema-instance"

#: The AXI4-Lite signals (AMBA names, lower case) the bus top has, in the order of the AMBA
#: specification; a slave has no AxPROT here (docs/bus.md).
AXIL_SIGNALS = ("awaddr", "awvalid", "awready", "wdata", "wstrb", "wvalid", "wready", "bresp",
                "bvalid", "bready", "araddr", "arvalid", "arready", "rdata", "rresp", "rvalid",
                "rready")

#: Device families the component declares (Vivado shows an IP only for a part of a listed
#: family): the 7 series and UltraScale(+), the RTL being plain synchronous Verilog.
FAMILIES = ("artix7", "kintex7", "virtex7", "spartan7", "zynq", "kintexu", "virtexu",
            "kintexuplus", "virtexuplus", "zynquplus")

SYNTH_VIEW = "xilinx_anylanguagesynthesis"
SIM_VIEW = "xilinx_anylanguagebehavioralsimulation"


# -- The port list --------------------------------------------------------------------------------

@dataclass(frozen=True)
class Port:
    name: str
    direction: str      # "in" or "out"
    width: int
    msb: int = 0        # a vector's [msb:lsb]
    lsb: int = 0
    vector: bool = False


_DECL = re.compile(r"^\s*(input|output|inout)\s+(?:wire\s+|reg\s+)?(?:\[(\d+):(\d+)\]\s*)?"
                   r"(\\?\S+)\s*;", re.M)


def ports(verilog, module=TOP):
    """The ports of ``module`` in its header's order, from its declarations."""
    start = verilog.find(f"module {module}(")
    if start < 0:
        raise ValueError(f"no module {module} in the Verilog")
    body = verilog[start:verilog.index("endmodule", start)]
    header = body[body.index("(") + 1:body.index(");")]
    order = [name.strip() for name in header.split(",")]
    decl = {}
    for m in _DECL.finditer(body):
        direction, msb, lsb, name = m.groups()
        if direction == "inout":
            raise ValueError(f"{module}.{name}: an inout port has no place in this package")
        io = "out" if direction == "output" else "in"
        if msb is None:
            decl[name] = Port(name, io, 1)
        else:
            decl[name] = Port(name, io, abs(int(msb) - int(lsb)) + 1, int(msb), int(lsb), True)
    missing = [n for n in order if n not in decl]
    if missing:
        raise ValueError(f"{module}: ports without a declaration: {missing}")
    return [decl[n] for n in order]


def header_value(verilog, key):
    """A value of the generated Verilog's header comment (``//   key = value``)."""
    m = re.search(rf"^//\s+{re.escape(key)}\s+=\s+(.+)$", verilog, re.M)
    if m is None:
        raise ValueError(f"the Verilog's header has no {key}")
    return m.group(1).strip()


@dataclass(frozen=True)
class Interfaces:
    """Every port of the bus top, each in exactly one group."""
    clock: Port
    reset: Port
    axil: dict          # AMBA signal name (lower case) -> Port
    irq: Port
    trigger: Port
    channels: dict      # channel index -> {"ma": Port, "slo": Port}


def classify(port_list):
    """The ports grouped by interface; a port that fits none is refused, so that a new port of
    the bus top fails here (and in the freshness test) rather than being left out silently."""
    by_name = {p.name: p for p in port_list}
    fixed, axil, channels, unknown = {}, {}, {}, []
    for p in port_list:
        m = re.fullmatch(r"ch(\d+)_(ma|slo)", p.name)
        if p.name in ("clk", "rst", "irq", "trigger"):
            fixed[p.name] = p
        elif p.name.startswith("s_axil_") and p.name[len("s_axil_"):] in AXIL_SIGNALS:
            axil[p.name[len("s_axil_"):]] = p
        elif m:
            channels.setdefault(int(m.group(1)), {})[m.group(2)] = p
        else:
            unknown.append(p.name)
    if unknown:
        raise ValueError(f"ports of {TOP} that no interface takes: {unknown} "
                         f"(scripts/vendor_ip.py: classify)")
    lacking = [n for n in ("clk", "rst", "irq", "trigger") if n not in fixed]
    lacking += [f"s_axil_{s}" for s in AXIL_SIGNALS if s not in axil]
    lacking += [f"ch{i}_{s}" for i, ch in channels.items() for s in ("ma", "slo") if s not in ch]
    if lacking or sorted(channels) != list(range(len(channels))) or not channels:
        raise ValueError(f"{TOP} lacks the ports {lacking or 'of channel 0..n-1'}")
    expect = {"clk": ("in", 1), "rst": ("in", 1), "irq": ("out", 1), "trigger": ("in", 1)}
    for name, (direction, width) in expect.items():
        if (by_name[name].direction, by_name[name].width) != (direction, width):
            raise ValueError(f"{TOP}.{name} is not a {width}-bit {direction}put")
    return Interfaces(fixed["clk"], fixed["rst"], {s: axil[s] for s in AXIL_SIGNALS},
                      fixed["irq"], fixed["trigger"], dict(sorted(channels.items())))


def version_parts():
    """(Vivado's major.minor version, its core revision) from ``bissmaster.__version__``."""
    from bissmaster import __version__
    major, minor, *rest = __version__.split(".")
    return f"{major}.{minor}", int(rest[0]) if rest else 0


# -- Vivado: component.xml ---------------------------------------------------------------------

def _sub(parent, tag, text=None, ns=SPIRIT, **attrs):
    """A child element ``ns:tag``; attributes in the spirit namespace unless given as
    ``{namespace}name``."""
    el = ET.SubElement(parent, f"{{{ns}}}{tag}",
                       {k if k.startswith("{") else f"{{{SPIRIT}}}{k}": str(v)
                        for k, v in attrs.items()})
    if text is not None:
        el.text = str(text)
    return el


def _vlnv(parent, tag, vendor, library, name, version):
    return _sub(parent, tag, vendor=vendor, library=library, name=name, version=version)


def _bus_interface(parent, name, bus, abstraction, mode, port_maps, parameters=()):
    """One ``busInterface``: ``bus``/``abstraction`` as (vendor, library, name, version),
    ``mode`` an element (``slave``, ``master``) or (``slave``, memory map name), ``port_maps``
    (logical, physical) pairs, ``parameters`` (name, value, choice or None)."""
    bi = _sub(parent, "busInterface")
    _sub(bi, "name", name)
    _vlnv(bi, "busType", *bus)
    _vlnv(bi, "abstractionType", *abstraction)
    if isinstance(mode, tuple):
        el = _sub(bi, mode[0])
        _sub(el, "memoryMapRef", memoryMapRef=mode[1])
    else:
        _sub(bi, mode)
    maps = _sub(bi, "portMaps")
    for logical, physical in port_maps:
        pm = _sub(maps, "portMap")
        _sub(_sub(pm, "logicalPort"), "name", logical)
        _sub(_sub(pm, "physicalPort"), "name", physical)
    if parameters:
        params = _sub(bi, "parameters")
        for pname, value, choice in parameters:
            p = _sub(params, "parameter")
            _sub(p, "name", pname)
            attrs = {"id": f"BUSIFPARAM_VALUE.{name.upper()}.{pname}"}
            if choice:
                attrs["choiceRef"] = choice
            _sub(p, "value", value, **attrs)
    return bi


def register_map_2009():
    """The ``memoryMap`` of PeakRDL's IEEE 1685-2009 export of the register map (the same
    source and exporter as ``rtl/generated/biss_master_regs.xml``, which is the 2014 form)."""
    from peakrdl_ipxact import IPXACTExporter
    from peakrdl_ipxact.exporter import Standard
    from bissmaster.bus import regmap
    root = regmap.compile_rdl()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "regs.xml"
        IPXACTExporter(vendor=VENDOR, library=LIBRARY, version="1.0",
                       standard=Standard.IEEE_1685_2009).export(root.top, str(path))
        tree = ET.parse(path)
    mmap = tree.getroot().find(f"{{{SPIRIT}}}memoryMaps/{{{SPIRIT}}}memoryMap")
    return mmap, regmap.load().addr_width


def component_xml(verilog, memory_map=None):
    """The text of ``component.xml`` for the bus top in ``verilog``."""
    port_list = ports(verilog)
    ifs = classify(port_list)
    version, revision = version_parts()
    channels = len(ifs.channels)
    clk_hz = int(header_value(verilog, "sys_clk_hz"))
    mmap, addr_width = memory_map or register_map_2009()
    if ifs.axil["awaddr"].width != addr_width or ifs.axil["araddr"].width != addr_width:
        raise ValueError(f"the address ports are not the register map's {addr_width} bits")

    ET.register_namespace("spirit", SPIRIT)
    ET.register_namespace("xilinx", XILINX)
    ET.register_namespace("xsi", XSI)
    comp = ET.Element(f"{{{SPIRIT}}}component")
    _sub(comp, "vendor", VENDOR)
    _sub(comp, "library", LIBRARY)
    _sub(comp, "name", TOP)
    _sub(comp, "version", version)

    # Bus interfaces: the AXI4-Lite subordinate, clock, reset, interrupt.
    bis = _sub(comp, "busInterfaces")
    axi = "s_axil"
    _bus_interface(bis, axi, ("xilinx.com", "interface", "aximm", "1.0"),
                   ("xilinx.com", "interface", "aximm_rtl", "1.0"), ("slave", axi),
                   [(s.upper(), p.name) for s, p in ifs.axil.items()])
    _bus_interface(bis, ifs.reset.name, ("xilinx.com", "signal", "reset", "1.0"),
                   ("xilinx.com", "signal", "reset_rtl", "1.0"), "slave",
                   [("RST", ifs.reset.name)], [("POLARITY", "ACTIVE_HIGH", "choice_polarity")])
    _bus_interface(bis, ifs.clock.name, ("xilinx.com", "signal", "clock", "1.0"),
                   ("xilinx.com", "signal", "clock_rtl", "1.0"), "slave",
                   [("CLK", ifs.clock.name)],
                   [("ASSOCIATED_BUSIF", axi, None), ("ASSOCIATED_RESET", ifs.reset.name, None)])
    _bus_interface(bis, ifs.irq.name, ("xilinx.com", "signal", "interrupt", "1.0"),
                   ("xilinx.com", "signal", "interrupt_rtl", "1.0"), "master",
                   [("INTERRUPT", ifs.irq.name)],
                   [("SENSITIVITY", "LEVEL_HIGH", "choice_sensitivity")])

    # The register map: PeakRDL's, named after the interface that reaches it. The range is the
    # window the address ports decode (2**addr_width bytes, a power of two as Vivado's address
    # editor assigns): the registers span less of it, the rest reads 0 (docs/bus.md).
    mmaps = _sub(comp, "memoryMaps")
    mmap.find(f"{{{SPIRIT}}}name").text = axi
    block = mmap.find(f"{{{SPIRIT}}}addressBlock")
    block.find(f"{{{SPIRIT}}}range").text = hex(1 << addr_width)
    width = block.find(f"{{{SPIRIT}}}width")
    usage = ET.Element(f"{{{SPIRIT}}}usage")
    usage.text = "register"
    block.insert(list(block).index(width) + 1, usage)
    mmaps.append(mmap)

    # The model: two views on one file set, every port of the Verilog.
    model = _sub(comp, "model")
    views = _sub(model, "views")
    for view, display, env in ((SYNTH_VIEW, "Synthesis", ":vivado.xilinx.com:synthesis"),
                               (SIM_VIEW, "Simulation", ":vivado.xilinx.com:simulation")):
        v = _sub(views, "view")
        _sub(v, "name", view)
        _sub(v, "displayName", display)
        _sub(v, "envIdentifier", env)
        _sub(v, "language", "Verilog")
        _sub(v, "modelName", TOP)
        _sub(_sub(v, "fileSetRef"), "localName", f"{view}_view_fileset")
    model_ports = _sub(model, "ports")
    for p in port_list:
        port = _sub(model_ports, "port")
        _sub(port, "name", p.name)
        wire = _sub(port, "wire")
        _sub(wire, "direction", p.direction)
        if p.vector:
            vec = _sub(wire, "vector")
            _sub(vec, "left", p.msb, format="long")
            _sub(vec, "right", p.lsb, format="long")
        defs = _sub(_sub(wire, "wireTypeDefs"), "wireTypeDef")
        _sub(defs, "typeName", "wire")
        _sub(defs, "viewNameRef", SYNTH_VIEW)
        _sub(defs, "viewNameRef", SIM_VIEW)
        if p is ifs.trigger:        # left unconnected in a block design: no trigger
            _sub(_sub(wire, "driver"), "defaultValue", 0, format="long")

    choices = _sub(comp, "choices")
    for name, values in (("choice_polarity", ("ACTIVE_HIGH", "ACTIVE_LOW")),
                         ("choice_sensitivity", ("LEVEL_HIGH", "LEVEL_LOW", "EDGE_RISING",
                                                 "EDGE_FALLING"))):
        choice = _sub(choices, "choice")
        _sub(choice, "name", name)
        for value in values:
            _sub(choice, "enumeration", value)

    # File sets, paths relative to this file's folder (the IP repository's).
    verilog_rel = os.path.relpath(VERILOG, OUT)
    file_sets = _sub(comp, "fileSets")
    for view in (SYNTH_VIEW, SIM_VIEW):
        fs = _sub(file_sets, "fileSet")
        _sub(fs, "name", f"{view}_view_fileset")
        f = _sub(fs, "file")
        _sub(f, "name", verilog_rel)
        _sub(f, "fileType", "verilogSource")
        if view == SYNTH_VIEW:
            f = _sub(fs, "file")
            _sub(f, "name", XDC)
            for user_type in ("xdc", "USED_IN_implementation", "USED_IN_synthesis"):
                _sub(f, "userFileType", user_type)

    _sub(comp, "description",
         f"BiSS C / BiSS Safety master: {channels} channels behind an AXI4-Lite subordinate "
         f"(generated Verilog {TOP}.v, elaborated for a {clk_hz / 1e6:g} MHz clk; registers: "
         f"docs/registers.md).")
    params = _sub(comp, "parameters")
    p = _sub(params, "parameter")
    _sub(p, "name", "Component_Name")
    _sub(p, "value", f"{TOP}_v{version.replace('.', '_')}", resolve="user",
         id="PARAM_VALUE.Component_Name", order=1)

    ext = _sub(_sub(comp, "vendorExtensions"), "coreExtensions", ns=XILINX)
    fams = _sub(ext, "supportedFamilies", ns=XILINX)
    for fam in FAMILIES:
        _sub(fams, "family", fam, ns=XILINX, **{f"{{{XILINX}}}lifeCycle": "Production"})
    _sub(_sub(ext, "taxonomies", ns=XILINX), "taxonomy", "/UserIP", ns=XILINX)
    _sub(ext, "displayName", f"BiSS master, AXI4-Lite, {channels} channels", ns=XILINX)
    _sub(ext, "coreRevision", revision, ns=XILINX)

    ET.indent(comp, space="  ")
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            f"<!-- Generated by scripts/vendor_ip.py (make vendor) from rtl/generated/{TOP}.v and "
            "rtl/bissmaster/bus/biss_master.rdl; do not edit. docs/vendor.md -->\n"
            + ET.tostring(comp, encoding="unicode") + "\n")


# -- Vivado: the IP's constraints ------------------------------------------------------------

def ip_xdc(template, verilog):
    """``constraints/biss_master_bus.xdc`` scoped to the IP: its constraints without the
    instance prefix, for the channels of ``verilog``."""
    ifs = classify(ports(verilog))
    body = template.split("\n# The system clock", 1)
    if len(body) != 2:
        raise ValueError("biss_master_bus.xdc: no '# The system clock' line to start from")
    lines = ["# " + line if line else "#" for line in (
        f"Constraints of the IP {TOP} (Vivado applies an IP's XDC inside each instance: cell",
        "paths start at the instance, get_ports names the IP's own ports). Generated by",
        "scripts/vendor_ip.py (make vendor) from constraints/biss_master_bus.xdc with its",
        "instance path (bus_inst) taken out; do not edit. Not run through Vivado",
        "(docs/vendor.md, constraints/README.md).",
        "")]
    for i, ch in ifs.channels.items():
        lines.append(f"set ch{i}_ma_port   {ch['ma'].name}")
        lines.append(f"set ch{i}_slo_port  {ch['slo'].name}")
    text = "\n".join(lines) + "\n\n# The system clock" + body[1].replace("$bus_inst/", "")
    named = {int(n) for n in re.findall(r"\bch(\d+)/core/", text)}
    code = "\n".join(line for line in text.splitlines() if not line.lstrip().startswith("#"))
    if "bus_inst" in code or named != set(ifs.channels):
        raise ValueError(f"biss_master_bus.xdc constrains the channels {sorted(named)}, the IP "
                         f"has {sorted(ifs.channels)}: one block per channel")
    return text


# -- Quartus: Platform Designer _hw.tcl ------------------------------------------------------

def _tcl_word(text):
    return "{" + text + "}" if re.search(r"[\s\"$\[\]\\;]", text) else text


def hw_tcl(verilog):
    """The text of ``biss_master_axil_hw.tcl`` for the bus top in ``verilog``."""
    ifs = classify(ports(verilog))
    version, _ = version_parts()
    channels = len(ifs.channels)
    clk_hz = int(header_value(verilog, "sys_clk_hz"))
    verilog_rel = Path(os.path.relpath(VERILOG, OUT)).as_posix()
    qdir = {"in": "Input", "out": "Output"}
    out = [
        f"# {TOP}: the BiSS master's AXI4-Lite bus top as a Platform Designer component.",
        f"# Generated by scripts/vendor_ip.py (make vendor) from rtl/generated/{TOP}.v;",
        "# do not edit. Not run through Quartus: docs/vendor.md says what was checked.",
        "package require -exact qsys 16.1",
        "",
    ]

    def cmd(*words):
        out.append(" ".join(_tcl_word(str(w)) for w in words))

    description = (f"BiSS C / BiSS Safety master: {channels} channels behind an AXI4-Lite "
                   f"subordinate, elaborated for a {clk_hz / 1e6:g} MHz clock")
    for prop, value in (("NAME", TOP), ("DISPLAY_NAME", f"BiSS master (AXI4-Lite, {channels} "
                                                        f"channels)"),
                        ("DESCRIPTION", description), ("VERSION", version),
                        ("GROUP", "Interface Protocols/BiSS"), ("AUTHOR", VENDOR),
                        ("INTERNAL", "false"), ("OPAQUE_ADDRESS_MAP", "true"),
                        ("INSTANTIATE_IN_SYSTEM_MODULE", "true"), ("EDITABLE", "false"),
                        ("REPORT_TO_TALKBACK", "false"), ("ALLOW_GREYBOX_GENERATION", "false"),
                        ("REPORT_HIERARCHY", "false")):
        cmd("set_module_property", prop, value)

    out += ["", "# File sets: the generated Verilog (path relative to this file)."]
    for fileset in ("QUARTUS_SYNTH", "SIM_VERILOG"):
        cmd("add_fileset", fileset, fileset, "{}", "{}")
        cmd("set_fileset_property", fileset, "TOP_LEVEL", TOP)
        cmd("set_fileset_property", fileset, "ENABLE_RELATIVE_INCLUDE_PATHS", "false")
        cmd("set_fileset_property", fileset, "ENABLE_FILE_OVERWRITE_MODE", "false")
        cmd("add_fileset_file", f"{TOP}.v", "VERILOG", "PATH", verilog_rel, "TOP_LEVEL_FILE")

    out += ["", f"# Clock: every channel and the bus run on it (elaborated for {clk_hz} Hz)."]
    cmd("add_interface", "clock", "clock", "end")
    cmd("set_interface_property", "clock", "clockRate", 0)
    cmd("add_interface_port", "clock", ifs.clock.name, "clk", "Input", 1)

    out += ["", "# Reset: synchronous, active high."]
    cmd("add_interface", "reset", "reset", "end")
    cmd("set_interface_property", "reset", "associatedClock", "clock")
    cmd("set_interface_property", "reset", "synchronousEdges", "BOTH")
    cmd("add_interface_port", "reset", ifs.reset.name, "reset", "Input", 1)

    out += ["", "# AXI4-Lite subordinate: the register map (docs/registers.md), byte addresses,",
            "# one transaction at a time; no AxPROT."]
    cmd("add_interface", "s_axil", "axi4lite", "end")
    cmd("set_interface_property", "s_axil", "associatedClock", "clock")
    cmd("set_interface_property", "s_axil", "associatedReset", "reset")
    for prop in ("readAcceptanceCapability", "writeAcceptanceCapability",
                 "combinedAcceptanceCapability", "readDataReorderingDepth"):
        cmd("set_interface_property", "s_axil", prop, 1)
    for signal, p in ifs.axil.items():
        cmd("add_interface_port", "s_axil", p.name, signal, qdir[p.direction], p.width)

    out += ["", "# Interrupt sender: level, active high (irq_pending != 0)."]
    cmd("add_interface", "irq", "interrupt", "end")
    cmd("set_interface_property", "irq", "associatedAddressablePoint", "s_axil")
    cmd("set_interface_property", "irq", "associatedClock", "clock")
    cmd("set_interface_property", "irq", "associatedReset", "reset")
    cmd("add_interface_port", "irq", ifs.irq.name, "irq", "Output", 1)

    out += ["", "# trigger: synchronous to clk; a rising edge starts the channels that enable it."]
    cmd("add_interface", "trigger", "conduit", "end")
    cmd("set_interface_property", "trigger", "associatedClock", "clock")
    cmd("set_interface_property", "trigger", "associatedReset", "reset")
    cmd("add_interface_port", "trigger", ifs.trigger.name, "trigger", "Input", 1)

    out += ["", "# One conduit per channel: its MA output and SLO input, to the transceivers",
            "# (SLO is asynchronous: each core synchronizes it)."]
    for i, ch in ifs.channels.items():
        cmd("add_interface", f"ch{i}", "conduit", "end")
        cmd("set_interface_property", f"ch{i}", "associatedClock", "{}")
        for role in ("ma", "slo"):
            p = ch[role]
            cmd("add_interface_port", f"ch{i}", p.name, role, qdir[p.direction], p.width)
    return "\n".join(out) + "\n"


# -- main -------------------------------------------------------------------------------------

def outputs(verilog=None, template=None):
    """``{file name: text}`` of every file this script writes."""
    verilog = VERILOG.read_text() if verilog is None else verilog
    template = BUS_XDC.read_text() if template is None else template
    return {COMPONENT: component_xml(verilog), XDC: ip_xdc(template, verilog),
            HW_TCL: hw_tcl(verilog)}


def main(argv=None):
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    for name, text in outputs().items():
        (OUT / name).write_text(text)
        print(f"wrote {(OUT / name).relative_to(REPO)}")


if __name__ == "__main__":
    main()
