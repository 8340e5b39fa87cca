"""A point-to-point BiSS slave's control side and the limits bench's encoder with it: the
test side's own model of register access, from docs/protocol.md (section 10) and
docs/control.md only, shared by the RegisterAccess block tests, the control channel through
the whole master (tb/tests/control) and the limits (tb/tests/core/test_limits.py).
"""

from dataclasses import dataclass, field

from testkit.limits_bench import Encoder

#: ``ca_status`` codes (docs/control.md).
OK, CRC4_ERROR, NO_ANSWER, REFUSED, ABORTED, DATA_FAULT, BAD_REQUEST = range(7)
IDLE_FRAMES = 14        # spec: CDM = 0 frames before a control frame; as many cancel one
START_WAIT = 4          # the engine's wait for a late start bit, in these tests


def crc4(bits):
    """Spec section 10: CRC-4, x^4 + x + 1, start 0, MSB first; the value sent is inverted.
    Returns the 4 bits as sent, MSB first."""
    reg = 0
    for b in bits:
        fb = ((reg >> 3) & 1) ^ b
        reg = (reg << 1) & 0xF
        if fb:
            reg ^= 0b0011
    reg ^= 0xF
    return [(reg >> i) & 1 for i in (3, 2, 1, 0)]


def bits_of(value, n):
    return [(value >> i) & 1 for i in reversed(range(n))]


class _Cancel(Exception):
    pass


class Slave:
    """A point-to-point BiSS slave's control side, from docs/protocol.md, section 10 only.

    ``cds()`` is the CDS of the frame being sent; ``take(cdm)`` is the CDM of that frame (read
    at the end of the slave's timeout). 14 consecutive CDM = 0 cancel any control frame. Faults:
    ``answers=False`` (unidirectional: CDS always 0), ``delay`` frames of processing before the
    start bit, ``read_only`` addresses (a write there: no start bit), ``bad_crc_at`` (a read
    byte's CRC-4 sent wrong), ``echo_old`` (a write echoed with the byte the slave keeps).
    """

    def __init__(self, regs=None, *, slave_id=0, answers=True, delay=0, read_only=(),
                 bad_crc_at=None, echo_old=False):
        self.regs = dict(regs or {})
        self.slave_id = slave_id
        self.answers = answers
        self.delay = delay
        self.read_only = set(read_only)
        self.bad_crc_at = bad_crc_at
        self.echo_old = echo_old
        self.zeros = IDLE_FRAMES
        self.frames_in_control = 0
        self._gen = self._run()
        self._cds = next(self._gen)

    def cds(self):
        return self._cds if self.answers else 0

    def take(self, cdm):
        self._cds = self._gen.send(cdm)

    def _step(self, cds):
        cdm = yield cds
        self.zeros = 0 if cdm else self.zeros + 1
        if self.zeros >= IDLE_FRAMES:
            raise _Cancel
        return cdm

    def _run(self):
        cdm = yield 0
        while True:
            # Idle: S = 1 after at least 14 frames of CDM = 0.
            while not (cdm and self.zeros >= IDLE_FRAMES):
                self.zeros = 0 if cdm else min(self.zeros + 1, IDLE_FRAMES)
                cdm = yield 0
            self.zeros = 0
            try:
                yield from self._control_frame()
            except _Cancel:
                pass
            cdm = yield 0

    def _control_frame(self):
        # s0 + 1 .. s0 + 16: IDL0..7 (slave 0 answers 1,0,...) and 8 zeros; CTS, ID, ADR, CRC4, R.
        idl = [1] + [0] * 15
        got = []
        for k in range(16):
            got.append((yield from self._step(idl[k])))
        cts, ident, adr, crc, r = got[0], got[1:4], got[4:11], got[11:15], got[15]
        w = yield from self._step(r)              # s0 + 17: echo of R; W received
        s = yield from self._step(w)              # s0 + 18: echo of W; S received
        ident = int("".join(map(str, ident)), 2)
        addr = int("".join(map(str, adr)), 2)
        accepted = (cts == 1 and crc == crc4(got[0:11]) and ident == self.slave_id
                    and r != w and s == 1)
        while True:
            if not accepted or (w and addr in self.read_only):
                while True:                       # no start bit: until cancelled
                    yield from self._step(0)
            for _ in range(self.delay):
                yield from self._step(0)
            if w:
                old = bits_of(self.regs.get(addr, 0), 8)
                old += crc4(old)
                rx = [(yield from self._step(1))]                   # start bit; DATA7 in
                for k in range(11):                                 # echo one frame later
                    rx.append((yield from self._step(old[k] if self.echo_old else rx[-1])))
                data = int("".join(map(str, rx[:8])), 2)
                if crc4(rx[:8]) == rx[8:] and not self.echo_old:
                    self.regs[addr] = data
                p = yield from self._step(old[11] if self.echo_old else rx[-1])   # P in
            else:
                value = self.regs.get(addr, 0)
                payload = bits_of(value, 8)
                check = crc4(payload)
                if self.bad_crc_at == addr:
                    check[2] ^= 1
                yield from self._step(1)                            # start bit
                for b in payload + check[:-1]:
                    yield from self._step(b)
                p = yield from self._step(check[-1])                # CRC0; P in
            assert p == 0, "P must be 0"
            more = yield from self._step(0)                         # echo of P; S again?
            if not more:
                return
            addr += 1


#: The limits bench's settings for a control-channel encoder: its timeout ends this many
#: clocks after MA stopped, and the round trip in clocks.
RELEASE = 6
ROUND_TRIP = 3


@dataclass
class ControlEncoder(Encoder):
    """The limits bench's encoder with a slave's control side: the CDS slot of every frame is
    the slave's answer, and the slave reads the CDM as the inverted MA level in the clock its
    timeout ends (docs/protocol.md, section 10)."""
    slave: object = None
    timeout_ends: list = field(default_factory=list)     # (clock, MA level there)

    def step(self, ma):
        if self._idle and self._ma_prev and not ma:      # a new frame: its CDS slot
            self.bits = list(self.bits)
            self.bits[1] = self.slave.cds()
        was_idle = self._idle
        out = super().step(ma)
        if not was_idle and self._idle:                  # the timeout ends: CDM = not MA
            self.timeout_ends.append((self._t, ma))
            self.slave.take(1 - ma)
        return out
