# Quartus (Timing Analyzer) constraints for one instance of a multi-channel bus top,
# biss_master_axil or biss_master_wb (rtl/generated/biss_master_axil.v, biss_master_wb.v:
# 2 channels as committed; python -m bissmaster.generate --top axil|wb --channels N for 1..8).
# Each channel is one complete core, instance ch<i>|core, with its own pins ch<i>_ma and
# ch<i>_slo: it gets the constraints of biss_master.sdc, on paths with ch<i>|core in front.
# Not run through Quartus here (no vendor tools on the machine this was written on). See
# constraints/README.md; the .qsf assignments (per channel) are there.
#
# Adapt these names to your design:
#   bus_inst        : hierarchical instance path of the bus top, with | as separator
#   ch<i>_ma_port   : your top-level output port driving channel i's MA transceiver
#   ch<i>_slo_port  : your top-level input port from channel i's SLO transceiver
# (the defaults are the bus top's own port names: right when it is your top level).
# One block per channel; with more channels, copy a block and change the index everywhere.
set bus_inst      u_biss_bus
set ch0_ma_port   ch0_ma
set ch0_slo_port  ch0_slo
set ch1_ma_port   ch1_ma
set ch1_slo_port  ch1_slo

# The system clock (create_clock on clk) is defined by your design, not here.

# ---------------------------------------------------------------------------------------------
# Channel 0. (a) SLO synchronizer: registers ch0|core|sampler|sync|stage0 -> stage1; slo is
# asynchronous to clk, and the pin-to-stage0 delay is part of the measured round trip.
set_false_path -from [get_ports $ch0_slo_port] -to [get_registers "${bus_inst}|ch0|core|sampler|sync|stage0"]
# (b) MA output: a register (ch0|core|ma_clock|ma) straight to the pin (FAST_OUTPUT_REGISTER,
# README); no output delay is needed.
set_false_path -to [get_ports $ch0_ma_port]

# ---------------------------------------------------------------------------------------------
# Channel 1: the same on ch1.
set_false_path -from [get_ports $ch1_slo_port] -to [get_registers "${bus_inst}|ch1|core|sampler|sync|stage0"]
set_false_path -to [get_ports $ch1_ma_port]
