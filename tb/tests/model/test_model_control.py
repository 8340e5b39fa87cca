"""The encoder model's BiSS C control side (encoder_model.control, .control_master).

CRC-4 against a published table and the table-driven algorithms of the same source, the
amaranth library's CRC model and a polynomial long division; whole register accesses frame by
frame against tables written out by hand from docs/protocol.md section 10; the
idle and abort rules; slave ID; every fault; the BP3 EDS bank.
"""

import ast
import random
from pathlib import Path

import pytest
from amaranth.lib import crc as am_crc

from encoder_model import control as control_module
from encoder_model import control_master as master_module
from encoder_model.control import (BANK_SELECT, IDLE_FRAMES, Bp3Eds, ControlFaults,
                                   ControlSlave, RegisterFile, byte_bits, crc4, crc4_data,
                                   crc4_header, eds_checksum)
from encoder_model.control_master import (ControlMaster, ControlStatus, RegisterAccess,
                                          control_frame_cdm, decode_cds, exchange)

# -- CRC-4 ------------------------------------------------------------------------------------

# Published CRC-4 table for x^4 + x + 1, start 0, not inverted: entry i is the register after
# feeding the 4-bit value i. From the Lenz Encoders BiSS C master library,
# github.com/lenzencoders/BISS-C, BiSS_C_Master/lib/BiSS_C_Master/biss_c_master.c
# (commit 7bbf407864f1c6dfac3d2937395aed9ce6cd34de), ``tableCRC4``; the same values are the
# ``CRC4_table`` module of DE10-Lite/Quartus/USB_BISS.v in that repository.
TABLE_CRC4 = [0x0, 0x3, 0x6, 0x5, 0xC, 0xF, 0xA, 0x9, 0xB, 0x8, 0xD, 0xE, 0x7, 0x4, 0x1, 0x2]


def lenz_crc4_cts_adr(adr):
    """``CRC4_CTS_ADR`` of the same file: the header CRC for CTS = 1, ID = 0 (first nibble
    0b0100 -> table value 0xC), sent inverted (0xF - x)."""
    return 0xF - TABLE_CRC4[(adr & 0xF) ^ TABLE_CRC4[((adr >> 4) & 0xF) ^ 0xC]]


def lenz_crc4_data(data):
    """``CRC4_DATA`` of the same file."""
    return 0xF - TABLE_CRC4[(data & 0xF) ^ TABLE_CRC4[(data >> 4) & 0xF]]


def lenz_verilog_crc4_calc(data11):
    """``CRC4_calc`` of USB_BISS.v: 11 bits (CTS, ID, ADR) as {0, d[10:8]}, d[7:4], d[3:0]."""
    t = TABLE_CRC4[(data11 >> 8) & 0x7]
    t = TABLE_CRC4[((data11 >> 4) & 0xF) ^ t]
    t = TABLE_CRC4[(data11 & 0xF) ^ t]
    return ~t & 0xF


def long_division_crc4(bits):
    """A second implementation: (message * x^4) mod (x^4 + x + 1) with integers, inverted."""
    value = 0
    for bit in bits:
        value = (value << 1) | bit
    value <<= 4
    poly = 0b10011
    for shift in range(value.bit_length() - 5, -1, -1):
        if value >> (shift + 4) & 1:
            value ^= poly << shift
    return value ^ 0xF


def test_crc4_matches_published_table():
    for index, entry in enumerate(TABLE_CRC4):
        assert crc4(byte_bits(index, 4)) == entry ^ 0xF, index


def test_crc4_header_matches_published_algorithm():
    for adr in range(128):
        assert crc4_header(0, adr) == lenz_crc4_cts_adr(adr), adr
    for ident in range(8):
        for adr in range(128):
            assert crc4_header(ident, adr) == lenz_verilog_crc4_calc(1 << 10 | ident << 7 | adr)


def test_crc4_data_matches_published_algorithm():
    for value in range(256):
        assert crc4_data(value) == lenz_crc4_data(value), value


def test_crc4_hand_computed():
    # With the published table: header of ID 0, ADR 0x42: 0xF - T[2 ^ T[4 ^ 0xC]] = 0xF - T[9]
    # = 0x7; data 0x62: 0xF - T[2 ^ T[6]] = 0xF - T[8] = 0x4; data 0x00: 0xF.
    assert crc4_header(0, 0x42) == 0x7
    assert crc4_header(0, 0x40) == 0x1
    assert crc4_data(0x62) == 0x4
    assert crc4_data(0xA5) == 0x4
    assert crc4_data(0x00) == 0xF


