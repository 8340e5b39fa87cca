"""cocotb scenarios of the control channel (issue 13): register accesses through the ``ca_*``
ports of the default build against the encoder model's control side, and ``bissmaster.bp3``
(the host software under test, what a user runs against the hardware) run through them.

Expected values come from the encoder model (``encoder_model.control``: the register file, the
BP3 EDS, the control slave and its faults; ``control_master``: the reference CDM layout) and
from tb/master_contract.py (statuses, counters, the frame bound, written from the docs);
nothing here imports the RTL. Every cycle the core reports while these scenarios run is checked
field by field against the encoder model (``sim/shared/control_channel.FrameMonitor``), every
access's frame count against the documented bound, and every access that ends OK against the
reference master's CDM layout after 14 idle cycles (``ControlChannel.access``).

The encoder models here are BP3 encoders without the RESOLUTE 31.25 us rule, with a processing
time of 1 .. 3 us and either a static timeout of 12.5 us or an adaptive one of 1.5 MA periods
(docs/protocol.md, section 9): a register access costs hundreds of cycles, and this keeps them affordable.
Which rates, lengths and cables each scenario covers is in its docstring; the larger sets run
on Verilator, a subset on Icarus (about six times slower on this core).
"""

import cocotb
from cocotb.triggers import FallingEdge

from bissmaster import bp3
from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from encoder_model.control import Bp3Eds, ControlFaults, ControlSlave, RegisterFile
from master_contract import CA_STATUS, CRC_CODE, MAX_DATA_BITS, STATUS, ca_frame_bound, crc_config
from sim.shared.control_channel import IDLE_FRAMES, ControlChannel
from sim.shared.discovery import full_in_sim_long, full_run, long_on_icarus
from sim.shared.testbench import CLK_HZ, Testbench, preset

#: A BP3 encoder's processing time (Ack to Start) here: short, so that a 1,000-frame
#: identification stays affordable in simulation.
BP3_PROCESSING_S = (1e-6, 3e-6)
SERIAL, DEVICE_ID, MANUFACTURER_ID = b"\x12\x34\x56\x78", b"BP3MOD", b"iC"
STATIC_TIMEOUT_S = 12.5e-6


def adaptive_timeout(ma_hz):
    """An adaptive slave timeout: 1.5 MA periods (docs/protocol.md, section 9)."""
    return 1.5 / ma_hz


#: What the data channel reads before the encoder is identified: the longest frame this build
#: reads without a check that could fail (word 0 and word 1 at their widest, each with nE/nW;
#: no LC, no CRC: 99 bits), so that every BP3 frame (at most 63 bits after CDS with C = 0) and
#: every BiSS Safety frame of the presets (at most 96) fits. The master reads the encoder's bits,
#: then the line low (stop bit, timeout); the CDS bit is where it always is, after Start.
#: Positions are checked as that reading of the frame (``Testbench.line_bits``).
BOOTSTRAP = frames.FrameFormat("longest_unchecked", (
    frames.WordFormat(MAX_DATA_BITS[0], crc=frames.CRC_NONE),
    frames.WordFormat(MAX_DATA_BITS[1], crc=frames.CRC_NONE)))
BOOTSTRAP_CFG = {"cfg_w0_data_bits": MAX_DATA_BITS[0], "cfg_w0_nenw": 1, "cfg_w0_lc": 0,
                 "cfg_w0_crc": CRC_CODE["none"], "cfg_w1_enable": 1,
                 "cfg_w1_data_bits": MAX_DATA_BITS[1], "cfg_w1_nenw": 1, "cfg_w1_lc": 0,
                 "cfg_w1_crc": CRC_CODE["none"], "cfg_spw_check": 0}


def on_icarus():
    return "icarus" in cocotb.SIM_NAME.lower()


def bp3_registers(eds, *, pointer=1, **kwargs):
    """A BP3 encoder's register file laid out as ``bp3.identify`` assumes by default: register
    0x41 points to a common EDS part of one bank, the BP3 bank follows it."""
    common = bytes((0xC0 + i) & 0xFF for i in range(64))        # whatever the common part holds
    return RegisterFile(eds_bank=pointer, profile_id=eds.profile_id,
                        data_length=eds.data_length, serial_number=SERIAL,
                        device_id=DEVICE_ID, manufacturer_id=MANUFACTURER_ID,
                        banks={pointer: common, pointer + 1: eds.to_bytes()}, **kwargs)


