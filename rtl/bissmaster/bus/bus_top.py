"""The bus tops: ``channels`` BiSS master cores behind one register bank and one bus.

:class:`BusTop` only connects: the bus adapter (:class:`AxiLiteAdapter`,
:class:`WishboneAdapter` or the :class:`~bissmaster.bus.uart_bridge.UartBridge`), the
:class:`~bissmaster.bus.register_bank.RegisterBank` built from the register map, and one
:class:`BusChannel` per channel, each a :class:`~bissmaster.master.BissMaster` with its own
MA/SLO pins.
"""

from dataclasses import dataclass, field, replace

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from . import regmap as regmap_mod
from .bus_adapters import AxiLiteAdapter, AxiLiteSignature, WishboneAdapter, WishboneSignature
from ..master import BissMaster
from ..layouts import COUNT_SETTLE, config_ports
from ..params import COUNTER_HALF_BITS, CRC_TABLE, DATA_BITS_MAX, MAX_WORDS, Crc, MasterParams
from .register_bank import RegisterBank, block_signature
from .uart import divider as uart_divider
from .uart_bridge import DEFAULT_TIMEOUT_BITS, UartBridge, UartSignature, check_timeout_bits


@dataclass(frozen=True)
class Bus:
    """One bus a :class:`BusTop` can have in front of its register bank.

    ``adapter(addr_width, sys_clk_hz, **options)`` builds the adapter onto the bank's
    ``RegisterBus``; ``signature(addr_width)`` is the bus as its initiator sees it (the adapter's
    member ``member`` is its flip), whose members become the top's pins as ``prefix + name``;
    ``options`` are the bus's own elaboration parameters with their defaults, and
    ``check(sys_clk_hz, **options)`` refuses bad ones (ValueError) when the top is made.
    """
    title: str
    adapter: object
    signature: object
    member: str
    prefix: str
    options: dict = field(default_factory=dict)
    check: object = field(default=lambda sys_clk_hz, **options: None)


def _check_uart(sys_clk_hz, baud, timeout_bits):
    uart_divider(sys_clk_hz, baud)
    check_timeout_bits(timeout_bits)


#: The buses, by the name ``--top`` gives them.
BUSES = {
    "axil": Bus("AXI4-Lite", lambda aw, clk: AxiLiteAdapter(aw), AxiLiteSignature, "axil",
                "s_axil_"),
    "wb": Bus("Wishbone B4", lambda aw, clk: WishboneAdapter(aw),
              lambda aw: WishboneSignature(aw - 2), "wb", "wb_"),
    "uart": Bus("UART bridge",
                lambda aw, clk, baud, timeout_bits: UartBridge(
                    aw, sys_clk_hz=clk, baud=baud, timeout_bits=timeout_bits),
                lambda aw: UartSignature(), "uart", "uart_",
                options={"baud": 115200, "timeout_bits": DEFAULT_TIMEOUT_BITS},
                check=_check_uart),
}

#: Channel signals of the register map that the channel makes itself (not core ports).
CHANNEL_GLUE = ("trigger_enable", "frame_done", "frame_error", "done_count", "result_updates",
                *(f"cap_data_bits_w{w}" for w in range(MAX_WORDS)), "cap_words",
                "cap_timer_width", "cap_counters", "cap_timestamp", "cap_register_access",
                "cap_ssi")
#: A core with every port the register map can name: eight words, counters and chain words
#: in memory.
FULL_PARAMS = MasterParams(max_data_bits=(DATA_BITS_MAX,) * MAX_WORDS,
                           word_crcs=((Crc.CRC6, Crc.CRC16),) * MAX_WORDS, counter_ram=True,
                           chain_memory=True)
#: The CRC table's entry for word N (``crc_table``): the map's ``cfg_wN_crc_<field>`` at the
#: bits of :data:`~bissmaster.params.CRC_TABLE`.
CRC_TABLE_NAME = "crc_table"


def crc_table_fields(words):
    """``{signal: (table, entry, lsb)}``: where a ``crc_table`` core of ``words`` words finds
    each word's custom CRC polynomial, start value and inversion (RegisterBank, ``tables``)."""
    return {f"cfg_w{w}_crc_{name}": (CRC_TABLE_NAME, w, field.offset)
            for w in range(words) for name, field in CRC_TABLE}


