"""Train the scale-number reader (``streamread/models/digits.onnx``): a small convolutional
network read with CTC, for the numbers Tesseract misses: digits under about 12 px, blurred,
touching one another or a wall (the labels of a burette seen from a metre away).

Training words are rendered here: many faces (OpenCV's own, the Hershey vector fonts, DejaVu
in several cuts through Pillow), weights, widths, heights from 7 to 24 px, blur, noise,
contrast, and the debris a band of the strip keeps (a wall's edge, a mark's end, a neighbour's
stroke). About one sample in eight is no number at all (unit words, strokes, debris), labelled
empty: the reader must say nothing there rather than a digit. With ``--stills``, words cut
from rendered stills as the reader's bands show them are trained on beside them
(``scripts/still_words.py``: seeds outside the benchmarks' own), their debris kept to a share.

    python -m venv .train && .train/bin/pip install -r scripts/train-requirements.txt
    for part in a:4000-4749 b:4750-5499 c1:5500-6074 c2:6075-6649 d1:6650-7224 d2:7225-7799; do
        uv run python scripts/still_words.py --seeds ${part#*:} --out data/still_${part%%:*}.npz
    done
    .train/bin/python scripts/train_digits.py --out streamread/models/digits.onnx \
        --stills data/still_a.npz,data/still_b.npz,data/still_c1.npz,data/still_c2.npz,data/still_d1.npz,data/still_d2.npz

The words take about an hour on one core, the training about 54 minutes on two; seeded, so the
same files in the same order give the same network.
"""

from __future__ import annotations

import argparse
import glob
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the runtime's input and decoding, not a copy
sys.path.insert(0, str(Path(__file__).resolve().parent))  # still_words
from streamread.digits import ALPHABET, HEIGHT, decode, to_input  # noqa: E402
from streamread.ocr import glyphs_on_white  # noqa: E402

WIDTH = 128  # training width (inference takes any multiple of 4)
JUNK_SHARE = 0.12

try:
    from PIL import Image, ImageDraw, ImageFont
    PIL_FONTS = sorted(p for p in glob.glob("/usr/share/fonts/truetype/dejavu/DejaVu*.ttf")
                       if "Math" not in p and "Oblique" not in p and "Italic" not in p)
except ImportError:  # Pillow is optional: OpenCV's faces alone still train a usable reader
    PIL_FONTS = []
HERSHEY = (cv2.FONT_HERSHEY_SIMPLEX, cv2.FONT_HERSHEY_DUPLEX, cv2.FONT_HERSHEY_COMPLEX,
           cv2.FONT_HERSHEY_TRIPLEX, cv2.FONT_HERSHEY_PLAIN)
CV_FACES = ("sans", "uni")


def random_text(rng: np.random.Generator) -> str:
    """A scale number as printed: integers to 250, halves and tenths, a few with two decimals."""
    kind = rng.random()
    if kind < 0.45:
        return str(int(rng.integers(0, 60)))
    if kind < 0.65:
        return str(int(rng.integers(1, 26)) * 10)
    if kind < 0.9:
        whole = int(rng.integers(0, 10))
        return f"{whole}.{int(rng.integers(0, 10))}" if rng.random() < 0.85 else f"{whole}.5"
    return f"0.{int(rng.integers(0, 100)):02d}" if rng.random() < 0.5 else str(int(rng.integers(0, 1000)))


JUNK_WORDS = ("mL", "ml", "TC", "TD", "20°C", "In", "Ex", "A", "B", "cc", "±", "ISO", "Blau", "x", "-", "~")


