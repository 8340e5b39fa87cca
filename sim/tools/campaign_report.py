"""Tables of the reliability campaigns from their JSON results (sim/scenarios/campaigns.py).

    python -m sim.tools.campaign_report [DIR]     (default: sim_build/campaign/slice)

Prints Markdown tables (CRC detection, noise immunity, continuous noise, a glitch's cost, a
changing cable, SSI, false alarms, line faults and recovery, sign-of-life, configuration fuzz,
throughput, functional coverage with its holes) and writes them to DIR/report.md.
Exits non-zero if a coverage sample shows a fault ending in a status outside the legal table.
"""

import json
import sys
from collections import Counter
from pathlib import Path

from sim.shared import functional_coverage as coverage


def load(d):
    runs = {}
    for f in sorted(Path(d).glob("*.json")):
        if f.name.endswith(".cov.json"):
            continue
        runs[f.stem] = json.loads(f.read_text())
    return runs


def crc_table(run):
    out = ["| frame / word / error class | patterns | detected | undetected | rate | "
           "theory | valid with corrupted data | must all be detected |",
           "|---|---:|---:|---:|---:|---:|---:|---|"]
    for key, r in run.get("crc_table", {}).items():
        rate = r["undetected"] / r["patterns"] if r["patterns"] else 0
        theory = f"{r['theory']:.2e}" if not r["must_detect"] else "0"
        ok = "yes: all detected" if r["must_detect"] and r["undetected"] == 0 else (
            "**NO**" if r["must_detect"] else "no (beyond HD)")
        out.append(f"| {key} | {r['patterns']} | {r['detected']} | {r['undetected']} | "
                   f"{rate:.2e} | {theory} | {r['valid_corrupted']} | {ok} |")
    return out


def fault_table(runs):
    tally, recovery, blind = {}, {}, Counter()
    for run in runs.values():
        for kind, outcomes in run["tally"].items():
            t = tally.setdefault(kind, Counter())
            t.update(outcomes)
        for kind, dist in run.get("recovery", {}).items():
            r = recovery.setdefault(kind, Counter())
            r.update({int(n): c for n, c in dist.items()})
        for k, v in run.get("stats", {}).items():
            if k.startswith("crc_blind_spot_"):
                blind[k[len("crc_blind_spot_"):]] += v
    out = ["| fault kind | cycles | outcomes (status: count) | recoveries | cycles to the next "
           "valid frame (n: count) |", "|---|---:|---|---:|---|"]
    for kind in sorted(tally):
        t = tally[kind]
        rec = recovery.get(kind, Counter())
        outs = ", ".join(f"{s}: {n}" for s, n in t.most_common())
        dist = ", ".join(f"{n}: {c}" for n, c in sorted(rec.items())) or "-"
        out.append(f"| {kind} | {sum(t.values())} | {outs} | {sum(rec.values())} | {dist} |")
    return out, blind


def glitch_table(run, by=("class", "length", "ma_mhz")):
    """The glitch campaign's figures, rows merged over what ``by`` leaves out: frames, OK, each
    fault status, and results valid with a wrong position (issue 12's figure)."""
    rows = {}
    for r in run["glitch_table"].values():
        key = tuple(r[k] for k in by)
        row = rows.setdefault(key, {"frames": 0, "statuses": Counter(), "valid_wrong": 0})
        row["frames"] += r["frames"]
        row["statuses"].update(r["statuses"])
        row["valid_wrong"] += r["valid_wrong"]
    statuses = sorted({s for row in rows.values() for s in row["statuses"]} - {"OK"})
    names = {"class": "class", "length": "glitch length (of a bit)", "ma_mhz": "MA (MHz)"}
    out = ["| " + " | ".join(names[k] for k in by) + " | frames | OK | "
           + " | ".join(statuses) + " | **valid, wrong position** |",
           "|" + "---|" * len(by) + "---:|" * (3 + len(statuses))]
    classes = list(dict.fromkeys(k[0] for k in rows))       # the campaign's order
    order = sorted(rows, key=lambda k: (k[0] == "next cycle", classes.index(k[0])))
    for key in order:
        row = rows[key]
        out.append("| " + " | ".join(f"{k:g}" if isinstance(k, float) else str(k) for k in key)
                   + f" | {row['frames']} | {row['statuses']['OK']} | "
                   + " | ".join(str(row["statuses"][s]) for s in statuses)
                   + f" | {row['valid_wrong']} |")
    return out


