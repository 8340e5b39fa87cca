"""Host-side software: what a CPU or a PC runs, never hardware (BP3 identification and EDS
decoding; the UART bridge's host side, ``link``). What it owns, what it may import and where
new code goes: ``README.md`` beside this file."""
