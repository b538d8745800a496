#!/usr/bin/env python3
"""Compares two files written by `rtscalib predict` for the same input rows.

    scripts/compare-predictions.py A.csv B.csv [--min-zenith-deg 10 --max-zenith-deg 135]

For records (x, y, z) prints the RMS and largest point distance [m]; for
pixels (u, v) the RMS and largest pixel distance [px]. Rows whose zenith
angle lies in the critical regions are skipped (SPEC 1). Standard library only.
"""
import argparse
import csv
import math
import sys


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--min-zenith-deg", type=float, default=10.0)
    ap.add_argument("--max-zenith-deg", type=float, default=135.0)
    args = ap.parse_args()
    a, b = rows(args.a), rows(args.b)
    if len(a) != len(b):
        sys.exit(f"{args.a} has {len(a)} rows, {args.b} has {len(b)}: not the same input")
    cols, unit = (["x", "y", "z"], "m") if "x" in a[0] else (["u", "v"], "px")
    dists = []
    for i, (ra, rb) in enumerate(zip(a, b), start=2):
        theta = float(ra["theta"])
        zenith = theta if theta <= math.pi else 2 * math.pi - theta
        if not math.radians(args.min_zenith_deg) <= zenith <= math.radians(args.max_zenith_deg):
            continue
        try:
            dists.append(math.dist([float(ra[c]) for c in cols], [float(rb[c]) for c in cols]))
        except ValueError as e:
            sys.exit(f"{args.a}/{args.b}: row {i}: {e}")
    if not dists:
        sys.exit("no rows outside the critical regions")
    rms = math.sqrt(sum(d * d for d in dists) / len(dists))
    print(f"{len(dists)} rows: rms {rms:.4g} {unit}, max {max(dists):.4g} {unit}")


if __name__ == "__main__":
    main()
