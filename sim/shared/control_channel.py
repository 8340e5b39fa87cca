"""The host side of the register-access engine (``ca_*`` ports) in cocotb, and a monitor that
checks every frame the core reports while the control channel rides on the data channel.

* :class:`FrameMonitor` waits for every ``done`` of the core, whoever asked for the cycle (the
  host, ``periodic``, or the engine itself), and checks it field by field against what the
  encoder model sent (``Testbench.check_frame``): with register accesses running, every
  position is still checked.
* :class:`ControlChannel` runs one register access through the ports, as a host (a CPU on a
  bus) would: it fills the write buffer, strobes ``ca_start``, waits for ``ca_done`` no longer
  than the documented bound allows, and reads the read buffer back. It checks what the docs
  promise of every access: the number of request cycles against the bound
  (``master_contract.ca_frame_bound``) and, for an access that ended OK, the CDM bits the
  encoder model received against the reference master's layout
  (``encoder_model.control_master.control_frame_cdm``) after 14 idle cycles.
  ``read_registers`` / ``write_register`` raise :class:`AccessError` unless the status is OK:
  the transport ``bissmaster.bp3.identify`` expects (docs/control.md, "The
  transport"); :meth:`ControlChannel.run_host` runs such blocking host code against them.

Status codes and counters come from ``tb/master_contract.py``, written from docs/ports.md;
nothing here imports the RTL.
"""

from dataclasses import dataclass, field

import cocotb
from cocotb.simtime import get_sim_time
from cocotb.task import bridge, resume
from cocotb.triggers import Event, FallingEdge, ReadOnly, RisingEdge, Timer, with_timeout

from encoder_model import frames
from encoder_model.control_master import RegisterAccess, control_frame_cdm
from master_contract import (CA_COUNTERS, CA_STATUS, CA_STATUS_NAME, DEFAULT_ACK_LIMIT_S,
                             DEFAULT_BREAK_S, DEFAULT_TIMEOUT_LIMIT_S, STATUS, ca_frame_bound,
                             crc_status)
from sim.shared.testbench import CLK_HZ

#: CDM = 0 cycles before S (docs/protocol.md, section 10).
IDLE_FRAMES = 14
#: The core's status for a cycle whose Response carried an encoder fault (docs/ports.md).
FAULT_STATUS = {"no_response": "NO_ACK", "stuck_high": "NO_ACK", "ack_forever": "NO_START"}


def frame_status(parsed, view):
    """The status a frame with these parsed words gets (docs/ports.md, "Status codes")."""
    return crc_status([w["crc_ok"] for w in parsed["words"]]) or "OK"


@dataclass
class Checked:
    """One reported cycle, as the monitor checked it."""
    result: object              # testbench.Result
    status: str                 # the expected (and seen) status name
    record: object              # the encoder's CycleRecord
    sent: object                # testbench.Sent: what the encoder model sent


class FrameMonitor:
    """Checks every ``done`` of the core against the encoder model, in the background.

    ``view``: the frame format the master is configured for when it is not the encoder's own
    (``tb.fmt``), e.g. a longer CRC-less format read before the encoder's length is known
    (``Testbench.line_bits``). The expected status of a cycle is the CRC verdict of what the
    master reads, or :data:`FAULT_STATUS` for a queued encoder fault. Only one thing may wait
    for ``done`` at a time: do not call ``Testbench.request`` while the monitor runs.
    """

    def __init__(self, tb, view=None):
        self.tb = tb
        self.view = view
        self.checked: list[Checked] = []
        self._task = None
        self._event = Event()

    @property
    def count(self):
        return len(self.checked)

    def start(self):
        if self._task is None:
            self._task = cocotb.start_soon(self._watch())

    def stop(self):
        if self._task is not None:
            self._task.cancel()
            self._task = None

    async def wait_frames(self, n, limit_s=0.1):
        """Until ``n`` cycles in all have been checked (returns outside the read-only phase
        the monitor checks in, so the caller may drive inputs)."""
        async def wait():
            while self.count < n:
                self._event.clear()
                await self._event.wait()
        await with_timeout(wait(), round(limit_s * 1e9), "ns")
        await Timer(1, "ps")

    async def _watch(self):
        tb = self.tb
        while True:
            await RisingEdge(tb.dut.done)
            await ReadOnly()
            res = tb.read()
            tb.check_pending()
            self.checked.append(self._check(res))
            self._event.set()

    def _check(self, res):
        tb = self.tb
        sent, record = tb.sent[-1], tb.encoder.records[-1]
        view = self.view or tb.fmt
        fault = sent.response.fault if sent.response is not None else None
        if fault is not None:
            status = FAULT_STATUS[fault]
            assert res.status == STATUS[status] and res.valid == 0, \
                f"encoder fault {fault}: status {res.status}, expected {status}"
        else:
            status = frame_status(frames.parse_frame(view, tb.line_bits(sent, view)), view)
            tb.check_frame(res, status=status, sent=sent, record=record, view=view)
        return Checked(res, status, record, sent)


