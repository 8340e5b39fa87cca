"""CRC check of one data word, built from amaranth.lib.crc."""

from amaranth.hdl import *
from amaranth.lib import crc, wiring
from amaranth.lib.wiring import In, Out

from .params import Crc
from . import protocol


#: The two BiSS CRCs: start 0, sent inverted, MSB first (section 6 of the protocol digest).
ALGORITHMS = {
    Crc.CRC6: crc.Algorithm(crc_width=protocol.CRC6_WIDTH, polynomial=protocol.CRC6_POLY,
                            initial_crc=protocol.CRC_INIT, reflect_input=False,
                            reflect_output=False, xor_output=protocol.CRC6_XOR_OUT),
    Crc.CRC16: crc.Algorithm(crc_width=protocol.CRC16_WIDTH, polynomial=protocol.CRC16_POLY,
                             initial_crc=protocol.CRC_INIT, reflect_input=False,
                             reflect_output=False, xor_output=protocol.CRC16_XOR_OUT),
}


class WordCrc(wiring.Component):
    """Checks a word and its trailing CRC, one bit per ``valid``.

    Each available CRC has a bit-serial :class:`amaranth.lib.crc.Processor`. The whole word,
    data *and* received CRC, goes through it; a correct word leaves the register at the CRC's
    residue (``match_detected``), so no separate comparison is needed. ``ok`` is
    combinational from the register: final in the clock after the word's last bit.

    ``kind`` outside ``kinds`` (and not :attr:`Crc.NONE`) reads as a failed check; the master
    rejects that configuration before a cycle starts.
    """

    def __init__(self, kinds):
        self._kinds = tuple(Crc(k) for k in kinds)
        super().__init__({
            "kind": In(2),
            "start": In(1),
            "valid": In(1),
            "bit": In(1),
            "ok": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        match = {}
        for kind in self._kinds:
            m.submodules[kind.name.lower()] = proc = ALGORITHMS[kind](data_width=1).create()
            m.d.comb += [
                proc.start.eq(self.start),
                proc.valid.eq(self.valid),
                proc.data.eq(self.bit),
            ]
            match[kind] = proc.match_detected
        with m.Switch(self.kind):
            with m.Case(Crc.NONE):
                m.d.comb += self.ok.eq(1)
            for kind, matched in match.items():
                with m.Case(kind):
                    m.d.comb += self.ok.eq(matched)
        return m
