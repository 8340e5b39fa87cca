# Vivado constraints for one biss_master instance (rtl/generated/biss_master.v).
# Not run through Vivado here (no vendor tools on the machine this was written on): check the
# messages when you read it in. See constraints/README.md.
#
# Adapt these three names to your design:
#   biss_inst : hierarchical path of the biss_master instance (no leading slash)
#   ma_port   : your top-level output port driving the MA transceiver
#   slo_port  : your top-level input port from the SLO transceiver
# XDC files accept the Tcl commands set, list and expr, so plain variables work.
set biss_inst u_biss
set ma_port   biss_ma
set slo_port  biss_slo

# The system clock (create_clock on clk) is defined by your design, not here.

# ---------------------------------------------------------------------------------------------
# (a) SLO synchronizer: instance sampler/sync, registers stage0 -> stage1 (cells <reg>_reg after
#     synthesis). slo is asynchronous to clk. The first flop may go metastable; the second
#     gives it a clock to settle.
set_property ASYNC_REG TRUE [get_cells [list $biss_inst/sampler/sync/stage0_reg $biss_inst/sampler/sync/stage1_reg]]

# No timing relation exists between the encoder and clk. The pin-to-stage0 delay is part of the
# round trip that the core measures in every frame, so it needs no bound.
set_false_path -from [get_ports $slo_port] -to [get_cells $biss_inst/sampler/sync/stage0_reg]
# Instead of the false path, if your flow wants every path bounded (the value is an example):
# set_max_delay -datapath_only -from [get_ports $slo_port] -to [get_cells $biss_inst/sampler/sync/stage0_reg] 5.000

# ---------------------------------------------------------------------------------------------
# (b) MA output: driven straight from the register ma in submodule ma_clock. Putting it in the
#     IOB gives a short, fixed clock-to-pin delay.
set_property IOB TRUE [get_cells $biss_inst/ma_clock/ma_reg]

# No output delay is needed. The clock-to-pin delay adds to the round trip, which the core
# measures in every frame (from its own 2nd MA rising edge to the Ack edge at the SLO
# synchronizer). It only has to stay constant within a frame, and a placed-and-routed path does.
set_false_path -to [get_ports $ma_port]
