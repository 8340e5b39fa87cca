# Vivado constraints for the host link of biss_master_uart (rtl/generated/biss_master_uart.v,
# docs/uart_bridge.md), in addition to biss_master_bus.xdc, which constrains its channels as
# for the other bus tops (use the same bus_inst in both files).
# Not run through Vivado here (no vendor tools on the machine this was written on). See
# constraints/README.md.
#
# Adapt these names to your design:
#   bus_inst      : hierarchical path of the bus-top instance (no leading slash)
#   uart_rx_port  : your top-level input port from the USB-serial chip's TXD
#   uart_tx_port  : your top-level output port to the USB-serial chip's RXD
# (the defaults are the top's own port names: right when it is your top level).
set bus_inst      u_biss_bus
set uart_rx_port  uart_rx
set uart_tx_port  uart_tx

# uart_rx is asynchronous to clk: a 2-flop synchronizer, bus/receiver/sync: stage0 -> stage1.
set_property ASYNC_REG TRUE [get_cells [list $bus_inst/bus/receiver/sync/stage0_reg $bus_inst/bus/receiver/sync/stage1_reg]]
set_false_path -from [get_ports $uart_rx_port] -to [get_cells $bus_inst/bus/receiver/sync/stage0_reg]
# uart_tx comes straight from a flip-flop (bus/transmitter/tx); at UART rates no output delay
# matters.
set_false_path -to [get_ports $uart_tx_port]
