"""Scale numbers as the reader's bands show them, cut from rendered stills, with their true text.

The digit network (``streamread/models/digits.onnx``) was first trained on words rendered on
their own; what it reads in the pipeline are words from ``ocr.bands_beside``: a still's strip,
its marks inpainted, walls flattened, glyphs thresholded and upscaled. Here each still's strip
and marks come from the renderer's truth (the axis, every mark's ends and tier), so the bands
are those the reader makes once its marks are right, and every word boxed in them
(``digits.word_boxes``, as ``DigitReader.words`` boxes them) takes the text of the label
printed at its place. That gives

* training words for ``scripts/train_digits.py --stills`` (seeds 4000-7799; 7800-7999 are kept
  to measure; never the benchmarks' dev 1000-1599 or held-out 2000-2299 stills), and
* a measure of the readers on them (``--evaluate``): how many of a still's labels each reader
  reads right, given right marks (the part of the OCR stage the marks do not decide).

    uv run python scripts/still_words.py --seeds 7800-7999 --evaluate
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from streamread.apparatus import get_spec  # noqa: E402
from streamread.digits import MIN_CONFIDENCE, DigitReader, word_boxes, word_crop  # noqa: E402
from streamread.marks import major_gap_px  # noqa: E402
from streamread.ocr import INK_CONTRAST, bands_beside  # noqa: E402
from streamread.orientation import Ladder, cut_strip  # noqa: E402
from streamread.profile import default_profile  # noqa: E402
from streamread.reader import strip_upright  # noqa: E402
from streamread.segment import to_gray  # noqa: E402
from streamread.synth import render_still  # noqa: E402
from streamread.synth.truth import SceneTruth  # noqa: E402
from streamread.types import Mark, Marks, Upright  # noqa: E402

LABEL_REACH = 0.45  # of the labels' spacing: a word further from every label's row is no label's


def parse_seeds(text: str) -> list[int]:
    """``4000-4999`` or ``4000,4007``: the seeds, refusing the benchmarks' own."""
    seeds: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        if not (lo.isdigit() and (hi.isdigit() or not hi)):
            raise SystemExit(f"--seeds: expected a range like 4000-4999 or seeds like 4000,4007, got {text!r}")
        seeds.extend(range(int(lo), int(hi or lo) + 1))
    bench = [s for s in seeds if 1000 <= s < 1600 or 2000 <= s < 2300]
    if bench:
        raise SystemExit(f"--seeds: expected seeds outside the benchmarks' 1000-1599 and 2000-2299, got {bench[0]}")
    return seeds


def _text_up_px(truth: SceneTruth) -> np.ndarray:
    """Unit image direction in which the labels' text stands upright (the apparatus's up)."""
    (x0, y0), (x1, y1) = truth.axis_px
    v0, v1 = truth.axis_values_ml
    d = np.array([x1 - x0, y1 - y0], float) * (1.0 if v1 > v0 else -1.0)  # values increasing
    if get_spec(truth.apparatus).increases_downward:
        d = -d
    return d / max(np.linalg.norm(d), 1e-9)


def truth_strip(image: np.ndarray, truth: SceneTruth,
                ) -> tuple[np.ndarray, Marks, list[tuple[float, str]], Upright] | None:
    """The upright strip (labels reading upright), its true marks and labelled rows, as the
    reader would cut it once its ladder were right; None where too few marks are in frame."""
    seen = [m for m in truth.marks if m.in_frame]
    labels = [m for m in seen if m.label]
    if len(seen) < 6 or len(labels) < 2:
        return None
    up = _text_up_px(truth)
    angle = math.degrees(math.atan2(-up[1], -up[0]))  # the strip's +y runs down the text
    centres = np.array([m.center_px for m in seen])
    along = (centres - centres.mean(0)) @ -up
    bar = max(math.dist(*m.ends_px) for m in seen)
    ladder = Ladder(segments=(), axis_angle_deg=angle, center_px=tuple(centres.mean(0)),
                    extent_px=float(np.ptp(along)), bar_length_px=bar)
    spacing = truth.px_per_division
    upright = strip_upright(ladder, spacing, False)
    strip = cut_strip(image, upright)
    marks = []
    for m in seen:
        ends = upright.from_input(np.array(m.ends_px))
        y = float(ends[:, 1].mean())
        tier = m.tier if m.tier == "major" else "minor"
        marks.append(Mark(y_up=y, x0_up=float(ends[:, 0].min()), x1_up=float(ends[:, 0].max()),
                          thickness_up=max(1.0, 0.12 * spacing), tier=tier))
    marks.sort(key=lambda m: m.y_up)
    marks = [Mark(m.y_up, m.x0_up, m.x1_up, m.thickness_up, m.tier, i) for i, m in enumerate(marks)]
    rows = [(float(upright.from_input(np.array([m.center_px]))[0, 1]), str(m.label)) for m in labels]
    return strip, Marks(tuple(marks), spacing), rows, upright


