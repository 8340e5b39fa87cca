"""The bus side: the register map (SystemRDL), the register bank, the AXI4-Lite and Wishbone
adapters, the UART bridge and the multi-channel bus top. What it owns, what it may import and
where a new block goes: ``README.md`` beside this file."""