#: Pulses of the bank taken into a flip-flop beside the core, so they reach it one clock
#: later: the bank's pulse register sits by the bank, and with several channels the route from
#: ``ctrl.abort``'s into a core's controller and timers was the critical path
#: (docs/performance.md). Not ``start`` (it would delay every request; the trigger pin's path
#: does not pass the bank), not ``clear_counters`` (the core's counter bank registers it).
RETIMED_PULSES = ("abort_cycle",)
#: Bits of each count in the register map (two counts per counter register, as in the core's
#: counter memory): :data:`~bissmaster.params.COUNTER_HALF_BITS`. The longest wait of a cycle's
#: end for its counts is :data:`~bissmaster.layouts.COUNT_SETTLE` (docs/ports.md, Counters: a
#: read issued 11 clocks after an event returns it).
COUNT_BITS = COUNTER_HALF_BITS
#: Global signals of the register map, made by the top.
GLOBAL_SIGNALS = ("channels", "trigger", "irq_pending")


#: The settings whose map field may be wider than the core's port, and whose 0 the core
#: refuses (BusChannel): the words' lengths (7 bits, 1..64; 0 is an enabled word of length 0)
#: and the MA half period (16 bits; a narrower ``half_period_width`` build; 0 is below the
#: least half period, 2).
_CUT_TO_ZERO = frozenset([*(f"cfg_w{w}_data_bits" for w in range(MAX_WORDS)),
                          "cfg_ma_half_period"])


