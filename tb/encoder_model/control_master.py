"""BiSS C control communication, master side, as a test-side reference (docs/protocol.md, section 10).

What a correct master sends (CDM, one bit per data frame) for a register read or write of one
or more consecutive registers, and what it makes of the slave's answers (CDS): the expected
behaviour the RTL's register-access engine is compared with. Written from the protocol
description, like :mod:`encoder_model.control`; it imports nothing from ``rtl/``.

* :func:`control_frame_cdm`: the CDM bits from S to the last P for a slave that answers without
  delay (32 bits, plus 14 per further register).
* :class:`ControlMaster`: the same, one frame at a time and adaptive: it keeps CDM = 1 while a
  slave delays its start bit (up to ``max_start_wait`` frames), sends the 14 idle frames before
  every access, checks IDL, the R/W echo, the start bits, the CRC-4 of read bytes and the echo of
  written ones, and ends each access with a :class:`ControlResult`.
* :func:`decode_cds`: the result a master reaches from a recorded CDS stream.
* :func:`exchange`: a master and an :class:`~encoder_model.control.ControlSlave` side by side.

Frame convention: in frame ``n`` the master receives CDS(n) (the bit after Start) and then sends
CDM(n) (MA through the timeout); the slave answers CDM(n) in CDS(n + 1).
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass

from .control import (ADDRESS_BITS, ADDRESS_COUNT, CRC4_WIDTH, DATA_BITS, ID_BITS, IDL_BITS,
                      IDLE_FRAMES, bits_value, byte_bits, crc4_data, crc4_header)

__all__ = ["RegisterAccess", "ControlStatus", "ControlResult", "control_frame_cdm",
           "ControlMaster", "decode_cds", "exchange", "MAX_REGISTERS"]

MAX_REGISTERS = 64          # one EDS bank; the model allows up to the whole address space
FRAMES_FIRST_REGISTER = 32  # S .. P of an access of one register
FRAMES_PER_REGISTER = 14    # S, 12 slots, P of every further register


@dataclass(frozen=True)
class RegisterAccess:
    """A read of ``count`` registers or a write of ``data``, from ``address`` on."""
    address: int
    count: int = 1
    data: bytes | None = None
    slave_id: int = 0

    def __post_init__(self):
        if not isinstance(self.address, int) or not 0 <= self.address < ADDRESS_COUNT:
            raise ValueError(f"address must be 0..0x7F, not {self.address!r}")
        if not isinstance(self.slave_id, int) or not 0 <= self.slave_id < (1 << ID_BITS):
            raise ValueError(f"slave_id must be 0..7, not {self.slave_id!r}")
        if self.data is not None:
            object.__setattr__(self, "data", bytes(self.data))
            object.__setattr__(self, "count", len(self.data))
        if not isinstance(self.count, int) or not 1 <= self.count <= ADDRESS_COUNT:
            raise ValueError(f"count must be 1..{ADDRESS_COUNT}, not {self.count!r}")

    @classmethod
    def read(cls, address, count=1, *, slave_id=0):
        return cls(address, count, None, slave_id)

    @classmethod
    def write(cls, address, data, *, slave_id=0):
        return cls(address, len(bytes(data)), bytes(data), slave_id)

    @property
    def is_write(self):
        return self.data is not None

    def header_bits(self):
        """CDM s0+1 .. s0+17: CTS = 1, ID, ADR, CRC4 over those 11 bits, R, W."""
        r, w = (0, 1) if self.is_write else (1, 0)
        return ([1] + byte_bits(self.slave_id, ID_BITS) + byte_bits(self.address, ADDRESS_BITS)
                + byte_bits(crc4_header(self.slave_id, self.address), CRC4_WIDTH) + [r, w])

    def slot_bits(self, index):
        """The 12 CDM bits after the slave's start bit for register ``index`` of the access:
        DATA and its CRC-4 for a write, zeros for a read."""
        if not self.is_write:
            return [0] * (DATA_BITS + CRC4_WIDTH)
        value = self.data[index]
        return byte_bits(value) + byte_bits(crc4_data(value), CRC4_WIDTH)


class ControlStatus(enum.Enum):
    OK = "ok"
    NO_ANSWER = "no answer"         # no IDL bit: a unidirectional encoder, or none at all
    REFUSED = "refused"             # IDL seen, but an R/W echo or a start bit missing
    CRC_ERROR = "crc error"         # a read byte's CRC-4, or a write's or P's echo, wrong


@dataclass
class ControlResult:
    """How one access ended. ``data``: the bytes read, or written and echoed, before the end."""
    access: RegisterAccess
    status: ControlStatus
    data: bytes
    reason: str = ""                # which check failed
    failed_register: int | None = None  # index in the access of the register that failed
    s_frame: int = 0                # master frame number of the first S
    end_frame: int = 0              # frame in which the result was known (its CDM is idle)


def control_frame_cdm(access):
    """CDM from S to the last P, for a slave that sends its start bits without delay.

    ``32 + 14 * (count - 1)`` bits: S, header, S, then per register 12 slots and P, the next
    register's S right after P.
    """
    bits = [1] + access.header_bits() + [1]
    for index in range(access.count):
        if index:
            bits.append(1)                      # S: next register
        bits += access.slot_bits(index) + [0]   # slots, P
    return bits


class ControlMaster:
    """A reference master's control side, one frame per :meth:`step`; accesses run in order.

    Parameters
    ----------
    idle_frames : int
        CDM = 0 frames before each S, counted after the previous access ended (P included in
        the access, so P + ``idle_frames`` zeros).
    initial_idle : int
        Idle frames already on the line before the first step.
    max_start_wait : int
        Frames the master keeps CDM = 1 waiting for a late start bit (0: none expected late).
    """

    def __init__(self, *, idle_frames=IDLE_FRAMES, initial_idle=0, max_start_wait=0):
        if not isinstance(max_start_wait, int) or max_start_wait < 0:
            raise ValueError(f"max_start_wait must be an int >= 0, not {max_start_wait!r}")
        self.idle_frames = idle_frames
        self.max_start_wait = max_start_wait
        self.queue: deque[RegisterAccess] = deque()
        self.results: list[ControlResult] = []
        self.frame = -1             # number of the frame of the last step (0 = first)
        self._idle = initial_idle
        self._run = None

    def submit(self, access):
        self.queue.append(access)

    @property
    def busy(self):
        return self._run is not None or bool(self.queue)

    def step(self, cds):
        """CDS of this frame in, this frame's CDM out."""
        if cds not in (0, 1):
            raise ValueError(f"cds must be 0 or 1, not {cds!r}")
        self.frame += 1
        if self._run is not None:
            try:
                return self._run.send(cds)
            except StopIteration as done:
                self.results.append(done.value)
                self._run, self._idle = None, 0
        if self.queue and self._idle >= self.idle_frames:
            self._run = self._access(self.queue.popleft())
            next(self._run)
            return self._run.send(cds)
        self._idle += 1
        return 0

    def _access(self, acc):
        """One access as a coroutine: ``cds = yield cdm`` sends this frame's CDM and receives
        the next frame's CDS."""
        cds = yield
        s_frame = self.frame

        def result(status, data, reason="", failed=None):
            return ControlResult(acc, status, bytes(data), reason, failed, s_frame, self.frame)

        seen = {}
        cds = yield 1                                   # S
        for k, bit in enumerate(acc.header_bits(), start=1):
            seen[k] = cds                               # CDS(s0 + k)
            cds = yield bit
        seen[18] = cds
        r, w = acc.header_bits()[-2:]
        if not any(seen[k] for k in range(1, IDL_BITS + 1)):
            return result(ControlStatus.NO_ANSWER, b"", "no IDL bit")
        if (seen[17], seen[18]) != (r, w):
            return result(ControlStatus.REFUSED, b"", f"R/W echo {seen[17]}{seen[18]}", 0)
        data = bytearray()
        cds = yield 1                                   # S: the data part
        for index in range(acc.count):
            waited = 0
            while cds == 0:                             # the slave's start bit
                if waited >= self.max_start_wait:
                    return result(ControlStatus.REFUSED, data, "no start bit", index)
                waited += 1
                cds = yield 1
            slots = acc.slot_bits(index)
            answer = []
            for bit in slots:
                cds = yield bit
                answer.append(cds)
            cds = yield 0                               # P; cds = its echo
            if acc.is_write:
                if answer != slots:
                    return result(ControlStatus.CRC_ERROR, data, "write echo", index)
                value = acc.data[index]
            else:
                value = bits_value(answer[:DATA_BITS])
                if bits_value(answer[DATA_BITS:]) != crc4_data(value):
                    return result(ControlStatus.CRC_ERROR, data, "read CRC-4", index)
            if cds != 0:
                return result(ControlStatus.CRC_ERROR, data, "P echo", index)
            data.append(value)
            if index + 1 < acc.count:
                cds = yield 1                           # S: the next register
        return result(ControlStatus.OK, data)


def decode_cds(access, cds, *, max_start_wait=0):
    """The result a master reaches from ``cds[i]`` = CDS of frame s0 + i (the master sends the
    CDM of :class:`ControlMaster`; with ``max_start_wait`` it waits for late start bits)."""
    master = ControlMaster(initial_idle=IDLE_FRAMES, max_start_wait=max_start_wait)
    master.submit(access)
    for bit in cds:
        master.step(bit)
        if not master.busy:
            return master.results[0]
    raise ValueError(f"{len(cds)} CDS frames do not finish the access")


def exchange(master, slave, *, max_frames=100_000):
    """Step ``master`` and ``slave`` together until the master has nothing left to do.

    Returns the frames as ``(cds, cdm)`` pairs: the CDS the slave put in the frame and the CDM
    the master sent after it.
    """
    frames = []
    while master.busy:
        if len(frames) >= max_frames:
            raise RuntimeError(f"master still busy after {max_frames} frames")
        cds = slave.cds
        cdm = master.step(cds)
        slave.step(cdm)
        frames.append((cds, cdm))
    return frames
