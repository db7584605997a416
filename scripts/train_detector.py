"""Train the bundled apparatus detector on synthetic renders and export it as YOLO-format ONNX.

A compact model of our own, not ultralytics (AGPL-3.0, and it wants opencv-python): a
depthwise-separable CNN to stride 16 with dilated context and a global-context vector, one
anchor-free prediction per cell (YOLOv8's decoupled idea, reduced): box centre offset, log
width and height, and one sigmoid score per class. The export wraps decoding so the ONNX file
has exactly Ultralytics' layout: input ``[1, 3, S, S]`` RGB 0-1 letterboxed, output
``[1, 4 + 3, N]`` (cx, cy, w, h in input pixels, then class scores), with the class names in
the metadata. CPU only, reproducible from the seeds:

    python -m venv .train && .train/bin/pip install -r scripts/train-requirements.txt
    (the data commands and the two training stages are in README.md, "The apparatus detector")

(``uv`` would fetch the CUDA build of torch; the plain venv takes the CPU wheel.)
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812
from torch import nn

CLASS_NAMES = ("syringe", "measuring_cylinder", "burette")
STRIDE = 16


def dwsep(cin: int, cout: int, stride: int = 1, dilation: int = 1) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(cin, cin, 3, stride, padding=dilation, dilation=dilation, groups=cin, bias=False),
        nn.BatchNorm2d(cin), nn.ReLU(inplace=True),
        nn.Conv2d(cin, cout, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))


class Residual(nn.Module):
    def __init__(self, block: nn.Module) -> None:
        super().__init__()
        self.block = block

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.block(x)


class TinyDetector(nn.Module):
    """Raw outputs per cell: [dx, dy, log_w, log_h, class logits...] on a stride-16 grid."""

    def __init__(self, n_classes: int = 3) -> None:
        super().__init__()
        self.features = nn.Sequential(
            nn.Conv2d(3, 16, 3, 2, 1, bias=False), nn.BatchNorm2d(16), nn.ReLU(inplace=True),   # /2
            dwsep(16, 32, 2), Residual(dwsep(32, 32)),                                         # /4
            dwsep(32, 64, 2), Residual(dwsep(64, 64)), Residual(dwsep(64, 64)),                # /8
            dwsep(64, 128, 2),                                                                 # /16
            Residual(dwsep(128, 128, dilation=1)), Residual(dwsep(128, 128, dilation=2)),
            Residual(dwsep(128, 128, dilation=4)), Residual(dwsep(128, 128, dilation=8)))
        self.context = nn.Linear(128, 128)
        self.box = nn.Sequential(nn.Conv2d(128, 64, 1), nn.ReLU(inplace=True), nn.Conv2d(64, 4, 1))
        self.cls = nn.Sequential(nn.Conv2d(128, 64, 1), nn.ReLU(inplace=True), nn.Conv2d(64, n_classes, 1))
        nn.init.constant_(self.cls[-1].bias, -4.0)  # rare positives: start near "nothing here"

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        f = self.features(x)
        g = self.context(f.mean(dim=(2, 3)))[:, :, None, None]
        f = F.relu(f + g)
        return self.box(f), self.cls(f)


def decode(box: torch.Tensor, size: int) -> torch.Tensor:
    """Raw box outputs [B, 4, H, W] -> cx, cy, w, h in input pixels, [B, 4, H, W]."""
    b, _, h, w = box.shape
    ys, xs = torch.meshgrid(torch.arange(h, dtype=box.dtype), torch.arange(w, dtype=box.dtype), indexing="ij")
    cx = (xs + 0.5 + 2.0 * torch.tanh(box[:, 0])) * STRIDE
    cy = (ys + 0.5 + 2.0 * torch.tanh(box[:, 1])) * STRIDE
    bw = torch.exp(box[:, 2].clamp(-6, 1.5)) * size
    bh = torch.exp(box[:, 3].clamp(-6, 1.5)) * size
    return torch.stack([cx, cy, bw, bh], dim=1)


class Exported(nn.Module):
    """The ONNX graph: decoding included, Ultralytics' output layout [1, 4 + C, N]."""

    def __init__(self, model: TinyDetector, size: int) -> None:
        super().__init__()
        self.model, self.size = model, size

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        box, cls = self.model(x)
        boxes = decode(box, self.size)
        out = torch.cat([boxes, torch.sigmoid(cls)], dim=1)
        return out.flatten(2)


