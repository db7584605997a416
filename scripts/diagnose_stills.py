"""Stage-by-stage diagnosis of the still reader against renderer truth.

For each seeded still: did orientation find the scale axis, is the mark grid's spacing right,
how many numbers did OCR read right, is the fit's division right, where is the indicator
relative to the truth, and what is the final error. Prints one line per image and totals.

    uv run python scripts/diagnose_stills.py --count 40 [--seed 0] [--apparatus syringe]
"""

from __future__ import annotations

import argparse
import collections
import math

import numpy as np

from streamread.reader import ReaderOptions, calibrate, read_with
from streamread.synth import render_still


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--apparatus", default=None)
    parser.add_argument("--known-kind", action="store_true", help="tell the reader the apparatus kind")
    args = parser.parse_args()
    failures: collections.Counter[str] = collections.Counter()
    errors = []
    for seed in range(args.seed, args.seed + args.count):
        image, truth = render_still(seed, args.apparatus)
        timings: dict[str, float] = {}
        options = ReaderOptions(apparatus=truth.kind if args.known_kind else "auto")
        cal, why = calibrate(image, options, timings)
        head = f"{seed:4d} {truth.apparatus:15s} {truth.level_ml:8.3f}"
        if cal is None:
            failures[f"calibrate: {why.split(' (')[0] if why else '?'}"] += 1
            print(f"{head} CAL FAIL: {why}")
            continue
        up = cal.upright
        (ax0, ay0), (ax1, ay1) = truth.axis_px
        axis = math.degrees(math.atan2(ay1 - ay0, ax1 - ax0)) % 180
        angle_err = abs((axis - up.angle_deg) % 180)
        angle_err = min(angle_err, 180 - angle_err)
        truth_labels = [(up.from_input(np.array([m.center_px]))[0][1], float(m.label)) for m in truth.marks
                        if m.label and m.in_frame]
        ok_reads = 0
        for r in cal.reads:
            if r.value is None:
                continue
            near = min(truth_labels, key=lambda t: abs(t[0] - r.y_up), default=None)
            if near and abs(near[0] - r.y_up) < 3 * truth.px_per_division and abs(near[1] - r.value) < 1e-6:
                ok_reads += 1
        step_ok = abs(cal.fit.minor_ml - truth.minor_ml) < 1e-9
        ind_truth_up = up.from_input(np.array([truth.indicator_px]))[0]
        value_at_truth = cal.fit.value_at(float(ind_truth_up[1]))
        fit_err = abs(value_at_truth - truth.level_ml) / truth.minor_ml
        reading = read_with(image, cal, timings=timings)
        if reading.level is None:
            failures[f"indicator: {reading.error}"] += 1
            print(f"{head} kind {cal.apparatus[:8]:8s} reads {ok_reads}/{len(cal.reads)} step {'ok' if step_ok else 'BAD'}"
                  f" fit@truth {fit_err:.2f} div, NO READING: {reading.error}")
            continue
        ind_dy = reading.indicator.y_up - ind_truth_up[1] if reading.indicator else float("nan")
        err = abs(reading.level - truth.level_ml) / truth.minor_ml
        errors.append(err)
        if err > 0.5:
            failures["wrong: fit" if fit_err > 0.5 else "wrong: indicator" if abs(ind_dy) > 0.5 * truth.px_per_division
                     else "wrong: other"] += 1
        print(f"{head} kind {cal.apparatus[:8]:8s} angle {angle_err:4.1f} reads {ok_reads}/{len(cal.reads)} step "
              f"{'ok' if step_ok else 'BAD'} fit@truth {fit_err:.2f} div ind dy {ind_dy:+.1f}px "
              f"(div {truth.px_per_division:.1f}px) -> {reading.level:.3f} err {err:.2f} div")
    e = np.array(errors)
    n = args.count
    print(f"\nread {len(e)}/{n}; within 0.5 div {(e <= 0.5).sum()}/{n}; median {np.median(e) if len(e) else float('nan'):.3f}"
          f"; wrong (>2 div) {(e > 2).sum()}")
    for k, v in failures.most_common():
        print(f"  {v:3d}  {k}")


if __name__ == "__main__":
    main()
