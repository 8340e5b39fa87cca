"""A board for the host tool's tests: ``MemoryBridge`` (the UART bridge in software) in front of
a small model of the bus top's register map, in virtual time.

The registers behave as docs/bus.md says where the host tool depends on it: ``id``,
``version``, ``channels`` constants; ``ctrl`` with its pulses (``start``, ``clear_counters``)
and stored fields; ``trigger.start`` starting every trigger-enabled channel; ``irq_status``
sticky, cleared by writing 1; the configuration registers stored, ``state.config_error`` while
the MA half period is below 2; ``result.status`` taking the snapshot of the result block;
the counters; the register-access engine answering from an encoder's register file
(``encoder_model.control.RegisterFile``) with ``ca.state``, ``ca.rbuf`` and
``irq_status.access_done``. A chain build (``chain_bits``: words 2..7 and their longest data
fields) has ``caps.words``, ``caps_chain*``, the settings of the words it has (others read 0,
writes ignored), ``count_chain*`` and the live ``chain.*`` results with ``chain.updates``
counting every ended cycle; ``tears[ch]`` cycles end in the middle of a result read (at
``chain.flags``), as when frames end faster than the host reads.

Addresses and fields come from the SystemRDL source through the test side's own reader
(sim/shared/regspec.py), never from the host code under test. A cycle ends the moment it is
started (``done`` at once); what it reports is the channel's :class:`FakeEncoder`'s.
"""

from dataclasses import dataclass, field

from bissmaster.host.link import MemoryBridge
from encoder_model.control import RegisterFile
from master_contract import CA_STATUS, STATUS
from sim.shared import regspec

MAP = regspec.load()
ID = 0x42695353
FRAME = ("OK", "CRC_ERROR_WORD0", "CRC_ERROR_WORD1", "CRC_ERROR_BOTH", "SIGN_OF_LIFE",
         "SPW_MISMATCH")
CHAIN_WORDS = range(2, 8)


def _per_chain_word(paths):
    """{word: (path, field)}: the fields of ``paths`` (low field first) dealt to words 2..7."""
    slots = [(path, f.name) for path in paths
             for f in sorted(MAP.channel[path].fields.values(), key=lambda f: f.lsb)]
    return dict(zip(CHAIN_WORDS, slots))


#: Each chain word's caps field and CRC count field, from the RDL.
CHAIN_CAPS = _per_chain_word(("caps_chain", "caps_chain2"))
CHAIN_COUNTS = _per_chain_word(("count_chain", "count_chain2", "count_chain3"))


@dataclass
class FakeEncoder:
    """What a channel's cycles report. ``positions``: position of cycle n (n from 0);
    ``statuses``: status name of cycle n (default OK); ``line_delay`` in clocks; ``word1``:
    word 1 of cycle n (two-word configurations). ``chain``: chain word w's data of cycle n,
    ``chain(w, n)``; ``chain_bad``: the chain words whose CRC fails in cycle n, ``chain_bad(n)``.
    ``registers``: an encoder register file for the register-access engine (None:
    NO_ANSWER); ``access_status``: a forced ca status name for every access."""
    positions: object = lambda n: 1000 + 7 * n
    statuses: object = lambda n: "OK"
    line_delay: int = 37
    word1: object = None
    chain: object = lambda w, n: 100 * w + n
    chain_bad: object = lambda n: ()
    registers: RegisterFile | None = None
    access_status: str | None = None
    cycles: int = 0
    accesses: list = field(default_factory=list)


