"""The indicator stage alone against renderer truth, each still's calibration held fixed.

A rule for the meniscus or the stopper changes only the indicator stage, yet ``bench_read.py``
re-runs detection, OCR and the fit for every still (0.4 s each), and two versions of a rule
are compared there on calibrations that may differ. This script calibrates each still of one
kind once (the bundled detector cropping, the kind given), keeps the calibrations in a cache
file, then finds only the indicator in every calibrated still: a rule is judged in seconds, on
the same calibrations every time.

    uv run python scripts/bench_indicator.py --apparatus burette --seed 3000 --count 600 [--verbose]

Rules are tried first on seeds 3000-3599 (the tuning set), then on the dev seeds 1000-1299,
and only then on the held-out seeds 2000-2299 (see README). The cache (``.cache/`` by default,
keyed by kind and seeds) is built on first use; ``--rebuild`` makes it again, which a change to
the renderer or to any stage before the indicator needs. Outcomes, in minor divisions: "ok"
within half a division, "off" up to two, "wrong" over two, "none" for no reading. Each line
for a still that is not "ok" also gives the calibration's own error at the truth's row
(``cal@truth``): a calibration off by divisions makes a wrong reading whatever the indicator.
"""

from __future__ import annotations

import argparse
import collections
import pickle
import time
from pathlib import Path

import numpy as np

from streamread.detector import OnnxDetector
from streamread.reader import ReaderOptions, calibrate, read_with
from streamread.synth import render_still
from streamread.synth.scene import sample_scene

APPARATUS = ("burette", "cylinder", "syringe")  # the reader's kinds, which also begin the catalogue's names


def calibrations(apparatus: str, seed: int, count: int, cache_dir: Path, rebuild: bool) -> list[tuple]:
    """(seed, truth, calibration or None, why) for each still of ``apparatus`` in the seeds."""
    path = cache_dir / f"calibrations_{apparatus}_{seed}_{count}.pkl"
    if path.is_file() and not rebuild:
        with path.open("rb") as f:
            return pickle.load(f)
    detector = OnnxDetector()
    found = []
    t = time.perf_counter()
    for s in range(seed, seed + count):
        if not sample_scene(s).apparatus.startswith(apparatus):
            continue
        image, truth = render_still(s)
        cal, why = calibrate(image, ReaderOptions(apparatus=apparatus, detector=detector))
        found.append((s, truth, cal, why))
    cache_dir.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        pickle.dump(found, f)
    print(f"calibrated {len(found)} stills in {time.perf_counter() - t:.0f} s; cached in {path}")
    return found


def outcome(err_div: float | None) -> str:
    if err_div is None:
        return "none"
    return "ok" if abs(err_div) <= 0.5 else "wrong" if abs(err_div) > 2 else "off"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--apparatus", choices=APPARATUS, required=True)
    parser.add_argument("--seed", type=int, default=3000)
    parser.add_argument("--count", type=int, default=600)
    parser.add_argument("--cache", type=Path, default=Path(".cache"), help="where calibrations are kept")
    parser.add_argument("--rebuild", action="store_true", help="calibrate again, replacing the cache")
    parser.add_argument("--verbose", action="store_true", help="a line for every still, not only those not ok")
    args = parser.parse_args()
    stills = calibrations(args.apparatus, args.seed, args.count, args.cache, args.rebuild)
    counts: collections.Counter[str] = collections.Counter()
    t = time.perf_counter()
    for s, truth, cal, _ in stills:
        if cal is None:
            continue
        image, _ = render_still(s)
        reading = read_with(image, cal)
        truth_row = float(cal.upright.from_input(np.array([truth.indicator_px]))[0, 1])
        cal_err = (cal.fit.value_at(truth_row) - truth.level_ml) / truth.minor_ml
        err = None if reading.level is None else (reading.level - truth.level_ml) / truth.minor_ml
        what = outcome(err)
        counts[what] += 1
        if what != "ok" or args.verbose:
            print(f"{s:5d} {truth.apparatus:15s} {what:5s} "
                  + (f"err {err:+7.2f} div" if err is not None else f"{'':15s}")
                  + f"  cal@truth {cal_err:+6.2f}  {reading.error or ''}")
    calibrated = sum(counts.values())
    print(f"{args.apparatus}, seeds {args.seed}-{args.seed + args.count - 1}: {len(stills)} stills, "
          f"{calibrated} calibrated; " + ", ".join(f"{k} {counts[k]}" for k in ("ok", "off", "wrong", "none"))
          + f" ({time.perf_counter() - t:.0f} s)")


if __name__ == "__main__":
    main()
