"""The BP3 demo scenario (make demo-bp3): a BP3 encoder model on the default build at 10 MHz
over 50 m; bissmaster.bp3.identify() through the register-access ports; the decoded EDS, the
derived settings and a few positions, each checked against the model, written as text to
$BISS_DEMO_TABLE for sim/tools/demo.py to print.

The encoder: a multiturn rotary BP3 encoder, 12 multiturn + 20 singleturn bits (DL_POS 32),
CRC-6, the shaft turning at 3,000 rpm. Before it is identified the data channel reads the
longest frame without checks (the host does not know its length yet); afterwards only the
derived settings configure it.
"""

import os

import cocotb

from bissmaster import bp3
from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from encoder_model.control import Bp3Eds, ControlSlave, RegisterFile
from master_contract import CA_STATUS_NAME, CRC_CODE, MAX_DATA_BITS, STATUS_NAME
from sim.shared.control_channel import ControlChannel
from sim.shared.testbench import Testbench

MT_BITS, ST_BITS = 12, 20
RPM = 3000
MA_HZ, CABLE_M = 10e6, 50
POSITIONS = 8

#: What each EDS field means (BP3 profile table, docs/protocol.md section 7).
MEANING = {
    "bp_ver": "profile version", "bp_len": "profile length, banks", "bp_id": "profile ID (= 0x42)",
    "dl": "data length (= 0x43)", "fb1": "feedback bit 1", "fb2": "feedback bit 2",
    "pon_pdl": "power-on delay, ms", "en_typ": "encoder type", "pos_num": "position values",
    "mt_len": "multiturn bits", "mt_fmt": "multiturn alignment", "co_len": "coarse bits",
    "co_fmt": "coarse format", "fi_len": "fine bits", "fi_fmt": "fine format",
    "mt_cnt": "revolutions", "sip_cnt": "signal periods / rev", "sip_res": "resolution / period",
    "cpoly": "CRC polynomial (no x^0)", "cstart": "CRC start value",
    "abs_acu": "absolute accuracy", "rel_acu": "repeat accuracy", "spd_acu": "speed accuracy",
    "hyst": "hysteresis", "spd_max": "max speed, 1/min", "acc_max": "max acceleration",
    "tmp_min": "min temperature, K", "tmp_max": "max temperature, K",
    "vlt_min": "min voltage, mV", "vlt_max": "max voltage, mV", "cur_max": "max current, mA",
    "chksum": "checksum (verified)",
}


def eds_table(ident):
    eds = ident.eds
    rows = []
    for symbol, address, code in bp3.EDS_LAYOUT:
        value = getattr(eds, symbol.lower())
        shown = (f"{value.name} ({int(value)})" if hasattr(value, "name")
                 else f"0x{value:0{2 * {'B': 1, 'H': 2, 'I': 4}[code]}X}" if symbol in
                 ("BP_ID", "CPOLY", "CSTART", "CHKSUM") else f"{value}")
        rows.append(f"  0x{address:02X}  {symbol:<8} {shown:<14} {MEANING[symbol.lower()]}")
    return "\n".join(rows)


