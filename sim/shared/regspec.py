"""The register map as the test side reads it: straight from the SystemRDL source (the spec),
with systemrdl-compiler, never from the register bank's Python (rtl/bissmaster/regmap.py).

Every register is named by its path: a global one as ``"id"``, a channel's as
``"ctrl"``, ``"result.status"``; :meth:`RegSpec.address` places it.
"""

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from systemrdl import RDLCompiler
from systemrdl.node import RegNode

ROOT = Path(__file__).resolve().parents[2]
RDL = ROOT / "rtl" / "regmap" / "biss_master.rdl"


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


@dataclass(frozen=True)
class MapSpec:
    globals: dict           # path -> RegSpec
    channel: dict           # path -> RegSpec
    channel_base: int
    channel_stride: int
    channel_slots: int
    size: int

    def address(self, path, ch=None):
        if ch is None:
            return self.globals[path].offset
        return self.channel_base + ch * self.channel_stride + self.channel[path].offset

    def reg(self, path, ch=None):
        return (self.globals if ch is None else self.channel)[path]


def _field(node):
    return FieldSpec(node.inst_name, node.lsb, node.width, node.get_property("sw").name,
                     node.get_property("hw").name, node.get_property("reset"),
                     bool(node.get_property("singlepulse")),
                     getattr(node.get_property("onwrite"), "name", None) == "woclr")


def _path(node, block):
    return node.get_path()[len(block.get_path()) + 1:]


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
            chan[path] = RegSpec(path, reg.absolute_address - ch0.absolute_address, True,
                                 {f.inst_name: _field(f) for f in reg.fields()})
    return MapSpec(glob, chan, ch0.absolute_address,
                   channels[1].absolute_address - ch0.absolute_address, len(channels), top.size)
