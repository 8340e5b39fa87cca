"""The C driver (sw/, ``libbissmaster.so``) called through ctypes, its bus hooks served by a
bus model of the simulation.

The driver is the software under test: the scenarios (sim/scenarios/driver.py) call its
functions as a CPU would and check what it returns against the encoder models, never against
the driver's own tables. Its structs are mirrored here field by field from
sw/include/biss_master.h (a field out of place reads as garbage, which the checks catch).

How a blocking C call meets the simulation (cocotb 2.x): :meth:`CDriver.call` runs the C
function in a thread with ``cocotb.task.bridge``; the driver calls its read/write hooks, ctypes
callbacks that block that thread on ``cocotb.task.resume(bus.read / bus.write)`` while the
simulation performs the AXI4-Lite transaction. An exception in a hook (a bus error response)
is kept and raised when the C call returns: ctypes itself would only print it.
"""

import ctypes
from ctypes import (CFUNCTYPE, POINTER, Structure, byref, c_bool, c_char_p, c_int, c_int64,
                    c_size_t, c_uint, c_uint8, c_uint16, c_uint32, c_uint64, c_void_p)

#: BISS_CHAIN_WORDS: words 2..7 of a chain.
CHAIN_WORDS = 6

READ32 = CFUNCTYPE(c_uint32, c_void_p, c_size_t)             # uintptr_t is size_t wide here
WRITE32 = CFUNCTYPE(None, c_void_p, c_size_t, c_uint32)


class Bus(Structure):
    _fields_ = [("base", c_size_t), ("read32", READ32), ("write32", WRITE32), ("ctx", c_void_p)]


class Channel(Structure):
    _fields_ = [("bus", Bus), ("base", c_size_t), ("index", c_uint8),
                ("max_data_bits", c_uint8 * 2), ("timer_width", c_uint8),
                ("has_counters", c_bool), ("has_timestamp", c_bool),
                ("has_register_access", c_bool), ("max_polls", c_uint32), ("has_ssi", c_bool),
                ("words", c_uint8), ("chain_data_bits", c_uint8 * CHAIN_WORDS),
                ("chain_words", c_uint8)]


class WordFormat(Structure):
    _fields_ = [("data_bits", c_uint8), ("crc", c_uint8), ("nenw", c_bool), ("lc", c_bool),
                ("gray", c_bool), ("crc_inverted", c_bool), ("crc_width", c_uint8),
                ("crc_poly", c_uint16), ("crc_start", c_uint16), ("is_signed", c_bool)]


class Config(Structure):
    _fields_ = [("ma_half_period", c_uint16), ("delay_limit", c_uint16),
                ("request_period", c_uint32), ("break_time", c_uint32),
                ("ack_limit", c_uint32), ("timeout_limit", c_uint32),
                ("word", WordFormat * 2), ("word1_enable", c_bool), ("end_check", c_bool),
                ("spw_check", c_bool), ("spw_tolerance", c_uint8),
                ("quiet_time", c_uint16), ("noise_limit", c_uint8), ("delay_tolerance", c_uint8),
                ("confirm_frames", c_uint8), ("ssi", c_bool), ("ssi_error", c_bool),
                ("ssi_error_low", c_bool), ("ssi_double", c_bool), ("ssi_delay", c_uint16),
                ("chain_words", c_uint8), ("chain", WordFormat * CHAIN_WORDS)]


class Preset(Structure):
    _fields_ = [("name", c_char_p), ("words", c_uint8), ("word", WordFormat * 2),
                ("spw_check", c_bool), ("spw_tolerance", c_uint8)]


class State(Structure):
    _fields_ = [(n, c_bool) for n in ("busy", "config_error", "periodic", "trigger_enable")]


class WordResult(Structure):
    """biss_word_result_t: a chain word's result."""
    _fields_ = [("data", c_uint64), ("ne", c_bool), ("nw", c_bool), ("crc_ok", c_bool)]


class Result(Structure):
    _fields_ = [("word0", c_uint64), ("word1", c_uint64), ("timestamp", c_uint32),
                ("seq", c_uint16), ("line_delay", c_uint16), ("status", c_uint8),
                ("lc", c_uint8)] + [(n, c_bool) for n in (
                    "cds", "w0_ne", "w0_nw", "w0_crc_ok", "w1_ne", "w1_nw", "w1_crc_ok",
                    "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch")] + [
                ("noise_events", c_uint8), ("delay_settled", c_bool), ("settled_delay", c_uint16),
                ("delay_spread", c_uint8), ("chain_words", c_uint8),
                ("chain", WordResult * CHAIN_WORDS)]

    def as_dict(self):
        """The keys of ``BusTestbench.result`` (``time`` for the timestamp), so that
        ``BusTestbench.check_result`` judges it against the encoder model; the chain words
        read as ``word<N>``, ``w<N>_ne``, ``w<N>_nw``, ``w<N>_crc_ok`` (N = 2 ..)."""
        d = {name: int(getattr(self, name)) for name, _ in self._fields_ if name != "chain"}
        d["time"] = d.pop("timestamp")
        for i in range(self.chain_words):
            w = self.chain[i]
            d.update({f"word{i + 2}": int(w.data), f"w{i + 2}_ne": int(w.ne),
                      f"w{i + 2}_nw": int(w.nw), f"w{i + 2}_crc_ok": int(w.crc_ok)})
        return d


