"""A board with the BiSS master's register map, as the host tool sees it.

:class:`Board` does over a :class:`~bissmaster.host.link.Link` what the C driver does over a
CPU bus (docs/driver.md), with the register map of :mod:`.regmap`: probe the core, read and
write a channel's configuration, request cycles (the global software trigger, or the core's
periodic requests) and read their results through the result snapshot, read the counters, and
read and write encoder registers through the register-access engine of the control channel.

Time: a board waits (polling, pacing samples) with ``sleep`` and reads ``now`` of its clock,
which is the transport's when it has one (``MemoryBridge``'s virtual time; a simulator's
``now``, with its ``sleep``) and the computer's otherwise, so the same code runs on a real port,
against the software model and in a simulation.
"""

import re
import time
from dataclasses import dataclass, field

from . import regmap
from .link import LinkError

__all__ = ["BoardError", "NoBoardError", "NotTheCoreError", "CapabilityError",
           "EncoderSilentError", "AccessError", "TornReadError", "Result", "ChainWord", "Frame",
           "Board"]


# -- Errors -----------------------------------------------------------------------------------

class BoardError(Exception):
    """A board operation that cannot go on; the message says why."""


class NoBoardError(BoardError):
    """Nothing answers on the line (the PING went unanswered every time)."""


class NotTheCoreError(BoardError):
    """Something answers, but its ``id`` / ``version`` / ``channels`` are not this core's."""


class CapabilityError(BoardError):
    """The build lacks what was asked for (a channel, the register-access engine)."""


class EncoderSilentError(BoardError):
    """The encoder does not answer: a register access with NO_ANSWER, or one that never ends."""


class AccessError(BoardError):
    """A register access of the control channel ended with a status other than OK.
    ``status`` is its name (docs/control.md, Statuses)."""

    def __init__(self, message, status):
        super().__init__(message)
        self.status = status


class TornReadError(BoardError):
    """Every try of a chain read (:data:`READ_TRIES`) saw ``chain.updates`` change: a frame
    ended during each, so no try was of one frame."""


# -- Chain words (words 2..7) -----------------------------------------------------------------

#: Tries of a chain read before :class:`TornReadError` (the C driver's BISS_READ_RETRIES).
READ_TRIES = 8


def _per_chain_word(registers):
    """``{word: (register, field)}``: the fields of ``registers`` (two words to a register,
    low field first) dealt to words 2..7 in order (caps_chain*, count_chain*)."""
    slots = [(register, name) for register in registers
             for name, _ in sorted(regmap.FIELDS[register].items(), key=lambda f: f[1][0])]
    return dict(zip(regmap.CHAIN_WORDS, slots))


#: Where each chain word's longest data field (caps) and CRC count are.
CHAIN_CAPS = _per_chain_word(("caps_chain", "caps_chain2"))
CHAIN_COUNTS = _per_chain_word(regmap.CHAIN_COUNTER_REGISTERS)


def chain_settings(word):
    """``{setting: (register, field)}`` of chain word ``word``: its settings are named
    ``wW_<field>`` after the fields of cfg_wW, cfg_wW_crc and cfg_wW_crc_start
    (``w2_data_bits``, ``w2_enable``, ``w2_crc_poly``, ...)."""
    return {f"w{word}_{name}": (register, name)
            for register in regmap.CHAIN_CONFIG_RUNS[word - regmap.CHAIN_WORDS[0]]
            for name in regmap.FIELDS[register]}


def setting_register(name):
    """``(register, field)`` of a configuration setting: a field of the configuration
    registers (``w0_data_bits``, or its port name ``cfg_w0_data_bits``: regmap.config_field),
    or a chain word's (``w2_data_bits``, :func:`chain_settings`). KeyError if none."""
    bare = name[4:] if name.startswith("cfg_") else name
    m = re.fullmatch(r"w(\d+)_(\w+)", bare)
    if m and int(m.group(1)) in regmap.CHAIN_WORDS:
        # ``wW_signed`` as words 0 and 1 name it (the field is is_signed: SystemRDL
        # reserves ``signed``).
        field_name = "is_signed" if m.group(2) == "signed" else m.group(2)
        found = chain_settings(int(m.group(1))).get(f"w{m.group(1)}_{field_name}")
        if found:
            return found
    try:
        return regmap.config_field(name)
    except KeyError as e:
        first, last = regmap.CHAIN_WORDS[0], regmap.CHAIN_WORDS[-1]
        chain = ", ".join(f"w{first}..{last}_" + n.split("_", 1)[1]
                          for n in chain_settings(first))
        raise KeyError(f"{e.args[0]}; chain words: {chain}") from None