def expected_config(dl_pos):
    """docs/control.md, "Derived settings", for a BP3 C = 0 encoder with CRC-6 (binary
    positions: Gray off)."""
    return {"cfg_w0_data_bits": dl_pos, "cfg_w0_nenw": 1, "cfg_w0_lc": 0, "cfg_w0_gray": 0,
            "cfg_w0_signed": 0,
            "cfg_w0_crc": CRC_CODE["crc6"], "cfg_w1_enable": 0, "cfg_spw_check": 0}


async def bench(dut, *, seed, cable_m=0, timeout_s=STATIC_TIMEOUT_S, slave=None):
    tb = Testbench(dut, seed=seed)
    tb.processing_s = BP3_PROCESSING_S
    await tb.start(cable=Cable(length_m=cable_m), timeout_s=timeout_s, control=slave,
                   min_cycle_s=0)
    return tb


async def new_encoder(tb, ctl, slave, fmt, ma_hz, cable_m, timeout_s, **cfg):
    """Put another encoder on the line (its control slave, frame format, cable and timeout),
    configure the data channel for it (``cfg``: overrides) and read 14 positions: the new
    encoder must have seen 14 idle cycles (CDM = 0) before it takes an S."""
    await tb.encoder_ready()
    tb.encoder.control = slave
    tb.encoder.set_cable(Cable(length_m=cable_m))
    tb.encoder.timeout_s = timeout_s
    tb.configure(fmt, ma_hz, **cfg)
    await ctl.read_positions(IDLE_FRAMES)


def finish(tb, ctl):
    """The end of every scenario: the access counters against the statuses seen, no MA fall
    while the encoder was in its timeout; what was checked, for the record."""
    ctl.check_counters()
    assert not tb.encoder.ignored_falls, tb.encoder.ignored_falls[:5]
    tb.dut._log.info("%d register accesses, %d cycles checked", len(ctl.log), ctl.monitor.count)


def assert_status(acc, name, bytes_done=None):
    assert acc.status == CA_STATUS[name], f"{acc}: expected {name}"
    if bytes_done is not None:
        assert acc.bytes_done == bytes_done, f"{acc}: expected {bytes_done} byte(s) done"


# -- BP3 identification ----------------------------------------------------------------------

IDENTIFY_ACCESSES = [(False, 0x40, 4), (True, 0x40, 1), (False, 0x40, 1), (False, 0x00, 64),
                     (True, 0x40, 1)]
IDENTIFY_ACCESSES_SELECTED = [(False, 0x40, 4), (False, 0x00, 64)]    # BP3 bank selected already


def check_identification(ident, eds, slave, log, bank_select):
    """What bp3.identify found, against the model's encoder; its accesses as documented."""
    assert ident.profile == bp3.ProfileId(1, bp3.CrcMode.SEPARATE, eds.data_length), ident.profile
    assert (ident.eds_bank, ident.profile_bank) == (1, 2)
    raw = eds.to_bytes()
    assert ident.eds.raw == raw, "the EDS read differs from the model's bank"
    for name in (f for f in bp3.Bp3Eds.__dataclass_fields__ if f not in ("raw", "chksum")):
        assert getattr(ident.eds, name) == eds.value_of(name), name
    assert ident.eds.chksum == raw[0x3F]
    assert ident.config == expected_config(eds.dl_pos), ident.config
    assert slave.registers.bank_select == bank_select, "bank select not restored"
    assert [(a.write, a.address, a.count) for a in log] == (
        IDENTIFY_ACCESSES if bank_select != 2 else IDENTIFY_ACCESSES_SELECTED), \
        [str(a) for a in log]