#: biss_counters_t, in its field order.
COUNTER_FIELDS = ("crc_word0", "crc_word1", "no_ack", "no_start", "delay_range", "slo_stuck_low",
                  "lc_repeat", "lc_skip", "lc_zero", "spw_mismatch", "overrun", "aborted",
                  "no_stop", "noisy_line", "delay_jump", "noise_event")


class Counters(Structure):
    _fields_ = [(n, c_uint16) for n in COUNTER_FIELDS] + [("crc_chain", c_uint16 * CHAIN_WORDS)]


class Bp3Id(Structure):
    _fields_ = [(n, c_uint8) for n in ("version", "crc_mode", "data_length", "position_bits")]


#: biss_bp3_eds_t, in its field order, with each field's C type.
BP3_EDS_FIELDS = (
    [(n, c_uint8) for n in ("bp_ver", "bp_len", "bp_id", "dl", "fb1", "fb2", "pon_pdl",
                            "en_typ", "pos_num", "mt_len", "mt_fmt", "co_len", "co_fmt",
                            "fi_len", "fi_fmt")]
    + [(n, c_uint32) for n in ("mt_cnt", "sip_cnt", "sip_res", "cpoly", "cstart")]
    + [(n, c_uint16) for n in ("abs_acu", "rel_acu", "spd_acu", "hyst", "spd_max", "acc_max",
                               "tmp_min", "tmp_max", "vlt_min", "vlt_max", "cur_max")]
    + [(n, c_uint8) for n in ("chksum", "eds_bank", "profile_bank")])


class Bp3Eds(Structure):
    _fields_ = BP3_EDS_FIELDS

    def as_dict(self):
        return {name: int(getattr(self, name)) for name, _ in self._fields_}


#: Every struct of biss_master.h this module mirrors, by its C name: the layout check
#: (tb/tests/bus/test_driver.py) compares each one's size and every field's offset with the
#: C compiler's.
STRUCTS = {"biss_bus_t": Bus, "biss_channel_t": Channel, "biss_word_format_t": WordFormat,
           "biss_config_t": Config, "biss_preset_t": Preset, "biss_state_t": State,
           "biss_word_result_t": WordResult, "biss_result_t": Result,
           "biss_counters_t": Counters, "biss_bp3_id_t": Bp3Id, "biss_bp3_eds_t": Bp3Eds}


_P = POINTER
#: Every function of biss_master.h: (restype, argtypes).
PROTOTYPES = {
    "biss_error_name": (c_char_p, [c_int]),
    "biss_status_name": (c_char_p, [c_uint]),
    "biss_probe": (c_int, [_P(Bus), _P(c_uint)]),
    "biss_trigger": (c_int, [_P(Bus)]),
    "biss_irq_pending": (c_uint32, [_P(Bus)]),
    "biss_channel_init": (c_int, [_P(Channel), _P(Bus), c_uint]),
    "biss_preset_count": (c_uint, []),
    "biss_preset_at": (_P(Preset), [c_uint]),
    "biss_preset_find": (_P(Preset), [c_char_p]),
    "biss_config_from_preset": (c_int, [_P(Config), c_char_p, c_uint32, c_uint32]),
    "biss_config_check": (c_int, [_P(Channel), _P(Config)]),
    "biss_configure": (c_int, [_P(Channel), _P(Config)]),
    "biss_crc_named": (c_int, [_P(WordFormat), c_uint]),
    "biss_configure_preset": (c_int, [_P(Channel), c_char_p, c_uint32, c_uint32]),
    "biss_start": (c_int, [_P(Channel)]),
    "biss_abort": (c_int, [_P(Channel)]),
    "biss_clear_counters": (c_int, [_P(Channel)]),
    "biss_set_periodic": (c_int, [_P(Channel), c_bool, c_uint32]),
    "biss_set_trigger_enable": (c_int, [_P(Channel), c_bool]),
    "biss_read_state": (c_int, [_P(Channel), _P(State)]),
    "biss_wait_done": (c_int, [_P(Channel), c_uint32]),
    "biss_read_result": (c_int, [_P(Channel), _P(Result)]),
    "biss_signed_data": (c_int64, [_P(Channel), c_uint, c_uint64]),
    "biss_read_counters": (c_int, [_P(Channel), _P(Counters)]),
    "biss_irq_enable": (c_int, [_P(Channel), c_uint32]),
    "biss_irq_status": (c_uint32, [_P(Channel)]),
    "biss_irq_clear": (c_int, [_P(Channel), c_uint32]),
    "biss_reg_read": (c_int, [_P(Channel), c_uint, c_uint, _P(c_uint8), c_uint, _P(c_uint)]),
    "biss_reg_write": (c_int, [_P(Channel), c_uint, c_uint, _P(c_uint8), c_uint, _P(c_uint)]),
    "biss_reg_abort": (c_int, [_P(Channel)]),
    "biss_bp3_decode_id": (c_int, [c_uint8, c_uint8, _P(Bp3Id)]),
    "biss_bp3_identify": (c_int, [_P(Channel), c_uint, _P(Bp3Id)]),
    "biss_bp3_decode_eds": (c_int, [_P(c_uint8), _P(Bp3Eds)]),
    "biss_bp3_read_eds": (c_int, [_P(Channel), c_uint, c_uint, _P(Bp3Eds)]),
    "biss_bp3_config": (c_int, [_P(Bp3Eds), _P(Config)]),
}


