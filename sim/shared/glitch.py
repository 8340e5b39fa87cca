"""Where a glitch lands on the SLO line, and what the master can read after it (issue 12).

Written from the protocol (docs/protocol.md, sections 2 and 4) and the encoder model,
not from the RTL: the glitch campaign (sim/scenarios/campaigns.py) and the crafted noise
scenarios (sim/scenarios/master.py) both use it.

Line time is counted from the **Ack edge at the master pin**: the master's second MA rising edge
plus the round trip. From there every MA period carries one *slot*: slot ``k`` is what the
encoder put on SLO at its MA rising edge ``k + 2``. With a processing time of ``n + 1/2`` MA
periods the encoder sends Start on rising edge ``n + 2``: slots ``0 .. n-1`` are the Ack (low),
slot ``n`` is Start, then CDS, the words, the stop bit (low), and SLO stays low through the
encoder's timeout while MA runs. A master that samples every slot once, in its middle, reads a
glitch that covers that instant as the inverted bit, and takes any high sample after the Ack
edge for Start.
"""

import itertools

from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge

from encoder_model import frames

#: The slot classes of a frame, in line order, then the encoder's timeout after it.
SLOT_CLASSES = ("ack", "start", "cds", "data", "crc", "stop", "timeout")


def processing_for_ack_slots(n_ack, ma_hz):
    """Processing time that gives exactly ``n_ack`` Ack slots before Start (half a period off
    every MA edge: no rounding can move Start). The protocol asks for at least 2 periods."""
    assert n_ack >= 2
    return (n_ack + 0.5) / ma_hz


def slot_classes(fmt, n_ack):
    """Class of every slot from the Ack edge: the Ack, Start, CDS, data (with nE/nW and LC) and
    CRC bits of every word, the stop bit."""
    classes = ["ack"] * n_ack + ["start", "cds"]
    for w in fmt.words:
        classes += ["data"] * (w.total_bits - w.crc_bits) + ["crc"] * w.crc_bits
    return classes + ["stop"]


class LineTiming:
    """Times (simulator steps, 1 ps) of the slots of one cycle at the master pin."""

    def __init__(self, t_first_fall, ma_hz, round_trip_s):
        self.period = round(1e12 / ma_hz)
        # MA: first fall, first rise half a period later, second rise one period after that.
        self.t_ack = t_first_fall + round(1.5 * self.period) + round(round_trip_s * 1e12)

    def slot_start(self, k):
        return self.t_ack + k * self.period

    def slot_of(self, t):
        """The slot a line time falls in (negative: before the Ack edge)."""
        return (t - self.t_ack) // self.period


async def cycle_timing(dut, ma_hz, round_trip_s):
    """Wait for the cycle's first MA falling edge: the timing of its slots."""
    await FallingEdge(dut.ma)
    return LineTiming(get_sim_time("step"), ma_hz, round_trip_s)


def line_after_ack(bits, n_ack):
    """The line from the Ack edge as the master's slots see it: Ack, the frame, then low (the
    stop bit, and the timeout while MA runs) for as long as a slipped reading can reach."""
    return [0] * n_ack + list(bits) + [0] * (len(bits) + 4)


def read_from(line, j, n):
    """The ``n`` bits a master reads when it takes slot ``j`` for Start (sampled high)."""
    return [1] + list(line[j + 1:j + n])


def glitch_readings(bits, n_ack, touched, max_touched=10):
    """Every reading a glitch can explain: any subset of the touched slots inverted, Start taken
    at any slot (a glitch high in the Ack, or a missed Start). ``touched``: slot indices a
    glitch overlapped (two at most per glitch shorter than a slot)."""
    n = len(bits)
    line = line_after_ack(bits, n_ack)
    touched = sorted(k for k in set(touched) if 0 <= k < len(line))[:max_touched]
    for r in range(len(touched) + 1):
        for subset in itertools.combinations(touched, r):
            flipped = list(line)
            for k in subset:
                flipped[k] ^= 1
            for j in range(len(line) - n + 1):
                yield read_from(flipped, j, n)


def slipped_reading(fmt, bits, n_ack, glitch_slot):
    """What a master reads when a glitch high on the sample of Ack slot ``glitch_slot`` is taken
    for Start: the parsed frame (``frames.parse_frame``)."""
    line = line_after_ack(bits, n_ack)
    return frames.parse_frame(fmt, read_from(line, glitch_slot, len(bits)))


def tail_reading(fmt, bits, n_ack, glitch_slot):
    """What a master reads in the cycle it starts at once after the slipped cycle of
    :func:`slipped_reading`, on the tail of the frame the encoder is still sending: the parsed
    frame, or None if it cannot read one (it waits for SLO high, SLO is low when it arms, or no
    Start comes).

    The slipped cycle gives the MA rises of a frame whose Start was rise ``glitch_slot + 2``:
    ``d = n_ack - glitch_slot`` rises short of the encoder's frame, which holds ``bits[N - d]``.
    If that is high, the next cycle's MA continues the encoder's frame (it has not timed out):
    the master arms at its 2nd rise, on the bit its 1st rise brought (low: DELAY_RANGE), takes
    the next falling edge for the Ack, the first high slot after it for Start, and reads on
    into the stop bit and the low line after it (MA still running)."""
    n, d = len(bits), n_ack - glitch_slot
    if d < 2 or not bits[n - d] or not bits[n - d + 1]:
        return None
    line = list(bits[n - d + 2:]) + [0] * (n + 4)       # slots from the 2nd MA rise on
    edge = line.index(0)
    start = next((k for k in range(edge + 1, len(line) - n + 1) if line[k]), None)
    return None if start is None else frames.parse_frame(fmt, read_from(line, start, n))


def search_values(fmt, rng, accept, tries=100_000):
    """Random single-word positions until ``accept(bits)`` returns something: (value, it)."""
    for _ in range(tries):
        value = frames.WordValue(rng.getrandbits(fmt.words[0].data_bits))
        found = accept(frames.build_frame(fmt, [value]))
        if found is not None:
            return value, found
    raise AssertionError("no such frame found")