def test_crc4_second_implementations():
    algo = am_crc.Algorithm(crc_width=4, polynomial=0x3, initial_crc=0, reflect_input=False,
                            reflect_output=False, xor_output=0xF)(data_width=1)
    rng = random.Random(4)
    for _ in range(500):
        bits = [rng.getrandbits(1) for _ in range(rng.randint(1, 40))]
        assert crc4(bits) == long_division_crc4(bits) == algo.compute(bits), bits


def test_crc4_rejects_non_bits():
    with pytest.raises(ValueError):
        crc4([0, 2])


# -- helpers ----------------------------------------------------------------------------------

EDS24 = Bp3Eds(24)
ID = dict(serial_number=b"\x01\x02\x03\x04", device_id=b"DEVICE", manufacturer_id=b"MF")


def bp3_slave(**kw):
    return ControlSlave(RegisterFile.bp3(EDS24, eds_bank=1, **ID), **kw)


def drive(slave, cdm_bits):
    """Step the slave with ``cdm_bits``; the CDS of every one of those frames."""
    cds = []
    for bit in cdm_bits:
        cds.append(slave.cds)
        slave.step(bit)
    return cds


def idle(n=IDLE_FRAMES):
    return [0] * n


# -- whole accesses, frame by frame, against hand-written tables ------------------------------

# Register read of 0x42 (BP3 profile ID 0x62) from slave 0, docs/protocol.md, section 10. One row per frame
# from s0 (the frame whose CDM is S): (offset, CDM sent after the frame, CDS in the frame).
READ_0X42 = [
    (0, 1, 0),      # S                      | (idle)
    (1, 1, 1),      # CTS                    | IDL0
    (2, 0, 0),      # ID2                    | IDL1
    (3, 0, 0),      # ID1                    | IDL2
    (4, 0, 0),      # ID0                    | IDL3
    (5, 1, 0),      # ADR6 (0x42 = 1000010)  | IDL4
    (6, 0, 0),      # ADR5                   | IDL5
    (7, 0, 0),      # ADR4                   | IDL6
    (8, 0, 0),      # ADR3                   | IDL7
    (9, 0, 0),      # ADR2                   | 0
    (10, 1, 0),     # ADR1                   | 0
    (11, 0, 0),     # ADR0                   | 0
    (12, 0, 0),     # CRC3 (0x7 = 0111)      | 0
    (13, 1, 0),     # CRC2                   | 0
    (14, 1, 0),     # CRC1                   | 0
    (15, 1, 0),     # CRC0                   | 0
    (16, 1, 0),     # R                      | 0
    (17, 0, 1),     # W                      | echo of R
    (18, 1, 0),     # S                      | echo of W
    (19, 0, 1),     # slot                   | slave start bit
    (20, 0, 0),     # slot                   | DATA7 (0x62 = 0110 0010)
    (21, 0, 1),     # slot                   | DATA6
    (22, 0, 1),     # slot                   | DATA5
    (23, 0, 0),     # slot                   | DATA4
    (24, 0, 0),     # slot                   | DATA3
    (25, 0, 0),     # slot                   | DATA2
    (26, 0, 1),     # slot                   | DATA1
    (27, 0, 0),     # slot                   | DATA0
    (28, 0, 0),     # slot                   | CRC3 (0x4 = 0100)
    (29, 0, 1),     # slot                   | CRC2
    (30, 0, 0),     # slot                   | CRC1
    (31, 0, 0),     # P                      | CRC0
    (32, 0, 0),     # (first idle frame)     | echo of P
]