async def identify_point(tb, ctl, eds, fmt, ma_hz, cable_m, timeout_s, bank_select,
                         positions=8):
    """A BP3 encoder (its EDS ``eds``, frames ``fmt``) put on the line with bank
    ``bank_select`` selected; the data channel reads the bootstrap frame; bp3.identify through
    the ports. C = 0: the data channel is configured from the derived settings alone and
    ``positions`` positions are read with them (CRC checked). C = 1: identify() must refuse."""
    slave = ControlSlave(bp3_registers(eds, bank_select=bank_select))
    ctl.monitor.view = BOOTSTRAP
    await new_encoder(tb, ctl, slave, fmt, ma_hz, cable_m, timeout_s, **BOOTSTRAP_CFG)
    first = len(ctl.log)
    t0 = tb.encoder.records[-1].t_first_fall_s
    what = f"BP3 C = {eds.c}, DL {eds.data_length} at {ma_hz / 1e6:g} MHz over {cable_m} m"
    try:
        ident = await ctl.run_host(bp3.identify)
    except bp3.UnsupportedEncoderError as e:
        # C = 1: the docs promise this refusal (derive_config, "C = 1"), after the whole EDS
        # was read and with the bank select restored.
        assert eds.c == 1, f"{what}: {e!r}"
        assert "C = 1" in str(e), e
        log = ctl.log[first:]
        assert all(a.status == CA_STATUS["OK"] for a in log), [str(a) for a in log]
        assert [(a.write, a.address, a.count) for a in log] == IDENTIFY_ACCESSES
        assert log[3].data == eds.to_bytes()
        assert slave.registers.bank_select == bank_select, "bank select not restored"
        tb.dut._log.info("%s: refused (%s)", what, e)
        # The host sets the words from the datasheet (the model's format) and reads positions.
        tb.configure(fmt, ma_hz)
    else:
        assert eds.c == 0, f"{what}: identify() configured a C = 1 encoder"
        log = ctl.log[first:]
        check_identification(ident, eds, slave, log, bank_select)
        # Only the derived settings change the data channel; the monitor checks the frames as
        # the encoder's own format (CRC, nE/nW), so a wrong setting fails here.
        for port, value in ident.config.items():
            getattr(tb.dut, port).value = value
    tb.dut._log.info("%s: identification took %d frames (%s), %.2f ms", what,
                     sum(a.frames for a in log), " + ".join(str(a.frames) for a in log),
                     (log[-1].t_done_s - t0) * 1e3)
    ctl.monitor.view = None
    for checked in await ctl.read_positions(positions):
        assert checked.status == "OK" and checked.result.valid


@cocotb.test()
@long_on_icarus
@full_in_sim_long(100_000_000)
async def bp3_identify_and_configure(dut):
    """bp3.identify() through the ports against BP3 encoder models, then the data channel set
    from derive_config() alone and positions read with it, every frame checked.

    Before identification the data channel reads the longest unchecked frame (``BOOTSTRAP``):
    the host does not know the encoder's length yet. Each identification is the documented
    sequence (read 0x40..0x43, select the BP3 bank, read it back, read the 64-byte bank,
    restore the bank select: 1,103 frames; 990 when the BP3 bank is selected already), its
    result compared field by field with the model's EDS. An encoder with C = 1 (BiSS Safety,
    RESOLUTE FS RSH frames) is identified, its EDS read, and refused with
    UnsupportedEncoderError naming C = 1 as the docs promise; the host then sets its words
    itself and reads positions. All at 10 MHz with an adaptive timeout. Verilator: DL_POS 24
    over 100 m (bank switched), DL_POS 55 over 0 m (bank selected already), C = 1 over 100 m
    (bank switched; DL_POS 1, the shortest frame, is read at 250 kHz in
    ``bp3_registers_every_rate``); Icarus: DL_POS 36 over 100 m (bank switched). Each identification
    is 12 .. 15 ms of simulated time (about 30 s of wall time on Verilator, five minutes on
    Icarus); the other rates are in ``bp3_registers_every_rate``. ``make test``'s Verilator run
    is the first (DL_POS 24: the whole sequence with the bank switched, the EDS field by field,
    the derived settings applied, positions); the full run (BISS_FULL=1, make sim-long) has all
    three. The two left out check host-side branches that tb/tests/host/test_bp3.py also checks
    on its fake encoder (the bank selected already; the C = 1 refusal).
    """
    tb = await bench(dut, seed=131)
    ctl = ControlChannel(tb)
    timeout_s = adaptive_timeout(10e6)
    points = [(Bp3Eds(24), frames.bp3(24), 100, 0), (Bp3Eds(55), frames.bp3(55), 0, 2),
              (Bp3Eds(36, c=1), preset("resolute_fs_rsh"), 100, 0)]
    if on_icarus():
        points = [(Bp3Eds(36), frames.bp3(36), 100, 0)]
    elif not full_run():
        points = points[:1]
    for eds, fmt, cable_m, bank_select in points:
        await identify_point(tb, ctl, eds, fmt, 10e6, cable_m, timeout_s, bank_select)
    finish(tb, ctl)


