"""The register-access buffers: 16 x 32 bits each way, host words, engine bytes."""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..layouts import BUFFER_ADDRESS_BITS, BUFFER_LANES, BUFFER_WORD_BITS, BUFFER_WORDS, \
    buffer_write_layout


class AccessBuffers(wiring.Component):
    """The write buffer (bytes to send) and the read buffer (bytes received) of a register access.

    Each is 16 words of 4 bytes, little endian: byte ``i`` is byte lane ``i % 4`` (bits
    ``8 (i % 4) + 7 .. 8 (i % 4)``) of word ``i // 4``. The host writes the write buffer a word
    at a time with a byte enable per lane (``wbuf``) and reads the read buffer a word at a time
    through a registered port (``rbuf_addr``, ``rbuf_en`` -> ``rbuf_data``: in a clock with
    ``rbuf_en`` high the word at ``rbuf_addr`` is read, ``rbuf_data`` holds it from the next
    clock until the next read). The engine takes and stores one byte, ``index``, at a time.

    After every reset the read buffer is cleared, a word per clock: a host read from the
    ``BUFFER_WORDS + 1``-th clock after the reset on returns 0 for every byte no read access
    has stored since. (The memories have no initial value in the generated Verilog, and a
    reset does not clear a memory: without this, a word read before the bytes of a read came
    in would be undefined, X in Icarus, where a bus model that reads it stops.) The write
    buffer is not cleared: the engine sends only the bytes the host wrote for the access.

    Attributes
    ----------
    wbuf : In(buffer_write_layout)
        The host's write port of the write buffer.
    rbuf_addr : In(4)
    rbuf_en : In(1)
    rbuf_data : Out(32)
        The host's read port of the read buffer, registered.
    index : In(6)
        The byte the engine is at.
    byte_to_send : Out(8)
        Byte ``index`` of the write buffer: its word is read every clock (registered), so the
        byte is valid from the clock after ``index`` was set, as long as ``index`` holds.
    store : In(1)
        Write ``byte_received`` to byte ``index`` of the read buffer in this clock.
    byte_received : In(8)
    """

    def __init__(self):
        super().__init__({
            "wbuf": In(buffer_write_layout()),
            "rbuf_addr": In(BUFFER_WORD_BITS),
            "rbuf_en": In(1),
            "rbuf_data": Out(BUFFER_LANES * 8),
            "index": In(BUFFER_ADDRESS_BITS),
            "byte_to_send": Out(8),
            "store": In(1),
            "byte_received": In(8),
        })

    def elaborate(self, platform):
        m = Module()
        width = BUFFER_LANES * 8
        word = self.index[2:]
        lane = self.index[:2]

        # The write buffer: the host writes words, the engine reads the byte at its index.
        m.submodules.wbuf = wbuf = Memory(shape=width, depth=BUFFER_WORDS, init=[])
        host_write = wbuf.write_port(granularity=8)
        word_to_send = wbuf.read_port()
        m.d.comb += [
            host_write.addr.eq(self.wbuf.addr), host_write.data.eq(self.wbuf.data),
            host_write.en.eq(self.wbuf.en),
            word_to_send.addr.eq(word),
            self.byte_to_send.eq(word_to_send.data.word_select(lane, 8)),
        ]

        # The read buffer: the engine stores a byte (one lane), the host reads words.
        m.submodules.rbuf = rbuf = Memory(shape=width, depth=BUFFER_WORDS, init=[])
        byte_received = rbuf.write_port(granularity=8)
        host_read = rbuf.read_port()
        # The clear after reset, through the engine's write port: word ``cleared`` in each clock
        # while ``clearing``. No byte is stored meanwhile: a read stores its first byte after
        # the frames of its address and of the byte (at least 14), and the first frame after
        # a reset comes after the power-up break.
        clearing = Signal(init=1)
        cleared = Signal(BUFFER_WORD_BITS)
        with m.If(clearing):
            m.d.sync += cleared.eq(cleared + 1)
            with m.If(cleared == BUFFER_WORDS - 1):
                m.d.sync += clearing.eq(0)
            m.d.comb += [byte_received.addr.eq(cleared), byte_received.data.eq(0),
                         byte_received.en.eq(Const(-1, BUFFER_LANES))]
        with m.Elif(self.store):
            m.d.comb += [byte_received.addr.eq(word),
                         byte_received.data.eq(self.byte_received.replicate(BUFFER_LANES)),
                         byte_received.en.eq(Cat(lane == k for k in range(BUFFER_LANES)))]
        m.d.comb += [host_read.addr.eq(self.rbuf_addr), host_read.en.eq(self.rbuf_en),
                     self.rbuf_data.eq(host_read.data)]
        return m