class BusChannel(wiring.Component):
    """One channel: a :class:`BissMaster` and the few signals the register map asks beyond the
    core's ports.

    Every signal of the map's channel block is connected by name to the core port of that
    name (``cfg_ma_half_period``, ``start``, ``word0_position``, the counter memory's
    ``count_addr`` / ``count_en`` / ``count_data``, ...), or
    made here (:data:`CHANNEL_GLUE`): the trigger gate, ``frame_done`` (``done``, held until
    the cycle's counts are in the counter memory), ``frame_error`` (the same for a status other
    than OK), ``done_count`` (counts ``frame_done``), ``result_updates`` (counts the core's
    ``done``, in the clock after it: the chain words are read live between two equal counts)
    and the build's capabilities. A signal that only other builds of the core have
    (``word1_position`` in a one-word build, ``word2_position`` .. ``word7_position`` in a
    build of fewer words, the ``ca_*`` ports of the register-access engine in a build
    without it) reads 0 and its configuration is not stored. A core port wider than the map's
    field is refused (e.g. a timer wider than the map's 24-bit time fields; the map holds
    every word up to 64 data bits, so no word length or position is). A word's length field
    wider than the core's ``cfg_w<W>_data_bits`` port (7 bits for a core whose words are all
    shorter than 64 bits, which has a 6-bit port) reaches the core as 0 when its top bit is
    set: a length the build cannot read is then an enabled word of length 0, ``BAD_CONFIG``,
    never a length cut to its low bits. So does a half period longer than a build of a narrower
    ``half_period_width`` holds (0 is below the least half period, 2: ``BAD_CONFIG``).

    Parameters
    ----------
    params : MasterParams
        The core's; a core with counters is built with ``counter_ram`` (the map reads the
        counters from its memory), every core with ``chain_memory`` (the map reads words 2..7
        from its chain memory; no change in a build of one or two words), ``config_hold``
        (the bank writes its configuration only while it is idle) and ``crc_table`` (the
        words' custom CRC polynomials, start values and inversions in the bank's CRC table;
        no change in a one-word build), and one with a
        timestamp with ``time_input`` (the top's one time base), whatever ``params`` says.
    regs : wiring.Signature
        The bank's channel block (:func:`~bissmaster.bus.register_bank.block_signature`).

    Attributes
    ----------
    regs : In(regs)
    trigger : In(1)
        The global trigger; starts the core when ``trigger_enable`` is set.
    time_now : In(timestamp_width)
        Only with a timestamp: the top's time base, captured by the core at its first MA rise.
    ma : Out(1)
    slo : In(1)
    cfg_hold : In(1)
        The bank's write of this channel's configuration waits: keep the core in IDLE.
    cfg_free : Out(1)
        The core is idle: the waiting write acts (the core is built with ``config_hold``).
    crc_table_addr : Out(range(words))
    crc_table_data : In(CRC_TABLE)
        Only in builds of two words or more with custom CRCs: the core's read of the bank's
        CRC table (:func:`crc_table_fields`).
    frame_valid, frame_error : Out(1)
        Only with ``status=True`` (a board's LEDs): one-clock pulses when a cycle ends with a
        valid frame, or with any other status (``frame_error`` of the register map).
    """

    def __init__(self, params, regs, status=False):
        if params.counters:
            if params.counter_width > COUNT_BITS:
                raise ValueError(f"the register map holds {COUNT_BITS}-bit counts; this build's "
                                 f"counter_width is {params.counter_width}")
            # The map reads the data channel's counters from the core's counter memory.
            params = replace(params, counter_ram=True)
        # The map reads words 2..7 from the core's chain memory (none in a two-word build),
        # and the bank writes the core's configuration only while it is idle (no copy per
        # cycle in the core).
        params = replace(params, chain_memory=True, config_hold=True, crc_table=True)
        if params.timestamped:
            # One time base for every channel (BusTop's `time_now`), not a counter per core.
            params = replace(params, time_input=True)
        self.params = params
        self.status = status
        full = BissMaster.ports(FULL_PARAMS)
        core = BissMaster.ports(params)
        #: The map's configuration signals kept in the bank's CRC table (``crc_table``): each
        #: word's custom CRC polynomial, start value and inversion.
        self.table = (crc_table_fields(params.words) if params.crc_table_built else {})
        #: The map's configuration signals this channel's core does not have (word 1 in a
        #: one-word build, SSI or register access in a build without): the bank stores none
        #: of them (:class:`~bissmaster.bus.register_bank.RegisterBank`, ``absent``).
        self.absent = frozenset(name for name, member in regs.members.items()
                                if member.flow == Out and name not in CHANNEL_GLUE
                                and name not in core and name not in self.table)
        #: The map's configuration signals the core reads through its cycles (its ``cfg_*``
        #: ports): the bank writes them only while the core is idle (``held``).
        self.held = frozenset(name for name, _, _ in config_ports(params)
                              if name in regs.members) | frozenset(self.table)
        for name, member in regs.members.items():
            if name in CHANNEL_GLUE:
                continue
            if name not in full:
                raise ValueError(f"the register map names {name!r}, which is neither a port "
                                 f"of biss_master nor a signal of the bus channel")
            held = Shape.cast(member.shape).width
            if name in core and Shape.cast(core[name].shape).width > held:
                raise ValueError(f"the register map holds {held} bits of {name}; "
                                 f"this build's port has {Shape.cast(core[name].shape).width}")
        super().__init__({
            "regs": In(regs),
            "trigger": In(1),
            **({"time_now": In(params.timestamp_width)} if params.timestamped else {}),
            "ma": Out(1, init=1),
            "slo": In(1, init=1),
            "cfg_hold": In(1),
            "cfg_free": Out(1),
            **({"crc_table_addr": Out(range(params.words)), "crc_table_data": In(CRC_TABLE)}
               if self.table else {}),
            **({"frame_valid": Out(1), "frame_error": Out(1)} if status else {}),
        })

    def elaborate(self, platform):
        m = Module()
        p = self.params
        m.submodules.core = core = BissMaster(p, trigger=True)
        regs = self.regs
        # A cycle's end as the host is told of it (irq_status.done and .error, result.seq):
        # the core's `done`, held until its counts are in the counter memory, so that a host
        # reading the counters on the interrupt reads this cycle's (at most 12 clocks later;
        # the next cycle's end reports it at once).
        ended = Signal()
        if p.counter_ram:
            pending, pending_ok = Signal(), Signal()
            waited = Signal(range(COUNT_SETTLE + 1))
            report = Signal()
            m.d.comb += report.eq(pending & (~core.count_busy | core.done
                                             | (waited == COUNT_SETTLE)))
            with m.If(report):
                m.d.sync += pending.eq(0)
            m.d.sync += waited.eq(Mux(pending & ~report, waited + 1, 0))
            with m.If(core.done):
                m.d.sync += [pending.eq(1), pending_ok.eq(core.valid)]
            # Registered, for timing (the decision sits behind the memory's busy).
            ended_ok = Signal()
            m.d.sync += [ended.eq(report), ended_ok.eq(pending_ok)]
        else:
            m.d.comb += ended.eq(core.done)
            ended_ok = core.valid
        glue = {
            "trigger_enable": None,
            "frame_done": ended,
            "frame_error": ended & ~ended_ok,
            "done_count": None,
            "result_updates": None,
            **{f"cap_data_bits_w{w}": p.max_data_bits[w] if w < p.words else 0
               for w in range(MAX_WORDS)},
            "cap_words": p.words,
            "cap_timer_width": p.timer_width,
            "cap_counters": int(p.counters),
            "cap_timestamp": int(p.timestamped),
            "cap_register_access": int(p.register_access),
            "cap_ssi": int(p.ssi),
        }
        # The map's signals, by name: to and from the core's ports, or made here.
        for name, member in regs.signature.members.items():
            signal = getattr(regs, name)
            if name in glue:
                if glue[name] is not None:
                    m.d.comb += signal.eq(glue[name])
            elif name in RETIMED_PULSES and hasattr(core, name):
                m.d.sync += getattr(core, name).eq(signal)
            elif hasattr(core, name):
                port = getattr(core, name)
                if member.flow != In:
                    m.d.comb += signal.eq(port)
                elif name in _CUT_TO_ZERO and len(signal) > len(port):
                    # A value the port cannot hold: 0, which the core refuses (BAD_CONFIG).
                    m.d.comb += port.eq(Mux(signal[len(port):].any(), 0, signal))
                else:
                    m.d.comb += port.eq(signal)

        # Every ended cycle counted, so a host sees a lost result.
        with m.If(ended):
            m.d.sync += regs.done_count.eq(regs.done_count + 1)
        # Every change of the core's result registers (`done`) counted, in the clock after
        # it: reads between two equal counts are of one frame (the chain words, read live).
        with m.If(core.done):
            m.d.sync += regs.result_updates.eq(regs.result_updates + 1)
        # The top's one time base, for the timestamp.
        if p.timestamped:
            m.d.comb += core.time_now.eq(self.time_now)
        # The global trigger starts the core only when enabled.
        m.d.comb += [
            core.trigger.eq(self.trigger & regs.trigger_enable),
            self.ma.eq(core.ma),
            core.slo.eq(self.slo),
            core.cfg_hold.eq(self.cfg_hold),
            self.cfg_free.eq(~core.busy),
        ]
        if self.table:
            m.d.comb += [self.crc_table_addr.eq(core.crc_table_addr),
                         core.crc_table_data.eq(self.crc_table_data)]
        if self.status:
            m.d.comb += [self.frame_valid.eq(core.done & core.valid),
                         self.frame_error.eq(core.done & ~core.valid)]
        return m


