#!/usr/bin/env python3
"""The table of scripts/instructions.sh from callgrind's dumps.

usage: instruction_report.py <dump-dir> <commit>

<dump-dir> holds cases.txt (one line per case: name and the number of steps counted, as printed by
mjukf_instruction_counts) and callgrind's dumps cg.out.N, one per case, named by the case in their
`desc: Trigger: Client Request:` line, with the case's total in their `totals:` line.
"""
import glob
import os
import sys

PLANTS = ["flexible_joint", "coupled_tank", "chain_n2_p1"]
FILTERS = ["ukf", "jukf", "mjukf", "mjukf_auto", "dual"]
LABELS = {"ukf": "UKF", "jukf": "JUKF", "mjukf": "MJUKF", "mjukf_auto": "MJUKF automatic", "dual": "dual"}
TRIGGER = "desc: Trigger: Client Request: "


def main():
    dumps, commit = sys.argv[1], sys.argv[2]
    steps = {}
    with open(os.path.join(dumps, "cases.txt")) as f:
        for line in f:
            name, n = line.split()[:2]
            steps[name] = int(n)
    per_step = {}
    for path in glob.glob(os.path.join(dumps, "cg.out*")):
        name = total = None
        with open(path) as f:
            for line in f:
                if line.startswith(TRIGGER):
                    name = line[len(TRIGGER):].strip()
                elif line.startswith("totals:"):
                    total = int(line.split()[1])
        if name in steps and total is not None:
            per_step[name] = total / steps[name]
    missing = sorted(set(steps) - set(per_step))
    if missing:
        sys.exit("no callgrind dump for: " + ", ".join(missing))

    def cell(name):
        v = per_step.get(name)
        return "–" if v is None else f"{v:,.0f}"

    def ratio(a, b):
        a, b = per_step.get(a), per_step.get(b)
        return "–" if a is None or not b else f"{a / b:.2f}"

    print(f"Instructions per step (callgrind, Release, no `-march`; mean of {max(steps.values())} steps after "
          f"200 uncounted ones; commit `{commit}`):")
    print()
    print("| plant | filter | scalar | step | floor | step/floor | open | step, square root | square root/full |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scalar in ("double", "float"):
        for p in PLANTS:
            for f in FILTERS:
                s = f"/{p}/{f}/{scalar}"
                if "step" + s not in per_step:
                    continue
                print(f"| {p} | {LABELS[f]} | {scalar} | {cell('step' + s)} | {cell('floor' + s)} | "
                      f"{ratio('step' + s, 'floor' + s)} | {cell('open' + s)} | {cell('step_sr' + s)} | "
                      f"{ratio('step_sr' + s, 'step' + s)} |")

    # Issue 21's goals on the smallest chain (bench/chain_cases.hpp: RK4, the input 2 sin(3t) evaluated
    # three times a step, which the floor counts too).
    goals = (("jukf", 1300), ("mjukf", 1000))
    if all(f"step/chain_n2_p1/{f}/double" in per_step for f, _ in goals):
        print()
        print("The chain at n = 2, p = 1 (`chain_n2_p1`, bench/chain_cases.hpp), against the instruction goals:")
        print()
        print("| filter | goal | step | floor | |")
        print("|---|---|---|---|---|")
        for f, goal in goals:
            step = per_step[f"step/chain_n2_p1/{f}/double"]
            print(f"| {LABELS[f]} | ≤ {goal:,} | {step:,.0f} | {cell(f'floor/chain_n2_p1/{f}/double')} | "
                  f"{'met' if step <= goal else '**missed**'} |")
    sub = [(n, f"step{n}/chain_n2_p1/jukf/double") for n in (4, 8)]
    if all(name in per_step for _, name in sub):
        print()
        print("The chain's JUKF with each 1 ms time update subdivided into RK4 steps (`step4/…`, `step8/…`):")
        print()
        print("| RK4 steps per update | step | step / one-step step |")
        print("|---|---|---|")
        one = "step/chain_n2_p1/jukf/double"
        print(f"| 1 | {cell(one)} | 1.00 |")
        for n, name in sub:
            print(f"| {n} | {cell(name)} | {ratio(name, one)} |")


if __name__ == "__main__":
    main()
