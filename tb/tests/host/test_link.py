"""The host's side of the UART bridge (rtl/bissmaster/host/link.py): framing, CRC-8, the
retries of Link, the transports.

The protocol's numbers are checked against docs/uart_bridge.md, the page both sides are
written from (the RTL's against the same tables: tb/tests/bus/test_uart_bridge.py); the CRC
against the CRC catalogue's check value for CRC-8/AUTOSAR. Link runs against MemoryBridge (the
software model of the bridge, virtual time), with bytes of requests and answers lost or damaged
on purpose; the RTL itself meets Link in the cocotb scenario (sim/scenarios/bus.py).
"""

import re
import subprocess
import sys

import pytest

from bissmaster.host import link
from bissmaster.host.link import (BridgeError, Link, LinkError, MemoryBridge, SerialTransport,
                                  crc8, encode_request)
from testkit import REPO

DOC = REPO / "docs" / "uart_bridge.md"
BAUD = 115_200
TIMEOUT_S = 1000 / BAUD         # the bridge's default inter-byte timeout


# -- The documented protocol ----------------------------------------------------------------

def doc_table(first_header):
    """The rows of the docs/uart_bridge.md table whose first header cell is ``first_header``:
    a list of {header: cell} (backticks removed)."""
    lines = DOC.read_text().splitlines()
    for i, line in enumerate(lines):
        cells = [c.strip().strip("`") for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0] == first_header:
            rows = []
            for row in lines[i + 2:]:
                if not row.startswith("|"):
                    break
                rows.append(dict(zip(cells, (c.strip().strip("`")
                                             for c in row.strip().strip("|").split("|")))))
            return rows
    raise AssertionError(f"docs/uart_bridge.md has no table headed {first_header!r}")


def test_opcodes_and_lengths_are_the_documented_ones():
    rows = doc_table("opcode")
    assert {r["opcode"]: int(r["code"], 16) for r in rows} == link.OPCODES
    assert {r["opcode"]: int(r["request bytes"]) for r in rows} == link.REQUEST_LENGTH


def test_statuses_are_the_documented_ones():
    rows = doc_table("status")
    assert {r["status"]: int(r["code"], 16) for r in rows} == link.STATUSES


def test_constants_are_the_documented_ones():
    consts = {r["constant"]: r["value"] for r in doc_table("constant")}
    assert int(consts["SYNC_REQUEST"], 16) == link.SYNC_REQUEST
    assert int(consts["SYNC_RESPONSE"], 16) == link.SYNC_RESPONSE
    assert int(consts["CRC polynomial"], 16) == link.CRC8_POLY
    assert int(consts["CRC initial value"], 16) == link.CRC8_INIT
    assert int(consts["CRC final XOR"], 16) == link.CRC8_XOR_OUT
    assert int(consts["CRC check"], 16) == link.CRC8_CHECK
    assert consts["CRC reflected"] == "no"
    assert int(consts["inter-byte timeout"].split()[0]) == link.DEFAULT_TIMEOUT_BITS
    assert int(consts["burst words"].split("..")[1]) == link.MAX_BURST


def test_crc8_is_the_catalogue_crc8_autosar():
    # reveng's CRC catalogue, CRC-8/AUTOSAR: width=8 poly=0x2f init=0xff refin=false
    # refout=false xorout=0xff check=0xdf residue=0x42.
    assert crc8(b"123456789") == 0xDF == link.CRC8_CHECK
    assert crc8(b"") == 0x00
    # The residue: the CRC register after a codeword, before the final XOR.
    for msg in (b"123456789", b"\xa5\x11\x00\x00", bytes(range(20))):
        assert crc8(msg + bytes([crc8(msg)])) ^ 0xFF == 0x42


def _poly_mod(a, g=0x100 | link.CRC8_POLY):
    """``a`` mod ``g``, polynomials over GF(2) as integers."""
    while a.bit_length() >= g.bit_length():
        a ^= g << (a.bit_length() - g.bit_length())
    return a


