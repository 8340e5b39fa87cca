# Quartus (Timing Analyzer) constraints for one biss_master instance
# (rtl/generated/biss_master.v). Not run through Quartus here (no vendor tools on the machine
# this was written on). See constraints/README.md; the .qsf assignments are there.
#
# Adapt these three names to your design:
#   biss_inst : hierarchical instance path of biss_master, with | as separator (e.g. sub|u_biss)
#   ma_port   : your top-level output port driving the MA transceiver
#   slo_port  : your top-level input port from the SLO transceiver
set biss_inst u_biss
set ma_port   biss_ma
set slo_port  biss_slo

# The system clock (create_clock on clk) is defined by your design, not here.

# ---------------------------------------------------------------------------------------------
# (a) SLO synchronizer: registers sampler|sync|stage0 -> sampler|sync|stage1. slo is asynchronous to
#     clk, and the pin-to-stage0 delay is part of the round trip that the core measures in
#     every frame.
set_false_path -from [get_ports $slo_port] -to [get_registers "${biss_inst}|sampler|sync|stage0"]

# ---------------------------------------------------------------------------------------------
# (b) MA output: a register (ma_clock|ma) straight to the pin; put it in the I/O register
#     with FAST_OUTPUT_REGISTER (README). Its clock-to-pin delay adds to the measured round
#     trip, so no output delay is needed; it only has to stay constant within a frame.
set_false_path -to [get_ports $ma_port]