@cocotb.test()
async def demo_bp3(dut):
    counts_per_rev = 1 << ST_BITS
    eds = Bp3Eds(MT_BITS + ST_BITS, mt_len=MT_BITS)
    regs = RegisterFile(eds_bank=1, profile_id=eds.profile_id, data_length=eds.data_length,
                        serial_number=b"\x00\x01\xE2\x40", device_id=b"BP3DEM",
                        manufacturer_id=b"iC",
                        banks={1: bytes(64), 2: eds.to_bytes()})   # common part, BP3 bank
    slave = ControlSlave(regs)
    tb = Testbench(dut, seed=2027)
    tb.processing_s = (1e-6, 3e-6)
    start_pos = 5 * counts_per_rev + counts_per_rev // 3                # 5 turns + 120 degrees
    tb._position_at = lambda t: int(start_pos + RPM / 60 * counts_per_rev * t)
    await tb.start(cable=Cable(length_m=CABLE_M), timeout_s=1.5 / MA_HZ, control=slave,
                   min_cycle_s=0)
    # Not identified yet: read the longest frame the build reads, without checks.
    view = frames.FrameFormat("longest_unchecked", (
        frames.WordFormat(MAX_DATA_BITS[0], crc=frames.CRC_NONE),
        frames.WordFormat(MAX_DATA_BITS[1], crc=frames.CRC_NONE)))
    tb.configure(frames.bp3(MT_BITS + ST_BITS), MA_HZ, cfg_w0_data_bits=MAX_DATA_BITS[0],
                 cfg_w0_crc=CRC_CODE["none"], cfg_w1_enable=1,
                 cfg_w1_data_bits=MAX_DATA_BITS[1], cfg_w1_nenw=1, cfg_w1_lc=0,
                 cfg_w1_crc=CRC_CODE["none"], cfg_spw_check=0)
    ctl = ControlChannel(tb, view=view)
    await ctl.read_positions(14)            # the line idle: 14 frames with CDM = 0
    t0 = tb.encoder.records[-1].t_first_fall_s
    ident = await ctl.run_host(bp3.identify)
    t1 = ctl.log[-1].t_done_s
    assert ident.eds.raw == eds.to_bytes()
    frames_during = sum(a.frames for a in ctl.log)
    for port, value in ident.config.items():
        getattr(dut, port).value = value
    ctl.monitor.view = None
    checked = await ctl.read_positions(POSITIONS)

    p = ident.profile
    lines = [
        f"Registers 0x42/0x43: 0x{p.to_bytes()[0]:02X} 0x{p.to_bytes()[1]:02X} -> BP3 "
        f"version {p.version}, C = {int(p.crc_mode)} ({p.crc_mode.name}), DL = {p.data_length} "
        f"({p.position_bits} position bits + nE, nW)",
        f"EDS pointer (0x41) = 0x{ident.eds_bank:02X}; BP3 bank read: 0x{ident.profile_bank:02X} "
        f"(the common part assumed one bank); bank select restored",
        "",
        "  byte  field    value          meaning",
        eds_table(ident),
        "",
        "Register accesses (ca_* ports):",
        *(f"  {'write' if a.write else 'read':<5} "
          + f"0x{a.address:02X}{f'..0x{a.address + a.count - 1:02X}' if a.count > 1 else '':<6}"
          + f" {a.frames:>4} frames  {CA_STATUS_NAME[a.status]}" for a in ctl.log),
        f"Identification: {frames_during} data frames, {(t1 - t0) * 1e3:.1f} ms at "
        f"{MA_HZ / 1e6:g} MHz over {CABLE_M} m; every frame's position checked on the way.",
        "",
        "Derived settings (bp3.derive_config), written to the core:",
        "  " + ", ".join(f"{k} = {v}" for k, v in ident.config.items()),
        "",
        "  #  position (32 bits)  turn  angle/deg  nE nW  CRC-6  status  model sent",
    ]
    fmt = frames.bp3(MT_BITS + ST_BITS)
    for i, c in enumerate(checked, 1):
        f = c.result.fields
        pos = f["word0_position"]
        sent = frames.parse_frame(fmt, c.sent.bits)["words"][0]["position"]
        lines.append(f"{i:>3}  {pos:>18}  {pos >> ST_BITS:>4}  "
                     f"{(pos % counts_per_rev) * 360 / counts_per_rev:>9.3f}  "
                     f"{f['word0_ne']:>2} {f['word0_nw']:>2}  "
                     f"{'ok' if f['word0_crc_ok'] else 'BAD':>5}  {STATUS_NAME[c.result.status]:<6}  "
                     f"{sent:>10}")
    with open(os.environ["BISS_DEMO_TABLE"], "w") as out:
        out.write("\n".join(lines) + "\n")

