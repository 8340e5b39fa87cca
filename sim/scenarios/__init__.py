"""cocotb scenario modules, run inside the simulator: the regression (master), the reliability
campaigns, the demo and the performance measurements. Every ``@cocotb.test`` is one scenario."""
