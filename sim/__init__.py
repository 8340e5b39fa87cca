"""Simulation of the generated ``biss_master`` Verilog under cocotb (see sim/README.md).

``sim.shared``: the code scenarios and tools build on; ``sim.scenarios``: the cocotb test
modules; ``sim.tools``: command-line tools (``python -m sim.tools.<name>``). The ``test_*.py``
modules here are the pytest entries that run the scenarios.
"""
