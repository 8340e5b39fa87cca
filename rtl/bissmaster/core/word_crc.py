"""CRC check of one data word, built from amaranth.lib.crc."""

from amaranth.hdl import *
from amaranth.lib import crc, wiring
from amaranth.lib.wiring import In, Out

from ..params import Crc
from .. import protocol


#: The two BiSS CRCs: start 0, sent inverted, MSB first (section 6 of docs/protocol.md).
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

    Each available CRC has a bit-serial shift register (MSB first, not reflected, the
    :data:`ALGORITHMS` parameters). The whole word, data *and* received CRC, goes through it; a
    correct word leaves the register at the CRC's residue, so no separate comparison with the
    received CRC is needed. The residue compare is made on the register's *next* value and
    registered with it, so ``ok`` is one small mux of flip-flops (no compare in front of the
    master's verdict): final in the clock after the word's last bit, as before.

    ``start`` (with or without ``valid``) restarts the register from the initial value, like
    :class:`amaranth.lib.crc.Processor`.

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
            algo = ALGORITHMS[kind]
            params = algo(data_width=1)
            width = algo.crc_width
            residue = params.residue()
            init = algo.initial_crc
            reg = Signal(width, init=init, name=f"{kind.name.lower()}_reg")
            matched = Signal(init=int(init == residue), name=f"{kind.name.lower()}_match")
            source = Mux(self.start, init, reg)
            feedback = source[-1] ^ self.bit
            nxt = Cat(C(0, 1), source[:-1]) ^ Mux(feedback, algo.polynomial, 0)
            # ``nxt == residue`` for both feedback values, from the register alone; the
            # incoming bit then only picks one (no compare behind ``valid`` and ``bit``).
            shifted = Cat(C(0, 1), reg[:-1])
            shifted_init = (init << 1) & (2**width - 1)
            match_fb = [shifted == residue, (shifted ^ algo.polynomial) == residue]
            match_fb_init = [int((shifted_init ^ (algo.polynomial if fb else 0)) == residue)
                             for fb in (0, 1)]
            match_nxt = Mux(self.start,
                            Mux(feedback, match_fb_init[1], match_fb_init[0]),
                            Mux(feedback, match_fb[1], match_fb[0]))
            with m.If(self.valid):
                m.d.sync += [reg.eq(nxt), matched.eq(match_nxt)]
            with m.Elif(self.start):
                m.d.sync += [reg.eq(init), matched.eq(int(init == residue))]
            match[kind] = matched
        with m.Switch(self.kind):
            with m.Case(Crc.NONE):
                m.d.comb += self.ok.eq(1)
            for kind, matched in match.items():
                with m.Case(kind):
                    m.d.comb += self.ok.eq(matched)
        return m
