"""Train the bore networks (``streamread/models/meniscus.onnx``, ``stopper.onnx``) on rendered stills.

Two steps, in two environments:

1. ``gather`` (the project's own: ``uv run``) renders stills of measuring cylinders and
   burettes (``--indicator meniscus``) or syringes (``--indicator stopper``), calibrates each
   as the reader does (``bench_indicator.py``'s calibrations: the bundled detector cropping,
   the kind given, cached in ``--cache``), and keeps each calibrated bore as the network sees
   it (``bore_net.bore_input``, a syringe's turned nozzle up) with the truth's row. Never the
   dev or held-out seeds: the tuning set 3000-3599 and fresh seeds from 4000 on.

       uv run python scripts/train_bore_net.py gather --indicator stopper --seed 4000 --count 1000 --out /tmp/stop_4000.pkl

2. ``train`` (a venv with torch and onnx, as for ``train_digits.py``: see
   ``scripts/train-requirements.txt``) fits the network and writes the ONNX model.

       /tmp/train/bin/python scripts/train_bore_net.py train --data /tmp/stop_*.pkl --out streamread/models/stopper.onnx

The network: 2-D convolutions over the bore (5 planes: B, G, R, normalised grey, print mask),
strided across the columns down to 4, then the mean and the maximum over the columns; along the
rows, four dilated 1-D convolutions (about 60 rows, 7.5 divisions, of context each way) and a
score per row. A "none here" score comes from the rows' features pooled. The loss is the
cross-entropy of a softmax over the rows the reader may choose and "none", the truth's row
smoothed over its neighbours. Augmented: the rows cut to a random part (so that the surface is
sometimes outside: "none"), mirrored left-right, brightness and contrast.
"""

from __future__ import annotations

import argparse
import glob
import math
import pickle
import random
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))  # bench_indicator's calibrations


def gather(indicator: str, seed: int, count: int, out: Path, cache_dir: Path, rebuild: bool) -> None:
    from bench_indicator import calibrations  # its calibrations, made once and cached, are the ones scored

    from streamread.bore_net import CONTEXT_DIV, bore_input
    from streamread.indicator import meniscus_view, stopper_view
    from streamread.orientation import cut_strip
    from streamread.profile import default_profile
    from streamread.reader import _rows_seen
    from streamread.segment import to_gray
    from streamread.synth import render_still

    kinds = ("syringe",) if indicator == "stopper" else ("burette", "cylinder")
    samples = []
    t = time.perf_counter()
    for apparatus in kinds:
        for s, _, cal, _ in calibrations(apparatus, seed, count, cache_dir, rebuild):
            if cal is None:
                continue
            image, truth = render_still(s)
            strip = cut_strip(image, cal.upright)
            rows_seen = _rows_seen(cal, image.shape[:2])
            if indicator == "stopper":
                seen = stopper_view(strip.shape, cal.marks, cal.fit, cal.bore_x_up, rows_seen)
                if seen is None:
                    continue
                masked, (lo, hi), turned = seen
                d = cal.fit.division_px
            else:
                view = meniscus_view(to_gray(strip), cal.marks, cal.fit, cal.bore_x_up,
                                     default_profile(cal.apparatus).indicator.min_contrast, strip, rows_seen)
                if view is None:
                    continue
                masked, (lo, hi), d, turned = view.masked, view.allowed_rows, view.d, False
            if hi <= lo:
                continue
            context = int(round(CONTEXT_DIV * d))
            planes, scale, first = bore_input(strip, masked, cal.bore_x_up, d, (lo - context, hi + context))
            ty = float(cal.upright.from_input(np.array(truth.indicator_px))[0][1])

            def index(y: float) -> float:
                return (y + 0.5 - first) * scale - 0.5
            target = index(ty) if truth.visible and lo <= ty <= hi else -1.0
            first_i, last_i = index(lo), index(hi)
            if turned:  # as ``BoreNet.locate`` turns it: the nozzle at the top
                n = planes.shape[1]
                planes = planes[:, ::-1]
                target = n - 1 - target if target >= 0 else -1.0
                first_i, last_i = n - 1 - last_i, n - 1 - first_i
            samples.append(dict(seed=s, planes=planes.astype(np.float16), target=target, lo=first_i, hi=last_i))
    with out.open("wb") as f:
        pickle.dump(samples, f)
    print(f"{len(samples)} bores ({sum(x['target'] >= 0 for x in samples)} with a {indicator}) in "
          f"{time.perf_counter() - t:.0f} s: {out}")


