"""Code the scenarios and tools share: the cocotb testbench, the reference model, the campaign
engine, functional coverage, scenario discovery, the simulator runner and the clock wrapper."""