# Register write of 0xA5 to 0x40 (bank select), slave 0.
WRITE_0X40 = [
    (0, 1, 0),      # S                      | (idle)
    (1, 1, 1),      # CTS                    | IDL0
    (2, 0, 0),      # ID2                    | IDL1
    (3, 0, 0),      # ID1                    | IDL2
    (4, 0, 0),      # ID0                    | IDL3
    (5, 1, 0),      # ADR6 (0x40 = 1000000)  | IDL4
    (6, 0, 0),      # ADR5                   | IDL5
    (7, 0, 0),      # ADR4                   | IDL6
    (8, 0, 0),      # ADR3                   | IDL7
    (9, 0, 0),      # ADR2                   | 0
    (10, 0, 0),     # ADR1                   | 0
    (11, 0, 0),     # ADR0                   | 0
    (12, 0, 0),     # CRC3 (0x1 = 0001)      | 0
    (13, 0, 0),     # CRC2                   | 0
    (14, 0, 0),     # CRC1                   | 0
    (15, 1, 0),     # CRC0                   | 0
    (16, 0, 0),     # R                      | 0
    (17, 1, 0),     # W                      | echo of R
    (18, 1, 1),     # S                      | echo of W
    (19, 1, 1),     # DATA7 (0xA5 = 1010 0101) | slave start bit
    (20, 0, 1),     # DATA6                  | echo of DATA7
    (21, 1, 0),     # DATA5                  | echo of DATA6
    (22, 0, 1),     # DATA4                  | echo of DATA5
    (23, 0, 0),     # DATA3                  | echo of DATA4
    (24, 1, 0),     # DATA2                  | echo of DATA3
    (25, 0, 1),     # DATA1                  | echo of DATA2
    (26, 1, 0),     # DATA0                  | echo of DATA1
    (27, 0, 1),     # CRC3 (0x4 = 0100)      | echo of DATA0
    (28, 1, 0),     # CRC2                   | echo of CRC3
    (29, 0, 1),     # CRC1                   | echo of CRC2
    (30, 0, 0),     # CRC0                   | echo of CRC1
    (31, 0, 0),     # P                      | echo of CRC0
    (32, 0, 0),     # (first idle frame)     | echo of P
]

# Sequential read of 0x42, 0x43: READ_0X42 up to P, then the continuation (c0 = s0 + 32).
READ_0X42_0X43 = READ_0X42[:32] + [
    (32, 1, 0),     # S: next register       | echo of P
    (33, 0, 1),     # slot                   | slave start bit
    (34, 0, 0),     # slot                   | DATA7 (0x43 = DL 0x1A = 0001 1010)
    (35, 0, 0),     # slot                   | DATA6
    (36, 0, 0),     # slot                   | DATA5
    (37, 0, 1),     # slot                   | DATA4
    (38, 0, 1),     # slot                   | DATA3
    (39, 0, 0),     # slot                   | DATA2
    (40, 0, 1),     # slot                   | DATA1
    (41, 0, 0),     # slot                   | DATA0
    (42, 0, 0),     # slot                   | CRC3 (0x7 = 0111)
    (43, 0, 1),     # slot                   | CRC2
    (44, 0, 1),     # slot                   | CRC1
    (45, 0, 1),     # P                      | CRC0
    (46, 0, 0),     # (first idle frame)     | echo of P
]


def check_table(slave, access, table, value):
    """The table's CDM is what the reference master sends, and the slave answers the table's
    CDS, frame by frame; the master's decoding of that CDS gives ``value``."""
    offsets, cdm, cds = zip(*table)
    assert list(offsets) == list(range(len(table)))
    assert control_frame_cdm(access) == list(cdm[:-1])
    master = ControlMaster()
    master.submit(access)
    frames = exchange(master, slave)
    assert [f[1] for f in frames] == idle() + list(cdm)
    assert [f[0] for f in frames] == idle() + list(cds)
    (result,) = master.results
    assert result.status is ControlStatus.OK and result.data == value
    assert (result.s_frame, result.end_frame) == (IDLE_FRAMES, IDLE_FRAMES + len(table) - 1)
    assert decode_cds(access, list(cds)).data == value


def test_register_read_frame_by_frame():
    slave = bp3_slave()
    check_table(slave, RegisterAccess.read(0x42), READ_0X42, b"\x62")
    assert [(a.write, a.address, a.value) for a in slave.accesses] == [(False, 0x42, 0x62)]


def test_register_write_frame_by_frame():
    slave = bp3_slave()
    check_table(slave, RegisterAccess.write(0x40, b"\xA5"), WRITE_0X40, b"\xA5")
    assert slave.registers.bank_select == 0xA5
    assert slave.accesses[-1].executed


def test_sequential_read_frame_by_frame():
    check_table(bp3_slave(), RegisterAccess.read(0x42, 2), READ_0X42_0X43, b"\x62\x1A")


def test_slave_alone_follows_the_table():
    # Without the master: the literal CDM in, the literal CDS out.
    slave = bp3_slave()
    cdm = [row[1] for row in READ_0X42]
    assert drive(slave, idle() + cdm)[IDLE_FRAMES:] == [row[2] for row in READ_0X42]
    assert slave.state == "idle"


