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

PLANTS = ["flexible_joint", "coupled_tank"]
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


if __name__ == "__main__":
    main()