def giou(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Generalised IoU of boxes given as cx, cy, w, h (rows)."""
    ax0, ay0, ax1, ay1 = a[:, 0] - a[:, 2] / 2, a[:, 1] - a[:, 3] / 2, a[:, 0] + a[:, 2] / 2, a[:, 1] + a[:, 3] / 2
    bx0, by0, bx1, by1 = b[:, 0] - b[:, 2] / 2, b[:, 1] - b[:, 3] / 2, b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3] / 2
    iw = (torch.min(ax1, bx1) - torch.max(ax0, bx0)).clamp(min=0)
    ih = (torch.min(ay1, by1) - torch.max(ay0, by0)).clamp(min=0)
    inter = iw * ih
    union = a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter + 1e-6
    cw = torch.max(ax1, bx1) - torch.min(ax0, bx0)
    ch = torch.max(ay1, by1) - torch.min(ay0, by0)
    hull = cw * ch + 1e-6
    iou = inter / union
    return iou - (hull - union) / hull


def targets(boxes: list[np.ndarray], grid: int, n_classes: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Per cell: class targets [B, C, H, W], positive mask [B, H, W], box target (cx, cy, w, h) [B, 4, H, W].

    A cell is positive for a box when its centre lies inside the box and within 2.5 cells of the
    box centre (centre sampling); where two boxes claim a cell the smaller one wins.
    """
    b = len(boxes)
    cls_t = torch.zeros(b, n_classes, grid, grid)
    pos = torch.zeros(b, grid, grid, dtype=torch.bool)
    box_t = torch.zeros(b, 4, grid, grid)
    centres = (torch.arange(grid) + 0.5) * STRIDE
    cy, cx = torch.meshgrid(centres, centres, indexing="ij")
    for i, rows in enumerate(boxes):
        for row in sorted(rows, key=lambda r: -(r[3] - r[1]) * (r[4] - r[2])):  # large first, small overwrite
            c, x0, y0, x1, y1 = (float(v) for v in row)
            bcx, bcy = (x0 + x1) / 2, (y0 + y1) / 2
            inside = (cx > x0) & (cx < x1) & (cy > y0) & (cy < y1)
            near = ((cx - bcx).abs() <= 2.5 * STRIDE) & ((cy - bcy).abs() <= 2.5 * STRIDE)
            cells = inside & near
            if not cells.any():  # a thin box between centres: its nearest cell
                j = int(np.clip(bcx // STRIDE, 0, grid - 1))
                k = int(np.clip(bcy // STRIDE, 0, grid - 1))
                cells = torch.zeros_like(cells)
                cells[k, j] = True
            pos[i][cells] = True
            cls_t[i, :, cells] = 0.0
            cls_t[i, int(c), cells] = 1.0
            box_t[i, :, cells] = torch.tensor([bcx, bcy, x1 - x0, y1 - y0])[:, None]
    return cls_t, pos, box_t


def augment(images: np.ndarray, boxes: list[np.ndarray], rng: np.random.Generator) -> tuple[np.ndarray, list[np.ndarray]]:
    """Flips and 90-degree turns (the apparatus appears at any rotation) and a little colour jitter."""
    out_images, out_boxes = [], []
    size = images.shape[1]
    for image, rows in zip(images, boxes):
        rows = rows.copy()
        if rng.random() < 0.5:
            image = image[:, ::-1]
            rows[:, [1, 3]] = size - rows[:, [3, 1]]
        if rng.random() < 0.5:
            image = image[::-1]
            rows[:, [2, 4]] = size - rows[:, [4, 2]]
        if rng.random() < 0.5:  # transpose: a 90-degree turn combined with the flips above
            image = image.transpose(1, 0, 2)
            rows = rows[:, [0, 2, 1, 4, 3]]
        gain = rng.uniform(0.8, 1.2, 3)
        image = np.clip(image.astype(np.float32) * gain + rng.uniform(-15, 15), 0, 255)
        out_images.append(image)
        out_boxes.append(rows)
    return np.stack(out_images), out_boxes


def to_tensor(images: np.ndarray) -> torch.Tensor:
    """BGR uint8/float NHWC -> RGB float NCHW in 0-1 (as the runtime feeds the model)."""
    return torch.from_numpy(np.ascontiguousarray(images[..., ::-1].transpose(0, 3, 1, 2), dtype=np.float32) / 255.0)


def load(paths: list[str]) -> tuple[np.ndarray, list[np.ndarray]]:
    all_images, all_boxes = [], []
    for path in paths:
        data = np.load(path)
        rows = data["boxes"]
        all_images.append(data["images"])
        all_boxes += [rows[rows[:, 0] == i][:, 1:] for i in range(len(data["images"]))]
    return np.concatenate(all_images), all_boxes


def train(args: argparse.Namespace) -> TinyDetector:
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    images, boxes = load(args.data)
    size = images.shape[1]
    grid = size // STRIDE
    model = TinyDetector(len(CLASS_NAMES))
    if args.init:  # continue from an earlier run (same architecture)
        model.load_state_dict(torch.load(args.init))
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    steps = args.epochs * math.ceil(len(images) / args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=steps, pct_start=0.1)
    start = time.time()
    for epoch in range(args.epochs):
        order = rng.permutation(len(images))
        model.train()
        total = 0.0
        for s in range(0, len(order), args.batch):
            idx = order[s: s + args.batch]
            batch_images, batch_boxes = augment(images[idx], [boxes[i] for i in idx], rng)
            x = to_tensor(batch_images)
            cls_t, pos, box_t = targets(batch_boxes, grid, len(CLASS_NAMES))
            box_raw, cls_raw = model(x)
            n_pos = max(int(pos.sum()), 1)
            # focal-weighted BCE: thousands of empty cells must not drown the few positives
            p = torch.sigmoid(cls_raw)
            bce = F.binary_cross_entropy_with_logits(cls_raw, cls_t, reduction="none")
            weight = torch.where(cls_t > 0.5, 1 - p, p) ** 2
            loss_cls = (bce * weight).sum() / n_pos
            pred = decode(box_raw, size).permute(0, 2, 3, 1)[pos]
            true = box_t.permute(0, 2, 3, 1)[pos]
            if len(true):
                loss_box = (1 - giou(pred, true)).mean() + 0.5 * (
                    (pred[:, :2] - true[:, :2]).abs() / size).sum(1).mean() + 0.5 * (
                    torch.log(pred[:, 2:] + 1) - torch.log(true[:, 2:] + 1)).abs().sum(1).mean()
            else:
                loss_box = torch.zeros(())
            loss = loss_cls + 2.0 * loss_box
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += float(loss.detach()) * len(idx)
        print(f"epoch {epoch + 1}/{args.epochs}: loss {total / len(images):.4f} ({time.time() - start:.0f} s)",
              file=sys.stderr, flush=True)
    return model


def export(model: TinyDetector, size: int, out: Path) -> None:
    import onnx

    model.eval()
    wrapper = Exported(model, size)
    dummy = torch.zeros(1, 3, size, size)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(wrapper, (dummy,), str(out), input_names=["images"], output_names=["output0"],
                      opset_version=13, dynamo=False)
    proto = onnx.load(str(out))
    proto.ir_version = min(proto.ir_version, 8)  # onnxruntime 1.31 refuses IR 14
    names = {i: n for i, n in enumerate(CLASS_NAMES)}
    for key, value in (("names", repr(names)), ("imgsz", repr([size, size])), ("stride", str(STRIDE)),
                       ("task", "detect"), ("description", "streamread apparatus detector (synthetic training)")):
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.save(proto, str(out))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="+", help="training set(s) from detector_data.py")
    parser.add_argument("--init", help="start from these weights (.pt) instead of from scratch")
    parser.add_argument("--epochs", type=int, default=30)
    parser.add_argument("--batch", type=int, default=32)
    parser.add_argument("--lr", type=float, default=3e-3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--out", default="streamread/models/apparatus.onnx")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    model = train(args)
    size = int(np.load(args.data[0])["images"].shape[1])
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    torch.save(model.state_dict(), Path(args.out).with_suffix(".pt"))
    export(model, size, Path(args.out))
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