@pytest.mark.parametrize("count", [1, 2, 64])
def test_sequential_reads(count):
    eds = EDS24.to_bytes()
    slave = bp3_slave()
    master = ControlMaster()
    master.submit(RegisterAccess.write(BANK_SELECT, b"\x01"))
    master.submit(RegisterAccess.read(0x00, count))
    exchange(master, slave)
    select, read = master.results
    assert select.status is ControlStatus.OK
    assert read.status is ControlStatus.OK and read.data == eds[:count]
    # 32 frames S..P for the first register, 14 for every further one; 14 idle frames after P
    assert read.end_frame - read.s_frame == 32 + 14 * (count - 1)
    assert read.s_frame - select.end_frame == IDLE_FRAMES
    if count == 64:
        assert eds_checksum(read.data) == read.data[0x3F]


def test_sequential_write():
    slave = bp3_slave()
    master = ControlMaster()
    master.submit(RegisterAccess.write(0x48, b"\x11\x22\x33"))
    master.submit(RegisterAccess.read(0x48, 3))
    exchange(master, slave)
    assert [r.status for r in master.results] == [ControlStatus.OK] * 2
    assert master.results[1].data == b"\x11\x22\x33"


def test_isolated_access_costs_46_frames():
    master = ControlMaster()
    for _ in range(3):
        master.submit(RegisterAccess.read(0x42))
    exchange(master, bp3_slave())
    starts = [r.s_frame for r in master.results]
    assert starts == [14, 14 + 46, 14 + 92]


@pytest.mark.parametrize("wrap", [True, False])
def test_address_wrap(wrap):
    regs = RegisterFile(manufacturer_id=b"MF", banks={0: bytes(range(0x80, 0xC0))})
    slave = ControlSlave(regs, wrap_address=wrap)
    result = run_one(slave, RegisterAccess.read(0x7E, 3))
    if wrap:
        assert result.status is ControlStatus.OK
        assert result.data == b"MF\x80"                 # 0x7E, 0x7F, then 0x00
    else:
        assert (result.status, result.failed_register, result.data) == (
            ControlStatus.REFUSED, 2, b"MF")


def run_one(slave, access, **master_kw):
    master = ControlMaster(**master_kw)
    master.submit(access)
    exchange(master, slave)
    return master.results[0]


# -- idle and abort ---------------------------------------------------------------------------

def test_no_control_frame_without_idle_frames():
    # 13 idle frames: the 1 is not an S, the slave stays idle and answers nothing.
    slave = bp3_slave()
    cdm = [row[1] for row in READ_0X42]
    cds = drive(slave, idle(13) + cdm)
    assert not any(cds) and slave.accesses == []


@pytest.mark.parametrize("table, strict, gap, answered", [
    (READ_0X42, False, 1, True),        # 12 slot zeros + P + 1 = 14 zeros on the line
    (WRITE_0X40, False, 10, False),     # CRC1, CRC0, P + 10 = 13
    (WRITE_0X40, False, 11, True),
    (READ_0X42, True, 13, False),       # strict: 14 frames after P (46 frames per access)
    (READ_0X42, True, 14, True),
    (WRITE_0X40, True, 13, False),
    (WRITE_0X40, True, 14, True),
])
def test_idle_frames_after_an_access(table, strict, gap, answered):
    slave = bp3_slave(strict_idle=strict)
    cdm = [row[1] for row in table[:32]]
    read = [row[1] for row in READ_0X42[:32]]
    cds = drive(slave, idle() + cdm + idle(gap) + read + idle(1))
    second = cds[IDLE_FRAMES + 32 + gap:]
    assert (second == [row[2] for row in READ_0X42]) == answered
    assert any(second) == answered


@pytest.mark.parametrize("strict", [False, True])
@pytest.mark.parametrize("cut", [1, 2, 6, 11, 16, 17])
def test_abort_by_14_zeros_and_recovery(cut, strict):
    # A control frame cut after ``cut`` CDM bits (the last one a 1), then zeros: the 14th
    # cancels it; those 14 zeros are the idle frames of the next access, which then works.
    slave = bp3_slave(strict_idle=strict)
    header = control_frame_cdm(RegisterAccess.read(0x42))[:cut]
    assert header[-1] == 1
    drive(slave, idle() + header + idle(13))
    assert slave.in_control_frame and slave.aborts == 0
    drive(slave, [0])
    assert not slave.in_control_frame and slave.aborts == 1
    cds = drive(slave, [row[1] for row in READ_0X42])
    assert cds == [row[2] for row in READ_0X42]