@cocotb.test()
@long_on_icarus
@full_in_sim_long(100_000_000)
async def bp3_registers_every_rate(dut):
    """Register reads at every MA rate over 0 m and 100 m, each with its own BP3 encoder:
    250 kHz DL_POS 1, 1 MHz DL_POS 36, 5 MHz DL_POS 55, 10 MHz DL_POS 24 (the data channel set
    for the encoder, as after an identification). One sequential read of 0x40..0x43 (bank
    select, EDS pointer, profile ID, DL: what identification starts with) each, checked against
    the model and decoded with bp3.decode_profile_id; 14 positions before it (the new encoder's
    idle cycles) and 2 after it. Timeouts: static 12.5 us over 0 m, adaptive over 100 m.
    Icarus: each rate once (0 m at 250 kHz and 5 MHz, 100 m at 1 and 10 MHz), 0x42..0x43.
    make test's Verilator run: the same four points, 0x40..0x43; the eight in the full run
    (BISS_FULL=1, make sim-long)."""
    tb = await bench(dut, seed=133)
    ctl = ControlChannel(tb)
    points = [(ma, dl, cable) for ma, dl in ((250e3, 1), (1e6, 36), (5e6, 55), (10e6, 24))
              for cable in (0, 100)]
    first, count = 0x40, 4
    each_rate_once = [(250e3, 1, 0), (1e6, 36, 100), (5e6, 55, 0), (10e6, 24, 100)]
    if on_icarus():
        points = each_rate_once
        first, count = 0x42, 2
    elif not full_run():
        points = each_rate_once
    for ma_hz, dl_pos, cable_m in points:
        eds = Bp3Eds(dl_pos)
        regs = bp3_registers(eds)
        slave = ControlSlave(regs)
        timeout_s = STATIC_TIMEOUT_S if cable_m == 0 else adaptive_timeout(ma_hz)
        await new_encoder(tb, ctl, slave, frames.bp3(dl_pos), ma_hz, cable_m, timeout_s)
        data = await ctl.read_registers(0, first, count)
        assert data == bytes(regs.read(a) for a in range(first, first + count)), data.hex()
        profile = bp3.decode_profile_id(data[-2], data[-1])
        assert (profile.crc_mode, profile.position_bits) == (bp3.CrcMode.SEPARATE, dl_pos)
        tb.dut._log.info("%g MHz, %d m, DL_POS %d: read 0x%02X..0x%02X in %d frames",
                         ma_hz / 1e6, cable_m, dl_pos, first, first + count - 1,
                         ctl.log[-1].frames)
        await ctl.read_positions(2)
    finish(tb, ctl)


#: A BP3 encoder whose EDS names a CRC other than BiSS's (issue 26): x^16 + x^12 + x^5 + 1
#: (0x11021) from 0xFFFF, sent inverted as BiSS CRCs are. CPOLY is the polynomial without x^0,
#: shifted down one bit (docs/protocol.md, section 7): 0x8810. The model computes the CRC itself
#: (frames.CustomCrc); what the core is expected to be set to comes from crc_config.
CUSTOM_CRC_EDS = {"cpoly": 0x11021 >> 1, "cstart": 0xFFFF}
CUSTOM_CRC = frames.CustomCrc(16, 0x1021, start=0xFFFF, inverted=True)
CUSTOM_CRC_DL_POS = 6