PAD = 64  # rows of context the gathered bores hold beyond the rows to choose from (CONTEXT_DIV * 8)


def _network():  # noqa: ANN202 - torch is imported here only
    import torch
    from torch import nn

    class MeniscusNetwork(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.columns = nn.Sequential(
                nn.Conv2d(5, 16, 3, padding=1, stride=(1, 2)), nn.ReLU(),
                nn.Conv2d(16, 32, 3, padding=1, stride=(1, 2)), nn.ReLU(),
                nn.Conv2d(32, 32, 3, padding=1, stride=(1, 2)), nn.ReLU(),
            )
            layers: list[nn.Module] = [nn.Conv1d(64, 48, 5, padding=2), nn.ReLU()]
            for dilation in (2, 4, 8):
                layers += [nn.Conv1d(48, 48, 5, padding=2 * dilation, dilation=dilation), nn.ReLU()]
            self.rows = nn.Sequential(*layers)
            self.row_score = nn.Conv1d(48, 1, 1)
            self.none_score = nn.Linear(96, 1)

        def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            f = self.columns(x)  # (B, 32, H, 4)
            f = torch.cat([f.mean(dim=3), f.amax(dim=3)], dim=1)  # (B, 64, H)
            f = self.rows(f)  # (B, 48, H)
            pooled = torch.cat([f.mean(dim=2), f.amax(dim=2)], dim=1)
            return self.row_score(f)[:, 0], self.none_score(pooled)[:, 0]

    return MeniscusNetwork()


WINDOW = 320  # rows of a training cut (40 divisions): a whole bore costs four times more and teaches no more
EDGE = 32  # rows at a cut's ends left out of the choice: their context is cut off


def _augmented(sample: dict, rng: random.Random) -> tuple[np.ndarray, int, int, float]:
    """(planes, first row to choose, last, target row or -1) of a random cut of ``sample``:
    ``WINDOW`` rows around the surface four times in five, anywhere else the fifth."""
    planes = sample["planes"]
    height = planes.shape[1]
    lo, hi, target = int(math.ceil(sample["lo"])), int(sample["hi"]), sample["target"]
    if height > WINDOW:
        if target >= 0 and rng.random() < 0.8:
            top = int(target) - rng.randint(EDGE, WINDOW - EDGE)
        else:
            top = rng.randint(0, height - WINDOW)
        top = min(max(0, top), height - WINDOW)
        planes = planes[:, top: top + WINDOW]
        lo, hi = max(lo - top, EDGE if top > 0 else 0), min(hi - top, WINDOW - 1 - EDGE)
        target = target - top if target >= 0 and lo <= target - top <= hi else -1.0
    planes = planes.astype(np.float32)
    if rng.random() < 0.5:
        planes = planes[:, :, ::-1]
    gain, shift = rng.uniform(0.75, 1.25), rng.uniform(-0.12, 0.12)
    planes = planes.copy()
    planes[:3] = np.clip(planes[:3] * gain + shift, -0.5, 0.5)
    return planes, lo, hi, target


def _batch(items: list[tuple[np.ndarray, int, int, float]]):  # noqa: ANN202
    import torch
    height = max(p.shape[1] for p, *_ in items)
    x = np.zeros((len(items), 5, height, items[0][0].shape[2]), np.float32)
    allowed = np.zeros((len(items), height), bool)
    soft = np.zeros((len(items), height + 1), np.float32)  # the last column: "none"
    rows = np.arange(height)
    for i, (p, lo, hi, target) in enumerate(items):
        x[i, :, : p.shape[1]] = p
        allowed[i, lo: hi + 1] = True
        if target < 0:
            soft[i, -1] = 1
        else:
            w = np.exp(-0.5 * ((rows - target) / 1.0) ** 2) * allowed[i]
            soft[i, :-1] = w / w.sum()
    return torch.from_numpy(x), torch.from_numpy(allowed), torch.from_numpy(soft)


def _loss(model, x, allowed, soft):  # noqa: ANN001, ANN202
    import torch
    rows, none = model(x)
    rows = rows.masked_fill(~allowed, -1e4)
    logits = torch.cat([rows, none[:, None]], dim=1)
    return -(soft * torch.log_softmax(logits, dim=1)).sum(dim=1).mean(), logits


def train(paths: list[str], out: Path, epochs: int, seed: int, batch_size: int) -> None:
    import torch
    torch.manual_seed(seed)
    rng = random.Random(seed)
    samples = [s for p in paths for s in pickle.load(open(p, "rb"))]
    rng.shuffle(samples)
    n_val = max(1, len(samples) // 8)
    val, fit = samples[:n_val], samples[n_val:]
    print(f"{len(fit)} bores to fit, {len(val)} to validate")
    model = _network()
    optimiser = torch.optim.AdamW(model.parameters(), lr=2e-3, weight_decay=1e-4)
    steps = epochs * math.ceil(len(fit) / batch_size)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, max_lr=2e-3, total_steps=steps)
    for epoch in range(epochs):
        model.train()
        rng.shuffle(fit)
        t, total = time.perf_counter(), 0.0
        for b in range(0, len(fit), batch_size):
            x, allowed, soft = _batch([_augmented(s, rng) for s in fit[b: b + batch_size]])
            loss, _ = _loss(model, x, allowed, soft)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            schedule.step()
            total += float(loss.detach()) * len(x)
        print(f"epoch {epoch + 1}: loss {total / len(fit):.3f}, {evaluate(model, val)} "
              f"({time.perf_counter() - t:.0f} s)")
    export(model, out)


def evaluate(model, samples: list[dict]) -> str:  # noqa: ANN001
    """Right (within 4 rows, half a division), wrong, and "none" answers at the reader's confidence."""
    import torch

    from streamread.bore_net import MIN_CONFIDENCE, PX_PER_DIVISION
    model.eval()
    right = wrong = none = 0
    with torch.no_grad():
        for s in samples:
            planes = s["planes"].astype(np.float32)
            lo, hi = int(math.ceil(s["lo"])), int(s["hi"])
            x, allowed, _ = _batch([(planes, lo, hi, -1.0)])
            _, logits = _loss(model, x, allowed, torch.zeros(1, x.shape[2] + 1))
            p = torch.softmax(logits[0], dim=0).numpy()
            best = int(np.argmax(p[:-1]))
            if p[max(0, best - int(PX_PER_DIVISION)): best + int(PX_PER_DIVISION) + 1].sum() < MIN_CONFIDENCE:
                none += 1
            elif s["target"] >= 0 and abs(best - s["target"]) <= 4:
                right += 1
            else:
                wrong += 1
    return f"right {right}, wrong {wrong}, none {none} of {len(samples)}"


def export(model, out: Path) -> None:  # noqa: ANN001
    import onnx
    import torch

    from streamread.bore_net import WIDTH
    model.eval()
    example = torch.zeros(1, 5, 200, WIDTH)
    torch.onnx.export(model, (example,), str(out), input_names=["bore"], output_names=["rows", "none"],
                      dynamic_axes={"bore": {2: "height"}, "rows": {1: "height"}}, opset_version=17, dynamo=False)
    proto = onnx.load(str(out))
    proto.ir_version = min(proto.ir_version, 13)  # onnxruntime 1.31 refuses IR 14
    onnx.save(proto, str(out))
    print(f"wrote {out} ({out.stat().st_size // 1024} kB)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="step", required=True)
    g = sub.add_parser("gather", help="render, calibrate and keep the bores (project environment)")
    g.add_argument("--indicator", choices=("meniscus", "stopper"), default="meniscus")
    g.add_argument("--seed", type=int, default=4000)
    g.add_argument("--count", type=int, default=1000)
    g.add_argument("--out", type=Path, required=True)
    g.add_argument("--cache", type=Path, default=Path(".cache"),
                   help="where the calibrations are kept (bench_indicator.py's cache: made on first use)")
    g.add_argument("--rebuild", action="store_true", help="calibrate again, replacing the cache")
    t = sub.add_parser("train", help="fit the network and write the ONNX model (torch environment)")
    t.add_argument("--data", nargs="+", required=True)
    t.add_argument("--out", type=Path, default=Path("streamread/models/meniscus.onnx"))
    t.add_argument("--epochs", type=int, default=30)
    t.add_argument("--batch-size", type=int, default=8)
    t.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    if args.step == "gather":
        gather(args.indicator, args.seed, args.count, args.out, args.cache, args.rebuild)
    else:
        train([p for pattern in args.data for p in sorted(glob.glob(pattern))], args.out, args.epochs, args.seed,
              args.batch_size)


if __name__ == "__main__":
    main()
