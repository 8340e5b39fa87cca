"""The bus tops' register map, read from its one source, ``biss_master.rdl`` beside this file.

:func:`load` compiles the SystemRDL file with ``systemrdl-compiler`` and walks the elaborated
model into plain data (:class:`RegisterMap`): the global registers, one channel's registers and
where the channel slots are. The register bank (:mod:`bissmaster.bus.register_bank`) is built from
that data, never from a hand-written list; :func:`main` writes the PeakRDL outputs (C header,
Markdown, IP-XACT) from the same compiled model.

How a field becomes hardware is read from its SystemRDL properties (the conventions are stated
at the top of the .rdl file): ``hdl_path_slice`` names the signal it connects to, the access
properties give its :class:`Kind`, a regfile with the user property ``snapshot`` is read
through a snapshot.
"""

import argparse
import enum
import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

#: The register map source, shipped inside the package (bus/biss_master.rdl) so that an installed
#: wheel builds the bus tops; a package resource, so that it is found from a zipped wheel too.
RDL = resources.files(__package__) / "biss_master.rdl"
TOP = "biss_master_regs"
#: The channel array of the map (a regfile array at the top level).
CHANNEL = "channel"
DATA_WIDTH = 32


class Kind(enum.Enum):
    """What a field is in hardware, from its SystemRDL access properties."""
    CONFIG = "config"   # sw = rw, hw = r: a register the hardware reads
    PULSE = "pulse"     # singlepulse: a write of 1 gives a one-clock pulse, reads 0
    LIVE = "live"       # sw = r, hw = w: the hardware's value, read live (or through a snapshot)
    CONST = "const"     # sw = r, hw = na: the reset value
    IRQ = "irq"         # intr, woclr: sticky, set by its event, write 1 to clear
    BUFFER = "buffer"   # a byte lane of a window (an external register array onto a memory)


@dataclass(frozen=True)
class Field:
    name: str
    lsb: int
    width: int
    kind: Kind
    reset: int
    signal: str | None = None   # the hardware signal (hdl_path_slice), None: not connected
    signal_lsb: int = 0         # the field holds signal[signal_lsb + width - 1 : signal_lsb]
    enable: str | None = None   # IRQ: "register.field" of its enable (same block)


@dataclass(frozen=True)
class Register:
    path: str                   # inside its block, e.g. "ctrl", "result.status"
    offset: int                 # byte offset inside its block
    fields: tuple
    snapshot: str | None = None     # the snapshot group (regfile path) it is read through
    takes_snapshot: bool = False    # reading it copies the whole group
    window: str | None = None   # a window: the memory's port name (ports <window>_addr, ...)
    count: int = 1              # a window's words (array elements, 4 bytes apart)
    writable: bool = False      # a window: written (sw = w) rather than read (sw = r)
    memory: str | None = None   # a word of a read-only memory (ports <memory>_addr, ...)

    def field(self, name):
        return next(f for f in self.fields if f.name == name)

    @property
    def window_ports(self):
        """A window's memory ports: :func:`window_ports`."""
        return window_ports(self.window, self.count, self.writable)


