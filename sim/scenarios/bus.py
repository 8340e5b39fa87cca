"""cocotb scenarios of the bus tops (biss_master_axil, biss_master_wb), two channels.

Run through pytest (sim/test_bus.py) on Verilator and Icarus, each on both buses (the bus
under test comes in ``BISS_BUS``). Registers, fields, reset values and access types are read
from the SystemRDL source (sim/shared/regspec.py); positions are checked against what each
channel's encoder model sent.
"""

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge, Timer

from encoder_model import frames
from master_contract import STATUS
from sim.shared.bus_testbench import BUS, CLK_HZ, BusTestbench
from sim.shared.discovery import only_on_buses

#: The default bus tops have two channels; channel 0 reads a BiSS Safety encoder, channel 1 a
#: BiSS C one (different presets at the same time).
CHANNELS = 2
SAFETY, BISS_C = frames.PRESETS["resolute_fs_rsh"], frames.PRESETS["evolute_36"]
#: Addresses no register answers at (the reserved control-channel window, a gap, the slot of
#: a channel the build lacks, beyond the map): read 0, writes ignored.
UNMAPPED = (0x014, 0x1FC, 0x200 + 0x100, 0x200 + 0x1BC, 0x200 + 0x7C, 0x200 * (CHANNELS + 1),
            0x11FC, 0x1FFC)


def _stored(f):
    """A field software writes and reads back (a configuration register)."""
    return f.sw == "rw" and not f.singlepulse and not f.woclr


@cocotb.test()
async def reset_values_and_access_types(dut):
    """Every register of the map: reset values (every field the RDL gives one), then access:
    rw fields keep what is written (all ones, then 0), r fields ignore writes, singlepulse
    fields read 0, woclr fields stay 0 when nothing sets them; unmapped addresses read 0."""
    tb = BusTestbench(dut)
    await tb.start()
    m = tb.map
    blocks = [(None, m.globals)] + [(ch, m.channel) for ch in range(CHANNELS)]
    checked = 0
    for ch, regs in blocks:
        for path, spec in regs.items():
            word = await tb.read(path, ch)
            for f in spec.fields.values():
                if f.reset is not None:
                    assert f.get(word) == f.reset, \
                        f"{path}.{f.name} (ch {ch}): reset {f.get(word):#x} != RDL {f.reset:#x}"
                    checked += 1
    dut._log.info("%d reset values checked", checked)

    for ch, regs in blocks:
        for path, spec in regs.items():
            if path in ("trigger", "ctrl"):
                continue                            # pulses that start cycles: below
            before = await tb.read(path, ch)
            stored = [f for f in spec.fields.values() if _stored(f)]
            ones = sum(f.mask for f in stored)
            # Everything written as ones: the stored fields take it, the rest ignore it.
            await tb.write(path, 0xFFFFFFFF if stored else ~before & 0xFFFFFFFF, ch)
            after = await tb.read(path, ch)
            for f in spec.fields.values():
                if _stored(f):
                    assert f.get(after) == (1 << f.width) - 1, f"{path}.{f.name}: not rw"
                elif f.woclr or f.sw == "r":
                    if f.reset is not None:         # a deterministic value: unchanged
                        assert f.get(after) == f.get(before), f"{path}.{f.name}: not r"
            assert after & ~sum(f.mask for f in spec.fields.values()) == 0, \
                f"{path}: bits outside every field read {after:#x}"
            if stored:
                await tb.write(path, 0, ch)
                assert await tb.read(path, ch) & ones == 0, f"{path}: rw fields do not clear"
    # Pulses read 0 after a write of 1 (ctrl.start on the unconfigured core is a BAD_CONFIG).
    for ch in range(CHANNELS):
        await tb.write_fields("ctrl", ch, start=1, abort=1, clear_counters=1)
        assert (await tb.read_fields("ctrl", ch)) == {k: 0 for k in m.channel["ctrl"].fields}
    await tb.write_fields("trigger", start=1)
    assert await tb.read("trigger") == 0
    for addr in UNMAPPED:
        await tb.bus.write(addr, 0xFFFFFFFF)
        assert await tb.bus.read(addr) == 0, f"unmapped {addr:#x} does not read 0"


@cocotb.test()
async def byte_strobes(dut):
    """A write of some byte lanes changes those lanes only (wstrb / sel)."""
    tb = BusTestbench(dut)
    await tb.start()
    addr = tb.addr("cfg_period", 1)          # request_period: 24 bits, lanes 0..2
    await tb.bus.write(addr, 0x00ABCDEF)
    for lane, value, expect in ((0, 0x11, 0xABCD11), (1, 0x2200, 0xAB2211), (2, 0x330000, 0x332211)):
        await tb.bus.write(addr, value, 1 << lane)
        assert await tb.bus.read(addr) == expect, f"lane {lane}"
    await tb.bus.write(addr, 0x00445500, 0b0110)
    assert await tb.bus.read(addr) == 0x445511
    # The lane of a pulse is honoured too: ctrl.start is in lane 0.
    await tb.bus.write(tb.addr("ctrl", 0), 0x1, 0b0010)
    assert (await tb.read_fields("irq_status", 0))["done"] == 0, "a masked lane started a cycle"


@cocotb.test()
async def two_channels_two_presets(dut):
    """Channel 0 reads a RESOLUTE FS (BiSS Safety, 36 + 28 bits), channel 1 an EVOLUTE 36
    (BiSS C), both periodic at once at different MA rates; every result checked."""
    tb = BusTestbench(dut, seed=2)
    await tb.start([SAFETY, BISS_C])
    await tb.configure(0, SAFETY, 5e6, request_period=8000)
    await tb.configure(1, BISS_C, 2.5e6, request_period=6000)
    await tb.encoders_ready()
    for ch in range(CHANNELS):
        await tb.write_fields("ctrl", ch, periodic=1)
    seen = {0: set(), 1: set()}
    while min(len(s) for s in seen.values()) < 6:
        for ch in range(CHANNELS):
            await tb.wait_irq_status(ch, "done")
            res = await tb.result(ch)
            tb.check_result(ch, res)
            seen[ch].add(res["time"])
    for ch in range(CHANNELS):
        await tb.write_fields("ctrl", ch, periodic=0)
    dut._log.info("results checked: %s", {ch: len(s) for ch, s in seen.items()})