def test_abort_while_waiting_for_a_late_start_bit():
    slave = bp3_slave(start_delay=20)
    cdm = control_frame_cdm(RegisterAccess.read(0x42))[:19]     # up to the second S
    drive(slave, idle() + cdm + idle(14))
    assert slave.aborts == 1 and slave.state == "idle"
    assert run_one(slave, RegisterAccess.read(0x42), initial_idle=14,
                   max_start_wait=20).data == b"\x62"


def test_legal_control_frames_never_have_14_zeros():
    # Spec: inside a legal control frame the longest run of CDM = 0 is 13.
    def longest_zero_run(bits):
        run = best = 0
        for bit in bits:
            run = run + 1 if bit == 0 else 0
            best = max(best, run)
        return best

    worst = 0
    for ident in range(8):
        for adr in range(128):
            worst = max(worst, longest_zero_run(control_frame_cdm(
                RegisterAccess.read(adr, 2, slave_id=ident))))
            worst = max(worst, longest_zero_run(control_frame_cdm(
                RegisterAccess.write(adr, b"\x00\x00", slave_id=ident))))
    for value in range(256):
        worst = max(worst, longest_zero_run(control_frame_cdm(
            RegisterAccess.write(0x48, bytes([value, value])))))
    assert worst == 13


# -- slave ID -----------------------------------------------------------------------------------

def test_wrong_slave_id_is_not_answered():
    slave = bp3_slave()
    access = RegisterAccess.read(0x42, slave_id=3)
    cds = drive(slave, idle() + control_frame_cdm(access) + [0])[IDLE_FRAMES:]
    assert cds == [0, 1] + [0] * 31           # the IDL bits (slave 0), then nothing
    result = decode_cds(access, cds)
    assert (result.status, result.reason) == (ControlStatus.REFUSED, "R/W echo 00")
    assert slave.accesses == []


@pytest.mark.parametrize("ident", [3, 7])
def test_slave_with_another_id(ident):
    slave = ControlSlave(RegisterFile.bp3(EDS24, **ID), slave_id=ident)
    access = RegisterAccess.read(0x42, slave_id=ident)
    cds = drive(slave, idle() + control_frame_cdm(access) + [0])[IDLE_FRAMES:]
    assert cds[1:9] == [int(i == ident) for i in range(8)]  # one-hot IDL at its own position
    assert decode_cds(access, cds).data == b"\x62"
    assert run_one(ControlSlave(RegisterFile(), slave_id=ident),
                   RegisterAccess.read(0x42)).status is ControlStatus.REFUSED


def test_bad_header_crc_is_not_answered():
    slave = bp3_slave()
    cdm = control_frame_cdm(RegisterAccess.read(0x42))
    cdm[15] ^= 1                                  # CRC0
    cds = drive(slave, idle() + cdm + [0])[IDLE_FRAMES:]
    assert cds == [0, 1] + [0] * 31 and slave.accesses == []


def test_command_frames_are_not_answered():
    slave = bp3_slave()
    cdm = control_frame_cdm(RegisterAccess.read(0x42))
    cdm[1] = 0                                    # CTS = 0: a command (not modelled)
    cds = drive(slave, idle() + cdm + [0])[IDLE_FRAMES:]
    assert cds == [0, 1] + [0] * 31


# -- faults -----------------------------------------------------------------------------------

def test_fault_crc_of_the_answer():
    slave = bp3_slave(faults=ControlFaults(crc_xor=0x8))
    result = run_one(slave, RegisterAccess.read(0x42))
    assert (result.status, result.reason, result.data) == (
        ControlStatus.CRC_ERROR, "read CRC-4", b"")
    cds = drive(bp3_slave(faults=ControlFaults(crc_xor=0x8)),
                idle() + [row[1] for row in READ_0X42])[IDLE_FRAMES:]
    want = [row[2] for row in READ_0X42]
    want[28] ^= 1                                 # CRC3 of the answer
    assert cds == want


