"""cocotb test bench for ``biss_master``'s SSI channel mode (cfg_ssi = 1).

``Testbench`` (clock, reset, ports, the confirmation watch, ``request`` and ``read``) with an
SSI encoder on the pins instead of the BiSS one: ``encoder_model.cocotb_ssi.SsiLineEncoder``.
The expected values come from what that encoder latched and sent (its ``SsiRecord``, parsed
by ``encoder_model.ssi.parse_ssi``) and from master_contract's SSI facts, never from the RTL.
"""

from dataclasses import replace

from cocotb.triggers import Timer

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from encoder_model.cocotb_ssi import SsiLineEncoder
from encoder_model.ssi import ACTIVE_LOW, REPEAT_RING, REPEAT_ZEROS, SsiFormat, parse_ssi
from master_contract import (FRAME_STATUSES, SSI_FIELD_STATUSES, SSI_PORTS, SSI_STATUSES, STATUS,
                             SSI_STATUS_COUNTERS, STATUS_NAME, port_position, ssi_ma_pulses,
                             ssi_ne_nw, ssi_word_bits)
from sim.shared.testbench import CLK_HZ, Testbench


class SsiTestbench(Testbench):
    """``start(cable, fmt)``, ``configure_ssi(fmt, ma_hz, ...)``, ``request()``, ``check(res)``.

    Positions are random per latch (``position`` set: that value); ``errors`` (the error
    flag, True = active) and ``nenw`` (nE, nW line levels) are what the encoder sends next.
    """

    def __init__(self, dut, *, seed=1):
        super().__init__(dut, seed=seed)
        missing = [n for n in SSI_PORTS if not hasattr(dut, n)]
        assert not missing, f"this build has no SSI ports {missing} (master_contract.SSI_BUILDS)"
        self.ssi_fmt = None
        self.double = False
        self.ssi_delay = None
        self.word = None                # the frames.WordFormat the master is configured for
        self.position = None            # None: random per latch
        self.errors = (False,)
        self.nenw = (1, 1)
        self.next_record = 0            # first encoder record no result has claimed yet
        self.ssi_pending = []           # (record, pulses, aborted) to check once it ended
        self.status_counts = None       # the status counters after the last checked result
        self.frame_line_delay = None    # line_delay of the last frame checked

    # -- setup ------------------------------------------------------------------------------
    async def start(self, cable=Cable(), fmt=SsiFormat(13)):
        self._first_fmt = fmt
        self.cable = cable
        await super().start(cable)

    def _make_encoder(self, cable, timeout_s, control, min_cycle_s):
        return SsiLineEncoder(self.dut.ma, self.dut.slo, self._first_fmt, self._ssi_position_at,
                              cable=cable, errors_at=self._errors_at, nenw_at=self._nenw_at,
                              rng=self.rng)

    def _ssi_position_at(self, t):
        fmt = self.encoder.fmt
        return self.rng.getrandbits(fmt.data_bits) if self.position is None else self.position

    def _errors_at(self, t):
        return tuple(self.errors[:self.encoder.fmt.error_bits])

    def _nenw_at(self, t):
        return self.nenw

    def set_cable(self, cable):
        self.cable = cable
        self.encoder.set_cable(cable)

    def true_delay_clocks(self):
        """The true round trip (cable both ways + encoder internal delay), in clocks."""
        return self.clocks(self.cable.round_trip_s())

    def configure_ssi(self, fmt, ma_hz=None, *, half_period=None, delay=None, double=False,
                      signed=False, repeat=None, **cfg):
        """The cfg_* ports for an SSI encoder of format ``fmt`` (an ssi.SsiFormat: one error bit
        at most; its nE nW and CRC are the word-0 ports'), ``delay``: cfg_ssi_delay (default:
        the true round trip, rounded); ``double``: double transmission (the encoder repeats in
        ring mode; ``repeat``: the encoder's repeat mode instead); ``cfg``: port overrides."""
        assert fmt.error_bits <= 1, "the core has one SSI error bit"
        fmt = replace(fmt, repeat=repeat or (REPEAT_RING if double else REPEAT_ZEROS))
        self.word = frames.WordFormat(fmt.data_bits, nenw=fmt.nenw, crc=fmt.crc, gray=fmt.gray,
                                      signed=signed)
        delay = round(self.true_delay_clocks()) if delay is None else delay
        ports = {"cfg_ssi": 1, "cfg_ssi_delay": delay, "cfg_ssi_error": fmt.error_bits,
                 "cfg_ssi_error_low": int(fmt.error_bits == 1
                                          and fmt.error_polarity[0] == ACTIVE_LOW),
                 "cfg_ssi_double": int(double)}
        ports.update(cfg)
        self.configure(frames.FrameFormat("ssi", (self.word,)), ma_hz, half_period=half_period,
                       **ports)
        self.ssi_fmt, self.double, self.ssi_delay = fmt, double, ports["cfg_ssi_delay"]
        self.encoder.set_format(fmt)
        self.status_counts = self._status_counts(self.read().counters)

    def _status_counts(self, counters):
        names = {n for ns in SSI_STATUS_COUNTERS.values() for n in ns}
        return {n: v for n, v in counters.items() if n in names}

    @property
    def pulses(self):
        """MA pulses of one cycle (master_contract.ssi_ma_pulses)."""
        fmt = self.ssi_fmt
        n = ssi_word_bits(fmt.data_bits, fmt.error_bits, fmt.nenw, fmt.crc_bits)
        assert n == fmt.total_bits          # the model's word is the contract's N
        return ssi_ma_pulses(n, self.double)

    # -- one request --------------------------------------------------------------------------
    def check_pending(self):
        """Records that ended since: no MA edge came after the result was read (an aborted
        cycle's: MA back high, at most the full count). BiSS cycles (a scenario that swaps the
        encoders): Testbench's checks."""
        super().check_pending()
        for item in [i for i in self.ssi_pending if i[0].ended]:
            self.ssi_pending.remove(item)
            rec, pulses, aborted = item
            if aborted:
                assert 1 <= rec.ma_falls == rec.ma_rises <= pulses, \
                    f"aborted: {rec.ma_falls} falls / {rec.ma_rises} rises of {pulses}"
            else:
                assert (rec.ma_falls, rec.ma_rises) == (pulses, pulses), \
                    f"MA pulses {rec.ma_falls} falls / {rec.ma_rises} rises, expected {pulses}"
        if isinstance(self.encoder, SsiLineEncoder):
            assert self.encoder.logic.stray_rises == 0, "an MA rise with the encoder's line high"

    async def finish(self):
        """End of a scenario: every transmission's line went high, all its checks done."""
        await self.wait_idle()
        await Timer(round(self.ssi_fmt.tm_s * 1e9) + 1000, "ns")
        self.check_pending()
        assert not self.ssi_pending, self.ssi_pending

    def check(self, res, status="OK", *, cycle=True):
        """A result against the encoder's record: the status (after the confirmation rule),
        ``valid``, ``line_delay`` = cfg_ssi_delay, the MA pulses the encoder saw, and with the
        statuses of SSI_FIELD_STATUSES the position, nE / nW and crc_ok as sent.
        ``cycle=False``: no MA edge at all was due (BAD_CONFIG, SLO_STUCK_LOW). ABORTED: at most
        the full count of pulses, MA back high (checked once the encoder's line is high).
        Returns the encoder's record of the cycle (None without one)."""
        status = self.expected_status(res, status)
        assert status in SSI_STATUSES, status
        got = STATUS_NAME.get(res.status, res.status)
        recs = self.encoder.records[self.next_record:]
        self.next_record = len(self.encoder.records)
        assert res.status == STATUS[status], f"status {got}, expected {status}; {recs}"
        assert res.valid == int(status == "OK"), f"valid {res.valid} with status {status}"
        if self.has_counters:
            # one count in the status's counter(s), none in the others (BAD_CONFIG: none)
            now = self._status_counts(res.counters)
            want = dict(self.status_counts)
            for name in SSI_STATUS_COUNTERS.get(status, ()):
                want[name] += 1
            assert now == want, f"status counters {now}, expected {want} after {status}"
            self.status_counts = now
        f = res.fields
        # line_delay is "updated on frames" (docs/ports.md): cfg_ssi_delay after a frame, the
        # last frame's after a cycle without one (NO_STOP, SLO_STUCK_LOW, ABORTED)
        if status in FRAME_STATUSES:
            assert f["line_delay"] == self.ssi_delay, \
                f"line_delay {f['line_delay']}, cfg_ssi_delay {self.ssi_delay}"
            self.frame_line_delay = self.ssi_delay
        elif status != "BAD_CONFIG" and self.frame_line_delay is not None:
            assert f["line_delay"] == self.frame_line_delay, \
                f"line_delay {f['line_delay']} after {status}, the last frame's " \
                f"{self.frame_line_delay}"
        if not cycle:
            assert recs == [], f"the encoder latched {len(recs)} time(s): {recs}"
            return None
        assert len(recs) == 1, f"{len(recs)} latches for one cycle: {recs}"
        rec = recs[0]
        aborted = status == "ABORTED"
        # every rise has reached the encoder before the master decided the last bit
        if not aborted:
            assert (rec.ma_falls, rec.ma_rises) == (self.pulses, self.pulses), \
                f"MA pulses {rec.ma_falls} falls / {rec.ma_rises} rises, expected {self.pulses}"
        self.ssi_pending.append((rec, self.pulses, aborted))
        if not self.cable.jitter_s:
            self.check_clock(rec, cut=aborted)
        if status in SSI_FIELD_STATUSES:
            self.check_fields(res, rec)
        return rec

    def check_clock(self, rec, cut=False):
        """MA at the configured half period: each rise a half period after its fall, each fall a
        half period after the rise before it (the cable delays every edge alike). ``cut``: an
        aborted cycle, whose last edge came when the abort did."""
        half = self.half_period / CLK_HZ
        edges = sorted(rec.t_falls_s + rec.t_rises_s)[:-1 if cut else None]
        gaps = {round((b - a) / half, 6) for a, b in zip(edges, edges[1:])}
        assert gaps <= {1.0}, f"MA half periods of {sorted(gaps)} x cfg_ma_half_period"

    def check_fields(self, res, rec):
        """Position, nE / nW and crc_ok as the encoder sent them: the first copy as it went on
        the line (its faults applied: a ``flip`` in both copies, a level ``force``d in copy 1)."""
        fmt, f = rec.fmt, res.fields
        sent = (rec.levels[:fmt.total_bits] if len(rec.levels) >= fmt.total_bits
                else [b ^ (i in rec.faults.flip) for i, b in enumerate(rec.word)])
        reading = parse_ssi(fmt, sent)
        want = port_position(self.word, reading.position, len(self.dut.word0_position))
        assert f["word0_position"] == want, \
            f"position {f['word0_position']:#x}, sent {want:#x} (latched {rec.position:#x})"
        flags = ssi_ne_nw(error_active=reading.errors[0] if fmt.error_bits else None,
                          nenw=(reading.ne, reading.nw) if fmt.nenw else None)
        if flags is not None:
            assert (f["word0_ne"], f["word0_nw"]) == flags, \
                f"ne/nw {(f['word0_ne'], f['word0_nw'])}, expected {flags}"
        crc_ok = 1 if reading.crc_ok is None else int(reading.crc_ok)
        if f["word0_crc_ok"] is None:         # Icarus: an X for a word without CRC (Testbench)
            assert reading.crc_ok is None, "word0_crc_ok reads X"
        else:
            assert f["word0_crc_ok"] == crc_ok, f"crc_ok {f['word0_crc_ok']}, expected {crc_ok}"