@cocotb.test()
async def bp3_custom_crc_identify_and_configure(dut):
    """A BP3 encoder whose EDS names CRC 0x11021 from 0xFFFF (CPOLY 0x8810, CSTART 0xFFFF) and
    whose frames carry it: identified through ``bissmaster.bp3``, the data channel set from
    derive_config() alone, positions read.

    DL_POS 6 at 10 MHz over 0 m, adaptive timeout, processing 0.3 .. 0.8 us (a cycle of about
    4 us). The data channel reads the encoder's own frame while the host reads its profile
    (every cycle checked by the monitor): registers 0x40..0x43 through the ports, decoded by
    bp3.decode_profile_id; bp3.decode_eds() + derive_config() take the model's bank (the
    64-byte EDS read through the ports, 1,103 frames, is ``bp3_identify_and_configure``'s
    and does not depend on the CRC the EDS names). The derived settings must be a custom CRC (cfg_w0_crc = 3, width 16,
    polynomial 0x1021, start 0xFFFF, inverted) as the model's CRC says; word 0's CRC is then set
    to the named CRC-6 by the test, so only the derived settings can make the cycles OK; they
    are applied alone and 8 positions read, each OK with the model's CRC good.
    """
    eds = Bp3Eds(CUSTOM_CRC_DL_POS, **CUSTOM_CRC_EDS)
    fmt = frames.FrameFormat("bp3_6_crc_0x11021",
                             (frames.WordFormat(CUSTOM_CRC_DL_POS, crc=CUSTOM_CRC),))
    slave = ControlSlave(bp3_registers(eds))
    timeout_s = adaptive_timeout(10e6)
    tb = await bench(dut, seed=139, timeout_s=timeout_s)
    assert tb.has_custom_crc, "the default build has custom CRCs"
    tb.processing_s = (0.3e-6, 0.8e-6)     # a short cycle: the identification is ~1,100 of them
    ctl = ControlChannel(tb)
    await new_encoder(tb, ctl, slave, fmt, 10e6, 0, timeout_s)
    regs = await ctl.read_registers(0, 0x40, 4)
    assert regs == bytes(slave.registers.read(a) for a in range(0x40, 0x44)), regs.hex()
    profile = bp3.decode_profile_id(regs[2], regs[3])
    decoded = bp3.decode_eds(eds.to_bytes(), profile=profile)
    config = bp3.derive_config(decoded)
    assert (decoded.cpoly, decoded.cstart) == (eds.cpoly, eds.cstart)
    code, custom = crc_config(CUSTOM_CRC)
    assert config == {"cfg_w0_data_bits": CUSTOM_CRC_DL_POS, "cfg_w0_nenw": 1, "cfg_w0_lc": 0,
                      "cfg_w0_gray": 0, "cfg_w0_signed": 0, "cfg_w0_crc": code,
                      **{f"cfg_w0_crc_{k}": v for k, v in custom.items()},
                      "cfg_w1_enable": 0, "cfg_spw_check": 0}, config
    # Word 0 set to CRC-6 (what the core would check without the derived settings), then
    # the derived settings alone.
    tb.dut.cfg_w0_crc.value = CRC_CODE["crc6"]
    for k in custom:
        getattr(tb.dut, f"cfg_w0_crc_{k}").value = 0
    for port, value in config.items():
        getattr(tb.dut, port).value = value
    for checked in await ctl.read_positions(8):
        assert checked.status == "OK" and checked.result.valid
        assert frames.parse_frame(fmt, checked.sent.bits)["crc_ok"], "the model's CRC"
    finish(tb, ctl)


# -- Write, read back, a whole bank --------------------------------------------------------------

@cocotb.test()
@long_on_icarus
async def write_read_back_and_bank_read(dut):
    """A user register written and read back; four written in one sequential access and read
    back in one; the bank select written, then the 64-byte BP3 EDS bank read in one access
    (914 cycles from S to the last P, 927 in all after the write) and compared with the model.
    BP3 DL_POS 24 at 10 MHz over 100 m, adaptive timeout. Icarus reads the first 16 bytes of
    the bank (its 64-byte read is the one in ``bp3_identify_and_configure``)."""
    eds = Bp3Eds(24)
    regs = bp3_registers(eds)
    slave = ControlSlave(regs)
    tb = await bench(dut, seed=134, cable_m=100, timeout_s=adaptive_timeout(10e6), slave=slave)
    tb.configure(frames.bp3(24), 10e6)
    ctl = ControlChannel(tb)
    await ctl.write_register(0, 0x50, b"\xA5")
    assert regs.read(0x50) == 0xA5
    assert await ctl.read_registers(0, 0x50, 1) == b"\xA5"
    block = bytes([0x00, 0xFF, 0x5A, 0x81])
    await ctl.write_register(0, 0x60, block)
    assert bytes(regs.read(a) for a in range(0x60, 0x64)) == block
    assert await ctl.read_registers(0, 0x5F, 6) == bytes([0]) + block + bytes([0])
    await ctl.write_register(0, 0x40, b"\x02")
    assert regs.bank_select == 2
    count = 16 if on_icarus() else 64
    bank = await ctl.read_registers(0, 0x00, count)
    assert bank == eds.to_bytes()[:count], bank.hex()
    acc = ctl.log[-1]
    tb.dut._log.info("%d-byte read: %d frames, %.2f ms", count, acc.frames,
                     (acc.t_done_s - acc.t_start_s) * 1e3)
    if count == 64:         # the bank decodes (the host software on what the hardware read)
        assert bp3.decode_eds(bank).dl == eds.data_length
    finish(tb, ctl)


# -- Every fault status --------------------------------------------------------------------------

async def good_read(ctl, regs, address=0x42, count=2):
    data = await ctl.read_registers(0, address, count)
    assert data == bytes(regs.read(a) for a in range(address, address + count)), data.hex()


async def during(ctl, frames_in, action, access):
    """Start ``access`` (a coroutine), run ``action()`` once ``frames_in`` cycles of it have
    been reported, return the access's result."""
    before = ctl.monitor.count
    task = cocotb.start_soon(access)
    await ctl.monitor.wait_frames(before + frames_in)
    await action()
    return await task


