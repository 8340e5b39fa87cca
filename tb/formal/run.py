"""Runs the formal checks and prints a table: check, method, depth, result, seconds.

    python tb/formal/run.py            # every check (a few minutes)
    python tb/formal/run.py --fast     # the fast slice (what pytest runs)
    python tb/formal/run.py -k crc     # checks whose name contains "crc"
    python tb/formal/run.py --list

Methods: ``k-induction`` = BMC of depth k from reset (base case) + the induction step of depth k:
a proof for every reachable state. ``BMC`` = no counterexample in the first ``depth`` clocks
after reset. ``cover`` = the solver must reach every Cover statement within ``depth`` clocks
(the properties are not vacuous). ``mutation`` = a deliberately weakened harness or a wrong
reference: the solver must find a counterexample within ``depth`` clocks (the assertions can
fail). Exit status 1 if any check does not give its expected answer.

Environment: BISS_FORMAL_SOLVER=yices (default) or z3.
"""

import argparse
import sys
import time
from dataclasses import dataclass

from bissmaster.params import Crc, MasterParams
from formal import flow
from formal.harnesses import (ConfirmationHarness, DecoderCrcHarness, LivenessLimits, MaClockHarness,
                              MasterCrcHarness, MasterLivenessHarness, MasterMaHarness,
                              RegisterAccessEndsHarness, SamplerHarness,
                              SamplerImmunityHarness, SamplerCleanLineHarness)

# -- Parameter sets ------------------------------------------------------------------------------
#: The shipped default build: two words (55 and 40 data bits), both CRCs on each, 24-bit timers.
DEFAULT = MasterParams()
#: The smallest build MasterParams allows (1 MHz system clock: 40/40/80-clock default limits;
#: 16-bit timers; 5-bit delay counter), one word of up to 2 data bits with CRC-6: whole request
#: cycles fit in a few dozen clocks.
SMALL = MasterParams(sys_clk_hz=1_000_000, max_data_bits=(2,), word_crcs=((Crc.CRC6,),),
                     max_line_delay=16, timer_width=16, counter_width=1, timestamp_width=16,
                     register_access=False)
#: SMALL with the register-access engine: the MA proof with the CDM hold (every ``ca_*``
#: input free, so every CDM sequence the engine can make).
SMALL_CA = MasterParams(sys_clk_hz=1_000_000, max_data_bits=(2,), word_crcs=((Crc.CRC6,),),
                        max_line_delay=16, timer_width=16, counter_width=1, timestamp_width=16,
                        start_wait_frames=2)
#: A chain of three slaves (issue 26): words of up to 24, 16 and 8 data bits, each with CRC-6
#: or CRC-16 (the harness's own CRCs; custom CRCs are the CRC engine's tests).
CHAIN3 = MasterParams(max_data_bits=(24, 16, 8), word_crcs=((Crc.CRC6, Crc.CRC16),) * 3,
                      custom_crc=False, ssi=False, register_access=False)
#: One word of up to 4 data bits with CRC-6 only: the mutation checks (no lemmas) stay fast.
TINY_DECODER = MasterParams(max_data_bits=(4,), word_crcs=((Crc.CRC6,),))

#: Liveness settings. FAST: half period 2, Ack limit <= 6 (the Ack edge and the slot-0 sample
#: need about 5 clocks after the second MA rise), timeout and break <= 2, a 1-bit word without
#: nE/nW, LC or CRC. FULL: up to 2 data bits and nE/nW (a half period of 3 as well would need
#: depth 72: more than 10 minutes).
LIVE_FAST = LivenessLimits()
LIVE_FULL = LivenessLimits(data_bits_max=2, nenw=True)
LIVE_SLACK = 0       # the bound is exact to within one clock (README: liveness_small_slack-2)
#: CRC end to end through the master: CRC-6 or none, up to 2 data bits (frames of at most 8
#: bits: the longest first cycle ends by clock 56).
CRC_LIMITS = LivenessLimits(data_bits_max=2, crcs=(Crc.NONE, Crc.CRC6))

