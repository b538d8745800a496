#!/usr/bin/python3
"""docs/benchmarks.md from Google Benchmark's JSON output.

The goals live in bench/goals.yaml: one entry per figure a user cares about,
with the benchmark that measures it (its JSON `name`), what it measures, and
the goal, either a time (`< 20 ms`, `<= 5 s`) compared with the benchmark's
real time, or a counter (`images/s >= 20`). This script runs the benchmark
programs (or reads JSON files written before) and writes the table, so
anyone regenerates it on their own machine:

    scripts/benchmarks.py --build build                 # run, then write
    scripts/benchmarks.py --json-dir build/bench-json   # write from JSON only

Each program runs once with every benchmark goals.yaml names from it
(`--benchmark_filter`), `--benchmark_repetitions` as goals.yaml says, and
the median of the repetitions is the figure.
"""
import argparse
import json
import os
import re
import subprocess
import sys

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UNITS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def parse_goal(text):
    """'< 20 ms' -> ('time', '<', 0.02); 'images/s >= 20' -> ('counter images/s', '>=', 20)."""
    m = re.fullmatch(r"\s*(<=|<|>=|>)\s*([0-9.e+-]+)\s*(ns|us|ms|s)\s*", text)
    if m:
        return ("time", m.group(1), float(m.group(2)) * UNITS[m.group(3)])
    m = re.fullmatch(r"\s*(\S+)\s*(<=|<|>=|>)\s*([0-9.e+-]+)\s*", text)
    if m:
        return ("counter " + m.group(1), m.group(2), float(m.group(3)))
    raise ValueError(f"bench/goals.yaml: goal '{text}': expected '< N ms' or 'COUNTER >= N'")


def met(op, value, limit):
    return {"<": value < limit, "<=": value <= limit, ">": value > limit, ">=": value >= limit}[op]


def seconds(run):
    return run["real_time"] * UNITS[run.get("time_unit", "ns")]


def format_time(s):
    if s >= 1:
        return f"{s:.2f} s"
    if s >= 1e-3:
        return f"{s * 1e3:.3g} ms"
    return f"{s * 1e6:.3g} us"


def run_programs(build, goals, json_dir, repetitions_default):
    os.makedirs(json_dir, exist_ok=True)
    by_program = {}
    for g in goals:
        by_program.setdefault(g["program"], []).append(g)
    for program, entries in by_program.items():
        exe = os.path.join(build, "bench", program)
        if not os.access(exe, os.X_OK):
            sys.exit(f"{exe} not found: build it with `cmake --build {build} --target benchmarks`")
        names = "|".join("^" + re.escape(e["benchmark"]) + "$" for e in entries)
        reps = max(int(e.get("repetitions", repetitions_default)) for e in entries)
        out = os.path.join(json_dir, program + ".json")
        cmd = [exe, f"--benchmark_filter={names}", f"--benchmark_repetitions={reps}",
               "--benchmark_format=json", f"--benchmark_out={out}", "--benchmark_out_format=json"]
        print("+", " ".join(cmd), file=sys.stderr)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def load_runs(json_dir):
    runs, context = {}, None
    for name in sorted(os.listdir(json_dir)):
        if not name.endswith(".json"):
            continue
        with open(os.path.join(json_dir, name)) as f:
            data = json.load(f)
        context = context or data.get("context", {})
        for b in data.get("benchmarks", []):
            if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
                continue
            key = b.get("run_name", b["name"])
            # A median replaces the single runs of its benchmark.
            if b.get("aggregate_name") == "median" or key not in runs:
                runs[key] = b
    return runs, context or {}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", help="build folder whose bench/ programs to run")
    ap.add_argument("--json-dir", help="folder of Google Benchmark JSON files (default BUILD/bench-json)")
    ap.add_argument("--goals", default=os.path.join(ROOT, "bench", "goals.yaml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "benchmarks.md"))
    args = ap.parse_args()
    with open(args.goals) as f:
        goals = yaml.safe_load(f)["goals"]
    json_dir = args.json_dir or (os.path.join(args.build, "bench-json") if args.build else None)
    if json_dir is None:
        sys.exit("give --build BUILD (run the benchmarks) or --json-dir DIR (read their JSON)")
    if args.build:
        run_programs(args.build, goals, json_dir, 3)
    runs, context = load_runs(json_dir)

    lines = [
        "# Speed",
        "",
        "Written by `scripts/benchmarks.py` from the JSON output of the Google Benchmark",
        "programs in `bench/` (`cmake --build build --target benchmarks`, then",
        "`scripts/benchmarks.py --build build`); the goals and what each benchmark",
        "measures are in `bench/goals.yaml`. Wall time, median of the repetitions;",
        f"rtscalib built as the README's main command builds it (Release); machine:"
        f" {context.get('num_cpus', '?')} CPUs at {context.get('mhz_per_cpu', '?')} MHz, load average"
        f" {' '.join(f'{x:.1f}' for x in context.get('load_avg', []))} when the programs started;"
        " one program at a time.",
        "",
        "| what | goal | measured | met | benchmark |",
        "| --- | --- | --- | --- | --- |",
    ]
    missing = []
    for g in goals:
        run = runs.get(g["benchmark"])
        kind, op, limit = parse_goal(g["goal"])
        if run is None:
            missing.append(g["benchmark"])
            lines.append(f"| {g['what']} | {g['goal']} | not run | | `{g['program']}` `{g['benchmark']}` |")
            continue
        if kind == "time":
            value = seconds(run)
            shown = format_time(value)
        else:
            counter = kind.split(" ", 1)[1]
            if counter not in run:
                sys.exit(f"{g['benchmark']}: no counter '{counter}' in its JSON output")
            value = float(run[counter])
            shown = f"{value:.3g} {counter}"
        extra = []
        for c in g.get("show", []):
            if c in run:
                extra.append(f"{c} {float(run[c]):.3g}")
        if extra:
            shown += " (" + ", ".join(extra) + ")"
        ok = "yes" if met(op, value, limit) else "**no**"
        lines.append(f"| {g['what']} | {g['goal']} | {shown} | {ok} | `{g['program']}` `{g['benchmark']}` |")
    lines.append("")
    with open(args.out, "w") as f:
        f.write("\n".join(lines))
    print(f"wrote {args.out}", file=sys.stderr)
    if missing:
        print("not run: " + ", ".join(missing), file=sys.stderr)


if __name__ == "__main__":
    main()