def window_ports(name, count, writable):
    """The ports of a memory behind ``count`` words of the map, ``{name: (output of the bank?,
    width)}``: the word address, the data (out for a write window, in for a read window), the
    enable (a write: one per byte lane; a read: one)."""
    return {f"{name}_addr": (True, (count - 1).bit_length()),
            f"{name}_data": (writable, DATA_WIDTH),
            f"{name}_en": (True, DATA_WIDTH // 8 if writable else 1)}


@dataclass(frozen=True)
class RegisterMap:
    globals: tuple              # Registers at absolute byte addresses
    channel: tuple              # Registers of one channel, offsets inside the channel block
    channel_base: int           # byte address of channel 0
    channel_stride: int         # bytes from one channel to the next
    channel_slots: int          # channels the map has room for
    size: int                   # bytes the whole map spans

    @property
    def addr_width(self):
        """Byte-address bits the map needs."""
        return (self.size - 1).bit_length()

    def channel_address(self, n, register):
        return self.channel_base + n * self.channel_stride + register.offset

    @staticmethod
    def memories(registers):
        """``{memory: (byte offset of its first word, words)}`` of the memory registers of
        ``registers``; a memory's words are adjacent, its first aligned to the power of two
        that holds them (its word address is then the bus address's low bits)."""
        found = {}
        for reg in registers:
            if reg.memory:
                found.setdefault(reg.memory, []).append(reg.offset)
        out = {}
        for name, offsets in found.items():
            first, count = min(offsets), len(offsets)
            if (sorted(offsets) != list(range(first, first + 4 * count, 4))
                    or (first // 4) % (1 << (count - 1).bit_length())):
                raise ValueError(f"memory {name}: its registers must be adjacent words, the "
                                 f"first aligned to the power of two that holds them "
                                 f"(offsets {offsets})")
            out[name] = (first, count)
        return out

    def signals(self, registers):
        """``{signal: (kind, width)}`` of every connected field of ``registers``; a signal made
        of several fields (a position split over two registers) is as wide as all of them.
        The ports of a window or a memory have the kind :attr:`Kind.BUFFER` (their direction:
        :func:`window_ports`)."""
        found = {}
        for name, (_, count) in self.memories(registers).items():
            found.update({port: (Kind.BUFFER, width)
                          for port, (_, width) in window_ports(name, count, False).items()})
        for reg in registers:
            if reg.window:
                found.update({name: (Kind.BUFFER, width)
                              for name, (_, width) in reg.window_ports.items()})
                continue
            if reg.memory:
                continue
            for f in reg.fields:
                if f.signal is None:
                    continue
                kind, width = found.get(f.signal, (f.kind, 0))
                if kind != f.kind:
                    raise ValueError(f"signal {f.signal} is both {kind.value} and {f.kind.value}")
                found[f.signal] = (kind, max(width, f.signal_lsb + f.width))
        return found


_SLICE = re.compile(r"^(\w+)(?:\[(\d+):(\d+)\])?$")


def _kind(node):
    sw_w, hw = node.is_sw_writable, node.get_property("hw").name
    if node.parent.external:
        return Kind.BUFFER
    if node.get_property("intr"):
        if node.get_property("onwrite") is None or node.get_property("onwrite").name != "woclr":
            raise ValueError(f"{node.get_path()}: an interrupt field must be woclr")
        return Kind.IRQ
    if node.get_property("singlepulse"):
        return Kind.PULSE
    if sw_w and node.is_sw_readable and hw == "r":
        return Kind.CONFIG
    if not sw_w and hw == "w":
        return Kind.LIVE
    if not sw_w and hw == "na":
        return Kind.CONST
    raise ValueError(f"{node.get_path()}: access sw={node.get_property('sw').name} hw={hw} "
                     f"is not one the register bank builds")


def _field(node, block, memory=False):
    kind = _kind(node)
    signal, signal_lsb = None, 0
    path = [p for p in (node.get_property("hdl_path_slice") or []) if p]
    if path:
        m = _SLICE.match(path[0])
        if not m or len(path) != 1:
            raise ValueError(f"{node.get_path()}: hdl_path_slice must be one 'name' or "
                             f"'name[hi:lo]', not {path!r}")
        signal = m.group(1)
        if m.group(2) is not None:
            hi, lo = int(m.group(2)), int(m.group(3))
            if hi - lo + 1 != node.width:
                raise ValueError(f"{node.get_path()}: slice {path[0]} is not {node.width} bits")
            signal_lsb = lo
    if kind == Kind.BUFFER and signal is not None:
        raise ValueError(f"{node.get_path()}: a window's fields are byte lanes of its memory "
                         f"(the register's hdl_path), not signals of their own")
    if memory and (kind != Kind.LIVE or signal is not None):
        raise ValueError(f"{node.get_path()}: a memory register's fields are bits of its word: "
                         f"read only (sw = r, hw = w), no hdl_path_slice")
    if kind in (Kind.PULSE, Kind.LIVE) and signal is None and not memory:
        raise ValueError(f"{node.get_path()}: a {kind.value} field needs hdl_path_slice")
    enable = None
    if kind == Kind.IRQ and node.get_property("enable") is not None:
        en = node.get_property("enable")
        enable = _relative(en.parent, block) + "." + en.inst_name
    reset = node.get_property("reset")
    return Field(node.inst_name, node.lsb, node.width, kind, 0 if reset is None else int(reset),
                 signal, signal_lsb, enable)


def _relative(node, block):
    """The path of ``node`` inside ``block`` (dots, no array indices)."""
    full, base = node.get_path(empty_array_suffix=""), block.get_path(empty_array_suffix="")
    rel = full[len(base) + 1:] if full.startswith(base + ".") else full
    return re.sub(r"\[\d+\]", "", rel)


def _registers(block, regs):
    """Registers of ``regs`` (RegNodes under ``block``), offsets relative to ``block``."""
    from systemrdl.node import RegfileNode
    out = []
    for reg in regs:
        if reg.get_property("regwidth") != DATA_WIDTH:
            raise ValueError(f"{reg.get_path()}: registers must be {DATA_WIDTH} bits")
        snapshot, takes = None, False
        parent = reg.parent
        if isinstance(parent, RegfileNode) and parent.get_property("snapshot", default=False):
            snapshot = _relative(parent, block)
            first = min(r.raw_absolute_address for r in parent.registers())
            takes = reg.raw_absolute_address == first
        window, count, writable = _window(reg)
        memory = reg.get_property("memory", default=None) or None
        if memory and (window or snapshot):
            raise ValueError(f"{reg.get_path()}: a memory register is neither a window nor in "
                             f"a snapshot")
        out.append(Register(_relative(reg, block),
                            reg.raw_absolute_address - block.absolute_address,
                            tuple(_field(f, block, bool(memory)) for f in reg.fields()),
                            snapshot, takes, window, count, writable, memory))
    return tuple(sorted(out, key=lambda r: r.offset))


def _window(reg):
    """``(port name, words, writable)`` of an external register array (a window onto a memory),
    ``(None, 1, False)`` of any other register."""
    if not reg.external:
        if reg.is_array:
            raise ValueError(f"{reg.get_path()}: a register array must be an external window")
        return None, 1, False
    name = reg.get_property("hdl_path")
    if not name or not reg.is_array or len(reg.array_dimensions) != 1 \
            or reg.array_stride != DATA_WIDTH // 8:
        raise ValueError(f"{reg.get_path()}: an external register must be a one-dimensional "
                         f"array of adjacent words with an hdl_path (a window onto a memory)")
    fields = list(reg.fields())
    writable = all(f.is_sw_writable and not f.is_sw_readable for f in fields)
    if not writable and not all(f.is_sw_readable and not f.is_sw_writable for f in fields):
        raise ValueError(f"{reg.get_path()}: a window is written only (sw = w) or read only "
                         f"(sw = r)")
    if sorted((f.lsb, f.width) for f in fields) != [(8 * k, 8) for k in range(DATA_WIDTH // 8)]:
        raise ValueError(f"{reg.get_path()}: a window's fields are its {DATA_WIDTH // 8} byte "
                         f"lanes")
    return name, reg.array_dimensions[0], writable


def compile_rdl(path=RDL):
    """The elaborated systemrdl-compiler root of the register map (``path``: a file or a
    package resource)."""
    from systemrdl import RDLCompiler
    rdlc = RDLCompiler()
    with resources.as_file(path) as real:      # a real file even inside a zipped wheel
        if not Path(real).is_file():
            raise FileNotFoundError(f"the register map source {path} is not there")
        rdlc.compile_file(str(real))
    return rdlc.elaborate(top_def_name=TOP)


def load(path=RDL):
    """The :class:`RegisterMap` of the SystemRDL source."""
    from systemrdl.node import RegfileNode, RegNode
    top = compile_rdl(path).top
    global_regs, channel = [], None
    for child in top.children(unroll=False):
        if isinstance(child, RegNode):
            global_regs.append(child)
        elif isinstance(child, RegfileNode) and child.inst_name == CHANNEL and child.is_array:
            channel = child
        else:
            raise ValueError(f"{child.get_path()}: the top level holds registers and the "
                             f"'{CHANNEL}' regfile array only")
    if channel is None or len(channel.array_dimensions) != 1:
        raise ValueError(f"the map needs a one-dimensional regfile array '{CHANNEL}'")
    first = next(c for c in top.children(unroll=True) if c.inst_name == CHANNEL)
    chan_regs = [n for n in first.descendants() if isinstance(n, RegNode)]
    return RegisterMap(
        globals=_registers(top, global_regs),
        channel=_registers(first, chan_regs),
        channel_base=first.absolute_address,
        channel_stride=channel.array_stride,
        channel_slots=channel.array_dimensions[0],
        size=top.size,
    )


# -- The PeakRDL outputs --------------------------------------------------------------------
def write_header(root, path):
    """C99 (no ``static_assert``, no ``<assert.h>``: the driver in sw/ builds with
    ``-std=c99 -pedantic``), macro names from each register's path
    (``BISS_MASTER_REGS__CHANNELX__IRQ_STATUS__DONE_bm``) rather than from its type, whose
    name carries a hash wherever the RDL assigns a property from outside (``->enable``)."""
    from peakrdl_cheader.c_standards import CStandard
    from peakrdl_cheader.exporter import CHeaderExporter
    CHeaderExporter().export(root.top, str(path), std=CStandard.gnu99, reuse_typedefs=False)


def write_markdown(root, path):
    """The map's top level (global registers, the channel slots), then one channel in full:
    peakrdl-markdown would otherwise repeat every register for each of the 8 slots."""
    import tempfile
    from peakrdl_markdown import MarkdownExporter
    top = root.top
    channel = next(c for c in top.children(unroll=True) if c.inst_name == CHANNEL)
    stride = top.get_child_by_name(CHANNEL).array_stride
    parts = []
    with tempfile.TemporaryDirectory() as tmp:
        for node, depth, name in ((top, 2, "top.md"), (channel, 0, "channel.md")):
            MarkdownExporter().export(node, f"{tmp}/{name}", depth=depth,
                                      input_files=["rtl/bissmaster/bus/biss_master.rdl"])
            parts.append(Path(f"{tmp}/{name}").read_text())
    intro = (f"# Register map\n\nGenerated by `make regmap` (peakrdl-markdown) from "
             f"`rtl/bissmaster/bus/biss_master.rdl`; do not edit. Bus semantics, the result "
             f"snapshot, interrupts and the trigger: [bus.md](bus.md).\n\n"
             f"Below: the global registers and the channel slots, then every register of "
             f"one channel at channel 0's addresses: channel n's registers are "
             f"{stride:#x} * n higher.\n\n")
    # The top part's summary of each slot repeats the channel's register table: drop it.
    top_part = parts[0].split(f"\n## {CHANNEL} register file")[0]
    Path(path).write_text(intro + top_part.rstrip() + "\n\n" + parts[1])


def write_ipxact(root, path):
    from peakrdl_ipxact import IPXACTExporter
    IPXACTExporter(vendor="bissmaster", library="bissmaster",
                   version="1.0").export(root.top, str(path))


def main(argv=None):
    ap = argparse.ArgumentParser(description="Write the register map's C header, Markdown "
                                 "and IP-XACT from rtl/bissmaster/bus/biss_master.rdl (PeakRDL).")
    ap.add_argument("--header", help="C header (peakrdl-cheader)")
    ap.add_argument("--markdown", help="Markdown documentation (peakrdl-markdown)")
    ap.add_argument("--ipxact", help="IP-XACT XML (peakrdl-ipxact)")
    args = ap.parse_args(argv)
    root = compile_rdl()
    load()                          # the bank's reading of it must hold too
    for path, write in ((args.header, write_header), (args.markdown, write_markdown),
                        (args.ipxact, write_ipxact)):
        if path:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            write(root, path)


if __name__ == "__main__":
    main()
