#!/usr/bin/env python3
"""Writes docs/performance-scaling.md from the JSON of scripts/scaling.sh.

    python3 bench/scaling_report.py <results-dir> <output.md>

<results-dir> holds scaling.json (mjukf_scaling_bench: the kernels chosen by size),
scaling_coefficientwise.json (mjukf_scaling_bench_coefficientwise: the small-size kernels at every
size, as before issue 21), optionally kernels.json (mjukf_kernel_bench) and compile_cost.txt
(scripts/compile_cost.sh), and commit, *.load. Times are medians of the repetitions' CPU times.
"""

import json
import math
import os
import re
import sys

FILTERS = [("ukf", "UKF (θ fixed)"), ("jukf", "JUKF"), ("mjukf", "MJUKF (paper: T, ξ fixed)"),
           ("mjukf_auto", "MJUKF automatic"), ("dual", "dual")]
SIZES = [2, 4, 8, 16, 32]


def medians(path):
    """name -> (cpu time in ns, counters) of the median aggregates."""
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        data = json.load(f)
    scale = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
    out = {}
    for b in data["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        name = b["run_name"]
        out[name] = (b["cpu_time"] * scale[b["time_unit"]], b)
    return out


def read(path, default="?"):
    try:
        with open(path) as f:
            return f.read().strip()
    except OSError:
        return default


def fmt_time(ns):
    if math.isnan(ns):
        return "–"
    if ns >= 1e4:
        return f"{ns / 1e3:,.1f} µs"
    if ns >= 1e3:
        return f"{ns / 1e3:,.2f} µs"
    return f"{ns:,.0f} ns"


def scaling_rows(new, old):
    rows = []
    for p in (1, 4):
        for key, label in FILTERS:
            for n in SIZES:
                name = f"scaling/{key}/n{n}/p{p}"
                if name not in new:
                    continue
                step, b = new[name]
                floor = new.get(f"scaling_floor/{key}/n{n}/p{p}", (math.nan, None))[0]
                old_step = old.get(name, (math.nan, None))[0]
                old_floor = old.get(f"scaling_floor/{key}/n{n}/p{p}", (math.nan, None))[0]
                rows.append(dict(p=p, key=key, label=label, n=n, L=int(b["L"]), points=int(b["points"]),
                                 step=step, floor=floor, old=old_step, old_floor=old_floor))
    return rows


def exponent(rows, key, p, field):
    by_n = {r["n"]: r for r in rows if r["key"] == key and r["p"] == p}
    if 16 not in by_n or 32 not in by_n:
        return math.nan
    a, b = by_n[16], by_n[32]
    return math.log(b[field] / a[field]) / math.log(b["L"] / a["L"])


def kernel_table(kernels, scalar):
    forms = [("covariance", "coefficientwise"), ("covariance", "gemm"), ("covariance", "triangle"),
             ("covariance", "blocks"),
             ("cross", "coefficientwise"), ("cross", "product"), ("cross", "blocks"),
             ("subtract", "coefficientwise"), ("subtract", "rank_update"), ("subtract", "gemm"),
             ("subtract", "blocks"),
             ("cholesky", "unrolled"), ("cholesky", "blocked"), ("cholesky", "columns")]
    sizes = kernel_sizes(kernels, scalar)
    lines = ["| L | " + " | ".join(f"{k} {f}" for k, f in forms) + " |", "|---" * (len(forms) + 1) + "|"]
    for size in sizes:
        cells = []
        for group in range(0, len(forms)):
            k, f = forms[group]
            t = kernels.get(f"kernel/{k}/{f}/{scalar}/{size}", (math.nan, None))[0]
            same = [kernels.get(f"kernel/{k}/{g}/{scalar}/{size}", (math.inf, None))[0] for kk, g in forms if kk == k]
            cell = f"{t:,.0f}" if not math.isnan(t) else "–"
            if t == min(same):
                cell = f"**{cell}**"
            cells.append(cell)
        lines.append(f"| {size} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def kernel_sizes(kernels, scalar):
    return sorted({int(m.group(1)) for name in kernels
                   for m in [re.match(rf"kernel/\w+/\w+/{scalar}/(\d+)$", name)] if m})


def ranges(sizes):
    """'8, 9, 11 and 17–19' for the sizes [8, 9, 11, 17, 18, 19]."""
    parts, run = [], []
    for n in sizes:
        if run and n != run[-1] + 1:
            parts.append(run)
            run = []
        run.append(n)
    if run:
        parts.append(run)
    text = [f"{r[0]}" if len(r) == 1 else f"{r[0]}, {r[1]}" if len(r) == 2 else f"{r[0]}–{r[-1]}" for r in parts]
    return ", ".join(text[:-1]) + " and " + text[-1] if len(text) > 1 else "".join(text)


def border(kernels, kernel, written, general, scalar):
    """Where the general form overtakes the written-out one in this run: the smallest measured L from which
    it is as fast or faster at every larger measured L (as the tables show them, rounded to ns), and the
    smaller sizes where it is faster or equal as well."""
    sizes = [n for n in kernel_sizes(kernels, scalar)
             if f"kernel/{kernel}/{written}/{scalar}/{n}" in kernels and f"kernel/{kernel}/{general}/{scalar}/{n}" in kernels]
    if not sizes:
        return None, ""
    t = {n: (round(kernels[f"kernel/{kernel}/{written}/{scalar}/{n}"][0]),
             round(kernels[f"kernel/{kernel}/{general}/{scalar}/{n}"][0])) for n in sizes}
    start = len(sizes)
    while start > 0 and t[sizes[start - 1]][1] <= t[sizes[start - 1]][0]:
        start -= 1
    if start == len(sizes):
        return f"above {sizes[-1]}", ""
    text = f"{sizes[0]} or below" if start == 0 else f"{sizes[start]}"
    faster = [n for n in sizes[:start] if t[n][1] < t[n][0]]
    equal = [n for n in sizes[:start] if t[n][1] == t[n][0]]
    notes = ([f"{general} also at {ranges(faster)}"] if faster else []) + ([f"equal at {ranges(equal)}"] if equal else [])
    return text, ", ".join(notes)


def border_cell(kernels, kernel, written, general):
    found = {scalar: border(kernels, kernel, written, general, scalar) for scalar in ("double", "float")}
    if all(b is None for b, _ in found.values()):
        return "not in this run"
    cell = "; ".join(b or "–" for b, _ in found.values())
    notes = "; ".join(f"{scalar}: {note}" for scalar, (_, note) in found.items() if note)
    return f"{cell} ({notes})" if notes else cell


KERNEL_SECTION = "## The kernels chosen by size, and their thresholds"
COMPILE_SECTION = "## Compile time and peak memory"
NOTES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "compile_time_notes.md")


def notes_lines():
    """The hand-written notes the page ends with (bench/compile_time_notes.md), less its comment lines."""
    if not os.path.exists(NOTES):
        return []
    with open(NOTES, encoding="utf-8") as f:
        return [line for line in f.read().splitlines() if not line.startswith("<!--")]


def kept_section(page, heading):
    """The section of an existing page under `heading`, up to the next section of the same level or the
    notes the page ends with, whichever comes first; "" if the page or the section is not there."""
    try:
        with open(page, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError:
        return ""
    if heading not in lines:
        return ""
    start = lines.index(heading)
    notes = next((line for line in notes_lines() if line.strip()), None)
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ") or lines[i] == notes),
               len(lines))
    return "\n".join(lines[start:end]).rstrip()


def fmt(x, digits=2):
    return "–" if math.isnan(x) else f"{x:.{digits}f}"


def main():
    results, output = sys.argv[1], sys.argv[2]
    new = medians(os.path.join(results, "scaling.json"))
    old = medians(os.path.join(results, "scaling_coefficientwise.json"))
    kernels = medians(os.path.join(results, "kernels.json"))
    rows = scaling_rows(new, old)
    commit = read(os.path.join(results, "commit"))
    out = []
    w = out.append
    w("# Performance at scale: the chain of masses\n")
    w("Generated by `bash scripts/scaling.sh` (this page only; `docs/performance.md` is `scripts/bench.sh`'s,")
    w("whose full run takes about 10 minutes and two builds of its own, so the scaling runs, with two more")
    w("builds, are kept apart). The model family is `bench/chain_model.hpp`: n/2 unit masses in a chain")
    w("with cubic springs and dampers, a known force on the first, the n/2 positions measured, RK4 at")
    w("h = 1 ms, p = 1 (stiffness) or 4 (stiffness, cubic stiffness, damping, input gain) unknown")
    w("parameters. `scaling/<filter>/n<n>/p<p>` (`bench/scaling_bench.cpp`) times one measurement step (a")
    w("time update over one step, then a measurement update); its floor is defined as the step benchmarks'")
    w("(`bench/step_cases.hpp`): the filter's points, one RK4 step each with the parameters the filter")
    w("gives it, the input evaluated once per stage time. Times are medians of 5 repetitions of the")
    w("benchmark thread's CPU time, Release (`-O3`, no `-march`), on the shared 2-core machine: compare")
    w("ratios within one run.\n")
    options = read(os.path.join(results, "scaling.options"), "")
    if options:
        w(f"Options of the runs: {options}.\n")
    w(f"Run at commit `{commit}` (plus the working tree); load average before the runs: "
      f"{read(os.path.join(results, 'scaling.load'))} (kernels chosen by size), "
      f"{read(os.path.join(results, 'scaling_coefficientwise.load'))} (small-size kernels).\n")
    w("**now**: the kernels chosen by size (`detail/linear_algebra.hpp`, the thresholds below);")
    w("**before**: the same code built with `MJUKF_GENERAL_KERNELS_FROM=1000`, i.e. the written-out")
    w("kernels at every size as before issue 21 (`mjukf_scaling_bench_coefficientwise`), run right after.")
    w("L is the augmented dimension of the state filter: n + p for the JUKF, n for the others (the MJUKF")
    w("and the dual estimate θ outside their n-dimensional state filter). The MJUKF (paper) is the paper's:")
    w("T and ξ fixed and the covariance of θ̂ not followed (`followParameterCovariance = false`, as the")
    w("step benchmarks' MJUKF); the automatic MJUKF has both automatic modes and the covariance of θ̂,")
    w("whose sensitivities add p propagations per time update to its points. (Versions of this page")
    w("before December 2026 timed the fixed MJUKF with the library's default, the covariance of θ̂")
    w("followed, against a floor of its 2n + 1 points alone.)\n")

    if rows:
        jukf = [r for r in rows if r["key"] == "jukf" and r["p"] == 4 and r["n"] == 32]
        w("## Goals (issue 21)\n")
        w("| goal | now | before | |")
        w("|---|---|---|---|")
        if jukf:
            r = jukf[0]
            ratio, old_ratio = r["step"] / r["floor"], r["old"] / r["old_floor"]
            w(f"| JUKF step/floor at n = 32, p = 4 ≤ 5 | {fmt(ratio)} | {fmt(old_ratio)} | "
              f"{'met' if ratio <= 5 else '**missed**'} |")
        for key, label in FILTERS:
            for p in (1, 4):
                e, eo = exponent(rows, key, p, "step"), exponent(rows, key, p, "old")
                if math.isnan(e):
                    continue
                w(f"| {label}, p = {p}: cost exponent n = 16 → 32 ≤ 2.4 | {fmt(e)} | {fmt(eo)} | "
                  f"{'met' if e <= 2.4 else '**missed**'} |")
        w("")
        w("The exponent is log(t₃₂ / t₁₆) / log(L₃₂ / L₁₆) of the step time. The floor grows as points ×")
        w("model cost ∝ L · n, so its own exponent (last column of the exponent table) is about 2: an")
        w("exponent of the step near 2 means a step/floor that hardly grows. \"–\": not measured in this run.\n")

        w("## Step, floor and step/floor\n")
        for p in (1, 4):
            w(f"### p = {p}\n")
            w("| filter | n | L | points | step now | floor | step/floor now | step before | step/floor before "
              "| before/now |")
            w("|---|---|---|---|---|---|---|---|---|---|")
            for r in rows:
                if r["p"] != p:
                    continue
                w(f"| {r['label']} | {r['n']} | {r['L']} | {r['points']} | {fmt_time(r['step'])} | "
                  f"{fmt_time(r['floor'])} | {r['step'] / r['floor']:.2f} | {fmt_time(r['old'])} | "
                  f"{fmt(r['old'] / r['old_floor'])} | {fmt(r['old'] / r['step'])} |")
            w("")
        w("step/floor before divides by the floor measured in the before run (the floor does not depend on")
        w("the kernels; its two measurements differ by the machine's noise).\n")

        w("### Cost exponents between n = 16 and n = 32\n")
        w("| filter | p | L₁₆ → L₃₂ | step now | step before | floor |")
        w("|---|---|---|---|---|---|")
        for key, label in FILTERS:
            for p in (1, 4):
                by_n = {r["n"]: r for r in rows if r["key"] == key and r["p"] == p}
                if 16 not in by_n or 32 not in by_n:
                    continue
                w(f"| {label} | {p} | {by_n[16]['L']} → {by_n[32]['L']} | {fmt(exponent(rows, key, p, 'step'))} | "
                  f"{fmt(exponent(rows, key, p, 'old'))} | {fmt(exponent(rows, key, p, 'floor'))} |")
        w("")

    # The kernel micro-benchmark is optional and slow (MJUKF_SCALING_KERNELS=1): a run without it keeps
    # the section of the page it replaces, whose own line says at which commit it was measured.
    previous_kernels = "" if kernels else kept_section(output, KERNEL_SECTION)
    if previous_kernels:
        w(previous_kernels)
        w("")
    if kernels:
        w(f"{KERNEL_SECTION}\n")
        w("`mjukf_kernel_bench` (`bench/kernel_size_bench.cpp`): each kernel of `detail/linear_algebra.hpp`")
        w("that is chosen by size, in each of its forms, on a point set of 2L + 1 points, ns per call")
        w("(median of 5, the fastest form of each kernel in bold). covariance: Σ Wᵢ dᵢ dᵢᵀ (L × L);")
        w("cross: Σ Wᵢ dᵢ eᵢᵀ (L × ⌈L/2⌉); subtract: P − U Uᵀ (U L × ⌈L/2⌉); cholesky: the factor of an")
        w("L × L P. Forms: coefficientwise/unrolled (written out, as before), blocks (the library's")
        w("general form of the products: `productWithTranspose`, register blocks over the operands in")
        w("place, one triangle for covariance and subtract), and the general forms before it, Eigen's:")
        w("gemm (its general product, both triangles), triangle (its product into the lower triangle,")
        w("mirrored), product (GEMM), rank_update (`selfadjointView<Lower>().rankUpdate`, mirrored);")
        w("blocked (Eigen's in-place LLT, the Cholesky's general form until `columns`), columns")
        w("(left-looking, a matrix-vector product per column). A form a run did not have shows as –.\n")
        kernels_commit = read(os.path.join(results, "kernels.commit"))
        w(f"Run at commit `{kernels_commit}` (plus the working tree); load average before the run: "
          f"{read(os.path.join(results, 'kernels.load'))}.\n")
        w("Thresholds chosen (`generalKernelsFrom` in `detail/linear_algebra.hpp`), with Eigen's forms as")
        w("the general ones; blocks replaced them without moving the thresholds. They were read, while")
        w("that earlier run was going, off the wall-clock medians of its text output. The last column is")
        w("where the tables below (CPU-time medians, the figure this page uses everywhere) put the border")
        w("between the written-out form and blocks, the two forms the library now chooses between, within")
        measured = sorted(set(kernel_sizes(kernels, "double")) | set(kernel_sizes(kernels, "float")))
        w(f"the sizes measured (L = {', '.join(map(str, measured))}): the thresholds are left as chosen until")
        w("a change of them is measured on the filters' steps as well. The Cholesky's was chosen with")
        w("Eigen's blocked LLT; the factor by columns that replaced it took fewer instructions at every size")
        w("from the threshold on (CHANGELOG), and it was not measured again.\n")
        w("| kernel | double | float | border, written out / general form (double; float) |")
        w("|---|---|---|---|")
        w(f"| covariance: blocks from | 9 | 9 | {border_cell(kernels, 'covariance', 'coefficientwise', 'blocks')} |")
        w("| covariance: one triangle from (the MJUKF's P_θ) | 20 | 28 | – (blocks are one triangle) |")
        w(f"| cross-covariance: blocks from | 11 | 14 | {border_cell(kernels, 'cross', 'coefficientwise', 'blocks')} |")
        w(f"| P − U Uᵀ: blocks from | 20 | 24 | {border_cell(kernels, 'subtract', 'coefficientwise', 'blocks')} |")
        w(f"| Cholesky: by columns from | 20 (see below) | 24 | {border_cell(kernels, 'cholesky', 'unrolled', 'columns')} |")
        w("")
        w("The one deliberate exception is the double Cholesky: the unrolled factor stayed up to 10 %")
        w("faster than Eigen's blocked LLT up to L = 32 (36: blocked faster), but its straight-line code")
        w("and compile time grow as L³ (the micro-benchmark, with both forms at every size, took about 20")
        w("minutes to compile on the shared machine), and the factorisation is a small part of a step at")
        w("these sizes; it is general from L = 20. P − U Uᵀ's general form (blocks) computes one")
        w("triangle and mirrors it, so that the committed P is exactly symmetric, in both types.\n")
        for scalar in ("double", "float"):
            w(f"### {scalar} (ns per call)\n")
            w(kernel_table(kernels, scalar))
            w("")

    cost_path = os.path.join(results, "compile_cost.txt")
    previous_cost = "" if os.path.exists(cost_path) else kept_section(output, COMPILE_SECTION)
    if previous_cost:  # compile_cost.sh is optional too (MJUKF_SCALING_COMPILE=1)
        w(previous_cost)
        w("")
    if os.path.exists(cost_path):
        w(f"{COMPILE_SECTION}\n")
        w("`bash scripts/compile_cost.sh`: one translation unit per filter on the chain (p = 4, RK4) at")
        w("n = 4 and n = 32, and one with all four filters at n = 4, `g++ -std=c++17 -O2 -c`, from")
        w("`/usr/bin/time -v`: the compiler's CPU time (user + system; on the shared machine the wall-clock")
        w("time also counts other processes, so it is the CPU time that compares), the wall-clock time and")
        w("the maximum resident set size. Each unit builds its filter on the heap and makes one time and one")
        w("measurement update. \"written out\": the same unit with `MJUKF_GENERAL_KERNELS_FROM=1000`, the")
        w("kernels as before issue 21. Issue 21's goal: all four at n = 4 within 6 s on the CI machine")
        w("(8.2 s measured by the issue, 31.7 s at n = 32).\n")
        header = [line[2:] for line in read(cost_path, "").splitlines() if line.startswith("# ")]
        if header:
            w("Run: " + "; ".join(header) + ".\n")
        w("| unit | n | CPU seconds | wall-clock seconds | peak memory (MB) |")
        w("|---|---|---|---|---|")
        for line in read(cost_path, "").splitlines():
            m = re.match(r"(\S+) n=(\d+) cpu_seconds=([\d.]+) wall_seconds=([\d.]+) max_rss_kb=(\d+)", line)
            if m:
                w(f"| {m.group(1).replace('_', ' ')} | {m.group(2)} | {float(m.group(3)):.1f} | "
                  f"{float(m.group(4)):.1f} | {int(m.group(5)) / 1024:,.0f} |")
        w("")
    # Measurements of where the compile time goes, written by hand (bench/compile_time_notes.md).
    if os.path.exists(NOTES):
        w("\n".join(notes_lines()))

    with open(output, "w") as f:
        f.write("\n".join(out).rstrip() + "\n")


if __name__ == "__main__":
    main()
