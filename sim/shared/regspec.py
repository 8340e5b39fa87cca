"""The register map as the test side reads it: straight from the SystemRDL source (the spec),
with systemrdl-compiler, never from the register bank's Python (rtl/bissmaster/bus/regmap.py).

Every register is named by its path: a global one as ``"id"``, a channel's as
``"ctrl"``, ``"result.status"``; :meth:`RegSpec.address` places it. A register array (the
register-access buffers ``ca.wbuf``, ``ca.rbuf``) is one entry: its first element's offset,
``count`` elements 4 bytes apart.
"""

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from systemrdl import RDLCompiler
from systemrdl.node import RegNode

ROOT = Path(__file__).resolve().parents[2]
RDL = ROOT / "rtl" / "bissmaster" / "bus" / "biss_master.rdl"


@dataclass(frozen=True)
class FieldSpec:
    name: str
    lsb: int
    width: int
    sw: str                 # "rw", "r", "w"
    hw: str                 # "r", "w", "rw", "na"
    reset: int | None
    singlepulse: bool
    woclr: bool

    @property
    def mask(self):
        return ((1 << self.width) - 1) << self.lsb

    def get(self, word):
        return (word >> self.lsb) & ((1 << self.width) - 1)

    def put(self, word, value):
        return (word & ~self.mask) | ((value << self.lsb) & self.mask)


@dataclass(frozen=True)
class RegSpec:
    path: str
    offset: int             # byte offset: absolute for a global, inside the block for a channel
    channel: bool
    fields: dict            # name -> FieldSpec
    count: int = 1          # elements of an array, 4 bytes apart


@dataclass(frozen=True)
class MapSpec:
    globals: dict           # path -> RegSpec
    channel: dict           # path -> RegSpec
    channel_base: int
    channel_stride: int
    channel_slots: int
    size: int

    def address(self, path, ch=None, index=0):
        """The byte address of register ``path`` (element ``index`` of an array)."""
        spec = self.reg(path, ch)
        assert 0 <= index < spec.count, f"{path}[{index}]: the array has {spec.count}"
        base = 0 if ch is None else self.channel_base + ch * self.channel_stride
        return base + spec.offset + 4 * index

    def reg(self, path, ch=None):
        return (self.globals if ch is None else self.channel)[path]


def _field(node):
    return FieldSpec(node.inst_name, node.lsb, node.width, node.get_property("sw").name,
                     node.get_property("hw").name, node.get_property("reset"),
                     bool(node.get_property("singlepulse")),
                     getattr(node.get_property("onwrite"), "name", None) == "woclr")


def _path(node, block):
    return node.get_path(empty_array_suffix="")[len(block.get_path()) + 1:]


@lru_cache(maxsize=1)
def load():
    rdlc = RDLCompiler()
    rdlc.compile_file(str(RDL))
    top = rdlc.elaborate(top_def_name="biss_master_regs").top
    glob, chan = {}, {}
    channels = [c for c in top.children(unroll=True) if c.inst_name == "channel"]
    for reg in top.registers():
        glob[reg.inst_name] = RegSpec(reg.inst_name, reg.absolute_address, False,
                                      {f.inst_name: _field(f) for f in reg.fields()})
    ch0 = channels[0]
    for reg in ch0.descendants():
        if isinstance(reg, RegNode):
            path = _path(reg, ch0)
            count = reg.array_dimensions[0] if reg.is_array else 1
            assert not reg.is_array or reg.array_stride == 4, path
            chan[path] = RegSpec(path, reg.raw_absolute_address - ch0.absolute_address, True,
                                 {f.inst_name: _field(f) for f in reg.fields()}, count)
    return MapSpec(glob, chan, ch0.absolute_address,
                   channels[1].absolute_address - ch0.absolute_address, len(channels), top.size)