@cocotb.test()
@long_on_icarus
async def every_fault_status(dut):
    """Every ca_status other than OK, each followed by a good access (recovery), the
    count_ca_* counters against the statuses seen, every frame checked. BP3 DL_POS 24 at 10 MHz
    over 100 m, adaptive timeout.

    NO_ANSWER: a unidirectional encoder (ControlFaults(unidirectional)) and the encoder gone
    silent from the first IDL bit. REFUSED: writes to read-only registers (profile ID, a bank
    byte), a sequential write running into the device ID (the first byte stored), another
    slave ID, the encoder silent from the R echo and from the second register's start bit.
    CRC4_ERROR: the model's corrupted CRC-4 on the first and on the second register (the first
    byte kept), and the encoder silent from the first data bit. DATA_FAULT: a data-channel CRC
    error in the header and in the data part, and an Ack that never ends (NO_START); a cycle
    the encoder does not answer at all (NO_ACK) is in ``idle_count_skips_missed_cycles``.
    ABORTED: ca_abort in the header, in the data part, and before S.
    BAD_REQUEST: count 0, count 65, a last address past 0x7F (done the clock after ca_start,
    no cycle). Each ends within the documented bound of cycles. Icarus runs one case of each
    status (the unidirectional encoder, the read-only write and the sequential write, silent
    from the second start bit, the second register's CRC-4, the header CRC error, the header
    abort and the one before S, every BAD_REQUEST)."""
    eds = Bp3Eds(24)
    regs = bp3_registers(eds)
    slave = ControlSlave(regs)
    tb = await bench(dut, seed=135, cable_m=100, timeout_s=adaptive_timeout(10e6), slave=slave)
    tb.configure(frames.bp3(24), 10e6)
    ctl = ControlChannel(tb)
    full = not on_icarus()
    both = lambda cases: [c[:-1] for c in cases if full or c[-1]]   # the last field: Icarus too
    await good_read(ctl, regs)

    # NO_ANSWER
    for faults, in both([(ControlFaults(unidirectional=True), True),
                         (ControlFaults(silent_from=1), False)]):
        slave.faults = faults
        assert_status(await ctl.access(0, 0x42, 2), "NO_ANSWER", 0)
        slave.faults = ControlFaults()
        await good_read(ctl, regs)

    # REFUSED: writes to read-only registers (the last one: the second register of a
    # sequential write, the first one stored), another slave ID, the encoder silent from the
    # R echo (s0 + 17) or from the second register's start bit (s0 + 33; one byte done).
    for address, data, stored in both([(0x42, b"\x00", 0, True), (0x10, b"\x33", 0, False),
                                       (0x77, b"\x11\x22", 1, True)]):
        before = [regs.read(a) for a in range(address, address + len(data))]
        acc = await ctl.access(0, address, len(data), write=True, data=data)
        assert_status(acc, "REFUSED", stored)
        after = [regs.read(a) for a in range(address, address + len(data))]
        assert after == list(data[:stored]) + before[stored:], (after, before)
        await good_read(ctl, regs)
    for slave_id, faults, done in both([(3, ControlFaults(), 0, False),
                                        (0, ControlFaults(silent_from=17), 0, False),
                                        (0, ControlFaults(silent_from=33), 1, True)]):
        slave.faults = faults
        acc = await ctl.access(slave_id, 0x42, 2)
        assert_status(acc, "REFUSED", done)
        assert acc.data == bytes(regs.read(a) for a in range(0x42, 0x42 + done))
        slave.faults = ControlFaults()
        await good_read(ctl, regs)

    # CRC4_ERROR: the model's corrupted CRC-4 (all registers; the second only: the first byte
    # kept), the encoder silent from the first data bit (zeros fail the CRC-4).
    for faults, done in both([(ControlFaults(crc_xor=0b0101), 0, False),
                              (ControlFaults(crc_xor=0b1000, crc_xor_registers=(1,)), 1, True),
                              (ControlFaults(silent_from=20), 0, False)]):
        slave.faults = faults
        acc = await ctl.access(0, 0x42, 2)
        assert_status(acc, "CRC4_ERROR", done)
        assert acc.data == bytes(regs.read(a) for a in range(0x42, 0x42 + done))
        slave.faults = ControlFaults()
        await good_read(ctl, regs)

    # DATA_FAULT: a cycle of the control frame fails on the data channel (queued after the
    # access's ``frames_in``-th cycle: it hits the next one).
    for frames_in, fault in both([(8, {"faults": frames.FrameFaults(crc_xor=(0x21,))}, True),
                                  (30, {"faults": frames.FrameFaults(flip_bits=(5,))}, False),
                                  (12, {"fault": "ack_forever"}, False)]):
        acc = await during(ctl, frames_in, _queue(tb, **fault), ctl.access(0, 0x42, 2))
        assert_status(acc, "DATA_FAULT")
        await good_read(ctl, regs)

    # ABORTED: in the header (the slave sees 14 zeros in the middle of its control frame: its
    # abort) and in the data part of a read (its slots and P are zeros anyway: to the slave the
    # read just ends) ...
    for frames_in, slave_aborts in both([(8, 1, True), (20, 0, False)]):
        aborts = slave.aborts
        acc = await during(ctl, frames_in, ctl.abort, ctl.access(0, 0x42, 2))
        assert_status(acc, "ABORTED", 0)
        await tb.encoder_ready()        # the encoder reads the last CDM when its timeout ends
        assert slave.aborts == aborts + slave_aborts, (frames_in, slave.aborts - aborts)
        await good_read(ctl, regs)
    # ... and before S: after a write 12 idle cycles come first; the abort ends it at once.
    await ctl.write_register(0, 0x50, b"\x77")
    acc = await during(ctl, 2, ctl.abort, ctl.access(0, 0x42, 2))
    assert_status(acc, "ABORTED", 0)
    assert not any(acc.cdm) and acc.frames <= 3, acc
    await good_read(ctl, regs)

    # BAD_REQUEST: nothing sent, done the clock after ca_start.
    for address, count in ((0x42, 0), (0x00, 65), (0x7F, 2), (0x41, 64)):
        cycles = len(tb.encoder.records)
        acc = await ctl.access(0, address, count)
        assert_status(acc, "BAD_REQUEST", 0)
        assert acc.frames == 0 and len(tb.encoder.records) == cycles, acc
        assert round((acc.t_done_s - acc.t_start_s) * CLK_HZ) <= 2, acc
    await good_read(ctl, regs, 0x7E, 2)                 # the last legal address, 0x7F
    finish(tb, ctl)
    names = [a.name for a in ctl.log]
    for name in CA_STATUS:
        assert name in names, f"status {name} never seen"
    tb.dut._log.info("statuses seen: %s", {n: names.count(n) for n in CA_STATUS})


