"""How well the apparatus detector finds and names apparatus.

    uv run python scripts/bench_detector.py data/heldout.npz [--model PATH] [--out DIR]

- held-out synthetic set (from ``detector_data.py`` with seeds the model never saw):
  recall and precision at IoU 0.5, class accuracy of the matched boxes, false boxes on
  images without an apparatus;
- the real photographs in ``../shared/real-dev`` when present: overlays of what it finds
  (written to ``--out``, never into the repository) and how many apparatus it finds with
  the right class (from ``labels.csv``);
- inference time per image at the model's input size on one core.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from streamread.detector import OnnxDetector  # noqa: E402

REAL = ROOT.parent / "shared" / "real-dev"


def iou(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("heldout")
    parser.add_argument("--model", default=None)
    parser.add_argument("--out", default="/tmp/streamread-detector")
    args = parser.parse_args()
    det = OnnxDetector(args.model, threads=1)
    data = np.load(args.heldout)
    images, rows = data["images"], data["boxes"]
    names = list(data["classes"])
    tp = fp = fn = right_class = 0
    empty_images = empty_false = 0
    times = []
    for i, image in enumerate(images):
        truth = [(names[int(r[1])], tuple(float(v) for v in r[2:6])) for r in rows[rows[:, 0] == i]]
        t = time.perf_counter()
        found = det.detect_all(image)
        times.append(time.perf_counter() - t)
        used = set()
        for kind, box in truth:
            best = max(((iou(box, d.xyxy), j) for j, d in enumerate(found) if j not in used), default=(0.0, -1))
            if best[0] >= 0.5:
                tp += 1
                used.add(best[1])
                right_class += found[best[1]].class_name == kind
            else:
                fn += 1
        fp += len(found) - len(used)
        if not truth:
            empty_images += 1
            empty_false += len(found) > 0
    recall = tp / max(tp + fn, 1)
    precision = tp / max(tp + fp, 1)
    print(f"held-out synthetic: {len(images)} images, {tp + fn} apparatus, {empty_images} without one")
    print(f"  recall {recall:.3f}, precision {precision:.3f} at IoU 0.5; class accuracy {right_class / max(tp, 1):.3f}"
          f"; false boxes on {empty_false}/{empty_images} empty images")
    print(f"  inference at {det.size}x{det.size} on one core: median {1000 * statistics.median(times):.1f} ms")

    labels = REAL / "labels.csv"
    if labels.is_file():
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        rows_real = list(csv.DictReader(open(labels)))
        kind_key = next((k for k in ("kind", "apparatus", "type", "class") if k in rows_real[0]), None)
        file_key = next((k for k in ("image", "file", "filename", "name") if k in rows_real[0]), None)
        right = 0
        for r in rows_real:
            path = REAL / r[file_key]  # type: ignore[index]
            image = cv2.imread(str(path))
            if image is None:
                continue
            t = time.perf_counter()
            found = det.detect_all(image)
            ms = 1000 * (time.perf_counter() - t)
            want = r.get(kind_key, "") if kind_key else ""
            ok = bool(found) and found[0].class_name == want
            right += ok
            for d in found:
                x0, y0, x1, y1 = (int(v) for v in d.xyxy)
                cv2.rectangle(image, (x0, y0), (x1, y1), (0, 0, 255), 3)
                cv2.putText(image, f"{d.class_name} {d.score:.2f}", (x0 + 4, max(20, y0 + 24)), cv2.FONT_HERSHEY_SIMPLEX,
                            0.8, (0, 0, 255), 2)
            cv2.imwrite(str(out / f"{path.stem}.detect.jpg"), image)
            top = f"{found[0].class_name} {found[0].score:.2f}" if found else "nothing"
            print(f"real {path.name}: truth {want or '?'}; found {len(found)} ({top}); {'right' if ok else 'wrong'}; "
                  f"{ms:.0f} ms")
        print(f"real photographs: {right}/{len(rows_real)} found with the right class (top box); overlays in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