# -- Results ----------------------------------------------------------------------------------

#: Statuses of the host's own, beside the core's: a triggered cycle whose ``done`` did not come
#: in time; in free-running mode, a sample without a cycle ended since the previous one.
NO_RESULT = ("TIMEOUT", "NO_NEW_RESULT")

@dataclass
class Result:
    """One result of a channel (the result block, one snapshot), and when the host took it.

    ``status`` is the status's name, or one of :data:`NO_RESULT`. The frame fields (positions, nE/nW, CRC verdicts, LC, line delay) are new
    only when :attr:`frame` is true; otherwise they are the last decoded frame's. ``chain``:
    the enabled chain words read, ``{word: ChainWord}`` (read with the snapshot as one frame).
    """
    channel: int
    time_s: float
    status: str
    seq: int = 0
    position: int = 0
    ne: int = 0
    nw: int = 0
    crc_ok: int = 0
    word1: int | None = None
    w1_ne: int = 0
    w1_nw: int = 0
    w1_crc_ok: int = 0
    lc: int = 0
    cds: int = 0
    line_delay: int = 0
    timestamp: int = 0
    chain: dict = field(default_factory=dict)

    @property
    def frame(self):
        return self.status in regmap.FRAME_STATUSES

    @property
    def encoder_silent(self):
        return self.status in regmap.NO_ENCODER_STATUSES or self.status in NO_RESULT


@dataclass
class ChainWord:
    """One chain word's result (``chain.wW_lo/_hi`` and its ``chain.flags``)."""
    data: int
    ne: int
    nw: int
    crc_ok: int


@dataclass(frozen=True)
class Frame:
    """A channel's configured frame as the tool reads it: ``two_words`` (word 1 enabled),
    ``chain`` (the enabled chain words, in order) and ``signed``: ``{word: bits}``, the width
    a two's-complement word is sign-extended from (its register's, from caps), 0 if unsigned."""
    two_words: bool
    chain: tuple = ()
    signed: dict = field(default_factory=dict)


def signed_data(data, bits):
    """A word's data as a signed number, for a word configured ``cfg_words.wN_signed``: the core
    has sign-extended the field to its register's width, ``bits`` (``caps.data_bits_wN``,
    docs/ports.md); this extends it on to Python's integers (as the C driver's
    ``biss_signed_data``). ``bits`` 0: ``data`` unchanged."""
    if not bits:
        return data
    data &= (1 << bits) - 1
    return data - (1 << bits) if data >> (bits - 1) else data


def decode_result(channel, words, time_s, two_words):
    """A :class:`Result` from the seven words of the result block (address order)."""
    w = dict(zip(regmap.RESULT_REGISTERS, words))
    st = regmap.get("result.status", w["result.status"])
    seq = regmap.get("result.seq", w["result.seq"])
    pos = w["result.w0_lo"] | regmap.get("result.w0_hi", w["result.w0_hi"], "data") << 32
    word1 = w["result.w1_lo"] | regmap.get("result.w1_hi", w["result.w1_hi"], "data") << 32
    return Result(
        channel=channel, time_s=time_s,
        status=regmap.STATUS_NAME.get(st["status"], f"STATUS_{st['status']}"),
        seq=seq["seq"], position=pos, ne=st["w0_ne"], nw=st["w0_nw"], crc_ok=st["w0_crc_ok"],
        word1=word1 if two_words else None, w1_ne=st["w1_ne"], w1_nw=st["w1_nw"],
        w1_crc_ok=st["w1_crc_ok"], lc=st["lc"], cds=st["cds"], line_delay=seq["line_delay"],
        timestamp=w["result.timestamp"])


#: Read after the chain words, in one burst: their flags, then the closing read of the update
#: count (the map puts ``chain.flags`` just below ``chain.updates`` for it).
CHAIN_CLOSING_REGISTERS = ("chain.flags", "chain.updates")