#: Register access: the engine built with a read's start-bit wait of 2 frames (the bound is
#: proven for the shipped 16 as well). The bound is exact (tb/tests/control/test_register_access.py
#: simulates a write that takes all of it; a formal cover of it, 151 clocks deep, did not end
#: within 30 minutes). ACCESS_TIGHT asks for a bound 7 frames smaller: from power-up the solver
#: finds a read of 45 frames (step 90).
ACCESS_WAIT = 2
ACCESS_TIGHT = -7


#: Timeout of the longest BMCs (seconds): with the SSI terms (2026-11-29) `liveness_small`
#: took 17 minutes and `master_crc_small` 23 on the shared 2-core machine, and `liveness_full`
#: did not end within the default 30.
LONG_BMC_S = 7200


@dataclass
class Check:
    name: str
    prop: str           # (a), (b), (c)
    method: str         # "k-induction", "BMC", "cover", "mutation"
    depth: int
    make: object        # () -> harness
    fast: bool
    timeout: float = 1800
    skip: int = 0       # cover, mutation: look only from this step on (long traces; shown
                        # as skip:depth)


CHECKS = [
    # (a) MA idles high, never glitches ----------------------------------------------------------
    Check("ma_clock", "a", "k-induction", 2, lambda: MaClockHarness(), True),
    Check("ma_clock", "a", "cover", 30, lambda: MaClockHarness(), True),
    Check("ma_clock_cdm", "a", "k-induction", 2, lambda: MaClockHarness(cdm=True), True),
    Check("ma_clock_cdm", "a", "cover", 30, lambda: MaClockHarness(cdm=True), True),
    Check("ma_clock_hp_unstable", "a", "mutation", 12,
          lambda: MaClockHarness(lemmas=False, mutation="hp_unstable"), True),
    Check("master_ma_small", "a", "k-induction", 2, lambda: MasterMaHarness(SMALL, lemmas=True), True),
    Check("master_ma_small", "a", "cover", 40, lambda: MasterMaHarness(SMALL, lemmas=True), True),
    Check("master_ma_small_cdm", "a", "k-induction", 2,
          lambda: MasterMaHarness(SMALL_CA, lemmas=True), True),
    Check("master_ma_small_cdm", "a", "cover", 40,
          lambda: MasterMaHarness(SMALL_CA, lemmas=True), False),
    Check("master_ma_small_live_hp", "a", "mutation", 20,
          lambda: MasterMaHarness(SMALL, mutation="live_hp"), True),
    Check("master_ma_default", "a", "k-induction", 2,
          lambda: MasterMaHarness(DEFAULT, lemmas=True), False),
    Check("master_ma_small_nolemmas", "a", "BMC", 24, lambda: MasterMaHarness(SMALL), False),
    # (b) every request cycle ends; the master returns to idle -----------------------------------
    # The BMC takes about 3 minutes (17 since the SSI terms of 2026-11-29, on a shared 2-core
    # machine): make formal only (its cover and the tight mutation, which show the harness
    # reaches the bound and bites, stay in the fast slice). The long BMCs get up to 2 hours.
    Check("liveness_small", "b", "BMC", LIVE_FAST.depth(SMALL.words, LIVE_SLACK),
          lambda: MasterLivenessHarness(SMALL, LIVE_FAST, slack=LIVE_SLACK), False, LONG_BMC_S),
    Check("liveness_small", "b", "cover", 40,
          lambda: MasterLivenessHarness(SMALL, LIVE_FAST, slack=LIVE_SLACK), True),
    Check("liveness_small_tight", "b", "mutation", LIVE_FAST.depth(SMALL.words, LIVE_SLACK),
          lambda: MasterLivenessHarness(SMALL, LIVE_FAST, slack=LIVE_SLACK, mutation="tight"), True),
    Check("liveness_small_slack-2", "b", "mutation", LIVE_FAST.depth(SMALL.words, -2),
          lambda: MasterLivenessHarness(SMALL, LIVE_FAST, slack=-2), False),
    Check("liveness_full", "b", "BMC", LIVE_FULL.depth(SMALL.words, LIVE_SLACK),
          lambda: MasterLivenessHarness(SMALL, LIVE_FULL, slack=LIVE_SLACK), False, LONG_BMC_S),
    Check("sampler_default", "b", "k-induction", 2,
          lambda: SamplerHarness(DEFAULT.delay_width), True),
    Check("sampler_default", "b", "cover", 20, lambda: SamplerHarness(DEFAULT.delay_width), True),
    Check("sampler_short_gap", "b", "mutation", 20,
          lambda: SamplerHarness(DEFAULT.delay_width, lemmas=False, mutation="short_gap"), True),
    # (d) One glitch up to the vote spacing never changes a decided bit (issue 12).
    Check("sampler_immunity", "d", "BMC", 60, lambda: SamplerImmunityHarness(8), False),
    Check("sampler_immunity", "d", "cover", 60, lambda: SamplerImmunityHarness(8), True),
    Check("sampler_immunity_long", "d", "mutation", 60,
          lambda: SamplerImmunityHarness(8, mutation="long"), True),
    # (d) A clean line with the jitter the votes allow never strobes ``noise`` (issue 28).
    Check("sampler_clean_line_small", "d", "BMC", 44,
          lambda: SamplerCleanLineHarness(8, hp_max=4, slots=3), True),
    Check("sampler_clean_line", "d", "BMC", 70, lambda: SamplerCleanLineHarness(8, hp_max=5), False),
    Check("sampler_clean_line", "d", "cover", 70, lambda: SamplerCleanLineHarness(8, hp_max=5),
          True),
    Check("sampler_clean_line_glitch", "d", "mutation", 70,
          lambda: SamplerCleanLineHarness(8, hp_max=5, mutation="glitch"), True),
    # (c) a frame with a CRC error is never reported valid ---------------------------------------
    Check("decoder_crc_default", "c", "k-induction", 2, lambda: DecoderCrcHarness(DEFAULT), True),
    Check("decoder_crc_default", "c", "cover", 30, lambda: DecoderCrcHarness(DEFAULT), True),
    Check("decoder_crc_chain3", "c", "k-induction", 2, lambda: DecoderCrcHarness(CHAIN3), True),
    Check("decoder_crc_chain3", "c", "cover", 30, lambda: DecoderCrcHarness(CHAIN3), False),
    Check("decoder_crc_chain3_wrong_poly", "c", "mutation", 24,
          lambda: DecoderCrcHarness(CHAIN3, lemmas=False, mutation="poly"), False),
    Check("decoder_crc_wrong_poly", "c", "mutation", 16,
          lambda: DecoderCrcHarness(TINY_DECODER, lemmas=False, mutation="poly"), True),
    Check("decoder_crc_no_invert", "c", "mutation", 16,
          lambda: DecoderCrcHarness(TINY_DECODER, lemmas=False, mutation="no_invert"), True),
    Check("master_crc_small", "c", "BMC", 56, lambda: MasterCrcHarness(SMALL, CRC_LIMITS), False,
          LONG_BMC_S),
    Check("master_crc_small", "c", "cover", 60, lambda: MasterCrcHarness(SMALL, CRC_LIMITS), False),
    # (f) no valid frame within cfg_confirm_frames frames of a fault (issue 28) ----------------
    Check("confirmation", "f", "k-induction", 2, lambda: ConfirmationHarness(DEFAULT), True),
    Check("confirmation", "f", "cover", 12, lambda: ConfirmationHarness(DEFAULT), True),
    Check("confirmation_unwired", "f", "mutation", 6,
          lambda: ConfirmationHarness(DEFAULT, lemmas=False, mutation="unwired"), True),
    # (e) every accepted register access ends within its frame bound (issue 13) ---------------
    Check("access_ends", "e", "k-induction", 1,
          lambda: RegisterAccessEndsHarness(start_wait=ACCESS_WAIT), True),
    Check("access_ends_default", "e", "k-induction", 1,
          lambda: RegisterAccessEndsHarness(start_wait=DEFAULT.start_wait_frames), False),
    Check("access_ends_read1", "e", "cover", 96,
          lambda: RegisterAccessEndsHarness(start_wait=ACCESS_WAIT, count_max=1, write=False,
                                            wbuf=False), False, skip=90),
    Check("access_ends_free_cdm", "e", "mutation", 72,
          lambda: RegisterAccessEndsHarness(start_wait=ACCESS_WAIT, count_max=1, wbuf=False,
                                            lemmas=False, mutation="free_cdm"), False, skip=60),
    Check("access_ends_tight", "e", "mutation", 96,
          lambda: RegisterAccessEndsHarness(start_wait=ACCESS_WAIT, count_max=1, wbuf=False,
                                            lemmas=False, slack=ACCESS_TIGHT), False, skip=84),
]


