"""The control channel: register access over CDM/CDS and its CRC-4. What it owns, what it may
import and where a new block goes: ``README.md`` beside this file."""