class RegisterModel:
    """The register map's behaviour, as the mapping MemoryBridge reads (``get``) and writes."""

    def __init__(self, channels=2, encoders=None, caps=None, chain_bits=None):
        self.n = channels
        self.encoders = encoders or {}
        self.words = {}                     # stored registers by address
        self.snapshot = {}
        self.live = {ch: self._empty_result() for ch in range(channels)}
        self.counters = {ch: {} for ch in range(channels)}
        self.rbuf = {ch: bytearray(64) for ch in range(channels)}
        self.wbuf = {ch: bytearray(64) for ch in range(channels)}
        self.caps = {"data_bits_w0": 55, "data_bits_w1": 40, "timer_width": 24, "counters": 1,
                     "timestamp": 1, "register_access": 1, **(caps or {})}
        self.chain_bits = dict(chain_bits or {})      # {word: longest data field} built
        if chain_bits:
            self.caps["words"] = 2 + len(self.chain_bits)
        self.updates = {ch: 0 for ch in range(channels)}
        self.tears = {ch: 0 for ch in range(channels)}
        self.time = 0
        self.log = []                       # (kind, register path, channel)

    # -- Helpers -----------------------------------------------------------------------------
    @staticmethod
    def _empty_result():
        return {"status": {}, "seq": {}, "w0": 0, "w1": 0, "time": 0, "line": {}, "chain": {},
                "flags": {}}

    def where(self, address):
        """(path, channel or None, index) of a byte address, or None if unmapped."""
        for path, spec in MAP.globals.items():
            if spec.offset == address:
                return path, None, 0
        ch, off = divmod(address - MAP.channel_base, MAP.channel_stride)
        if address < MAP.channel_base or not 0 <= ch < self.n:
            return None
        for path, spec in MAP.channel.items():
            if spec.offset <= off < spec.offset + 4 * spec.count:
                return path, ch, (off - spec.offset) // 4
        return None

    def fields(self, path, ch, word):
        return {n: f.get(word) for n, f in MAP.reg(path, ch).fields.items()}

    def pack(self, path, **values):
        word = 0
        for name, value in values.items():
            word = MAP.channel[path].fields[name].put(word, value)
        return word

    def stored(self, path, ch):
        return self.words.get(MAP.address(path, ch), 0)

    def cfg(self, ch):
        out = {}
        for path in ("cfg_ma", "cfg_period", "cfg_break", "cfg_ack", "cfg_timeout",
                     "cfg_words", "cfg_checks", "cfg_crc0", "cfg_crc0_start", "cfg_crc1",
                     "cfg_crc1_start", "cfg_ssi"):
            out.update(self.fields(path, ch, self.stored(path, ch)))
        return out

    def chain_cfg(self, ch, w):
        """Chain word ``w``'s settings (cfg_wW, _crc, _crc_start fields) as stored."""
        out = {}
        for end in ("", "_crc", "_crc_start"):
            path = f"cfg_w{w}{end}"
            out.update(self.fields(path, ch, self.stored(path, ch)))
        return out

    def chain_enabled(self, ch):
        return sorted(w for w in self.chain_bits if self.chain_cfg(ch, w)["enable"])

    def ctrl(self, ch):
        return self.fields("ctrl", ch, self.stored("ctrl", ch))

    def count(self, ch, name):
        self.counters[ch][name] = min(self.counters[ch].get(name, 0) + 1, 0xFFFF)

    # -- The mapping MemoryBridge uses --------------------------------------------------------
    def get(self, address, default=0):
        hit = self.where(address)
        if hit is None:
            return 0
        path, ch, index = hit
        self.log.append(("r", path, ch))
        if ch is None:
            return {"id": ID, "version": 2 << 16, "channels": self.n}.get(path, 0)
        if path == "state":
            return self.pack("state", busy=0, config_error=int(self.config_error(ch)))
        if path == "caps":
            return self.pack("caps", **self.caps)
        if path in ("caps_chain", "caps_chain2"):
            return self.pack(path, **{name: self.chain_bits.get(w, 0)
                                      for w, (p, name) in CHAIN_CAPS.items() if p == path})
        if path.startswith("count_chain"):
            return self.pack(path, **{name: self.counters[ch].get(f"crc_word{w}", 0)
                                      for w, (p, name) in CHAIN_COUNTS.items() if p == path})
        if path.startswith("chain."):
            live = self.live[ch]
            if path == "chain.flags" and self.tears[ch]:
                self.tears[ch] -= 1
                self.cycle(ch)              # a frame ends in the middle of the host's reads
            if path == "chain.updates":
                return self.pack(path, updates=self.updates[ch] & 0xFFFF)
            if path == "chain.flags":
                return self.pack(path, **live["flags"])
            w, half = int(path[len("chain.w")]), path[-2:]
            lo = MAP.channel[f"chain.w{w}_lo"].fields["data"]
            data = live["chain"].get(w, 0)
            return (data & ((1 << lo.width) - 1)) if half == "lo" else data >> lo.width
        if path.startswith("result."):
            if path == "result.status":
                if self.ctrl(ch)["periodic"]:
                    self.cycle(ch)          # periodic requests: a cycle ended since the last read
                self.snapshot[ch] = dict(self.live[ch])
            snap = self.snapshot.get(ch, self._empty_result())
            return {"result.status": self.pack("result.status", **snap["status"]),
                    "result.seq": self.pack("result.seq", **snap["seq"]),
                    "result.w0_lo": snap["w0"] & 0xFFFFFFFF, "result.w0_hi": snap["w0"] >> 32,
                    "result.w1_lo": snap["w1"] & 0xFFFFFFFF, "result.w1_hi": snap["w1"] >> 32,
                    "result.timestamp": snap["time"],
                    "result.line": self.pack("result.line", **snap.get("line", {}))}[path]
        if path.startswith("count_") or path.startswith("ca.count_"):
            prefix = "ca_" if path.startswith("ca.") else ""
            return self.pack(path, **{n: self.counters[ch].get(prefix + n, 0)
                                      for n in MAP.channel[path].fields})
        if path == "ca.rbuf":
            return int.from_bytes(self.rbuf[ch][4 * index:4 * index + 4], "little")
        if path == "ca.wbuf":
            return 0
        spec = MAP.channel[path]
        keep = sum(f.mask for f in spec.fields.values() if not f.singlepulse)
        return self.words.get(address, 0) & keep

    def __setitem__(self, address, value):
        hit = self.where(address)
        if hit is None:
            return
        path, ch, index = hit
        self.log.append(("w", path, ch))
        if ch is None:
            if path == "trigger" and value & 1:
                for c in range(self.n):
                    if self.ctrl(c)["trigger_enable"]:
                        self.cycle(c)
            return
        if path == "irq_status":
            self.words[address] = self.words.get(address, 0) & ~value
            return
        if path == "ca.wbuf":
            self.wbuf[ch][4 * index:4 * index + 4] = value.to_bytes(4, "little")
            return
        if path == "ca.ctrl":
            if self.fields("ca.ctrl", ch, value)["start"]:
                self.access(ch)
            return
        if path.startswith("cfg_w") and path[5].isdigit() and \
                int(path[5]) not in self.chain_bits:
            return                          # a chain word the build lacks: not stored
        self.words[address] = value
        if path == "ctrl":
            f = self.fields("ctrl", ch, value)
            if f["clear_counters"]:
                self.counters[ch] = {}
            if f["start"]:
                self.cycle(ch)

    # -- Behaviour ---------------------------------------------------------------------------
    def _irq(self, ch, **causes):
        a = MAP.address("irq_status", ch)
        self.words[a] = self.words.get(a, 0) | self.pack("irq_status", **causes)

    def cycle(self, ch):
        """One request cycle of channel ``ch``, ended at once."""
        enc = self.encoders.setdefault(ch, FakeEncoder())
        n = enc.cycles
        enc.cycles += 1
        self.time += 10_000
        status = enc.statuses(n)
        cfg = self.cfg(ch)
        if cfg["ma_half_period"] < 2:
            status = "BAD_CONFIG"
        live = self.live[ch]
        live["seq"] = {"seq": enc.cycles & 0xFFFF,
                       "line_delay": live["seq"].get("line_delay", 0)}
        st = dict(live["status"], status=STATUS[status])
        if status in FRAME:
            two = cfg["w1_enable"]
            st.update(w0_ne=1, w0_nw=1,
                      w0_crc_ok=int(status not in ("CRC_ERROR_WORD0", "CRC_ERROR_BOTH")),
                      w1_ne=two, w1_nw=two,
                      w1_crc_ok=int(bool(two) and status not in ("CRC_ERROR_WORD1",
                                                                 "CRC_ERROR_BOTH")),
                      lc=n % 64 if two else 0)
            live["w0"] = self._word(0, cfg, enc.positions(n))
            live["w1"] = self._word(1, cfg, enc.word1(n)) if (two and enc.word1) else 0
            live["seq"]["line_delay"] = enc.line_delay
            live["time"] = self.time
            status = self._chain_cycle(ch, enc, n, status, st)
            st["status"] = STATUS[status]
        counter = {"CRC_ERROR_WORD0": "crc_word0", "CRC_ERROR_BOTH": "crc_word0",
                   "NO_ACK": "no_ack", "SLO_STUCK_LOW": "slo_stuck_low",
                   "NO_START": "no_start"}.get(status)
        if counter:
            self.count(ch, counter)
        live["status"] = st
        self.updates[ch] += 1
        self._irq(ch, done=1, error=int(status != "OK"))

    def _chain_cycle(self, ch, enc, n, status, st):
        """The enabled chain words of cycle ``n``: data, flags, CRC counts; the status with
        their CRC verdicts (docs/driver.md: a bad later word is CRC_ERROR_WORD1, with word 0
        bad CRC_ERROR_BOTH)."""
        live = self.live[ch]
        live["chain"], live["flags"] = {}, {}
        bad = set(enc.chain_bad(n))
        for w in self.chain_enabled(ch):
            cfg = self.chain_cfg(ch, w)
            live["chain"][w] = self._field(enc.chain(w, n), cfg["data_bits"], cfg["is_signed"],
                                           self.chain_bits[w])
            live["flags"].update({f"w{w}_ne": 1, f"w{w}_nw": 1, f"w{w}_crc_ok": int(w not in bad)})
            if w in bad:
                self.count(ch, f"crc_word{w}")
        if bad & set(live["chain"]) and status in ("OK", "CRC_ERROR_WORD0"):
            status = "CRC_ERROR_BOTH" if status == "CRC_ERROR_WORD0" else "CRC_ERROR_WORD1"
        return status

    def _word(self, w, cfg, value):
        """Word ``w``'s register bits for a field of ``value`` (its low cfg_wN_data_bits bits):
        zeros above the field, or with ``cfg_wN_signed`` copies of its top bit up to the
        register's width, caps.data_bits_wN (docs/ports.md, word0_position)."""
        return self._field(value, cfg[f"w{w}_data_bits"], cfg.get(f"w{w}_signed"),
                           self.caps[f"data_bits_w{w}"])

    @staticmethod
    def _field(value, bits, signed, width):
        """The low ``bits`` of ``value``, sign-extended to ``width`` bits when ``signed``."""
        data = value & ((1 << bits) - 1)
        if signed and 0 < bits < width and data >> (bits - 1):
            data |= ((1 << width) - 1) ^ ((1 << bits) - 1)
        return data

    def access(self, ch):
        """One register access of ``ca.request``, ended at once."""
        enc = self.encoders.setdefault(ch, FakeEncoder())
        req = self.fields("ca.request", ch, self.stored("ca.request", ch))
        enc.accesses.append(dict(req, cfg=self.cfg(ch), chain=self.chain_enabled(ch)))
        done = 0
        if not 1 <= req["count"] <= 64 or req["address"] + req["count"] - 1 > 0x7F:
            status = "BAD_REQUEST"
        elif self.cfg(ch)["ma_half_period"] < 2:
            status = "DATA_FAULT"
        elif enc.access_status:
            status = enc.access_status
        elif enc.registers is None:
            status = "NO_ANSWER"
        else:
            status, done = "OK", req["count"]
            for i in range(req["count"]):
                if req["write"]:
                    if not enc.registers.write(req["address"] + i, self.wbuf[ch][i]):
                        status, done = "REFUSED", i
                        break
                else:
                    self.rbuf[ch][i] = enc.registers.read(req["address"] + i)
        if status not in ("OK", "BAD_REQUEST"):
            self.count(ch, {"NO_ANSWER": "ca_no_answer", "REFUSED": "ca_refused",
                            "CRC4_ERROR": "ca_crc4_error", "DATA_FAULT": "ca_data_fault",
                            "ABORTED": "ca_aborted"}[status])
        a = MAP.address("ca.state", ch)
        self.words[a] = self.pack("ca.state", busy=0, status=CA_STATUS[status],
                                  bytes_done=done)
        self._irq(ch, access_done=1)

    #: docs/ports.md: a custom CRC (code 3) runs 1..16 bits; code 3 with another width is
    #: invalid (word 1: when enabled).
    CUSTOM_CODE, CUSTOM_WIDTHS = 3, range(1, 17)

    def config_error(self, ch):
        """The rules of docs/ports.md this model keeps: an MA half period of 2 or more, and a
        custom CRC (code 3) of 1..16 bits on word 0 and on word 1 when enabled; the enabled
        words are words 0..N-1 with no gap (docs/bus.md, Chains), each chain word in the frame
        with 1..its caps data bits and a valid custom CRC."""
        cfg = self.cfg(ch)
        words = (0, 1) if cfg["w1_enable"] else (0,)
        chain = self.chain_enabled(ch)
        gap = chain != list(range(2, 2 + len(chain))) or (chain and not cfg["w1_enable"])
        return cfg["ma_half_period"] < 2 or bool(gap) or any(
            cfg[f"w{w}_crc"] == self.CUSTOM_CODE and cfg[f"w{w}_crc_width"] not in
            self.CUSTOM_WIDTHS for w in words) or any(
            not 1 <= c["data_bits"] <= self.chain_bits[w] or
            (c["crc"] == self.CUSTOM_CODE and c["crc_width"] not in self.CUSTOM_WIDTHS)
            for w in chain for c in [self.chain_cfg(ch, w)])

    def configure_chain(self, ch, w, **values):
        """Set chain word ``w``'s settings (fields of cfg_wW, _crc, _crc_start) directly."""
        for end in ("", "_crc", "_crc_start"):
            path = f"cfg_w{w}{end}"
            a = MAP.address(path, ch)
            for k, v in values.items():
                if k in MAP.channel[path].fields:
                    self.words[a] = MAP.channel[path].fields[k].put(self.words.get(a, 0), v)

    def configure(self, ch, **values):
        """Set configuration (and ctrl) fields directly: the test's own setup."""
        for path in ("cfg_ma", "cfg_period", "cfg_break", "cfg_ack", "cfg_timeout",
                     "cfg_words", "cfg_checks", "cfg_crc0", "cfg_crc0_start", "cfg_crc1",
                     "cfg_crc1_start", "ctrl"):
            mine = {k: v for k, v in values.items() if k in MAP.channel[path].fields}
            if mine:
                a = MAP.address(path, ch)
                word = self.words.get(a, 0)
                for k, v in mine.items():
                    word = MAP.channel[path].fields[k].put(word, v)
                self.words[a] = word


class FakeBridge(MemoryBridge):
    """MemoryBridge on a :class:`RegisterModel` (``model``)."""

    def __init__(self, model=None, **kw):
        super().__init__(timeout_s=1000 / 115200, **kw)
        self.model = self.registers = model or RegisterModel()


def biss_c_board(bits=26, ma_half_period=50, **model_kw):
    """A fake board whose channel 0 is configured for a BiSS C word of ``bits``."""
    model = RegisterModel(**model_kw)
    model.configure(0, ma_half_period=ma_half_period, w0_data_bits=bits, w0_nenw=1, w0_crc=1)
    return FakeBridge(model)