class BusTop(wiring.Component):
    """``channels`` BiSS master cores behind AXI4-Lite (``bus="axil"``), Wishbone B4
    (``bus="wb"``) or the UART bridge (``bus="uart"``, docs/uart_bridge.md), with one ``irq``
    and a ``trigger`` input (docs/bus.md). One free-running counter is the time base of every
    channel's timestamp (the cores are built with ``time_input``).

    Parameters
    ----------
    bus : "axil", "wb" or "uart"
    channels : int
        1 .. 8 (the map's channel slots).
    params : MasterParams, or a sequence of one per channel
    regmap : RegisterMap
        Default: :func:`bissmaster.bus.regmap.load` of ``rtl/bissmaster/bus/biss_master.rdl``.
    **options
        The bus's own parameters (:attr:`Bus.options`): for ``"uart"``, ``baud`` (default
        115200) and ``timeout_bits`` (the inter-byte timeout, default 1000), at the cores'
        ``sys_clk_hz``, which every channel must then share.
    status : bool
        Add the ports ``ch<n>_frame_valid`` and ``ch<n>_frame_error`` (one-clock pulses at the
        end of each cycle: a valid frame, or any other status), for a board's status LEDs
        (``bissmaster.boards``). Off by default: the generated bus tops do not have them.

    Attributes
    ----------
    s_axil_*, wb_* or uart_rx / uart_tx : the bus (flat Verilog names)
    trigger : In(1)
        Synchronous to ``clk``: a rising edge starts every trigger-enabled channel, as a write
        to the ``trigger`` register does.
    irq : Out(1)
        Registered: some channel has an enabled interrupt cause set.
    ch<n>_ma : Out(1)
    ch<n>_slo : In(1)
        One MA/SLO pair per channel n (asynchronous SLO, synchronized in each core).
    """

    def __init__(self, bus="axil", channels=2, params=None, regmap=None, status=False,
                 **options):
        if bus not in BUSES:
            raise ValueError(f"bus must be one of {sorted(BUSES)}, not {bus!r}")
        spec = BUSES[bus]
        unknown = set(options) - set(spec.options)
        if unknown:
            raise ValueError(f"bus {bus!r} has no option {sorted(unknown)[0]!r}"
                             + (f" (it takes {', '.join(spec.options)})" if spec.options
                                else ""))
        self.regmap = regmap or regmap_mod.load()
        if not isinstance(channels, int) or not 1 <= channels <= self.regmap.channel_slots:
            raise ValueError(f"channels must be an integer from 1 to "
                             f"{self.regmap.channel_slots}, not {channels!r}")
        if params is None or isinstance(params, MasterParams):
            params = [params or MasterParams()] * channels
        params = list(params)
        if len(params) != channels or not all(isinstance(p, MasterParams) for p in params):
            raise ValueError(f"params must be a MasterParams or one per channel ({channels})")
        self.bus, self.channels, self.params = bus, channels, params
        self.options = {**spec.options, **options}
        if spec.options:            # a bus with parameters of its own may count clocks
            clocks = {p.sys_clk_hz for p in params}
            if len(clocks) != 1:
                raise ValueError(f"the channels of a {spec.title} top share one clock: "
                                 f"sys_clk_hz {sorted(clocks)}")
            self.sys_clk_hz = clocks.pop()
        else:
            self.sys_clk_hz = params[0].sys_clk_hz
        spec.check(self.sys_clk_hz, **self.options)
        unknown = set(self.regmap.signals(self.regmap.globals)) - set(GLOBAL_SIGNALS)
        if unknown:
            raise ValueError(f"the register map's global signals {sorted(unknown)} are not "
                             f"made by the bus top")
        regs = block_signature(self.regmap, self.regmap.channel)
        # Built here, so that a register map the cores cannot follow is refused at once.
        self.status = status
        self._channels = [BusChannel(p, regs, status) for p in params]
        self._bus_members = list(spec.signature(self.regmap.addr_width).flip()
                                 .members.flatten())
        super().__init__({
            **{spec.prefix + path[-1]: member for path, member in self._bus_members},
            "trigger": In(1),
            "irq": Out(1),
            **{f"ch{n}_{pin}": member for n in range(channels)
               for pin, member in (("ma", Out(1, init=1)), ("slo", In(1, init=1)))},
            **{f"ch{n}_{pin}": Out(1) for n in range(channels) if status
               for pin in ("frame_valid", "frame_error")},
        })

    def elaborate(self, platform):
        m = Module()
        spec = BUSES[self.bus]
        member, prefix = spec.member, spec.prefix
        m.submodules.bus = adapter = spec.adapter(self.regmap.addr_width, self.sys_clk_hz,
                                                  **self.options)
        m.submodules.bank = bank = RegisterBank(self.regmap, self.channels,
                                                [c.absent for c in self._channels],
                                                [c.held for c in self._channels],
                                                [c.table for c in self._channels])
        wiring.connect(m, adapter.regs, bank.bus)

        # The bus pins, flat.
        inner = getattr(adapter, member)
        for path, mem in self._bus_members:
            pin, sig = getattr(self, prefix + path[-1]), getattr(inner, path[-1])
            m.d.comb += sig.eq(pin) if mem.flow == In else pin.eq(sig)

        # The global trigger: the register's pulse or the input's rising edge.
        trigger_in = Signal()
        m.d.sync += trigger_in.eq(self.trigger)
        trigger = Signal()
        m.d.comb += trigger.eq(bank.glob.trigger | (self.trigger & ~trigger_in))

        # One time base for every channel's timestamp (the cores capture it at their first MA
        # rise): one counter instead of one per core, and the channels' timestamps are one
        # clock's by construction.
        widths = [p.timestamp_width for p in self.params if p.timestamped]
        if widths:
            time_now = Signal(max(widths), name="time_now")
            m.d.sync += time_now.eq(time_now + 1)

        for n, channel in enumerate(self._channels):
            m.submodules[f"ch{n}"] = channel
            if channel.params.timestamped:
                m.d.comb += channel.time_now.eq(time_now[:channel.params.timestamp_width])
            wiring.connect(m, getattr(bank, f"ch{n}"), channel.regs)
            m.d.comb += [channel.trigger.eq(trigger),
                         channel.cfg_hold.eq(bank.cfg_hold[n]),
                         bank.cfg_free[n].eq(channel.cfg_free),
                         getattr(self, f"ch{n}_ma").eq(channel.ma),
                         channel.slo.eq(getattr(self, f"ch{n}_slo"))]
            if channel.table:
                m.d.comb += [getattr(bank, f"ch{n}_{CRC_TABLE_NAME}_addr").eq(
                                 channel.crc_table_addr),
                             channel.crc_table_data.eq(
                                 getattr(bank, f"ch{n}_{CRC_TABLE_NAME}_data"))]
            if self.status:
                m.d.comb += [getattr(self, f"ch{n}_frame_valid").eq(channel.frame_valid),
                             getattr(self, f"ch{n}_frame_error").eq(channel.frame_error)]

        m.d.comb += [bank.glob.channels.eq(self.channels), bank.glob.irq_pending.eq(bank.irq)]
        m.d.sync += self.irq.eq(bank.irq.any())
        return m
