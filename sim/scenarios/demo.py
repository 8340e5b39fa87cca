"""The demo scenario: a RESOLUTE FS RSH (BiSS Safety 36/28) encoder read by biss_master at
10 MHz over 50 m and at 5 MHz over 100 m, every frame checked, a table of frames written
to $BISS_DEMO_TABLE for sim/tools/demo.py to print."""

import os

import cocotb

from encoder_model import frames
from encoder_model.cocotb_encoder import Cable
from master_contract import STATUS_NAME
from sim.shared.testbench import CLK_HZ, Testbench

FRAMES_EACH = 6


@cocotb.test()
async def demo(dut):
    tb = Testbench(dut, seed=2026)
    fmt = frames.PRESETS["resolute_fs_rsh"]
    # A linear axis moving at 0.5 m/s, 1 nm CPW resolution: position follows the latch time.
    tb._position_at = lambda t: int(123_456_789 + 0.5e9 * t)
    await tb.start()
    rows = []
    for ma_hz, cable_m in ((10e6, 50), (5e6, 100)):
        cable = Cable(length_m=cable_m)
        tb.encoder.set_cable(cable)
        tb.configure(fmt, ma_hz)
        for _ in range(FRAMES_EACH):
            res = await tb.request()
            tb.check_frame(res)                 # every field against what the encoder sent
            f = res.fields
            rec = tb.encoder.records[-1]
            rows.append(
                f"{len(rows) + 1:>3} {ma_hz / 1e6:>5.1f} {cable_m:>5} "
                f"{f['word0_position']:>13} {f['word1_position']:>11} "
                f"{f['word0_ne']}{f['word0_nw']}/{f['word1_ne']}{f['word1_nw']} {f['lc']:>3} "
                f"{'ok ' if f['word0_crc_ok'] else 'BAD'}   {'ok ' if f['word1_crc_ok'] else 'BAD'}   "
                f"{STATUS_NAME[res.status]:<6} "
                f"{f['line_delay'] * 1e9 / CLK_HZ:>8.0f} {rec.round_trip_s * 1e9:>9.1f} "
                f"{f['timestamp']:>10}")
    header = ("  # MA/MHz cable/m  CPW (1 nm)  SPW (256 nm) nEnW  LC CRC-6 CRC-16 status "
              "delay/ns model/ns  timestamp")
    with open(os.environ["BISS_DEMO_TABLE"], "w") as f:
        f.write(header + "\n" + "\n".join(rows) + "\n")