def chain_result_registers(chain):
    """The chain data registers to read for the chain words ``chain``, in address order:
    every word's lo / hi up to the last of ``chain`` (one burst)."""
    if not chain:
        return ()
    return tuple(f"chain.w{w}_{half}" for w in range(regmap.CHAIN_WORDS[0], max(chain) + 1)
                 for half in ("lo", "hi"))


def decode_chain(words, flags_word, chain):
    """``{word: ChainWord}`` of the chain words ``chain`` from the words of
    :func:`chain_result_registers` and ``chain.flags``."""
    w = dict(zip(chain_result_registers(chain), words))
    flags = regmap.get("chain.flags", flags_word)
    out = {}
    for word in chain:
        lo_reg, hi_reg = f"chain.w{word}_lo", f"chain.w{word}_hi"
        lo_width = regmap.FIELDS[lo_reg]["data"][1]
        data = (regmap.get(lo_reg, w[lo_reg], "data")
                | regmap.get(hi_reg, w[hi_reg], "data") << lo_width)
        out[word] = ChainWord(data, *(flags[f"w{word}_{k}"] for k in ("ne", "nw", "crc_ok")))
    return out


# -- The board --------------------------------------------------------------------------------

class Board:
    """The register map behind ``link``.

    Parameters
    ----------
    link : bissmaster.host.link.Link
    sleep, now : callable, optional
        The clock (see the module's docstring); default: the transport's, else ``time``'s.
    poll_s : float
        Pause between two polls of a register that waits for the hardware.
    """

    def __init__(self, link, *, sleep=None, now=None, poll_s=2e-4):
        self.link = link
        transport = link.transport
        self.poll_s = poll_s
        if now is None:
            t = getattr(transport, "now", None)
            if t is None:
                now = time.monotonic
            else:
                now = (lambda: transport.now()) if callable(t) else (lambda: transport.now)
        if sleep is None:
            if hasattr(transport, "sleep"):
                sleep = transport.sleep
            elif isinstance(getattr(transport, "now", None), (int, float)):
                def sleep(s):                   # virtual time (MemoryBridge): let it pass
                    transport.now += max(s, 0.0)
            else:
                sleep = time.sleep
        self.now, self.sleep = now, sleep
        self.channels = None
        self._caps = {}
        self._word_caps = {}

    # -- Registers ----------------------------------------------------------------------------
    def read(self, register, ch=None):
        return self.link.read32(regmap.address(register, ch))

    def read_fields(self, register, ch=None):
        return regmap.get(register, self.read(register, ch))

    def write(self, register, value, ch=None):
        self.link.write32(regmap.address(register, ch), value)

    def write_fields(self, register, ch=None, **values):
        """Write ``register`` with the fields given, the others 0."""
        self.write(register, regmap.put(register, 0, **values), ch)

    def update(self, register, ch=None, **values):
        """Read ``register``, change the fields given, write it back (pulses read 0: a
        ``ctrl`` update starts nothing unless asked)."""
        self.write(register, regmap.put(register, self.read(register, ch), **values), ch)

    def read_block(self, registers, ch):
        """Consecutive registers (names in address order) in one READ_BURST."""
        first = regmap.address(registers[0], ch)
        assert [regmap.address(r, ch) for r in registers] == \
            [first + 4 * i for i in range(len(registers))], registers
        return self.link.read_burst(first, len(registers))

    # -- Probe --------------------------------------------------------------------------------
    def probe(self):
        """PING, then ``id``, ``version`` and ``channels``: ``{"version": (major, minor),
        "channels": n}``. Raises :class:`NoBoardError` if the PING is never answered (only
        timeouts), :class:`~bissmaster.host.link.LinkError` if answers come but are damaged,
        :class:`NotTheCoreError` if the registers are not this core's."""
        try:
            self.link.ping()
        except LinkError as e:
            s = self.link.stats
            if s["garbled"] == 0 and s["BAD_CRC"] == 0:
                raise NoBoardError(f"the board does not answer: {e}") from None
            raise
        ident, version, channels = self.link.read_burst(regmap.GLOBALS["id"], 3)
        if ident != regmap.ID_VALUE:
            raise NotTheCoreError(f"id reads {ident:#010x}, not {regmap.ID_VALUE:#010x} "
                                  f"(\"BiSS\"): not a BiSS master register map")
        v = regmap.get("version", version)
        if v["major"] != regmap.MAP_MAJOR:
            raise NotTheCoreError(f"register map version {v['major']}.{v['minor']}: this tool "
                                  f"reads version {regmap.MAP_MAJOR}.x")
        n = regmap.get("channels", channels, "count")
        if not 1 <= n <= regmap.MAX_CHANNELS:
            raise NotTheCoreError(f"channels reads {n}: 1..{regmap.MAX_CHANNELS} expected")
        self.channels = n
        return {"version": (v["major"], v["minor"]), "channels": n}

    def check_channel(self, ch):
        if self.channels is None:
            self.probe()
        if not 0 <= ch < self.channels:
            raise CapabilityError(f"channel {ch}: this build has channels 0.."
                                  f"{self.channels - 1}")

    def caps(self, ch):
        if ch not in self._caps:
            self._caps[ch] = self.read_fields("caps", ch)
        return self._caps[ch]

    def words(self, ch):
        """``caps.words``: the data words channel ``ch``'s build decodes, 1..8 (a map without
        the field, reading 0, counts as 1 or 2 from ``caps.data_bits_w1``, as the C driver)."""
        caps = self.caps(ch)
        return caps["words"] or (2 if caps["data_bits_w1"] else 1)

    def chain_words(self, ch):
        """The chain words (2..7) channel ``ch``'s build has."""
        return tuple(w for w in regmap.CHAIN_WORDS if w < self.words(ch))

    def word_caps(self, ch):
        """``{word: longest data field}`` of every word the build has: caps.data_bits_w0 /
        _w1, and caps_chain / caps_chain2 (each read once) for the chain words."""
        if ch not in self._word_caps:
            caps = self.caps(ch)
            bits = {0: caps["data_bits_w0"], 1: caps["data_bits_w1"]}
            read = {}
            for w in self.chain_words(ch):
                register, name = CHAIN_CAPS[w]
                if register not in read:
                    read[register] = self.read_fields(register, ch)
                bits[w] = read[register][name]
            self._word_caps[ch] = bits
        return self._word_caps[ch]

    def frame(self, ch):
        """The :class:`Frame` channel ``ch`` is configured for (cfg_words, each chain word's
        cfg_wW)."""
        cfg = self.read_fields("cfg_words", ch)
        enabled = {0: 1, 1: cfg["w1_enable"]}
        signed = {0: cfg["w0_signed"], 1: cfg["w1_signed"]}
        for w in self.chain_words(ch):
            word = self.read_fields(f"cfg_w{w}", ch)
            enabled[w], signed[w] = word["enable"], word["is_signed"]
        caps = self.word_caps(ch)
        return Frame(two_words=bool(enabled[1]),
                     chain=tuple(w for w in self.chain_words(ch) if enabled[w]),
                     signed={w: caps[w] if signed[w] else 0 for w in enabled})

    # -- Configuration ------------------------------------------------------------------------
    def config(self, ch):
        """Every configuration field of channel ``ch``, ``{field: value}``: the configuration
        registers' and those of each chain word the build has (``wW_<field>``)."""
        settings = {}
        for run in regmap.CONFIG_RUNS:
            for register, word in zip(run, self.read_block(run, ch)):
                settings.update(regmap.get(register, word))
        for w in self.chain_words(ch):
            run = regmap.CHAIN_CONFIG_RUNS[w - regmap.CHAIN_WORDS[0]]
            for register, word in zip(run, self.read_block(run, ch)):
                settings.update({f"w{w}_{k}": v for k, v in regmap.get(register, word).items()})
        return settings

    def configure(self, ch, settings):
        """Write configuration fields (``{field or cfg_port: value}``, a chain word's as
        ``wW_<field>``): each register touched is read, changed and written once. Returns
        ``state.config_error`` afterwards."""
        by_register = {}
        for name, value in settings.items():
            register, field = setting_register(name)
            by_register.setdefault(register, {})[field] = value
        registers = regmap.CONFIG_REGISTERS + sum(regmap.CHAIN_CONFIG_RUNS, ())
        for register in registers:                      # check every value before writing
            if register in by_register:
                regmap.put(register, 0, **by_register[register])
        for register in registers:
            if register in by_register:
                fields = by_register[register]
                if len(fields) == len(regmap.FIELDS[register]):
                    self.write_fields(register, ch, **fields)
                else:
                    self.update(register, ch, **fields)
        return self.read_fields("state", ch)["config_error"]

    # -- Results and counters -----------------------------------------------------------------
    def result(self, ch, frame=None):
        """The last result of channel ``ch`` for its :class:`Frame` (default: read from its
        configuration). One READ_BURST of the result block (its first register takes the
        snapshot); with chain words, the consistency rule of docs/bus.md ("Chains"), as the C
        driver's ``biss_read_result``: ``chain.updates``, the result block, the chain words
        (one burst), ``chain.updates`` again; equal counts mean one frame, else the set is
        read again (the second count the next try's first), :data:`READ_TRIES` tries in all,
        then :class:`TornReadError`."""
        if frame is None:
            frame = self.frame(ch)
        if not frame.chain:
            words = self.read_block(regmap.RESULT_REGISTERS, ch)
            return decode_result(ch, words, self.now(), frame.two_words)
        chain_registers = chain_result_registers(frame.chain)
        before = self.read_fields("chain.updates", ch)["updates"]
        for _ in range(READ_TRIES):
            words = self.read_block(regmap.RESULT_REGISTERS, ch)
            chain = self.read_block(chain_registers, ch)
            flags, updates = self.read_block(CHAIN_CLOSING_REGISTERS, ch)
            after = regmap.get("chain.updates", updates, "updates")
            if after == before:
                r = decode_result(ch, words, self.now(), frame.two_words)
                r.chain = decode_chain(chain, flags, frame.chain)
                return r
            before = after
        raise TornReadError(f"channel {ch}: chain.updates changed during each of {READ_TRIES} "
                            f"reads of the result and chain words: a frame ended within "
                            f"every read, none was of one frame")

    def counters(self, ch):
        """The data channel's 13 error counters, each chain word's CRC count the build has
        (``crc_word2`` ..) and the register-access engine's 5, by name (the engine's as
        ``ca_<name>``)."""
        out = {}
        for register, word in zip(regmap.COUNTER_REGISTERS,
                                  self.read_block(regmap.COUNTER_REGISTERS, ch)):
            out.update(regmap.get(register, word))
        chain = self.chain_words(ch)
        if chain:
            registers = tuple(r for r in regmap.CHAIN_COUNTER_REGISTERS
                              if r in {CHAIN_COUNTS[w][0] for w in chain})
            counts = dict(zip(registers, self.read_block(registers, ch)))
            for w in chain:
                register, name = CHAIN_COUNTS[w]
                out[f"crc_word{w}"] = regmap.get(register, counts[register], name)
        for register, word in zip(regmap.CA_COUNTER_REGISTERS,
                                  self.read_block(regmap.CA_COUNTER_REGISTERS, ch)):
            out.update({f"ca_{k}": v for k, v in regmap.get(register, word).items()})
        return out

    def clear_counters(self, ch):
        self.update("ctrl", ch, clear_counters=1)

    # -- Requesting cycles --------------------------------------------------------------------
    def trigger_and_read(self, channels, timeout_s, frames, seqs):
        """One cycle on every channel of ``channels`` at once (``trigger.start``; each must have
        ``ctrl.trigger_enable`` set) and its result. A cycle has ended when ``result.seq``
        (every ended cycle counts) differs from ``seqs[ch]``, the last one seen: the result
        block is read (one burst, one snapshot) until it does, up to ``timeout_s`` (then the
        result is TIMEOUT). Two accesses per channel and sample when the cycle is over by the
        time its result is asked for, as on a serial line it is (with chain words, the reads of
        :meth:`result`). ``frames``: {channel: Frame}; ``seqs`` is updated."""
        self.write_fields("trigger", start=1)
        deadline = self.now() + timeout_s
        results = []
        for ch in channels:
            while True:
                r = self.result(ch, frames[ch])
                if r.seq != seqs[ch]:
                    seqs[ch] = r.seq
                    break
                if self.now() >= deadline:
                    r = Result(ch, self.now(), "TIMEOUT")
                    break
                self.sleep(self.poll_s)
            results.append(r)
        return results

    def _wait_field(self, register, ch, field, timeout_s):
        """Poll until ``register.field`` is 1; False when ``timeout_s`` passes first."""
        deadline = self.now() + timeout_s
        while True:
            if self.read_fields(register, ch)[field]:
                return True
            if self.now() >= deadline:
                return False
            self.sleep(self.poll_s)

    # -- Register access over the control channel ---------------------------------------------
    def _check_access(self, ch, slave_id, address, count):
        if not self.caps(ch)["register_access"]:
            raise CapabilityError(f"channel {ch} was built without the register-access engine "
                                  f"(caps.register_access 0): no control channel")
        if not 0 <= slave_id <= 7:
            raise ValueError(f"slave ID must be 0..7, not {slave_id}")
        if not 1 <= count <= regmap.MAX_ACCESS_BYTES:
            raise ValueError(f"count must be 1..{regmap.MAX_ACCESS_BYTES}, not {count}")
        if not 0 <= address or address + count - 1 >= regmap.ENCODER_REGISTERS:
            raise ValueError(f"registers {address:#04x}..{address + count - 1:#04x}: encoder "
                             f"registers are 0x00..0x{regmap.ENCODER_REGISTERS - 1:02X}")
        if self.read_fields("ca.state", ch)["busy"]:
            raise BoardError(f"channel {ch}: a register access is running (ca.state.busy)")

    def _access(self, ch, slave_id, address, count, write, timeout_s):
        done = regmap.put("irq_status", access_done=1)
        self.write("irq_status", done, ch)
        self.write_fields("ca.request", ch, slave_id=slave_id, address=address, count=count,
                          write=int(write))
        self.write_fields("ca.ctrl", ch, start=1)
        if not self._wait_field("irq_status", ch, "access_done", timeout_s):
            self.write_fields("ca.ctrl", ch, abort=1)
            raise EncoderSilentError(f"channel {ch}: the register access did not end within "
                                     f"{timeout_s:g} s (aborted)")
        self.write("irq_status", done, ch)
        state = self.read_fields("ca.state", ch)
        status = regmap.CA_STATUS_NAME.get(state["status"], str(state["status"]))
        what = (f"{'writing' if write else 'reading'} {count} register(s) from "
                f"{address:#04x} of slave {slave_id}")
        if status == "NO_ANSWER":
            raise EncoderSilentError(f"channel {ch}: {what}: NO_ANSWER, the encoder does not "
                                     f"answer on the control channel (no encoder, or one "
                                     f"without a control side: CDS always 0)")
        if status != "OK":
            hint = {"DATA_FAULT": ": a data-channel cycle during the access did not end OK "
                                  "(configure the channel for the encoder's frame first)",
                    "REFUSED": ": a read-only register, a wrong slave ID, or no such register",
                    "CRC4_ERROR": ": a CRC-4 error on the control channel"}.get(status, "")
            raise AccessError(f"channel {ch}: {what}: {status}{hint}", status)
        if state["bytes_done"] != count:
            raise AccessError(f"channel {ch}: {what}: OK with {state['bytes_done']} byte(s) "
                              f"done of {count}", "SHORT")
        return state

    def reg_read(self, ch, slave_id, address, count, timeout_s=2.0):
        """``count`` encoder registers from ``address`` (one sequential access), as bytes."""
        self._check_access(ch, slave_id, address, count)
        self._access(ch, slave_id, address, count, False, timeout_s)
        words = self.link.read_burst(regmap.address("ca.rbuf", ch), -(-count // 4))
        return b"".join(w.to_bytes(4, "little") for w in words)[:count]

    def reg_write(self, ch, slave_id, address, data, timeout_s=2.0):
        """Write the bytes ``data`` to the encoder's registers from ``address``."""
        data = bytes(data)
        self._check_access(ch, slave_id, address, len(data))
        base = regmap.address("ca.wbuf", ch)
        for i in range(0, len(data), 4):
            self.link.write32(base + i, int.from_bytes(data[i:i + 4].ljust(4, b"\0"), "little"))
        self._access(ch, slave_id, address, len(data), True, timeout_s)