def _queue(tb, **kwargs):
    async def action():
        tb.queue(**kwargs)
    return action


@cocotb.test()
@long_on_icarus
async def idle_count_skips_missed_cycles(dut):
    """The 14 idle frames before S must be frames the encoder saw (docs/protocol.md, section 10: the slave
    counts them). After a write (its P and final cycle are 2 of them), 12 request cycles that
    the encoder does not answer (no Ack: unplugged, or its MA broken) and, separately, 12
    requests refused as BAD_CONFIG (no cycle on the line at all), and a read cancelled with
    DATA_FAULT by a cycle without an answer in its header, are each followed by a read. The
    engine once counted every reported cycle that carried CDM = 0, sent S in the read's first
    cycle, and the encoder (2 idle frames seen, 13 after the DATA_FAULT) ignored it: NO_ANSWER.
    Now S waits for 14 cycles that delivered a good frame (idle_count.py, ``idle_seen``):
    every read is OK. BP3 DL_POS 24 at
    10 MHz, 0 m."""
    regs = bp3_registers(Bp3Eds(24))
    slave = ControlSlave(regs)
    tb = await bench(dut, seed=138, timeout_s=adaptive_timeout(10e6), slave=slave)
    tb.configure(frames.bp3(24), 10e6)
    ctl = ControlChannel(tb)
    await good_read(ctl, regs)
    problems = []
    # 12 cycles without an answer (NO_ACK; the encoder model does not see them).
    await ctl.write_register(0, 0x50, b"\x01")
    for _ in range(12):
        tb.queue(fault="no_response")
    await ctl.read_positions(12)
    acc = await ctl.access(0, 0x42, 2)
    if acc.status != CA_STATUS["OK"]:
        problems.append(f"after 12 NO_ACK cycles: {acc}")
    await good_read(ctl, regs)
    # 12 requests refused for a bad configuration: nothing on the line.
    await ctl.write_register(0, 0x50, b"\x02")
    ctl.monitor.stop()
    dut.cfg_w0_data_bits.value = 0
    for _ in range(12):
        res = await tb.request(limit_s=1e-6)
        assert res.status == STATUS["BAD_CONFIG"], res.status
    dut.cfg_w0_data_bits.value = 24
    acc = await ctl.access(0, 0x42, 2)
    if acc.status != CA_STATUS["OK"]:
        problems.append(f"after 12 BAD_CONFIG requests: {acc}")
    await good_read(ctl, regs)
    # A DATA_FAULT from a cycle without an answer in the header (f12, CDM = 0): the cancel
    # counts that cycle among its 14 zeros.
    acc = await during(ctl, 12, _queue(tb, fault="no_response"), ctl.access(0, 0x42, 2))
    assert_status(acc, "DATA_FAULT")
    acc = await ctl.access(0, 0x42, 2)
    if acc.status != CA_STATUS["OK"]:
        problems.append(f"after a DATA_FAULT from a NO_ACK cycle: {acc}")
    await good_read(ctl, regs)
    assert not problems, "; ".join(problems)


