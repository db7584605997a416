"""Benchmark of the still reader: synthetic stills against renderer truth, real photographs against labels.

    uv run python scripts/bench_read.py --count 300 [--known-kind] [--real ../shared/real-dev] [--out DIR]

Errors are in minor divisions (|reading - truth| / minor division) and in ml. "No reading" is
counted apart from wrong readings (error over 2 divisions). Stage times are means over images.
The real photographs are read only when their folder exists; nothing is copied from them.
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import statistics
import time
from pathlib import Path

import cv2
import numpy as np

from streamread.overlay import draw_overlay
from streamread.reader import ReaderOptions, read_image
from streamread.synth import render_still

KIND_OPTION = {"syringe": "syringe", "measuring_cylinder": "cylinder", "burette": "burette"}


DETECTOR = None  # set by --detector


def synthetic(count: int, seed: int, known_kind: bool) -> dict[str, object]:
    rows = []
    stage_times: dict[str, list[float]] = collections.defaultdict(list)
    for s in range(seed, seed + count):
        image, truth = render_still(s)
        options = ReaderOptions(apparatus=KIND_OPTION[truth.kind] if known_kind else "auto", detector=DETECTOR)
        reading = read_image(image, options)
        for k, v in reading.timings_s.items():
            stage_times[k].append(v)
        err = None if reading.level is None else abs(reading.level - truth.level_ml) / truth.minor_ml
        rows.append({"seed": s, "apparatus": truth.apparatus, "kind": truth.kind, "truth_ml": truth.level_ml,
                     "read_ml": reading.level, "err_div": err, "minor_ml": truth.minor_ml, "error": reading.error})
        print(f"{s:5d} {truth.apparatus:15s} truth {truth.level_ml:8.3f} "
              + (f"read {reading.level:8.3f} err {err:5.2f} div" if err is not None else f"no reading: {reading.error}"),
              flush=True)
    return {"rows": rows, "times": {k: statistics.mean(v) for k, v in stage_times.items()}}


def summarise(rows: list[dict[str, object]]) -> dict[str, object]:
    n = len(rows)
    errs = np.array([r["err_div"] for r in rows if r["err_div"] is not None], dtype=float)
    ml = np.array([abs(r["read_ml"] - r["truth_ml"]) for r in rows if r["err_div"] is not None], dtype=float)
    return {
        "images": n, "read": int(len(errs)), "no_reading": n - int(len(errs)),
        "within_half_div": int((errs <= 0.5).sum()), "within_half_div_pct": 100.0 * float((errs <= 0.5).sum()) / max(n, 1),
        "median_err_div": float(np.median(errs)) if len(errs) else None,
        "wrong_over_2div": int((errs > 2).sum()), "wrong_pct": 100.0 * float((errs > 2).sum()) / max(n, 1),
        "mae_ml": float(ml.mean()) if len(ml) else None,
    }


def real(folder: Path, overlay_dir: Path | None) -> list[dict[str, object]]:
    rows = []
    with (folder / "labels.csv").open(newline="") as fh:
        for label in csv.DictReader(fh):
            image = cv2.imread(str(folder / label["image"]))
            kind = KIND_OPTION[label["kind"]]
            reading = read_image(image, ReaderOptions(apparatus=kind, detector=DETECTOR))
            minor = float(label["minor_div"])
            readable = label["readable"] != "no"
            err = None if reading.level is None else abs(reading.level - float(label["level"])) / minor
            rows.append({"image": label["image"], "kind": label["kind"], "truth": float(label["level"]),
                         "read": reading.level, "err_div": err, "readable": label["readable"], "error": reading.error,
                         "ok_1div": (err is not None and err <= 1.0) or (not readable and reading.level is None)})
            if overlay_dir is not None:
                overlay_dir.mkdir(parents=True, exist_ok=True)
                cv2.imwrite(str(overlay_dir / (Path(label["image"]).stem + ".overlay.png")), draw_overlay(image, reading))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1000, help="first seed (tests use low seeds; default 1000)")
    parser.add_argument("--known-kind", action="store_true", help="pass the apparatus kind, as --apparatus does")
    parser.add_argument("--detector", action="store_true", help="crop with the bundled ONNX detector first")
    parser.add_argument("--real", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared" / "real-dev")
    parser.add_argument("--out", type=Path, default=Path("out/bench_read"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    if args.detector:
        from streamread.detector import OnnxDetector

        global DETECTOR
        DETECTOR = OnnxDetector()
    syn = synthetic(args.count, args.seed, args.known_kind)
    rows = syn["rows"]
    report: dict[str, object] = {"synthetic": summarise(rows), "stage_mean_s": syn["times"],
                                 "per_kind": {k: summarise([r for r in rows if r["kind"] == k])
                                              for k in ("syringe", "measuring_cylinder", "burette")}}
    reasons = collections.Counter(str(r["error"]).split(",")[0] for r in rows if r["err_div"] is None)
    report["no_reading_reasons"] = dict(reasons.most_common(12))
    if (args.real / "labels.csv").is_file():
        real_rows = real(args.real, args.out / "real_overlays")
        report["real"] = {"rows": real_rows, "ok_within_1div": sum(bool(r["ok_1div"]) for r in real_rows),
                          "images": len(real_rows)}
    report["wall_s"] = time.perf_counter() - start
    (args.out / "report.json").write_text(json.dumps(report, indent=1))
    print(json.dumps({k: v for k, v in report.items() if k != "real"}, indent=1))
    if "real" in report:
        for r in report["real"]["rows"]:  # type: ignore[index]
            e = f"{r['err_div']:.2f} div" if r["err_div"] is not None else f"no reading ({r['error']})"
            print(f"real {r['image']} {r['kind']:18s} truth {r['truth']:8.3f} -> {e}")
        print(f"real: {report['real']['ok_within_1div']}/{report['real']['images']} within 1 division")  # type: ignore[index]


if __name__ == "__main__":
    main()
