"""The data channel: every block of a request cycle, MA -> SLO sampler -> decoder -> checks ->
verdict -> results and counters. What it owns, what it may import and where a new block goes:
``README.md`` beside this file."""