def _render_large(text: str, rng: np.random.Generator) -> np.ndarray:
    """White ``text`` on black at about 48 px digit height, cropped to its ink."""
    size = 48
    buf = np.zeros((size * 3, size * (len(text) + 2)), np.uint8)
    pick = rng.random()
    if pick < 0.4:
        face = cv2.FontFace(str(rng.choice(CV_FACES)))
        cv2.putText(buf, text, (size // 2, size * 2), 255, face, int(size / 0.76), int(rng.integers(300, 800)))
    elif pick < 0.65 or not PIL_FONTS:
        font = int(rng.choice(HERSHEY))
        scale = cv2.getFontScaleFromHeight(font, size, 1)
        cv2.putText(buf, text, (size // 2, size * 2), font, scale, 255, int(rng.integers(1, 6)), cv2.LINE_AA)
    else:
        font = ImageFont.truetype(str(rng.choice(PIL_FONTS)), int(size / 0.72))
        im = Image.fromarray(buf)
        ImageDraw.Draw(im).text((size // 2, size // 2), text, fill=255, font=font)
        buf = np.asarray(im).copy()
        if rng.random() < 0.3:  # bolder
            buf = cv2.dilate(buf, np.ones((3, 3), np.uint8), iterations=int(rng.integers(1, 3)))
    ys, xs = np.nonzero(buf > 40)
    if len(xs) == 0:
        return np.zeros((size, size), np.uint8)
    return buf[ys.min(): ys.max() + 1, xs.min(): xs.max() + 1]


def _junk_ink(rng: np.random.Generator) -> np.ndarray:
    """Something that is not a number: a unit word, strokes, a blot."""
    if rng.random() < 0.5:
        return _render_large(str(rng.choice(JUNK_WORDS)), rng)
    ink = np.zeros((48, int(rng.integers(10, 90))), np.uint8)
    for _ in range(int(rng.integers(1, 4))):
        p = (int(rng.integers(0, ink.shape[1])), int(rng.integers(0, 48)))
        q = (int(rng.integers(0, ink.shape[1])), int(rng.integers(0, 48)))
        cv2.line(ink, p, q, 255, int(rng.integers(2, 8)))
    return ink


def sample(rng: np.random.Generator) -> tuple[np.ndarray, str]:
    """One training word as the reader sees it: HEIGHT x WIDTH, dark on light, and its text."""
    junk = rng.random() < JUNK_SHARE
    text = "" if junk else random_text(rng)
    ink = _junk_ink(rng) if junk else _render_large(text, rng)
    squeeze = float(rng.uniform(0.45, 1.25))
    ink = cv2.resize(ink, (max(2, int(ink.shape[1] * squeeze)), ink.shape[0]), interpolation=cv2.INTER_AREA)
    # the size the digits had in the strip, then back up (the band was upscaled)
    digit_h = float(rng.uniform(7, 24))
    small = cv2.resize(ink, (max(2, int(ink.shape[1] * digit_h / ink.shape[0])), max(2, int(round(digit_h)))),
                       interpolation=cv2.INTER_AREA).astype(np.float32) / 255
    pad_y = [int(rng.integers(1, max(2, int(0.35 * digit_h)))) for _ in range(2)]
    pad_x = [int(rng.integers(1, max(2, int(0.6 * digit_h)))) for _ in range(2)]
    canvas = np.zeros((small.shape[0] + sum(pad_y), small.shape[1] + sum(pad_x)), np.float32)
    canvas[pad_y[0]: pad_y[0] + small.shape[0], pad_x[0]: pad_x[0] + small.shape[1]] = small
    h, w = canvas.shape
    if rng.random() < 0.35:  # a wall's edge or a mark's end left beside the digits
        x = int(rng.choice([int(rng.integers(0, max(1, pad_x[0]))), w - 1 - int(rng.integers(0, max(1, pad_x[1])))]))
        canvas[:, max(0, x - 1): x + 1] = np.maximum(canvas[:, max(0, x - 1): x + 1], rng.uniform(0.3, 1.0))
    if rng.random() < 0.25:
        y = int(rng.choice([int(rng.integers(0, max(1, pad_y[0]))), h - 1 - int(rng.integers(0, max(1, pad_y[1])))]))
        x0 = int(rng.integers(0, w // 2))
        canvas[y, x0: x0 + int(rng.integers(2, w))] = rng.uniform(0.3, 1.0)
    if rng.random() < 0.3:  # the smear an inpainted mark leaves just under or over a label
        below = h - 1 - int(rng.integers(0, max(1, pad_y[1]) + 2))
        y = int(rng.choice([below, int(rng.integers(0, max(1, pad_y[0]) + 2))]))
        canvas[max(0, y - 1): y + 2, :] = np.maximum(canvas[max(0, y - 1): y + 2, :], rng.uniform(0.2, 0.6))
    blur = float(rng.uniform(0.0, 1.6))
    if blur > 0.3:
        canvas = cv2.GaussianBlur(canvas, (0, 0), blur)
    paper, ink_level = float(rng.uniform(150, 255)), float(rng.uniform(0, 140))
    grey = paper - (paper - ink_level) * np.clip(canvas, 0, 1)
    grey += rng.normal(0, rng.uniform(0, 12), grey.shape) + np.linspace(0, rng.uniform(-25, 25), w)[None, :]
    grey = np.clip(grey, 0, 255).astype(np.uint8)
    if rng.random() < 0.6:
        grey = band_cleaned(grey)
    return fixed_width(to_input(grey)), text


def fixed_width(x: np.ndarray) -> np.ndarray:
    """A network input squeezed or padded (white) to ``WIDTH`` columns, to stack a batch."""
    if x.shape[1] > WIDTH:
        return cv2.resize(x, (WIDTH, HEIGHT), interpolation=cv2.INTER_AREA)
    return np.pad(x, ((0, 0), (0, WIDTH - x.shape[1])), constant_values=1.0)


def band_cleaned(grey: np.ndarray) -> np.ndarray:
    """What ``ocr.bands_beside`` makes of a label, at the strip's scale: its blobs of ink
    (adaptive threshold, dilated) kept and stretched from their darkest to the paper, the rest white."""
    ink = cv2.adaptiveThreshold(grey, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY_INV, 15, 12)
    return glyphs_on_white(grey, ink) if ink.any() else grey


def still_samples(paths: list[str], debris_share: float, rng: np.random.Generator,
                  ) -> tuple[np.ndarray, list[str]]:
    """Words cut from rendered stills by ``scripts/still_words.py``: labels as the reader's bands
    show them (a wall's shading through a digit, blur, inpainted marks' smears), and the bands'
    debris, kept to ``debris_share`` of them."""
    from still_words import load_words

    words = [w for path in paths for w in load_words(path)]
    labels = [w for w in words if w[1]]
    debris = [w for w in words if not w[1]]
    keep = int(len(labels) * debris_share / (1 - debris_share))
    if len(debris) > keep:
        debris = [debris[i] for i in rng.choice(len(debris), keep, replace=False)]
    chosen = labels + debris
    x = np.zeros((len(chosen), 1, HEIGHT, WIDTH), np.float32)
    for i, (pixels, _) in enumerate(chosen):
        x[i, 0] = fixed_width(pixels.astype(np.float32) / 255)
    return x, [t for _, t in chosen]


def build_model():  # noqa: ANN201 - torch is a training-only dependency
    import torch.nn as nn

    def block(c_in: int, c_out: int, pool: tuple[int, int]) -> list[nn.Module]:
        return [nn.Conv2d(c_in, c_out, 3, padding=1, bias=False), nn.BatchNorm2d(c_out), nn.ReLU(), nn.MaxPool2d(pool)]

    class Reader(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.body = nn.Sequential(*block(1, 16, (2, 2)), *block(16, 32, (2, 2)), *block(32, 48, (2, 1)),
                                      *block(48, 64, (2, 1)),
                                      nn.Conv2d(64, 96, (2, 1), bias=False), nn.BatchNorm2d(96), nn.ReLU())
            self.head = nn.Sequential(nn.Conv1d(96, 96, 3, padding=1), nn.ReLU(),
                                      nn.Conv1d(96, len(ALPHABET) + 1, 1))

        def forward(self, x):  # (N, 1, 32, W) -> (N, W/4, classes) log-probabilities
            f = self.body(x).squeeze(2)
            return self.head(f).permute(0, 2, 1).log_softmax(-1)

    return Reader()


def main() -> None:
    import torch

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="streamread/models/digits.onnx")
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--epochs", type=int, default=8)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--stills", default="",
                        help="comma-separated .npz files of words cut from rendered stills (scripts/still_words.py "
                             "--out), trained on beside the rendered words")
    parser.add_argument("--still-debris", type=float, default=0.25,
                        help="at most this share of the still words may be debris (labelled empty)")
    args = parser.parse_args()
    torch.manual_seed(args.seed)
    torch.set_num_threads(2)
    rng = np.random.default_rng(args.seed)
    t = time.time()
    xs = np.zeros((args.samples, 1, HEIGHT, WIDTH), np.float32)
    texts = []
    for i in range(args.samples):
        xs[i, 0], text = sample(rng)
        texts.append(text)
    print(f"{args.samples} samples rendered in {time.time() - t:.0f} s")
    if args.stills:
        still_x, still_texts = still_samples(args.stills.split(","), args.still_debris, rng)
        xs = np.concatenate([xs, still_x])
        texts += still_texts
        print(f"{len(still_texts)} words from stills ({sum(not t for t in still_texts)} debris)")
    val_n = 2000
    model = build_model()
    opt = torch.optim.AdamW(model.parameters(), lr=2e-3, weight_decay=1e-4)
    steps = args.epochs * ((len(texts) - val_n) // 128)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=3e-3, total_steps=steps)
    ctc = torch.nn.CTCLoss(blank=0, zero_infinity=True)
    targets = [torch.tensor([ALPHABET.index(c) + 1 for c in text], dtype=torch.long) for text in texts]
    for epoch in range(args.epochs):
        model.train()
        order = rng.permutation(np.arange(val_n, len(texts)))
        total = 0.0
        for b in range(0, len(order) - 127, 128):
            idx = order[b: b + 128]
            x = torch.from_numpy(xs[idx])
            logp = model(x).permute(1, 0, 2)  # (T, N, C)
            tgt = [targets[i] for i in idx]
            loss = ctc(logp, torch.cat(tgt) if any(len(g) for g in tgt) else torch.zeros(0, dtype=torch.long),
                       torch.full((len(idx),), logp.shape[0], dtype=torch.long),
                       torch.tensor([len(g) for g in tgt], dtype=torch.long))
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += float(loss.detach())
        model.eval()
        with torch.no_grad():
            out = model(torch.from_numpy(xs[:val_n])).numpy()
        right = sum(decode(row)[0] == texts[i] for i, row in enumerate(out))
        print(f"epoch {epoch + 1}: loss {total / max(1, len(order) // 128):.3f}, "
              f"validation words right {right / val_n:.3f} ({time.time() - t:.0f} s)")
    model.eval()
    dummy = torch.zeros(1, 1, HEIGHT, WIDTH)
    torch.onnx.export(model, dummy, args.out, input_names=["image"], output_names=["log_probs"],
                      dynamic_axes={"image": {0: "n", 3: "w"}, "log_probs": {0: "n", 1: "t"}}, opset_version=17,
                      dynamo=False)
    import onnx

    proto = onnx.load(args.out)
    proto.ir_version = min(proto.ir_version, 9)  # onnxruntime refuses IR 14 (onnx 1.23's default)
    onnx.save(proto, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