def test_fault_crc_of_one_register_of_a_sequential_read():
    slave = bp3_slave(faults=ControlFaults(crc_xor=0x1, crc_xor_registers=(1,)))
    result = run_one(slave, RegisterAccess.read(0x42, 3))
    assert (result.status, result.failed_register, result.data) == (
        ControlStatus.CRC_ERROR, 1, b"\x62")


def test_fault_crc_of_a_write_echo():
    slave = bp3_slave(faults=ControlFaults(crc_xor=0x2))
    result = run_one(slave, RegisterAccess.write(0x48, b"\x5C"))
    assert (result.status, result.reason) == (ControlStatus.CRC_ERROR, "write echo")
    assert slave.registers.read(0x48) == 0x5C     # the slave got it right; its answer is bad


def test_fault_unidirectional():
    slave = bp3_slave(faults=ControlFaults(unidirectional=True))
    for access in (RegisterAccess.read(0x42), RegisterAccess.write(0x40, b"\x01")):
        cdm = idle() + control_frame_cdm(access) + [0]
        assert not any(drive(slave, cdm))
        assert run_one(slave, access).status is ControlStatus.NO_ANSWER
    assert slave.accesses == [] and slave.registers.bank_select == 0


@pytest.mark.parametrize("mode, echo_w, reason", [
    ("no_start", 1, "no start bit"), ("no_echo", 0, "R/W echo 00")])
def test_refused_write_to_a_read_only_register(mode, echo_w, reason):
    slave = bp3_slave(refused_write=mode)
    access = RegisterAccess.write(0x42, b"\x00")
    cds = drive(slave, idle() + control_frame_cdm(access) + [0])[IDLE_FRAMES:]
    assert cds[1:9] == [1, 0, 0, 0, 0, 0, 0, 0]
    assert cds[17:20] == [0, echo_w, 0]           # echo of R, echo of W, no start bit
    assert not any(cds[19:])
    assert slave.registers.read(0x42) == 0x62
    assert [(a.write, a.address, a.executed, a.reason) for a in slave.accesses] == [
        (True, 0x42, False, "read-only")]
    result = run_one(bp3_slave(refused_write=mode), access)
    assert (result.status, result.reason) == (ControlStatus.REFUSED, reason)


def test_refused_write_inside_a_sequential_write():
    slave = bp3_slave()
    result = run_one(slave, RegisterAccess.write(0x77, b"\x01\x02"))   # 0x78: device ID
    assert (result.status, result.failed_register, result.data) == (
        ControlStatus.REFUSED, 1, b"\x01")
    assert slave.registers.read(0x77) == 0x01 and slave.registers.read(0x78) == ord("D")


def test_fault_write_protected():
    slave = bp3_slave(faults=ControlFaults(write_protected=True))
    assert run_one(slave, RegisterAccess.write(0x40, b"\x01")).status is ControlStatus.REFUSED
    assert slave.registers.bank_select == 0


@pytest.mark.parametrize("silent_from, status, reason", [
    (2, ControlStatus.REFUSED, "R/W echo 00"),
    (19, ControlStatus.REFUSED, "no start bit"),
    (24, ControlStatus.CRC_ERROR, "read CRC-4"),
    (33, ControlStatus.REFUSED, "no start bit"),      # the second register's start bit
])
def test_fault_stops_answering_mid_frame(silent_from, status, reason):
    slave = bp3_slave(faults=ControlFaults(silent_from=silent_from))
    result = run_one(slave, RegisterAccess.read(0x42, 2))
    assert (result.status, result.reason) == (status, reason)
    slave.faults = ControlFaults()
    master = ControlMaster(initial_idle=0)          # recovery: the next access works
    master.submit(RegisterAccess.read(0x42, 2))
    exchange(master, slave)
    assert master.results[0].data == b"\x62\x1A"


def test_late_start_bit():
    # The slave takes 2 more frames; the master keeps CDM = 1 until it sees the start bit.
    slave = bp3_slave(start_delay=2)
    master = ControlMaster(max_start_wait=2)
    master.submit(RegisterAccess.read(0x42))
    frames = exchange(master, slave)[IDLE_FRAMES:]
    cdm, cds = [f[1] for f in frames], [f[0] for f in frames]
    assert cdm[18:22] == [1, 1, 1, 0]             # S, kept while waiting, first slot
    assert cds[19:22] == [0, 0, 1]                # the start bit two frames late
    assert cds[22:30] == byte_bits(0x62)
    assert master.results[0].end_frame - master.results[0].s_frame == 32 + 2
    assert run_one(bp3_slave(start_delay=2), RegisterAccess.read(0x42),
                   max_start_wait=1).reason == "no start bit"