def noise_table(run):
    """noise_baseline and noise_immunity (issue 28): per row (its preset, pulse widths and end
    check), cycles, statuses, valid right / wrong, the valid-wrong rate with its 95 % upper
    bound, against the rate at which random bits pass the frame's CRCs."""
    setup = run["noise_setup"]
    out = [f"{setup.get('preset', 'per row')} at {setup['ma_hz'] / 1e6:g} MHz, "
           f"{setup['cable_m']} m; noise defences {setup.get('defences', 'defaults')} "
           f"({'in this core' if setup.get('defences_in_core') else 'not in this core'})"
           + (f"; pulses {setup['width_s'][0] * 1e9:.0f}..{setup['width_s'][1] * 1e9:.0f} ns, "
              f"mean gap {setup['mean_gap_s'] * 1e6:g} us." if "width_s" in setup else "."), "",
           "| setting | cycles | encoder answered | valid, right | **valid, wrong** | "
           "wrong rate (95 % upper bound) | CRC floor | statuses | line delay of the wrong ones |",
           "|---|---:|---:|---:|---:|---:|---:|---|---|"]
    total = Counter()
    for key, r in run["noise_table"].items():
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(r["statuses"].items()))
        floor = f"{r['crc_floor']:.1e}" if "crc_floor" in r else "-"
        out.append(f"| {key} | {r['cycles']} | {r['encoder_answered']} | {r['valid_right']} | "
                   f"**{r['valid_wrong']}** | {r['valid_wrong'] / max(1, r['cycles']):.2%} "
                   f"({r['valid_wrong_rate_95']:.2%}) | {floor} | {statuses} | "
                   f"{', '.join(map(str, r['wrong_line_delays'])) or '-'} |")
        total.update(cycles=r["cycles"], valid_wrong=r["valid_wrong"])
    out.append(f"| **all** | {total['cycles']} | | | **{total['valid_wrong']}** | | | | |")
    return out


def glitch_cost_table(run):
    """glitch_cost (issue 28, item 5): per setting, the status of the cycle one short glitch
    hit and how many cycles it cost."""
    setup = run["glitch_cost_setup"]
    out = [f"{setup['preset']} at {setup['ma_hz'] / 1e6:g} MHz, {setup['cable_m']} m; one "
           f"{setup['width_s'][0] * 1e9:g}..{setup['width_s'][1] * 1e9:g} ns glitch per cycle "
           f"(noise defences {'in' if setup['defences_in_core'] else 'not in'} this core).", "",
           "| setting | glitches | after the verdict | cycles lost per glitch | cost (cycles: "
           "glitches) | status of the cycle hit | valid, wrong |",
           "|---|---:|---:|---:|---|---|---:|"]
    for key, r in run["glitch_cost_table"].items():
        cost = ", ".join(f"{k}: {v}" for k, v in sorted(r["cost"].items(), key=lambda kv:
                                                           int(kv[0])))
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(r["statuses"].items()))
        out.append(f"| {key} | {r['glitches']} | {r['glitch_after_verdict']} | "
                   f"{r['cost_rate']:.3f} | {cost} | {statuses} | {r['valid_wrong']} |")
    return out


def cable_step_table(run):
    out = ["| setting | check in core | steps (clocks) | wobbles | frames | DELAY_JUMP | "
           "statuses |", "|---|---|---:|---:|---:|---:|---|"]
    for key, r in run["cable_step_table"].items():
        lo, hi = r["step_clocks_min_max"]
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(r["statuses"].items()))
        out.append(f"| {key} | {'yes' if r['check_in_core'] else 'no'} | {r['steps']} "
                   f"({lo:g}..{hi:g}) | {r['wobbles']} | {r['frames']} | "
                   f"{r['delay_jump_frames']} | {statuses} |")
    return out


def false_alarm_table(runs):
    """no_false_alarm, its runs merged (the soak splits it over processes): per MA rate."""
    rows = {}
    for run in runs:
        for key, r in run["false_alarm_table"].items():
            row = rows.setdefault(r["ma_mhz"], {"blocks": 0, "frames": 0, "relaxed_frames": 0,
                                                "statuses": Counter(), "delay_spread_max": 0,
                                                "jitter_ns": r["jitter_ns"], "beyond": 0,
                                                "beyond_statuses": Counter()})
            for k in ("blocks", "frames", "relaxed_frames"):
                row[k] += r[k]
            row["statuses"].update(r["statuses"])
            row["beyond"] += r.get("beyond_votes", 0)
            row["beyond_statuses"].update(r.get("beyond_votes_statuses", {}))
            row["delay_spread_max"] = max(row["delay_spread_max"], r["delay_spread_max"])
    out = ["| MA (MHz) | jitter per edge | blocks | frames | at a relaxed rate | **NOISY_LINE** "
           "| **DELAY_JUMP** | other statuses | an edge on a slot centre: frames (not OK) "
           "| round-trip spread in a block (clocks, max) |",
           "|---:|---:|---:|---:|---:|---:|---:|---|---|---:|"]
    for mhz in sorted(rows):
        r = rows[mhz]
        st = r["statuses"]
        other = ", ".join(f"{k} {v}" for k, v in sorted(st.items())
                          if k not in ("NOISY_LINE", "DELAY_JUMP"))
        beyond = ", ".join(f"{k} {v}" for k, v in sorted(r["beyond_statuses"].items()))
        out.append(f"| {mhz:g} | +/-{r['jitter_ns']:g} ns | {r['blocks']} | {r['frames']} | "
                   f"{r['relaxed_frames']} | **{st['NOISY_LINE']}** | **{st['DELAY_JUMP']}** | "
                   f"{other} | {r['beyond']} ({beyond or 'none'}) | {r['delay_spread_max']} |")
    return out


