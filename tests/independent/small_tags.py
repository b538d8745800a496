#!/usr/bin/env python3
"""Recall and accuracy of `rtscalib detect` on small tags it did not render.

render_session.py (beside this file, written from SPEC.md alone) renders its
session with smaller tags: 6 cm tag36h11 (2 cm apart) on boards 3, 4, 5 and
6 m from the instrument, so that its zoom 0 (fx 1500 px) sees tags of 15-30
px (1.9-3.8 px per code bit) and its zoom 1 (fx 3500 px) tags of 35-70 px.
Only the board constants are replaced, from outside (render_session.py is
not changed; its camera, chain, renderer and exact corners are its own).

Then `rtscalib detect` runs on the photos and every detected corner is
compared with render_session.py's exact projection. Printed per zoom: the
whole-tag recall (tags detected with all four corners / tags whose four
corners the exact list has, i.e. lie wholly in the image) and the RMS and
mean of the corner errors, per zoom and per size class (px per code bit along
the tag's shortest edge, from the exact corners). Exits 1 when a zoom's recall
is below 95 % or a size class's RMS above 0.1 px.

Usage: small_tags.py RTSCALIB_BINARY WORK_DIR [--ss N]   (about 3 minutes)
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import render_session as rs  # noqa: E402

TAG, SPACING = 0.06, 0.02
DISTANCES = [3.0, 4.0, 5.0, 6.0]
# Size classes: px per code bit (a tag36h11 quad is 8 bits across).
CLASSES = [(1.5, 2.5), (2.5, 3.5), (3.5, 5.0), (5.0, 7.0), (7.0, 100.0)]
MIN_RECALL = 0.95
MAX_RMS_PX = 0.1


def render(out, ss):
    rs.TAG, rs.SPACING = TAG, SPACING
    rs.MARGIN = TAG + SPACING
    rs.BOARD_PLACEMENT = [(p[0], p[1], p[2], d) + tuple(p[4:])
                          for p, d in zip(rs.BOARD_PLACEMENT, DISTANCES)]
    sys.argv = ["render_session.py", "--out", out, "--ss", str(ss)]
    rs.main()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rtscalib")
    ap.add_argument("work")
    ap.add_argument("--ss", type=int, default=4)
    ap.add_argument("--keep", action="store_true", help="reuse WORK's rendered photos")
    args = ap.parse_args()
    work = os.path.abspath(args.work)
    if not (args.keep and os.path.exists(os.path.join(work, "exact_pixels.csv"))):
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        render(work, args.ss)
    photos = os.path.join(work, "session_photo")
    detected = os.path.join(work, "detected.csv")
    subprocess.run([os.path.abspath(args.rtscalib), "detect", "--shots",
                    os.path.join(photos, "shots.csv"), "--targets",
                    os.path.join(photos, "targets.yaml"), "--out", detected, "--jobs", "2",
                    "--quiet", "--force"], check=True, stdout=subprocess.DEVNULL)

    exact = {}  # (shot, tag) -> {corner: (zoom, u, v)}
    for r in csv.DictReader(open(os.path.join(work, "exact_pixels.csv"))):
        exact.setdefault((r["shot"], int(r["target"])), {})[int(r["corner"])] = (
            int(r["zoom"]), float(r["u"]), float(r["v"]))
    found = {}
    for r in csv.DictReader(open(detected)):
        found.setdefault((r["shot"], int(r["target"])), {})[int(r["corner"])] = (
            float(r["u"]), float(r["v"]))

    per_zoom, per_class, failures = {}, {}, []
    for key, corners in exact.items():
        if len(corners) != 4:
            continue
        zoom = corners[0][0]
        uv = np.array([corners[k][1:] for k in range(4)])
        bit = min(np.linalg.norm(uv[(k + 1) % 4] - uv[k]) for k in range(4)) / 8
        cls = next(c for c in CLASSES if c[0] <= bit < c[1]) if bit >= CLASSES[0][0] else None
        z = per_zoom.setdefault(zoom, {"whole": 0, "found": 0, "err": []})
        z["whole"] += 1
        if cls is not None:
            c = per_class.setdefault((zoom, cls), {"whole": 0, "found": 0, "err": []})
            c["whole"] += 1
        d = found.get(key)
        if d is None or len(d) != 4:
            continue
        err = [np.array(d[k]) - uv[k] for k in range(4)]
        z["found"] += 1
        z["err"] += err
        if cls is not None:
            c["found"] += 1
            c["err"] += err

    def line(name, s):
        e = np.array(s["err"]) if s["err"] else np.zeros((0, 2))
        rms = math.sqrt((e ** 2).sum(axis=1).mean()) if len(e) else float("nan")
        mean = e.mean(axis=0) if len(e) else np.array([math.nan, math.nan])
        recall = s["found"] / s["whole"] if s["whole"] else float("nan")
        print(f"{name:28s} tags {s['whole']:5d}  found {s['found']:5d}  recall {100 * recall:6.2f} %"
              f"  corner RMS {rms:.4f} px  mean ({mean[0]:+.4f}, {mean[1]:+.4f}) px")
        return recall, rms

    for zoom in sorted(per_zoom):
        recall, rms = line(f"zoom {zoom}", per_zoom[zoom])
        if not recall >= MIN_RECALL:
            failures.append(f"zoom {zoom}: recall {100 * recall:.2f} % < {100 * MIN_RECALL:.0f} %")
        for cls in CLASSES:
            if (zoom, cls) in per_class:
                recall, rms = line(f"  {cls[0]:.1f}-{cls[1]:.1f} px per bit", per_class[(zoom, cls)])
                if rms > MAX_RMS_PX:
                    failures.append(f"zoom {zoom}, {cls} px per bit: RMS {rms:.4f} px")
    for f in failures:
        print("FAIL  " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