@dataclass
class Access:
    """One register access as the host saw it."""
    slave_id: int
    address: int
    count: int
    write: bool
    status: int
    bytes_done: int
    data: bytes                 # read: the bytes read (ca_bytes_done of them); write: sent
    frames: int                 # request cycles reported from ca_start to ca_done
    cdm: list = field(default_factory=list)     # CDM of the encoder's cycles meanwhile
    t_start_s: float = 0.0
    t_done_s: float = 0.0

    @property
    def name(self):
        return CA_STATUS_NAME.get(self.status, f"unknown status {self.status}")

    def __str__(self):
        kind = "write" if self.write else "read"
        return (f"{kind} of {self.count} register(s) at {self.address:#04x} (slave "
                f"{self.slave_id}): {self.name}, {self.bytes_done} byte(s) done, "
                f"{self.frames} frames")


class AccessError(Exception):
    """A register access through the transport functions did not end OK."""

    def __init__(self, access):
        super().__init__(str(access))
        self.access = access


class ControlChannel:
    """Register accesses through the ``ca_*`` ports of a started :class:`Testbench`.

    Every access is logged in :attr:`log`; :meth:`check_counters` compares the
    ``count_ca_*`` outputs with the statuses logged. The :attr:`monitor` runs from the first
    access on and checks every reported cycle (its ``view`` may be changed as the master's
    configuration is).
    """

    def __init__(self, tb, *, view=None):
        assert tb.has_register_access, "this build has no register-access engine"
        self.tb = tb
        self.dut = tb.dut
        self.monitor = FrameMonitor(tb, view)
        self.log: list[Access] = []
        self._counters0 = self._ca_counters() if tb.has_counters else None

    # -- the ports ----------------------------------------------------------------------------
    async def _strobe(self, name):
        await FallingEdge(self.dut.clk)
        getattr(self.dut, name).value = 1
        await FallingEdge(self.dut.clk)
        getattr(self.dut, name).value = 0

    async def fill_write_buffer(self, data):
        """One byte per clock, its own byte lane enabled (byte i is lane i % 4 of word i // 4,
        docs/ports.md); the other lanes carry ones, which must not be written."""
        dut = self.dut
        for i, byte in enumerate(bytes(data)):
            await FallingEdge(dut.clk)
            lane = i % 4
            dut.ca_wbuf_addr.value = i // 4
            dut.ca_wbuf_data.value = (0xFFFFFFFF & ~(0xFF << 8 * lane)) | byte << 8 * lane
            dut.ca_wbuf_en.value = 1 << lane
        await FallingEdge(dut.clk)
        dut.ca_wbuf_en.value = 0

    async def read_buffer(self, n):
        """Bytes 0 .. n - 1 of the read buffer: words of 4 bytes, little endian (the data port
        is registered: one clock after the read enable)."""
        dut, out = self.dut, bytearray()
        for w in range(-(-n // 4)):
            await FallingEdge(dut.clk)
            dut.ca_rbuf_addr.value = w
            dut.ca_rbuf_en.value = 1
            await FallingEdge(dut.clk)
            dut.ca_rbuf_en.value = 0
            out += int(dut.ca_rbuf_data.value).to_bytes(4, "little")
        return bytes(out[:n])

    async def abort(self):
        """One-clock ``ca_abort``."""
        await self._strobe("ca_abort")

    def cycle_time_bound_s(self):
        """A generous bound on one request cycle under today's configuration, from the
        documented limits (docs/ports.md): the request period, the Ack limit (it covers the
        encoder's processing time), the frame's MA periods with the round trip, the SLO-low
        limit (it covers the encoder's timeout and a CDM hold) and a break after a fault."""
        dut, tb = self.dut, self.tb
        period = 2 * tb.half_period / CLK_HZ
        bits = (self.monitor.view or tb.fmt).total_bits
        setting = lambda name, default: int(getattr(dut, name).value) / CLK_HZ or default
        return (int(dut.cfg_request_period.value) / CLK_HZ
                + setting("cfg_ack_limit", DEFAULT_ACK_LIMIT_S)
                + period * (bits + 8) + tb.encoder.cable.round_trip_s()
                + setting("cfg_timeout_limit", DEFAULT_TIMEOUT_LIMIT_S)
                + setting("cfg_break_time", DEFAULT_BREAK_S))

    # -- one access ---------------------------------------------------------------------------
    async def access(self, slave_id, address, count, *, write=False, data=None,
                     check_bound=True):
        """One access with any request (also an invalid one); returns the :class:`Access`.

        A write sends ``data`` (``count`` bytes). Waits for ``ca_done`` at most
        ``ca_frame_bound(count, write)`` cycles of :meth:`cycle_time_bound_s` (a hang fails here),
        then checks the reported cycles against that bound and, when the status is OK, the
        encoder's CDM against the reference layout.
        """
        tb, dut = self.tb, self.dut
        self.monitor.start()
        if write:
            data = bytes(data)
            await self.fill_write_buffer(data)
        await FallingEdge(dut.clk)
        assert not int(dut.ca_busy.value), "an access is still running"
        dut.ca_slave_id.value = slave_id
        dut.ca_address.value = address
        dut.ca_count.value = count
        dut.ca_write.value = int(write)
        frames_before, records_before = self.monitor.count, len(tb.encoder.records)
        bound = ca_frame_bound(max(1, min(count, 64)), write)
        limit_s = bound * self.cycle_time_bound_s() + 1e-3
        t_start = get_sim_time("step") * 1e-12
        done = cocotb.start_soon(with_timeout(RisingEdge(dut.ca_done), round(limit_s * 1e9),
                                                "ns"))
        dut.ca_start.value = 1
        await FallingEdge(dut.clk)
        dut.ca_start.value = 0
        await done
        await ReadOnly()
        status, bytes_done = int(dut.ca_status.value), int(dut.ca_bytes_done.value)
        t_done = get_sim_time("step") * 1e-12
        await Timer(1, "ps")
        frames_seen = self.monitor.count - frames_before
        cdm = [r.cdm for r in tb.encoder.records[records_before:]]
        if write:
            got = data[:bytes_done]
        else:
            got = await self.read_buffer(bytes_done)
        acc = Access(slave_id, address, count, write, status, bytes_done, got, frames_seen,
                     cdm, t_start, t_done)
        self.log.append(acc)
        tb.dut._log.info("register access: %s", acc)
        if check_bound:
            assert frames_seen <= bound, f"{acc}: more than the bound of {bound} frames"
        if status == CA_STATUS["OK"]:
            assert bytes_done == count, f"{acc}: OK with {bytes_done} of {count} bytes"
            self._check_cdm(acc, records_before)
        return acc

    def _check_cdm(self, acc, records_before):
        """An OK access: the encoder received S after 14 cycles of CDM = 0, then exactly the
        reference master's control frame (for a slave without a late start bit), then 0."""
        records = self.tb.encoder.records
        cdm = [r.cdm for r in records]
        first = records_before + acc.cdm.index(1)
        assert first >= IDLE_FRAMES and not any(cdm[first - IDLE_FRAMES:first]), \
            f"{acc}: S without {IDLE_FRAMES} idle cycles before it: {cdm[:first + 1][-20:]}"
        request = (RegisterAccess.write(acc.address, acc.data, slave_id=acc.slave_id)
                   if acc.write else
                   RegisterAccess.read(acc.address, acc.count, slave_id=acc.slave_id))
        expected = control_frame_cdm(request)
        sent = cdm[first:first + len(expected)]
        if self.tb.encoder.control is None or not self.tb.encoder.control.start_delay:
            assert sent == expected, f"{acc}: CDM {sent}, the reference sends {expected}"
        assert not any(cdm[first + len(expected):]), f"{acc}: CDM = 1 after the last P"

    async def read_positions(self, n):
        """``n`` single requests (``start``) on the data channel, each checked by the monitor;
        returns their :class:`Checked` records."""
        tb, dut = self.tb, self.dut
        self.monitor.start()
        out = []
        for _ in range(n):
            await tb.wait_idle()
            before = self.monitor.count
            await FallingEdge(dut.clk)
            dut.start.value = 1
            await FallingEdge(dut.clk)
            dut.start.value = 0
            await self.monitor.wait_frames(before + 1, limit_s=self.cycle_time_bound_s())
            out.append(self.monitor.checked[-1])
        return out

    # -- the transport of bissmaster.bp3 ------------------------------------------------------
    async def read_registers(self, slave_id, address, count):
        """``count`` consecutive registers from ``address``, one sequential access; raises
        :class:`AccessError` unless OK."""
        acc = await self.access(slave_id, address, count)
        if acc.status != CA_STATUS["OK"]:
            raise AccessError(acc)
        return acc.data

    async def write_register(self, slave_id, address, data):
        """The bytes ``data`` from ``address``, one access; raises :class:`AccessError`
        unless OK."""
        data = bytes(data)
        acc = await self.access(slave_id, address, len(data), write=True, data=data)
        if acc.status != CA_STATUS["OK"]:
            raise AccessError(acc)

    async def run_host(self, func, *args, **kwargs):
        """``func(read_registers, write_register, *args, **kwargs)``, a blocking host function
        such as ``bissmaster.bp3.identify``, run in a bridge thread with both transport
        functions made blocking (``cocotb.task.bridge`` / ``resume``)."""
        return await bridge(func)(resume(self.read_registers), resume(self.write_register),
                                  *args, **kwargs)

    # -- counters -----------------------------------------------------------------------------
    def _ca_counters(self):
        counters = self.tb.read().counters
        return {name: counters[name] for name in CA_COUNTERS.values()}

    def check_counters(self):
        """Every ``count_ca_*`` has grown by the number of logged accesses with its status."""
        if self._counters0 is None:
            return
        seen = self._ca_counters()
        grown = {name: seen[name] - self._counters0[name] for name in seen}
        expected = {counter: sum(a.name == status for a in self.log)
                    for status, counter in CA_COUNTERS.items()}
        assert grown == expected, f"counters grew {grown}, the statuses seen give {expected}"