def ssi_table(run):
    """The SSI campaign: per format class and event, the cycles, their statuses, results valid
    with a wrong reading, and single-bit errors plain SSI cannot see (undetectable by design:
    no CRC, read once; counted, not failures). Then the totals per event."""
    out = ["| format class | event | cycles | statuses | valid, wrong reading | undetectable "
           "by design |", "|---|---|---:|---|---:|---:|"]
    total = {}
    for key in sorted(run["ssi_table"]):
        r = run["ssi_table"][key]
        cls, event = key.split(" | ")
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(r["statuses"].items()))
        out.append(f"| {cls} | {event} | {r['cycles']} | {statuses} | {r['valid_wrong']} | "
                   f"{r['undetectable_by_design']} |")
        t = total.setdefault(event, {"cycles": 0, "statuses": Counter(), "valid_wrong": 0,
                                     "undetectable_by_design": 0})
        t["cycles"] += r["cycles"]
        t["statuses"].update(r["statuses"])
        t["valid_wrong"] += r["valid_wrong"]
        t["undetectable_by_design"] += r["undetectable_by_design"]
    for event, t in sorted(total.items()):
        statuses = ", ".join(f"{k} {v}" for k, v in sorted(t["statuses"].items()))
        out.append(f"| **all** | {event} | {t['cycles']} | {statuses} | {t['valid_wrong']} | "
                   f"{t['undetectable_by_design']} |")
    return out


def throughput(runs):
    out = ["| campaign | simulator | cycles | wall time | cycles/s |", "|---|---|---:|---:|---:|"]
    for name, run in sorted(runs.items()):
        camp, _, sim = name.rpartition("-")
        out.append(f"| {camp} | {sim} | {run['cycles']} | {run['wall_s']:.1f} s | "
                   f"{run['cycles_per_s']:.0f} |")
    total = sum(r["cycles"] for r in runs.values())
    wall = sum(r["wall_s"] for r in runs.values())
    out.append(f"| **all** | | {total} | {wall:.1f} s | {total / wall if wall else 0:.0f} |")
    return out


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    d = Path(argv[0]) if argv else Path(__file__).resolve().parents[2] / "sim_build" / \
        "campaign" / "slice"
    runs = load(d)
    if not runs:
        print(f"no campaign results in {d}")
        return 1
    lines = [f"# Campaign results ({d})", ""]
    for name, run in runs.items():
        if "crc_table" in run:
            lines += [f"## CRC detection ({name})", ""] + crc_table(run) + [""]
        if "glitch_table" in run:
            lines += [f"## Noise immunity, per class and MA rate ({name})", ""]
            lines += glitch_table(run, ("class", "ma_mhz")) + [""]
            lines += [f"## Noise immunity, per class and glitch length ({name})", ""]
            lines += glitch_table(run, ("class", "length")) + [""]
            lines += [f"## Noise immunity, every class ({name})", ""] + glitch_table(run) + [""]
        if "noise_table" in run:
            lines += [f"## Continuous noise ({name})", ""] + noise_table(run) + [""]
        if "glitch_cost_table" in run:
            lines += [f"## What one short glitch costs ({name})", ""] + glitch_cost_table(run)
            lines += [""]
        if "ssi_table" in run:
            lines += [f"## SSI: events and outcomes per format class ({name})", ""]
            lines += ssi_table(run) + [""]
        if "cable_step_table" in run:
            lines += [f"## A cable that changes length ({name})", ""] + cable_step_table(run)
            lines += [""]
    alarms = [run for run in runs.values() if "false_alarm_table" in run]
    if alarms:
        lines += ["## No false alarm: clean frames at the jitter limit (no_false_alarm)", ""]
        lines += false_alarm_table(alarms) + [""]
    table, blind = fault_table(runs)
    lines += ["## Faults, outcomes and recovery (all campaigns)", ""] + table + [""]
    lines.append("CRC blind spots (a corrupted word the CRC cannot see, explained by the "
                 "fault's own bit pattern): " + (", ".join(f"{k}: {v}" for k, v in blind.items())
                                                 or "none") + ".")
    lines += ["", "## Throughput", ""] + throughput(runs) + [""]
    cov = coverage.Coverage()
    for f in sorted(d.glob("*.cov.json")):
        cov.merge(coverage.Coverage.load(f))
    cov_lines, illegal = coverage.report(cov)
    lines += ["## Functional coverage", ""] + cov_lines + [""]
    text = "\n".join(lines)
    print(text)
    (d / "report.md").write_text(text + "\n")
    return 1 if illegal else 0


if __name__ == "__main__":
    sys.exit(main())