@dataclass
class Outcome:
    check: Check
    ok: bool
    result: str
    seconds: float
    detail: str = ""


def run_check(check):
    """Builds the harness and runs the solver. Returns an Outcome (``ok``: as expected)."""
    t0 = time.monotonic()
    smt2 = flow.build(check.name, check.make())
    detail = ""
    if check.method == "k-induction":
        status, _, log = flow.smtbmc(smt2, "bmc", check.depth, timeout=check.timeout)
        if status == "PASSED":
            status, _, log = flow.smtbmc(smt2, "induction", check.depth, timeout=check.timeout)
            result = "proven" if status == "PASSED" else f"induction {status}"
        else:
            result = f"base case {status}"
        ok = status == "PASSED"
    elif check.method == "BMC":
        status, _, log = flow.smtbmc(smt2, "bmc", check.depth, timeout=check.timeout)
        ok = status == "PASSED"
        result = "no counterexample" if ok else status
    elif check.method == "cover":
        status, _, log = flow.smtbmc(smt2, "cover", check.depth, timeout=check.timeout,
                                     skip=check.skip)
        ok = status == "PASSED"
        steps = flow.reached_cover_steps(log)
        result = f"all reached (steps {', '.join(map(str, steps))})" if ok else f"{status}"
    elif check.method == "mutation":
        status, _, log = flow.smtbmc(smt2, "bmc", check.depth, timeout=check.timeout,
                                     skip=check.skip)
        ok = status == "FAILED"
        result = "counterexample found (expected)" if ok else f"{status} (expected a counterexample)"
    else:
        raise ValueError(check.method)
    if not ok or check.method == "mutation":
        failed = flow.failed_properties(log)
        detail = "; ".join(failed)
    return Outcome(check, ok, result, time.monotonic() - t0, detail)