# -- register file and EDS --------------------------------------------------------------------

def test_register_file_map():
    regs = RegisterFile.bp3(EDS24, eds_bank=2, **ID)
    assert [regs.read(a) for a in range(0x40, 0x48)] == [0, 2, 0x62, 0x1A, 1, 2, 3, 4]
    assert bytes(regs.read(a) for a in range(0x78, 0x80)) == b"DEVICEMF"
    assert regs.read(0x00) == 0                   # bank 0: never set
    assert regs.write(BANK_SELECT, 2)
    assert bytes(regs.read(a) for a in range(64)) == EDS24.to_bytes()
    read_only = [0x00, 0x3F, 0x41, 0x42, 0x43, 0x44, 0x47, 0x78, 0x7D, 0x7E, 0x7F]
    assert not any(regs.writable(a) for a in read_only)
    assert not regs.write(0x41, 5) and regs.read(0x41) == 2
    assert all(regs.writable(a) for a in [0x40, 0x48, 0x77])
    user = RegisterFile(writable_banks=(3,), bank_select=3)
    assert user.write(0x10, 0x99) and user.read(0x10) == 0x99
    assert user.write(BANK_SELECT, 4) and not user.write(0x10, 1) and user.read(0x10) == 0


def test_eds_bank_bytes():
    bank = Bp3Eds(24, mt_len=12, spd_max=0x1234, sip_cnt=0x01020304, cstart=0).to_bytes()
    assert len(bank) == 64
    assert bank[0x00:0x04] == bytes([1, 1, 0x62, 26])         # BP_VER, BP_LEN, BP_ID, DL
    assert bank[0x04:0x06] == bytes([1, 2])                   # FB1 nE, FB2 nW
    assert bank[0x0A] == 12 and bank[0x0C] == 12              # MT_LEN, CO_LEN
    assert bank[0x10:0x14] == bytes([0, 0, 0x10, 0])          # MT_CNT 4096, big endian
    assert bank[0x14:0x18] == bytes([1, 2, 3, 4])             # SIP_CNT, big endian
    assert bank[0x1C:0x20] == bytes([0, 0, 0, 0x21])          # CPOLY 0x43 without x^0
    assert bank[0x2C:0x2E] == bytes([0x12, 0x34])             # SPD_MAX, big endian
    assert bank[0x3F] == sum(bank[:0x3F]) % 256


def test_eds_checksum():
    assert eds_checksum(bytes(range(64))) == 0xA1             # 0 + 1 + ... + 62 = 1953
    assert eds_checksum(bytes([0xFF] * 64)) == (63 * 0xFF) % 256
    with pytest.raises(ValueError):
        eds_checksum(bytes(63))


@pytest.mark.parametrize("dl_pos, c, profile_id", [(1, 0, 0x62), (55, 0, 0x62), (61, 1, 0x63)])
def test_eds_profile_and_length(dl_pos, c, profile_id):
    eds = Bp3Eds(dl_pos, c=c)
    assert (eds.profile_id, eds.data_length) == (profile_id, dl_pos + 2)
    assert eds.to_bytes()[2:4] == bytes([profile_id, dl_pos + 2])


@pytest.mark.parametrize("dl_pos, c", [(0, 0), (56, 0), (62, 1)])
def test_eds_rejects_lengths_outside_bp3(dl_pos, c):
    with pytest.raises(ValueError):
        Bp3Eds(dl_pos, c=c)


def test_arguments_checked():
    with pytest.raises(ValueError):
        RegisterAccess.read(0x80)
    with pytest.raises(ValueError):
        RegisterAccess.read(0, 0)
    with pytest.raises(ValueError):
        ControlSlave(refused_write="maybe")
    with pytest.raises(ValueError):
        ControlSlave().step(2)
    with pytest.raises(ValueError):
        RegisterFile(serial_number=b"123")
    with pytest.raises(ValueError):
        RegisterFile.bp3(EDS24, eds_bank=0xFF)


def test_control_model_imports_nothing_from_rtl():
    for module in (control_module, master_module):
        tree = ast.parse(Path(module.__file__).read_text())
        names = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                 for alias in node.names}
        names |= {node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
        assert not any(n.split(".")[0] == "bissmaster" for n in names), names
