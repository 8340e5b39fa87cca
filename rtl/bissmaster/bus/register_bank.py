"""The register bank of the bus tops, built from the register map (:mod:`bissmaster.bus.regmap`).

Nothing here names a register: every register, field, reset value, access kind and the signal
a field connects to come from the SystemRDL source, walked into a
:class:`~bissmaster.bus.regmap.RegisterMap`. The bank has one simple internal bus
(:class:`RegisterBus`, what the AXI4-Lite and Wishbone adapters drive) and, per channel and for
the global registers, one interface whose members are the map's signals.
"""

from amaranth.hdl import *
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .regmap import DATA_WIDTH, Kind, window_ports

STROBES = DATA_WIDTH // 8


class RegisterBus(wiring.Signature):
    """The bank's internal bus, as the initiator (a bus adapter) sees it.

    Word addresses. A write is issued by ``w_en`` high for one clock, byte lanes chosen by
    ``w_strb``; the bank registers it and it acts in the next clock (a pulse is high in the
    second clock after ``w_en``; a configuration register, one stage later, holds the new
    value from the third clock after ``w_en``, unless it holds pulses too; a channel's held
    configuration from the fourth, or after its core's cycle: see ``w_busy``). ``w_busy`` is
    high while the last write has not acted yet: the initiator issues no ``w_en`` while it is
    high, and answers a write once it is low in a clock after its ``w_en``; everything the
    write did is then visible. A read takes two steps, so that the address decode and the word select each have a clock of their own.
    ``r_en`` high in one clock: the address is decoded into a one-hot select, and a window's
    read enable acts then. ``r_load`` high in a later clock, at the latest the clock of the
    next ``r_en``: the selected register's value in that clock goes to ``r_data``, which holds
    it from the next clock until the clock after the next ``r_load``; a snapshot is taken
    then. So reads run one per clock (each ``r_load`` with the next ``r_en``), and the
    initiator can hold a word while the next read waits in the first step. A read and a write
    may come in the same clock; they are not ordered: the read returns the value of its
    ``r_load`` clock, the one before the write when ``r_load`` follows ``r_en`` at once.
    """

    def __init__(self, addr_width):
        self.addr_width = addr_width
        super().__init__({
            "r_en": Out(1),
            "r_addr": Out(addr_width),
            "r_load": Out(1),
            "r_data": In(DATA_WIDTH),
            "w_en": Out(1),
            "w_addr": Out(addr_width),
            "w_data": Out(DATA_WIDTH),
            "w_strb": Out(STROBES),
            "w_busy": In(1),
        })


def block_signature(regmap, registers):
    """The hardware side of a block of registers, seen from the bank: a member per signal of
    the map (:meth:`RegisterMap.signals`); the bank drives configuration and pulses, and reads
    live values and interrupt events."""
    members = {}
    for name, (kind, width) in regmap.signals(registers).items():
        members[name] = Out(width) if kind in (Kind.CONFIG, Kind.PULSE) else In(width)
    ports = [reg.window_ports for reg in registers if reg.window]
    ports += [window_ports(name, count, False)
              for name, (_, count) in regmap.memories(registers).items()]
    for window in ports:
        members.update({name: Out(width) if out else In(width)
                        for name, (out, width) in window.items()})
    return wiring.Signature(members)