def table(outcomes):
    rows = [("check", "prop", "method", "depth", "result", "seconds")]
    for o in outcomes:
        c = o.check
        rows.append((c.name, c.prop, c.method, f"{c.skip}:{c.depth}" if c.skip else str(c.depth),
                     ("PASS " if o.ok else "FAIL ") + o.result, f"{o.seconds:.1f}"))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = []
    for i, r in enumerate(rows):
        lines.append("  ".join(v.ljust(w) if j != 5 else v.rjust(w)
                               for j, (v, w) in enumerate(zip(r, widths))))
        if i == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fast", action="store_true", help="only the fast slice")
    ap.add_argument("-k", default="", help="only checks whose name contains this")
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args(argv)
    checks = [c for c in CHECKS if (c.fast or not args.fast) and args.k in c.name]
    if args.list:
        for c in checks:
            depth = f"{c.skip}:{c.depth}" if c.skip else str(c.depth)
            print(f"{c.name:28} ({c.prop}) {c.method:11} depth {depth:>7} "
                  f"{'fast' if c.fast else ''}")
        return 0
    print(f"formal: {len(checks)} checks, solver {flow.solver()}, build dir "
          f"{flow.BUILD.relative_to(flow.REPO)}", flush=True)
    outcomes = []
    t0 = time.monotonic()
    for c in checks:
        o = run_check(c)
        outcomes.append(o)
        depth = f"{c.skip}:{c.depth}" if c.skip else c.depth
        print(f"  {'ok  ' if o.ok else 'FAIL'} {c.name} {c.method} {depth}: {o.result} "
              f"({o.seconds:.1f} s){'  [' + o.detail + ']' if o.detail else ''}", flush=True)
    print()
    print(table(outcomes))
    bad = [o for o in outcomes if not o.ok]
    print(f"\n{len(outcomes) - len(bad)} passed, {len(bad)} failed "
          f"({time.monotonic() - t0:.0f} s)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