@cocotb.test()
@long_on_icarus
async def resolute_gives_no_answer(dut):
    """A RESOLUTE (BiSS Safety, FS RSH: unidirectional, CDS always 0, static 12.5 us timeout and
    the 31.25 us rule; no control slave at all): a single-register read and a 64-byte read
    both end NO_ANSWER well within the documented bound (65 and 1,955 cycles), and within
    that many cycles of time, at 10 MHz over 100 m; positions keep coming, every one checked."""
    tb = Testbench(dut, seed=136)
    await tb.start(cable=Cable(length_m=100))
    tb.configure(preset("resolute_fs_rsh"), 10e6)
    ctl = ControlChannel(tb)
    for count in (1, 64):
        acc = await ctl.access(0, 0x42, count) if count == 1 else await ctl.access(0, 0, 64)
        assert_status(acc, "NO_ANSWER", 0)
        cycle_s = ctl.cycle_time_bound_s()
        assert acc.frames <= ca_frame_bound(count, write=False)
        assert acc.t_done_s - acc.t_start_s <= ca_frame_bound(count, write=False) * cycle_s
        tb.dut._log.info("RESOLUTE, %d register(s): NO_ANSWER after %d cycles (bound %d), "
                         "%.0f us", count, acc.frames, ca_frame_bound(count, write=False),
                         (acc.t_done_s - acc.t_start_s) * 1e6)
        await ctl.read_positions(2)
    finish(tb, ctl)


# -- With the data channel running periodically --------------------------------------------------

@cocotb.test()
@long_on_icarus
async def access_while_periodic(dut):
    """Register accesses while ``periodic`` reads positions: with a 40 us request period the
    cycles keep their exact start-to-start period through the accesses (a CDM hold included),
    no overrun, every position checked; then the same with a period of 0 (as fast as the
    encoder allows; Verilator only). BP3 DL_POS 36 at 5 MHz over 100 m, static 12.5 us
    timeout."""
    eds = Bp3Eds(36)
    regs = bp3_registers(eds)
    slave = ControlSlave(regs)
    tb = await bench(dut, seed=137, cable_m=100, slave=slave)
    tb.configure(frames.bp3(36), 5e6)
    ctl = ControlChannel(tb)
    ctl.monitor.start()
    for period_clocks in (4000,) if on_icarus() else (4000, 0):
        await tb.wait_idle()
        dut.cfg_request_period.value = period_clocks
        await FallingEdge(dut.clk)
        dut.periodic.value = 1
        first = len(tb.encoder.records)
        await ctl.monitor.wait_frames(ctl.monitor.count + 5)
        await good_read(ctl, regs, 0x40, 4)
        await ctl.write_register(0, 0x55, bytes([period_clocks & 0xFF ^ 0x3C]))
        await good_read(ctl, regs, 0x55, 1)
        await ctl.monitor.wait_frames(ctl.monitor.count + 5)
        await FallingEdge(dut.clk)
        dut.periodic.value = 0
        records = tb.encoder.records[first + 1:-1]
        assert any(r.cdm for r in records)
        if period_clocks:
            starts = [r.t_first_fall_s for r in records]
            gaps = {round((b - a) * 1e9) for a, b in zip(starts, starts[1:])}
            assert gaps == {round(period_clocks / CLK_HZ * 1e9)}, gaps
        tb.dut._log.info("period %d clocks: %d cycles, %d of them CDM = 1", period_clocks,
                         len(records), sum(r.cdm for r in records))
    await tb.wait_idle()
    assert tb.read().counters["overrun"] == 0
    finish(tb, ctl)