def test_what_the_crc_detects_as_documented():
    """docs/uart_bridge.md, CRC: the generator is (x + 1) times a polynomial of period 127, so
    every odd number of bit errors is caught, and two bit errors are caught unless exactly 127
    bits apart (distance 4 up to 119 bits before the CRC: 14 whole bytes)."""
    g = 0x100 | link.CRC8_POLY
    assert bin(g).count("1") % 2 == 0                   # g(1) = 0: (x + 1) divides g
    q = 0                                               # g / (x + 1), over GF(2)
    rem = g
    while rem.bit_length() > 1:
        shift = rem.bit_length() - 2
        q |= 1 << shift
        rem ^= 0b11 << shift
    assert rem == 0
    period = next(n for n in range(1, 300) if _poly_mod(1 << n, q) == 1)
    assert period == 127 and _poly_mod(1 << 127) == 1
    # Two flipped bits 127 apart pass; nothing closer does (whole codewords, by brute force).
    msg = bytes(range(1, 17))                           # 128 bits before the CRC
    cw = bytearray(msg + bytes([crc8(msg)]))
    cw[0] ^= 0x80
    cw[15] ^= 0x01                                      # bits 0 and 127
    assert crc8(cw[:-1]) == cw[-1]
    short = bytes(range(1, 15))                         # 14 bytes, 112 bits: no pair passes
    cw = short + bytes([crc8(short)])
    n = len(cw) * 8
    for i in range(n):
        for j in range(i + 1, n):
            x = bytearray(cw)
            x[i // 8] ^= 0x80 >> (i % 8)
            x[j // 8] ^= 0x80 >> (j % 8)
            assert crc8(x[:-1]) != x[-1], (i, j)


def test_the_documented_example_packets():
    """The example packets of docs/uart_bridge.md (Examples), byte for byte."""
    text = DOC.read_text()
    examples = {
        "read": (encode_request("READ", 1, 0x0000), "a5 11 00 00"),
        "write": (encode_request("WRITE", 2, 0x0220, 0x00000018), "a5 22 20 02 18 00 00 00"),
        "burst": (encode_request("READ_BURST", 3, 0x0240, count=7), "a5 33 40 02 07"),
        "ping": (encode_request("PING", 0), "a5 00"),
    }
    for name, (packet, head) in examples.items():
        assert packet.hex(" ").startswith(head), name
        assert packet.hex(" ") in text, f"{name}: {packet.hex(' ')} not in the docs"


def test_encode_request_layout():
    assert encode_request("PING", 5) == bytes([0xA5, 0x50]) + bytes([crc8(b"\xa5\x50")])
    w = encode_request("WRITE", 15, 0xFFFC, 0x01020304)
    assert w[:8] == bytes([0xA5, 0xF2, 0xFC, 0xFF, 0x04, 0x03, 0x02, 0x01])
    assert w[8] == crc8(w[:8]) and len(w) == 9
    assert len(encode_request("READ_BURST", 0, 0, count=3)) == 6
    for bad in (dict(opcode="NOP", tag=0), dict(opcode="READ", tag=16),
                dict(opcode="READ", tag=0, address=0x10000),
                dict(opcode="WRITE", tag=0, address=0, value=-1)):
        with pytest.raises(ValueError):
            encode_request(**bad)


def test_host_code_imports_no_hardware():
    code = ("import sys, bissmaster.host.link; "
            "assert not [m for m in sys.modules if m.startswith('amaranth')], 'amaranth'; "
            "assert 'serial' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


# -- Link against the model ------------------------------------------------------------------

def make(registers=None, requests=None, responses=None, **kw):
    bridge = MemoryBridge(registers, timeout_s=TIMEOUT_S, requests=requests,
                          responses=responses)
    return Link(bridge, baud=BAUD, **kw), bridge


def faults(*plan):
    """A ``requests``/``responses`` hook damaging the n-th packet as ``plan[n]`` says (None: as
    is); packets after the plan pass unchanged. ``counter`` counts them."""
    state = {"n": 0}

    def hook(data):
        n = state["n"]
        state["n"] += 1
        f = plan[n] if n < len(plan) else None
        return f(data) if f else data
    hook.state = state
    return hook


def drop(i):
    return lambda d: d[:i] + d[i + 1:]


def flip(i, bit=0):
    return lambda d: d[:i] + bytes([d[i] ^ 1 << bit]) + d[i + 1:]


def test_read_write_burst_and_the_first_ping():
    lk, br = make({0x240 + 4 * i: i + 10 for i in range(7)})
    lk.write32(0x220, 0x18)
    assert lk.read32(0x220) == 0x18
    assert lk.read_burst(0x240, 7) == list(range(10, 17))
    assert br.accesses[:2] == [("w", 0x220, 0x18), ("r", 0x220, 0x18)]
    # PING first (no access), then one request per access.
    assert lk.stats["requests"] == 4 and lk.stats["attempts"] == 4
    with pytest.raises(ValueError, match="count must be 1..255"):
        lk.read_burst(0, 256)


def test_tags_advance_per_request_and_repeat_per_retry():
    sent = []
    hook = faults(None, None, drop(3))          # the write's first attempt loses a byte

    def spy(data):
        sent.append(data)
        return hook(data)
    lk, br = make(requests=spy)
    lk.read32(0)
    lk.write32(4, 1)
    assert [p[1] >> 4 for p in sent] == [1, 2, 3, 3]
    assert sent[2] == sent[3]
    assert br.accesses[-1] == ("w", 4, 1)


@pytest.mark.parametrize("fault, kind", [
    (drop(0), "timeout"),          # SYNC lost: the bridge sees no request
    (drop(4), "timeout"),          # a byte lost: a partial request, dropped by the bridge
    (flip(5, 3), "BAD_CRC"),       # a bit flipped: BAD_CRC from the bridge
    (flip(1, 0), "garbled"),       # the opcode changed: another command's answer
])
def test_a_damaged_request_is_retried_and_written_once(fault, kind):
    lk, br = make(requests=faults(None, fault))   # (the first packet is the PING)
    lk.write32(0x224, 0xCAFE)
    assert br.accesses == [("w", 0x224, 0xCAFE)]
    assert lk.stats[kind] >= 1 and lk.stats["attempts"] == 3


@pytest.mark.parametrize("fault, kind", [
    (drop(1), "garbled"),          # the echo lost: another command's answer
    (drop(3), "timeout"),          # the CRC byte lost
    (flip(2, 7), "garbled"),       # the status damaged
    (lambda d: d[:-1], "timeout"),
    (lambda d: b"\x00\xff" + d, None),      # noise before the answer: skipped
])
def test_a_damaged_answer_to_a_write_is_retried_and_written_once(fault, kind):
    lk, br = make(responses=faults(None, fault))
    lk.write32(0x224, 0xBEEF)
    assert br.accesses == [("w", 0x224, 0xBEEF)], "a retried write is not written again"
    if kind:
        assert lk.stats[kind] >= 1


def test_a_damaged_answer_to_a_read_is_retried():
    lk, br = make({0x230: 0x12345678}, responses=faults(None, flip(4, 2), drop(6)))
    assert lk.read32(0x230) == 0x12345678
    assert [a for a in br.accesses] == [("r", 0x230, 0x12345678)] * 3


def test_retries_are_bounded():
    lk, br = make(requests=faults(None, *[drop(2)] * 10), retries=2)
    with pytest.raises(LinkError, match=r"WRITE 0x0224: no good answer in 3 attempts"):
        lk.write32(0x224, 1)
    assert br.accesses == []
    lk2, _ = make(responses=faults(None, *[flip(3)] * 10), retries=0)
    with pytest.raises(LinkError, match="in 1 attempts.*bad CRC"):
        lk2.read32(0)


def test_a_refusal_is_not_retried():
    lk, br = make()
    for address in (0x222, 0x2000):
        with pytest.raises(BridgeError, match="BAD_ADDRESS") as e:
            lk.read32(address)
        assert e.value.status == "BAD_ADDRESS"
    assert lk.stats["attempts"] == 3         # the PING and one attempt each
    assert br.accesses == []


def test_the_model_answers_an_unknown_opcode_when_the_line_is_quiet():
    br = MemoryBridge(timeout_s=TIMEOUT_S)
    br.write(bytes([0xA5, 0x17, 1, 2, 3]))
    assert br.read(4, 0) == b""                          # still receiving
    got = br.read(4, TIMEOUT_S)
    assert got[:3] == bytes([0x5A, 0x17, link.STATUSES["BAD_COMMAND"]])
    assert got[3] == crc8(got[:3])


def test_a_new_link_pings_so_its_first_write_is_never_taken_for_a_retry():
    """The bridge keeps the last write; a new Link (after a restart of the host tool) may send
    the very same bytes first: its PING ends that memory."""
    lk, br = make()
    lk.write32(0x224, 5)
    again = Link(br, baud=BAUD)
    again.tag = lk.tag - 2          # so that its first write has the tag of the last one
    again.write32(0x224, 5)
    assert br.accesses == [("w", 0x224, 5)] * 2


# -- Transports ------------------------------------------------------------------------------

class FakePort:
    """Stands in for serial.Serial: what was written, what is there to read."""

    def __init__(self, incoming=b""):
        self.written, self.incoming = b"", bytearray(incoming)
        self.timeout, self.closed, self.flushed = None, False, 0

    def write(self, data):
        self.written += data

    def flush(self):
        self.flushed += 1

    def read(self, n):
        out, self.incoming = bytes(self.incoming[:n]), self.incoming[n:]
        return out

    def close(self):
        self.closed = True


def test_serial_transport_passes_bytes_and_the_timeout():
    port = FakePort(b"\x01\x02\x03")
    t = SerialTransport(port)
    t.write(b"\xa5\x00")
    assert port.written == b"\xa5\x00" and port.flushed == 1
    assert t.read(2, 0.25) == b"\x01\x02" and port.timeout == 0.25
    assert t.read(5, 0) == b"\x03" and port.timeout == 0
    t.close()
    assert port.closed


def test_serial_transport_without_pyserial_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "serial", None)        # import serial fails
    with pytest.raises(ImportError, match="pip install pyserial"):
        SerialTransport("/dev/ttyUSB9")


def test_link_over_a_fake_serial_port():
    """Link's bytes on a port that answers as the bridge would (MemoryBridge behind it)."""
    model = MemoryBridge({0x8: 2})

    class Port(FakePort):
        def write(self, data):
            model.write(data)
            self.incoming += model.read(4096, 0)
    lk = Link(SerialTransport(Port()), baud=3_000_000, latency=0.0)
    assert lk.read32(0x8) == 2


def test_link_parameters():
    with pytest.raises(ValueError, match="retries"):
        Link(MemoryBridge(), retries=-1)
    lk = Link(MemoryBridge(), baud=3_000_000, timeout_bits=200)
    assert lk.quiet_s == pytest.approx(220 / 3e6)
    assert re.search("retries", Link.__doc__)
