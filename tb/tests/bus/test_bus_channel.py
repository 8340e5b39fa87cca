"""BusChannel's glue between the register map and one core, on Amaranth's simulator: a word's
length field is 7 bits in the map (words 2..7: 1..64 data bits, docs/registers.md), and a core
whose words are all shorter than 64 bits has a 6-bit length port. A length that port cannot
hold must reach the core as 0 (an enabled word of length 0: BAD_CONFIG, docs/bus.md, Chains),
never cut to its low six bits (88 = 0b1011000 would read as 24, a valid length). The same for
the MA half period (16 bits in the map) of a build whose port is 8 bits (``half_period_width``,
docs/ports.md): 266 must not read as 10.

The core's own verdict on its configuration (``config_error``, state.config_error in the map)
is what is observed: the test side knows the legal lengths from the build it asks for.
"""

import pytest
from amaranth.hdl import ClockDomain, Module, Shape
from amaranth.sim import Simulator

from bissmaster.bus import regmap
from bissmaster.bus.bus_top import BusChannel
from bissmaster.bus.register_bank import block_signature
from bissmaster.master import BissMaster
from bissmaster.params import Crc, MasterParams

#: A four-word build whose words are all shorter than 64 bits (the synth configuration
#: chain-4's lengths): word 2 holds up to 24 data bits.
WORD2_MAX = 24
PARAMS = MasterParams(max_data_bits=(40, 32, WORD2_MAX, 16),
                      word_crcs=((Crc.CRC6, Crc.CRC16),) * 4, register_access=False, ssi=False)


def errors_after_writes(params, settings, field, values):
    """``config_error`` of a BusChannel of ``params`` after each of ``values`` is written to
    the map's ``field``, the other fields as ``settings`` gives them."""
    top = Module()
    top.domains.sync = ClockDomain()
    the_map = regmap.load()
    top.submodules.dut = dut = BusChannel(params, block_signature(the_map, the_map.channel))
    regs = dut.regs
    seen = []

    async def bench(ctx):
        for name, value in settings:
            ctx.set(getattr(regs, name), value)
        for value in values:
            ctx.set(getattr(regs, field), value)
            await ctx.tick().repeat(4)
            seen.append(ctx.get(regs.config_error))

    sim = Simulator(top)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return seen


def config_errors(lengths):
    """``config_error`` after each of ``lengths`` is written to cfg_w2.data_bits (word 2
    enabled, CRC-6, words 0 and 1 valid, word 3 disabled)."""
    return errors_after_writes(
        PARAMS, (("cfg_ma_half_period", 10), ("cfg_w0_data_bits", 26), ("cfg_w0_nenw", 1),
                 ("cfg_w0_crc", 1), ("cfg_w1_enable", 1), ("cfg_w1_data_bits", 12),
                 ("cfg_w1_nenw", 1), ("cfg_w1_crc", 1), ("cfg_w2_enable", 1),
                 ("cfg_w2_nenw", 1), ("cfg_w2_crc", 1)),
        "cfg_w2_data_bits", lengths)


def field_and_port_widths(params, name):
    """Widths of the map's field ``name`` and of the ``params`` build's port of that name."""
    the_map = regmap.load()
    field = block_signature(the_map, the_map.channel).members[name]
    port = BissMaster.ports(params)[name]
    return Shape.cast(field.shape).width, Shape.cast(port.shape).width


def test_the_port_is_narrower_than_the_field():
    """The premise: the map's field holds 64, this build's port does not."""
    assert field_and_port_widths(PARAMS, "cfg_w2_data_bits") == (7, 6)


#: A build whose MA half-period setting is 8 bits (``half_period_width``): half periods 2..255.
NARROW = MasterParams(max_data_bits=(36,), word_crcs=((Crc.CRC6,),), half_period_width=8,
                      register_access=False, ssi=False)


def half_period_errors(half_periods):
    """``config_error`` of the NARROW build after each of ``half_periods`` is written to the
    map's 16-bit cfg_ma_half_period (word 0 a valid BiSS C word)."""
    return errors_after_writes(
        NARROW, (("cfg_w0_data_bits", 26), ("cfg_w0_nenw", 1), ("cfg_w0_crc", 1)),
        "cfg_ma_half_period", half_periods)


def test_the_half_period_port_is_narrower_than_the_field():
    assert field_and_port_widths(NARROW, "cfg_ma_half_period") == (16, 8)


@pytest.mark.parametrize("half_periods, errors", [
    ((2, 255, 1, 0, 10), (0, 0, 1, 1, 0)),              # in range; below the least, 2
    ((256 + 10, 10, 512 + 255, 65535, 255), (1, 0, 1, 1, 0)),   # too long: never cut to 10, 255
])
def test_a_half_period_the_core_cannot_hold_is_bad_config(half_periods, errors):
    assert tuple(half_period_errors(half_periods)) == errors


@pytest.mark.parametrize("lengths, errors", [
    ((WORD2_MAX, 1, WORD2_MAX + 1, 0), (0, 0, 1, 1)),           # in range; too long; zero
    ((64, WORD2_MAX, 64 + WORD2_MAX, 1, 64 + 1), (1, 0, 1, 0, 1)),  # the top bit set: never cut
    ((127, WORD2_MAX), (1, 0)),
])
def test_a_length_the_core_cannot_hold_is_bad_config(lengths, errors):
    assert tuple(config_errors(lengths)) == errors
