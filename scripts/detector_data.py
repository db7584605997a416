"""Render the detector's training or held-out set: letterboxed images, boxes and classes.

    uv run python scripts/detector_data.py --out data/train.npz --seed 0 --count 4000
    uv run python scripts/detector_data.py --out data/heldout.npz --seed 900000 --count 400

Each image is a random synthetic scene (any apparatus, any rotation, clutter and look-alike
distractors: graduated rulers, labels with numbers, bottles, cables), letterboxed to a square
of ``--size`` pixels as the detector sees it. A share of scenes is the recording setup (the
apparatus centred and large) and a share has no apparatus at all (background and distractors
only: the model must learn to find nothing there). Seeds never overlap between the sets.
"""

from __future__ import annotations

import argparse
import multiprocessing
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from streamread.detector import CLASS_NAMES, letterbox  # noqa: E402
from streamread.synth.background import make_background  # noqa: E402
from streamread.synth.scene import render, sample_scene  # noqa: E402


def one(args: tuple[int, int, float]) -> tuple[np.ndarray, np.ndarray]:
    """(letterboxed image, boxes [K, 5] = class, x0, y0, x1, y1 in letterbox pixels) for one seed."""
    seed, size, empty_share = args
    rng = np.random.default_rng(seed)
    kind = rng.random()
    if kind < empty_share:  # no apparatus: clutter only (rulers, labels, bottles, cables)
        w, h = [(640, 480), (800, 600), (1280, 720), (960, 540)][int(rng.integers(0, 4))]
        scene = make_background(rng, w, h, dark=bool(rng.random() < 0.3), n_distractors=int(rng.integers(2, 9)))
        image = np.clip(scene * 255, 0, 255).astype(np.uint8)
        boxed, _, _ = letterbox(image, size)
        return boxed, np.zeros((0, 5), np.float32)
    if kind < empty_share + 0.23:  # the recording setup: centred, large, a little perspective
        params = sample_scene(seed, size_fraction=float(rng.uniform(0.5, 0.95)), centered=True,
                              tilt_scale=0.4, roll_deg=float(rng.uniform(0, 360)))
    else:
        params = sample_scene(seed)
    image, truth = render(params)
    boxed, scale, (px, py) = letterbox(image, size)
    if truth.box_xyxy is None:
        return boxed, np.zeros((0, 5), np.float32)
    x0, y0, x1, y1 = truth.box_xyxy
    box = np.array([[CLASS_NAMES.index(truth.kind), x0 * scale + px, y0 * scale + py, x1 * scale + px,
                     y1 * scale + py]], np.float32)
    return boxed, box


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--count", type=int, default=4000)
    parser.add_argument("--size", type=int, default=320)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--empty-share", type=float, default=0.12, help="share of scenes without an apparatus")
    args = parser.parse_args()
    jobs = [(args.seed + i, args.size, args.empty_share) for i in range(args.count)]
    with multiprocessing.Pool(args.workers) as pool:
        results = []
        for i, r in enumerate(pool.imap(one, jobs, chunksize=8)):
            results.append(r)
            if (i + 1) % 200 == 0:
                print(f"{i + 1}/{args.count}", file=sys.stderr, flush=True)
    images = np.stack([r[0] for r in results])
    boxes = np.concatenate([np.concatenate([np.full((len(r[1]), 1), i, np.float32), r[1]], axis=1)
                            for i, r in enumerate(results)])  # rows: image index, class, x0, y0, x1, y1
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.out, images=images, boxes=boxes, seeds=np.array([j[0] for j in jobs]),
                        classes=np.array(CLASS_NAMES))
    print(f"wrote {args.out}: {len(images)} images, {len(boxes)} boxes", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