def load(path):
    """The library at ``path`` with every prototype declared."""
    lib = ctypes.CDLL(str(path))
    for name, (restype, argtypes) in PROTOTYPES.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = restype, argtypes
    return lib


class CDriver:
    """The driver on one bus model (``read(addr)`` / ``write(addr, value)`` coroutines, e.g.
    ``bus_testbench.AxiLiteBus``) at byte address ``base``."""

    def __init__(self, lib_path, bus_model, base=0):
        self.lib = load(lib_path)
        self.model = bus_model
        self.transactions = 0
        self._hook_error = None
        # Kept as attributes: ctypes callbacks must outlive every call that may use them.
        self._read32, self._write32 = READ32(self._read_hook), WRITE32(self._write_hook)
        self.bus = Bus(base, self._read32, self._write32, None)

    def _read_hook(self, ctx, addr):
        from cocotb.task import resume
        try:
            self.transactions += 1
            return resume(self.model.read)(addr)
        except BaseException as e:          # noqa: BLE001 - re-raised by call()
            self._hook_error = self._hook_error or e
            return 0

    def _write_hook(self, ctx, addr, value):
        from cocotb.task import resume
        try:
            self.transactions += 1
            resume(self.model.write)(addr, value)
        except BaseException as e:          # noqa: BLE001 - re-raised by call()
            self._hook_error = self._hook_error or e

    async def call(self, name, *args):
        """``name(*args)`` of the library, run as a CPU would while the simulation goes on."""
        from cocotb.task import bridge
        fn = getattr(self.lib, name)
        self._hook_error = None

        def blocking():                     # bridge() wants a Python function (__qualname__)
            return fn(*args)
        ret = await bridge(blocking)()
        if self._hook_error is not None:
            raise self._hook_error
        return ret

    def error_name(self, code):
        return self.lib.biss_error_name(code).decode()

    async def check(self, name, *args):
        """``call``, and fail unless it returns BISS_OK."""
        ret = await self.call(name, *args)
        assert ret == 0, f"{name}: {self.error_name(ret)}"
        return ret

    # -- The handful of calls the scenarios make often ------------------------------------
    async def channel(self, index):
        ch = Channel()
        await self.check("biss_channel_init", byref(ch), byref(self.bus), index)
        return ch

    async def result(self, ch):
        res = Result()
        await self.check("biss_read_result", byref(ch), byref(res))
        return res.as_dict()

    async def reg_read(self, ch, address, count, slave_id=0):
        """biss_reg_read: (error name, the bytes done)."""
        buf, done = (c_uint8 * count)(), c_uint()
        ret = await self.call("biss_reg_read", byref(ch), slave_id, address, buf, count,
                              byref(done))
        return self.error_name(ret), bytes(buf[:done.value])

    async def reg_write(self, ch, address, data, slave_id=0):
        """biss_reg_write: (error name, bytes done)."""
        buf, done = (c_uint8 * len(data)).from_buffer_copy(bytes(data)), c_uint()
        ret = await self.call("biss_reg_write", byref(ch), slave_id, address, buf, len(data),
                              byref(done))
        return self.error_name(ret), done.value

    async def counters(self, ch):
        """biss_read_counters as a dict: COUNTER_FIELDS, and words 2..7's as crc_word2 ..
        crc_word7."""
        cnt = Counters()
        await self.check("biss_read_counters", byref(ch), byref(cnt))
        return {**{n: getattr(cnt, n) for n in COUNTER_FIELDS},
                **{f"crc_word{i + 2}": cnt.crc_chain[i] for i in range(CHAIN_WORDS)}}