def _dark_print(gray: np.ndarray, marks: Marks) -> bool:
    """Print darker than the glass around it (the usual), else light print (a dark syringe)."""
    on, off = [], []
    h, w = gray.shape
    for m in marks.marks:
        y, x = int(round(m.y_up)), int(round((m.x0_up + m.x1_up) / 2))
        if 2 <= y < h - 2 and 0 <= x < w:
            on.append(float(gray[y, x]))
            off.append(float(np.median(gray[[y - 2, y + 2], x])))
    return not on or float(np.median(np.array(on) - np.array(off))) <= 0


def _render_without(seed: int, module: object, name: str, stand_in: object) -> np.ndarray:
    """The still rendered again with one drawing function replaced (same noise seed)."""
    drawn = getattr(module, name)
    setattr(module, name, stand_in)
    try:
        return render_still(seed)[0]
    finally:
        setattr(module, name, drawn)


def _differs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (np.abs(a.astype(np.int16) - b.astype(np.int16)).max(axis=2) > 6).astype(np.uint8)


def text_ink(seed: int, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the still's printed numbers are, and where any other text is (a unit, "CLASS B",
    a ruler's or a paper's print behind): the still against itself rendered without them (the
    same noise seed, so only their pixels differ), as 0/1 masks."""
    from streamread.synth import background, draw

    labels = _differs(image, _render_without(seed, draw, "_draw_labels", lambda *args, **kwargs: None))
    blank = lambda *args, **kwargs: np.zeros((1, 1), np.uint8)  # noqa: E731 - text drawn as nothing
    drawn = background.text_mask
    background.text_mask = blank
    try:
        no_text = _render_without(seed, draw, "text_mask", blank)
    finally:
        background.text_mask = drawn
    return labels, _differs(image, no_text) & (1 - labels)


def still_words(seed: int, variants: bool = True) -> list[tuple[np.ndarray, str]]:
    """(word crop, true text) for every word the bands of one still box; "" for debris.

    A word takes a label's text where nearly all of that label's ink lies in its box and most of
    its own ink is that label's; it is debris where none of its ink is a label's; otherwise
    (a label cut in pieces, a label with a mark's end) it is left out. Only the unturned bands
    (their digits upright); with ``variants`` the struck-line and lifted-marks passes and the
    faint-ink threshold too, as the reader's later searches make them."""
    image, truth = render_still(seed)
    cut = truth_strip(image, truth)
    if cut is None:
        return []
    strip, marks, rows, upright = cut
    labels_px, other_px = text_ink(seed, image)
    grow = np.ones((3, 3), np.uint8)
    ink_up = cv2.dilate((cut_strip(labels_px * 255, upright) > 127).astype(np.uint8), grow) > 0
    other_up = cv2.dilate((cut_strip(other_px * 255, upright) > 127).astype(np.uint8), grow) > 0
    gray = to_gray(strip)
    dark = _dark_print(gray, marks)
    config = default_profile(truth.kind).ocr
    label_gap = major_gap_px(marks)
    passes: list[dict[str, object]] = [{}]
    if variants:
        passes += [{"unstrike": True}, {"lift_marks": True}, {"ink_contrast": INK_CONTRAST - 5}]
    out: list[tuple[np.ndarray, str]] = []
    for kwargs in passes:
        for band in bands_beside(gray, marks, dark, config, **kwargs):
            if band.turned or not (band.image < 128).any():
                continue
            bh, bw = band.image.shape
            # the band's pixels in strip pixels: column x0 + bx / scale, row by / scale
            xs = np.clip((band.x0 + np.arange(bw) / band.scale).astype(int), 0, ink_up.shape[1] - 1)
            ys = np.clip((np.arange(bh) / band.scale).astype(int), 0, ink_up.shape[0] - 1)
            on_label = ink_up[np.ix_(ys, xs)]
            on_other = other_up[np.ix_(ys, xs)]
            dark_px = band.image < 128
            for word in word_boxes(band.image):
                left, top, w, h = word
                box = (slice(top, top + h), slice(left, left + w))
                ink = dark_px[box]
                if not ink.any():
                    continue
                share = float(on_label[box][ink].mean())
                y = (top + h / 2) / band.scale
                gaps = [abs(y - row) for row, _ in rows]
                j = int(np.argmin(gaps))
                text: str | None = None
                if share < 0.05 and float(on_other[box][ink].mean()) < 0.05:
                    text = ""  # debris: a wall, a mark's end, a bubble, a background's edge
                elif share > 0.7 and gaps[j] <= LABEL_REACH * label_gap:
                    window = slice(max(0, int((rows[j][0] - LABEL_REACH * label_gap) * band.scale)),
                                   int((rows[j][0] + LABEL_REACH * label_gap) * band.scale))
                    label_all = int((on_label[window] & dark_px[window]).sum())
                    label_in = int((on_label[box] & ink).sum())
                    if label_all and label_in >= 0.9 * label_all:
                        text = rows[j][1]
                if text is None:
                    continue
                # a copy: the crop is a view that would keep the whole upscaled band alive (a
                # thousand seeds' bands filled 12 GB)
                out.append((word_crop(band.image, word).copy(), text))
    return out


def network_scores(words: list[tuple[np.ndarray, str]], reader: DigitReader) -> tuple[int, int, int]:
    """How the network reads ``words`` as the pipeline takes its words (at ``MIN_CONFIDENCE`` or
    more): labels read right, labels misread, debris read as a number."""
    reads = [text if conf >= MIN_CONFIDENCE else "" for text, conf in reader.read([c for c, _ in words])]
    right = sum(read == text for read, (_, text) in zip(reads, words) if text)
    wrong = sum(bool(read) and read != text for read, (_, text) in zip(reads, words) if text)
    debris_read = sum(bool(read) for read, (_, text) in zip(reads, words) if not text)
    return right, wrong, debris_read


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="7800-7999")
    parser.add_argument("--evaluate", action="store_true", help="score the bundled readers on the words")
    parser.add_argument("--model", help="the digit network to score (default: the bundled one)")
    parser.add_argument("--out", help="write the words to this .npz (crops at the network's input size)")
    args = parser.parse_args()
    from streamread.digits import digit_reader
    from streamread.ocr import word_reader

    words: list[tuple[np.ndarray, str]] = []
    for seed in parse_seeds(args.seeds):
        words.extend(still_words(seed, variants=not args.evaluate))
    labelled = [(c, t) for c, t in words if t]
    print(f"{len(words)} words, {len(labelled)} labels, {len(words) - len(labelled)} debris")
    if args.evaluate:
        net_right, _, net_junk = network_scores(words, digit_reader(args.model))
        tess = word_reader("0123456789.")
        tess_right = 0
        for crop, text in labelled:
            big = cv2.copyMakeBorder(crop, 10, 10, 10, 10, cv2.BORDER_CONSTANT, value=255)
            read = tess(big)
            tess_right += bool(read) and read[0][0] == text
        share = 100 * net_right / max(1, len(labelled))
        print(f"network (confidence {MIN_CONFIDENCE:.0f} or more) right {net_right}/{len(labelled)} ({share:.1f} %), "
              f"debris read as a number {net_junk}/{len(words) - len(labelled)}; "
              f"Tesseract right {tess_right}/{len(labelled)} ({100 * tess_right / max(1, len(labelled)):.1f} %)")
    if args.out:
        save_words(args.out, words)


def save_words(path: str, words: list[tuple[np.ndarray, str]]) -> None:
    """The words at the network's input height (uint8, their widths differ) and their texts."""
    from streamread.digits import to_input

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    inputs = [(to_input(crop) * 255).round().astype(np.uint8) for crop, _ in words]
    widths = np.array([x.shape[1] for x in inputs], np.int32)
    np.savez_compressed(path, pixels=np.concatenate([x.ravel() for x in inputs]) if inputs else np.zeros(0, np.uint8),
                        widths=widths, texts=np.array([t for _, t in words], dtype=str))


def load_words(path: str) -> list[tuple[np.ndarray, str]]:
    """``save_words``'s words: (input-height uint8 crop, text)."""
    from streamread.digits import HEIGHT

    data = np.load(path)
    pixels = data["pixels"]  # once: each key read decompresses the whole array
    out, at = [], 0
    for w, text in zip(data["widths"], data["texts"]):
        out.append((pixels[at: at + HEIGHT * w].reshape(HEIGHT, w), str(text)))
        at += HEIGHT * w
    return out


if __name__ == "__main__":
    main()