class RegisterBank(wiring.Component):
    """The register map in hardware, for ``channels`` channel slots.

    Field kinds (:class:`~bissmaster.bus.regmap.Kind`): CONFIG fields are registers with their
    reset values, written per byte lane; PULSE fields give a registered one-clock pulse for
    each 1 written and read 0; LIVE fields read their signal (a snapshot group reads a copy
    taken when its first register is read); CONST fields read their reset value (and so does
    a CONFIG field whose signal the channel's core does not have, ``absent``: no storage, its
    writes ignored); IRQ fields
    are sticky, set by their event and cleared by writing 1, a set winning over a clear in the
    same clock. Unmapped addresses read 0 and ignore writes. A window (an external register
    array) is a memory's port: a write of word ``i`` writes its strobed byte lanes to word ``i``
    (``<window>_en`` = the strobes, in the clock of the write); a read of word ``i`` enables
    the memory's registered read port in the ``r_en`` clock, and its data goes to ``r_data``
    at ``r_load``, as a register's word does (the port must hold it until its next read).
    Memory registers (``memory`` = NAME: the counters) are read the same way, as one read
    window over their words; their fields only document the word.

    Configuration read-back: a register of configuration only (CONFIG fields, CONST fields)
    is read from a memory of its block, written with its flip-flops, not from the block's
    read AND-OR (issue 27: the flip-flops feed the core every clock, the memory answers the
    bus; ``_shadow``). It reads exactly what the flip-flops hold, in the same clock.

    Held configuration (``held``, the bus tops: the settings their ``config_hold`` cores read
    through a cycle without a copy): a write of a register with such a field waits, at its
    second stage, for its channel's core to be idle (``cfg_free``), and holds the core in IDLE
    (``cfg_hold``) while it waits; its flip-flops (and the read-back memory) take it in the
    clock after the first clock both are true (the core is still held in IDLE then), so a
    cycle never sees its configuration change. ``w_busy`` covers the wait: the next write,
    and the bus's answer to this one, wait for it (up to the end of the cycle the core is
    in).

    Tables (``tables``, the bus tops' CRC table: settings a ``crc_table`` core reads one word
    at a time): a CONFIG field whose signal a channel's ``tables`` names is not a flip-flop but
    bits ``lsb ..`` of entry ``entry`` of that channel's table, a memory written with the
    field's held write (its byte lanes) and read combinationally by the core
    (``ch<n>_<table>_addr`` -> ``ch<n>_<table>_data``: an asynchronous read, a distributed
    RAM's read port on ECP5, Xilinx and Intel). A memory keeps its contents through a reset:
    after one, the bank writes every entry with its fields' reset values, one entry per clock,
    holding the core in IDLE (``cfg_hold``) and any held write until it is done. Read-back is
    the configuration memory's, as for every configuration-only register; on iCE40 (no
    distributed RAM, no configuration memory) the fields stay flip-flops and the table read
    is a multiplexer over them. A table field must be held, lie in a configuration-only
    register, and fill one byte lane's bits or whole aligned bytes.

    Writes: the request (``w_en``, address, data, strobes) is registered, and every write
    decodes from those flip-flops in the next clock. CONFIG fields are written one clock later
    still, lane by lane, from a per-register write flip-flop and a second copy of the data and
    strobes, each byte lane's strobe the enable of its flip-flops; those of a register that
    holds pulses too (``ctrl``) are written with its pulses, in one stage. The read path is two
    register stages (:class:`RegisterBus`): at ``r_en`` one select flip-flop per register (and
    per read window) registers whether the address is the register's; at ``r_load`` each block
    (the globals, each channel) registers the AND-OR of its registers' words with their
    selects and the data of its window read, and ``r_data`` is the OR of the blocks'
    registers. A snapshot group is copied at the ``r_load`` of its first register, which
    reads the live values copied; the group's other registers read the copy, so every word of
    the group read after the first belongs to the same snapshot.

    Parameters
    ----------
    regmap : RegisterMap
    channels : int
    absent : sequence of sets of str, one per channel, optional
        The signals of CONFIG fields that the channel's core does not have (a one-word build's
        word 1, a build without SSI or register access): those fields are not stored.
    held : sequence of sets of str, one per channel, optional
        The signals of CONFIG fields that the channel's core reads without a copy: a register
        with one of them is written only while the core is idle (above).
    tables : sequence of dicts, one per channel, optional
        ``{signal: (table, entry, lsb)}``: the CONFIG fields stored in the channel's tables
        (above); every table named gets the ports ``ch<n>_<table>_addr`` and ``_data``.

    Attributes
    ----------
    bus : In(RegisterBus)
    glob : Out(block_signature)
        The global registers' signals.
    ch0 .. ch<channels-1> : Out(block_signature)
        Each channel's signals.
    irq : Out(channels)
        Per channel: a cause is set in its IRQ fields and enabled.
    cfg_hold : Out(channels)
        Per channel: a write of its held configuration waits; keep the core in IDLE.
    cfg_free : In(channels)
        Per channel: its core is idle (not ``busy``); a waiting write acts in the next clock.
    """

    def __init__(self, regmap, channels, absent=None, held=None, tables=None):
        if not isinstance(channels, int) or not 1 <= channels <= regmap.channel_slots:
            raise ValueError(f"channels must be an integer from 1 to {regmap.channel_slots}, "
                             f"not {channels!r}")
        self.regmap = regmap
        self.channels = channels
        self.absent = [frozenset(a) for a in (absent or [()] * channels)]
        if len(self.absent) != channels:
            raise ValueError(f"absent must name one set per channel ({channels})")
        self.held = [frozenset(h) for h in (held or [()] * channels)]
        if len(self.held) != channels:
            raise ValueError(f"held must name one set per channel ({channels})")
        self.tables = [dict(t) for t in (tables or [{}] * channels)]
        if len(self.tables) != channels:
            raise ValueError(f"tables must give one mapping per channel ({channels})")
        table_members = {}
        kinds = regmap.signals(regmap.channel) if any(self.tables) else {}
        for n, table in enumerate(self.tables):
            signals = {}
            for signal, (name, entry, lsb) in table.items():
                kind, width = kinds.get(signal, (None, 0))
                if kind != Kind.CONFIG or signal not in self.held[n]:
                    raise ValueError(f"channel {n}: table field {signal!r} is not a held "
                                     f"configuration signal of the map")
                signals.setdefault(name, []).append((entry, lsb, width))
            for name, fields in signals.items():
                entries = max(e for e, _, _ in fields) + 1
                width = max(lsb + w for _, lsb, w in fields)
                table_members[f"ch{n}_{name}_addr"] = In(range(entries))
                table_members[f"ch{n}_{name}_data"] = Out(width)
        members = {
            "bus": In(RegisterBus(regmap.addr_width - 2)),
            "glob": Out(block_signature(regmap, regmap.globals)),
            **{f"ch{n}": Out(block_signature(regmap, regmap.channel)) for n in range(channels)},
            "irq": Out(channels),
            "cfg_hold": Out(channels),
            "cfg_free": In(channels),
            **table_members,
        }
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        rm = self.regmap
        # The configuration memories read asynchronously: distributed RAM on ECP5, Xilinx and
        # Intel. iCE40 has none, and its block RAM's address register cannot hold the reset
        # value every Amaranth register has: for an iCE40 platform (the board designs,
        # ``--family ice40``) the configuration is read back from its flip-flops.
        self._config_memory = getattr(platform, "family", None) != "iCE40"
        blocks = [(self.glob, 0, rm.globals, "g", frozenset(), None)]
        blocks += [(getattr(self, f"ch{n}"), rm.channel_base + n * rm.channel_stride,
                    rm.channel, f"ch{n}", self.absent[n], n) for n in range(self.channels)]
        # The write request, registered: every write decodes from these flip-flops, in the
        # clock after w_en, so that no path runs from the bus through the decode.
        bus = self.bus
        self._w_en = Signal(name="write_en")
        self._w_addr = Signal.like(bus.w_addr, name="write_addr")
        self._w_data = Signal.like(bus.w_data, name="write_data")
        self._w_strb = Signal.like(bus.w_strb, name="write_strb")
        m.d.sync += self._w_en.eq(bus.w_en)
        with m.If(bus.w_en):
            m.d.sync += [self._w_addr.eq(bus.w_addr), self._w_data.eq(bus.w_data),
                         self._w_strb.eq(bus.w_strb)]
        # CONFIG fields are written one clock later still, from a second copy of the data and
        # strobes and a per-register write flip-flop decoded from the first stage: with several
        # channels the shared word decode in front of every configuration register's enable
        # was a critical path (docs/performance.md).
        self._w2_data = Signal.like(bus.w_data, name="config_write_data")
        self._w2_strb = Signal.like(bus.w_strb, name="config_write_strb")
        with m.If(self._w_en):
            m.d.sync += [self._w2_data.eq(self._w_data), self._w2_strb.eq(self._w_strb)]
        # The configuration read-back memories' logic shared by blocks of one layout and one
        # set of absent signals (every channel of a top of one core build): ``_shadow``.
        self._shadow_shared = {}
        # Block-relative word addresses: the bits below the channel stride.
        self._block_bits = (rm.channel_stride // 4 - 1).bit_length()
        partials = []                  # each block's registered share of the read data
        irqs = []
        waiting = []                   # per channel with held registers: a write waits
        for port, base, registers, prefix, absent, channel in blocks:
            read_words, windows, snapshots = {}, [], {}
            irq = self._block(m, port, base, registers, prefix, read_words, windows, snapshots,
                              absent, channel, waiting)
            if prefix != "g":
                irqs.append(irq)
            selects = self._read_select(m, prefix, read_words)
            # A snapshot group is copied at the r_load of its first register (its select
            # flip-flop and r_load, no address decode in front of the copies' enable); that
            # register reads the live values, the very ones copied.
            for word, copies in snapshots.items():
                with m.If(selects[word] & self.bus.r_load):
                    m.d.sync += copies
            partials.append(self._read_partial(m, prefix, selects, read_words, windows))
        # Whole signals, never bit by bit: Icarus runs a combinational block written per bit
        # only once an input changes, and would read X until then.
        m.d.comb += self.irq.eq(Cat(irqs))
        # The next write (and the answer to this one) waits for this one to act.
        m.d.comb += bus.w_busy.eq(self._w_en | Cat(waiting).any())
        merged = 0
        for partial in partials:
            merged = merged | partial
        m.d.comb += self.bus.r_data.eq(merged)
        return m

    def _block(self, m, port, base, registers, prefix, read_words, windows, snapshots,
               absent, channel, waiting):
        """One block (the globals or a channel): storage, pulses, interrupts, windows and its
        read words; ``snapshots`` gets, per snapshot group, the word address of the register
        that takes it and the copies' assignments; CONFIG fields of ``absent`` signals read
        their reset value. A channel's registers of held configuration wait for its core
        (``waiting`` gets the block's wait flag). Returns the block's interrupt request."""
        held = frozenset() if channel is None else self.held[channel] - absent
        tables = {} if channel is None else {
            signal: place for signal, place in self.tables[channel].items()
            if signal not in absent}
        held_regs = [reg for reg in registers
                     if not reg.window and not reg.memory
                     and not any(f.kind == Kind.PULSE for f in reg.fields)
                     and any(f.kind == Kind.CONFIG and f.signal in held for f in reg.fields)]
        clearing = C(0)                # the tables' clear after reset (``_tables``)
        if held_regs:
            # A held write waits from its second stage until the core is idle, then acts in
            # the next clock (``go``, one clock, a flip-flop: no path from the core's state
            # into the write enables). The core is held from the first clock of the wait to
            # the clock of ``go``, so it is still idle then. The write request's flip-flops
            # hold the write meanwhile (``w_busy``).
            wait = Signal(name=f"{prefix}_config_wait")
            go = Signal(name=f"{prefix}_config_go")
            # After a reset the tables are written with their reset values first (``_tables``).
            clearing = (Signal(name=f"{prefix}_table_clearing", init=1)
                        if tables and self._config_memory else C(0))
            m.d.sync += go.eq(wait & ~go & self.cfg_free[channel] & ~clearing)
            m.d.comb += self.cfg_hold[channel].eq(wait | clearing)
            waiting.append(wait)
        bus = self.bus
        w_en, w_addr, w_data, w_strb = self._w_en, self._w_addr, self._w_data, self._w_strb
        held_writes = []               # the first-stage writes of the held registers
        storage = {}                   # "register.field" -> the Signal that holds it
        table_writes = []              # (field, its write enable, entry place) of table fields
        irq_terms = []
        # Registers of configuration only (read back from a memory, ``_shadow``).
        shadowed = [reg for reg in registers
                    if self._config_memory and self._shadowable(reg, absent)]
        shadow_writes = {}             # register path -> its config_write
        groups = {}                    # group -> the copies' assignments
        take = {}                      # group -> the word address of its first register
        for name, (offset, count) in self.regmap.memories(registers).items():
            self._read_window(m, port, name, (base + offset) // 4, count, windows, memory=True)
        for reg in registers:
            word = (base + reg.offset) // 4
            if reg.window:
                self._window(m, port, word, reg, windows)
                continue
            if reg.memory:
                continue
            reg_name = f"{prefix}_{reg.path.replace('.', '_')}"
            write = Signal(name=f"{reg_name}_write")
            m.d.comb += write.eq(w_en & (w_addr == word))
            # A register that holds pulses too (``ctrl``) is written in one stage, so that a
            # write of it acts all at once (``start`` with ``periodic``).
            staged = not any(f.kind == Kind.PULSE for f in reg.fields)
            config_write = None
            if reg in held_regs:
                # Addressed by the waiting write (the address holds until it has acted),
                # written when the core is idle.
                addressed = Signal(name=f"{reg_name}_config_addressed")
                m.d.sync += addressed.eq(w_addr == word)
                held_writes.append(write)
                config_write = Signal(name=f"{reg_name}_config_write")
                m.d.comb += config_write.eq(addressed & go)
            elif staged and any(f.kind == Kind.CONFIG for f in reg.fields):
                config_write = Signal(name=f"{reg_name}_config_write")
                m.d.sync += config_write.eq(write)
            parts = []                 # (lsb, the field's read value)
            for f in reg.fields:
                name = f"{reg_name}_{f.name}"
                data = w_data[f.lsb:f.lsb + f.width]
                # Bit i of the field is written only if its byte lane's strobe is set.
                lanes = Cat(w_strb[(f.lsb + i) // 8] for i in range(f.width))
                if f.kind == Kind.CONFIG and f.signal in absent:
                    # The core has no such setting: nothing to store (reads its reset value).
                    parts.append((f.lsb, C(f.reset, f.width)))
                    m.d.comb += self._signal(port, f).eq(f.reset)
                elif f.kind == Kind.CONFIG and f.signal in tables and self._config_memory:
                    # Stored in the channel's table: the memory's write (``_tables``); read
                    # back from the configuration memory.
                    if reg not in shadowed or reg not in held_regs:
                        raise ValueError(f"{reg.path}.{f.name}: a table field must be held and "
                                         f"in a register of configuration only")
                    table_writes.append((f, config_write, tables[f.signal]))
                elif f.kind == Kind.CONFIG:
                    reg_bits = Signal(f.width, init=f.reset, name=name)
                    storage[f"{reg.path}.{f.name}"] = reg_bits
                    # Lane by lane: each lane's strobe enables its flip-flops, no logic per bit.
                    if staged:
                        en, strb = config_write, self._w2_strb
                        data = self._w2_data[f.lsb:f.lsb + f.width]
                    else:
                        en, strb = write, w_strb
                    for lo, hi, lane in self._lanes(f):
                        with m.If(en & strb[lane]):
                            m.d.sync += reg_bits[lo:hi].eq(data[lo:hi])
                    parts.append((f.lsb, reg_bits))
                    if f.signal in tables:
                        # iCE40: the table is these flip-flops, read by a multiplexer.
                        table_writes.append((f, reg_bits, tables[f.signal]))
                    elif f.signal:
                        m.d.comb += self._signal(port, f).eq(reg_bits)
                elif f.kind == Kind.PULSE:
                    pulse = Signal(f.width, name=name)
                    m.d.sync += pulse.eq(Mux(write, data & lanes, 0))
                    m.d.comb += self._signal(port, f).eq(pulse)
                elif f.kind == Kind.CONST:
                    parts.append((f.lsb, C(f.reset, f.width)))
                elif f.kind == Kind.IRQ:
                    status = Signal(f.width, init=f.reset, name=name)
                    event = self._signal(port, f) if f.signal else C(0, f.width)
                    clear = Mux(write, data & lanes, 0)
                    for i in range(f.width):
                        # A set wins over a clear in the same clock. Conditions, not logic:
                        # an event that reads X in a four-state simulator then sets nothing.
                        with m.If(event[i]):
                            m.d.sync += status[i].eq(1)
                        with m.Elif(clear[i]):
                            m.d.sync += status[i].eq(0)
                    parts.append((f.lsb, status))
                    irq_terms.append((status, f.enable))
                elif f.kind == Kind.LIVE:
                    live = self._signal(port, f)
                    if reg.snapshot is None:
                        parts.append((f.lsb, live))
                    else:
                        copy = Signal(f.width, init=f.reset, name=f"{name}_snapshot")
                        groups.setdefault(reg.snapshot, []).append(copy.eq(live))
                        # The register that takes the snapshot reads the live value, copied
                        # in the clock it is read (r_load); the group's others read the copy.
                        parts.append((f.lsb, live if reg.takes_snapshot else copy))
            if reg.takes_snapshot:
                take[reg.snapshot] = word
            if reg in shadowed:
                shadow_writes[reg.path] = config_write
                continue
            read_words[word] = self._word(parts)
        for group, copies in groups.items():
            snapshots[take[group]] = copies
        if held_regs:
            # A write of a held register starts the wait; ``go`` ends it.
            with m.If(Cat(held_writes).any()):
                m.d.sync += wait.eq(1)
            with m.Elif(go):
                m.d.sync += wait.eq(0)
        if shadowed:
            self._shadow(m, base, registers, shadowed, shadow_writes, absent, prefix, windows)
        if table_writes:
            self._tables(m, channel, prefix, table_writes, clearing)
        # A cause requests an interrupt while set and enabled.
        irq = Signal(name=f"{prefix}_irq")
        m.d.comb += irq.eq(Cat((status & storage[enable]).any()
                               for status, enable in irq_terms if enable).any())
        return irq

    def _tables(self, m, channel, prefix, table_writes, clearing):
        """A channel's tables (class docstring, Tables): per table, one memory per field
        position (the same field of every entry), written with the field's held write and
        read asynchronously at ``ch<n>_<table>_addr``; on iCE40 ``table_writes`` holds each
        field's flip-flops instead, read by compares with the address."""
        sweep = None
        if self._config_memory:
            # After a reset, every entry is written with its reset values, one per clock.
            entries = max(entry for _, _, (_, entry, _) in table_writes) + 1
            sweep = Signal(range(entries), name=f"{prefix}_table_sweep")
            with m.If(clearing):
                m.d.sync += sweep.eq(sweep + 1)
                with m.If(sweep == entries - 1):
                    m.d.sync += clearing.eq(0)
        by_table = {}
        for f, source, (name, entry, lsb) in table_writes:
            by_table.setdefault(name, {}).setdefault(lsb, []).append((entry, f, source))
        for name, groups in by_table.items():
            addr = getattr(self, f"ch{channel}_{name}_addr")
            out = getattr(self, f"ch{channel}_{name}_data")
            value = C(0, len(out))
            for lsb, fields in sorted(groups.items()):
                if self._config_memory:
                    data = self._table_memory(m, f"{prefix}_{name}_{lsb}", addr, fields,
                                              clearing, sweep)
                else:
                    data = 0
                    for entry, _, bits in fields:
                        data = data | Mux(addr == entry, bits, 0)
                value = value | (Value.cast(data) << lsb)
            m.d.comb += out.eq(value)

    def _table_memory(self, m, name, addr, fields, clearing, sweep):
        """One field position of a table: a memory of one entry per word, written by the
        field's register writes (its byte lanes) or, while ``clearing``, with the entry's
        reset value at the sweep's entry; returns its asynchronous read at ``addr``."""
        f0 = fields[0][1]
        if any(f.lsb != f0.lsb or f.width != f0.width for _, f, _ in fields):
            raise ValueError(f"{name}: a table field has the same bits in every entry's register")
        lanes = [lane for _, _, lane in self._lanes(f0)]
        if len(lanes) > 1 and (f0.lsb % 8 or f0.width % 8):
            raise ValueError(f"{name}: a table field fills one byte lane or whole aligned bytes")
        depth = max(entry for entry, _, _ in fields) + 1
        memory = Memory(shape=f0.width, depth=depth, init=[])
        m.submodules[f"{name}_table"] = memory
        wr = memory.write_port(granularity=8 if len(lanes) > 1 else None)
        writes = Cat(write for _, _, write in fields)
        entry = Signal(range(depth), name=f"{name}_table_write_entry")
        reset = C(0, f0.width)
        for at, f, write in fields:
            with m.If(write):
                m.d.comb += entry.eq(at)
            if f.reset:
                reset = reset | Mux(sweep == at, f.reset, 0)
        strobes = Cat(self._w2_strb[lane] for lane in lanes)
        m.d.comb += [
            wr.addr.eq(Mux(clearing, sweep, entry)),
            wr.data.eq(Mux(clearing, reset, self._w2_data[f0.lsb:f0.lsb + f0.width])),
            wr.en.eq(Mux(clearing, 2**len(wr.en) - 1, Mux(writes.any(), strobes, 0))),
        ]
        rd = memory.read_port(domain="comb")
        m.d.comb += rd.addr.eq(addr)
        return rd.data

    @staticmethod
    def _shadowable(reg, absent):
        """A register of configuration only (CONFIG and CONST fields, at least one CONFIG field
        stored): read back from the block's configuration memory (``_shadow``)."""
        if reg.window or reg.memory:
            return False
        return (all(f.kind in (Kind.CONFIG, Kind.CONST) for f in reg.fields)
                and any(f.kind == Kind.CONFIG and f.signal not in absent for f in reg.fields))

    @staticmethod
    def _shadow_constants(reg, absent):
        """``(mask, reset, const)`` of a configuration-only register: the bits of its stored
        fields, their reset values, and the value of its fields read as constants (CONST
        fields, CONFIG fields the core lacks)."""
        mask = reset = const = 0
        for f in reg.fields:
            bits = ((1 << f.width) - 1) << f.lsb
            if f.kind == Kind.CONFIG and f.signal not in absent:
                mask |= bits
                reset |= (f.reset << f.lsb) & bits
            else:
                const |= (f.reset << f.lsb) & bits
        return mask, reset, const

    def _shadow(self, m, base, registers, shadowed, shadow_writes, absent, prefix, windows):
        """The read-back of a block's configuration-only registers from a memory (issue 27),
        instead of their flip-flops' words in the block's read AND-OR: every write of such a
        register writes its strobed byte lanes, stored fields only, into the memory as well,
        in the clock its flip-flops take it; a read of it reads the memory through an
        asynchronous port at ``r_load``, addressed by a register set at ``r_en``, so it
        returns the value of its ``r_load`` clock as a flip-flop's word does. Yosys maps it to
        distributed RAM and no LUT on ECP5 (an address register and an asynchronous read is
        its 16x4 RAM's read port), and to RAM32M on Xilinx and MLABs on Cyclone V; not built
        for iCE40 (no distributed RAM; ``elaborate``).

        A memory keeps its contents through a reset, the flip-flops do not: one flag per
        register says it was written since reset. Until then it reads its reset value, and
        its first write fills the lanes it does not strobe with their reset values."""
        count = len(shadowed)
        mask, reset, const = zip(*(self._shadow_constants(reg, absent) for reg in shadowed))
        data, r_index, r_shadow = self._shadow_common(m, registers, shadowed, absent, mask,
                                                      reset)
        low = self._block_bits
        bus = self.bus
        writes = Cat(shadow_writes[reg.path] for reg in shadowed)
        written = Signal(count, name=f"{prefix}_config_written")
        m.d.sync += written.eq(written | writes)
        memory = Memory(shape=DATA_WIDTH, depth=count, init=[])
        m.submodules[f"{prefix}_config_memory"] = memory
        wr = memory.write_port(granularity=8)
        first = (writes & ~written).any()
        m.d.comb += [
            wr.addr.eq(Cat(Cat(writes[k] for k in range(count) if k >> b & 1).any()
                           for b in range(len(wr.addr)))),
            wr.data.eq(data),
            wr.en.eq(Mux(writes.any(), self._w2_strb | first.replicate(len(wr.en)), 0)),
        ]
        # The read: the register's index taken at r_en, the memory read at r_load.
        hit = Signal(name=f"{prefix}_config_read")
        m.d.comb += hit.eq(bus.r_en & (bus.r_addr[low:] == base // 4 >> low) & r_shadow)
        index = Signal(range(count), name=f"{prefix}_config_read_index")
        with m.If(hit):
            m.d.sync += index.eq(r_index)
        rd = memory.read_port(domain="comb")
        m.d.comb += rd.addr.eq(index)
        value = Signal(DATA_WIDTH, name=f"{prefix}_config_read_data")
        # The register's constants by compares with the index, not an Array (a case block in
        # the Verilog, which Icarus runs only once an input changes: README Notes).
        unwritten, fixed = 0, 0
        for k in range(count):
            if reset[k]:
                unwritten = unwritten | Mux(index == k, reset[k], 0)
            if const[k]:
                fixed = fixed | Mux(index == k, const[k], 0)
        m.d.comb += value.eq(Mux(written.bit_select(index, 1), rd.data, unwritten) | fixed)
        windows.append((hit, value))

    def _shadow_common(self, m, registers, shadowed, absent, mask, reset):
        """What the configuration memories of every block of one layout and one absent set
        share: the data to write (at the second write stage, with the other configuration
        data: the strobed lanes masked to the register's stored fields, the others its reset
        value), and, from the read address at r_en, whether it names such a register and its
        index. Returns ``(data, r_index, r_shadow)``."""
        key = (tuple(reg.path for reg in registers), frozenset(absent))
        if key in self._shadow_shared:
            return self._shadow_shared[key]
        low = self._block_bits
        n = len(self._shadow_shared)
        words = [reg.offset // 4 for reg in shadowed]
        w_mask = Signal(DATA_WIDTH, name=f"config_memory{n}_write_mask")
        w_fill = Signal(DATA_WIDTH, name=f"config_memory{n}_write_fill")
        with m.Switch(self._w_addr[:low]):
            for word, mk, rs in zip(words, mask, reset):
                with m.Case(word):
                    m.d.comb += [w_mask.eq(mk), w_fill.eq(rs)]
        data = Signal(DATA_WIDTH, name=f"config_memory{n}_write_data")
        lanes = Cat(self._w_strb[i // 8] for i in range(DATA_WIDTH))
        with m.If(self._w_en):
            m.d.sync += data.eq((self._w_data & w_mask & lanes) | (w_fill & ~lanes))
        r_index = Signal(range(len(shadowed)), name=f"config_memory{n}_read_index")
        r_shadow = Signal(name=f"config_memory{n}_read_hit")
        with m.Switch(self.bus.r_addr[:low]):
            for k, word in enumerate(words):
                with m.Case(word):
                    m.d.comb += [r_index.eq(k), r_shadow.eq(1)]
        self._shadow_shared[key] = data, r_index, r_shadow
        return data, r_index, r_shadow

    def _read_select(self, m, prefix, read_words):
        """Read stage 1 of one block: at ``r_en``, one flip-flop per register, set when the
        address is the register's (all clear when no register is addressed). Returns
        ``{word address: select}``.

        One-hot selects and an AND-OR, not a switch on the address: Yosys maps a switch on the
        address bits inside the block as a binary multiplexer tree twice as large, and the
        decode then sits in the same clock as the AND-OR."""
        selects = {}
        for addr in read_words:
            select = Signal(name=f"{prefix}_read_select_{addr:x}")
            with m.If(self.bus.r_en):
                m.d.sync += select.eq(self.bus.r_addr == addr)
            selects[addr] = select
        return selects

    def _read_partial(self, m, prefix, selects, read_words, windows):
        """Read stage 2 of one block: at ``r_load``, the word of the block's register selected
        (a one-hot AND-OR; 0 when none is) or the registered data of the block's window that
        was read, into the block's own flip-flops. The bank's read data is the OR of the
        blocks' (at most one is not 0): one register per block instead of one AND-OR over
        the whole bank in front of one register, so that with several channels no read path
        spans every channel's registers."""
        pairs = [(selects[addr], value) for addr, value in read_words.items()]
        for n, (read, window_data) in enumerate(windows):
            chosen = Signal(name=f"{prefix}_window{n}_read")
            with m.If(self.bus.r_en):
                m.d.sync += chosen.eq(read)
            pairs.append((chosen, window_data))
        merged = 0
        for chosen, value in pairs:
            merged = merged | Mux(chosen, value, 0)
        partial = Signal(DATA_WIDTH, name=f"{prefix}_read_data")
        with m.If(self.bus.r_load):
            m.d.sync += partial.eq(merged)
        return partial

    def _window(self, m, port, word, reg, windows):
        """A window: the bus's word address inside it, its strobes or read enable, its data."""
        if not reg.writable:
            self._read_window(m, port, reg.window, word, reg.count, windows)
            return
        bits = self._window_bits(reg.path, word, reg.count)
        ports = {name[len(reg.window) + 1:]: getattr(port, name) for name in reg.window_ports}
        hit = self._w_en & (self._w_addr[bits:] == word >> bits)
        m.d.comb += [ports["addr"].eq(self._w_addr[:bits]), ports["data"].eq(self._w_data),
                     ports["en"].eq(Mux(hit, self._w_strb, 0))]

    def _read_window(self, m, port, name, word, count, windows, memory=False):
        """A read window (or a memory's registers) of ``count`` words from word ``word``: the
        bus's word address inside it and its read enable; its data joins ``windows``. A
        memory's registers may be fewer than the power of two they are aligned to (the
        chain words: 12 of 16): the words above them are not the memory's."""
        bus = self.bus
        bits = self._window_bits(name, word, 1 << (count - 1).bit_length() if memory else count)
        ports = {p[len(name) + 1:]: getattr(port, p) for p in window_ports(name, count, False)}
        hit = bus.r_en & (bus.r_addr[bits:] == word >> bits)
        if count != 1 << bits:
            hit &= bus.r_addr[:bits] < count
        m.d.comb += [ports["addr"].eq(bus.r_addr[:bits]), ports["en"].eq(hit)]
        windows.append((hit, ports["data"]))

    @staticmethod
    def _window_bits(name, word, count):
        bits = (count - 1).bit_length()
        if count != 1 << bits or word % count:
            raise ValueError(f"{name}: a window has a power-of-two number of words and is "
                             f"aligned to its size")
        return bits

    @staticmethod
    def _signal(port, f):
        """The bits of ``port``'s signal that field ``f`` holds (the signal itself when the
        field holds all of it)."""
        signal = getattr(port, f.signal)
        if f.signal_lsb == 0 and f.width == len(signal):
            return signal
        return signal[f.signal_lsb:f.signal_lsb + f.width]

    @staticmethod
    def _lanes(f):
        """``(lo, hi, lane)``: the bits ``lo:hi`` of field ``f`` that byte lane ``lane`` holds."""
        at = 0
        while at < f.width:
            lane = (f.lsb + at) // 8
            hi = min(f.width, (lane + 1) * 8 - f.lsb)
            yield at, hi, lane
            at = hi

    @staticmethod
    def _word(parts):
        """A register's read value from its fields' ``(lsb, value)``, 0 between fields."""
        pieces, at = [], 0
        for lsb, value in sorted(parts, key=lambda p: p[0]):
            if lsb > at:
                pieces.append(C(0, lsb - at))
            pieces.append(value)
            at = lsb + len(value)
        if at < DATA_WIDTH:
            pieces.append(C(0, DATA_WIDTH - at))
        return Cat(pieces)
