"""Scale numbers read by a small network, for the digits Tesseract misses.

Tesseract reads nothing, or a wrong digit, from labels under about 12 px tall, blurred, or
touching each other or the tube's wall: a burette's "21" seen from a metre away. The bundled
``models/digits.onnx`` (trained by ``scripts/train_digits.py`` on rendered words in many
faces and on words cut from rendered stills as the OCR stage's bands show them,
``scripts/still_words.py``; never on the stills the benchmarks score) reads a word crop as a
sequence: a stack of convolutions squeezes the 32 px tall crop to one row of columns, each
column scores blank, 0-9 and ".", and CTC's best path gives the text. A word of debris reads as nothing.

``DigitReader.words`` has the contract of ``ocr.word_reader``'s callable (a prepared band in,
``Word`` tuples out), so ``ocr.read_numbers`` takes either. Tesseract's layout analysis is
replaced by grouping the band's blobs of ink into words (a band holds only the digits, on white).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import cv2
import numpy as np

from streamread.ocr import Word, joined_into_words
from streamread.onnxmodel import load_session

ALPHABET = "0123456789."  # class 0 is CTC's blank; class i + 1 is ALPHABET[i]
HEIGHT = 32  # the network's input height
INK_REACH = 15  # px: the neighbourhood whose darkest pixel sets a label's own ink level
INK_CONTRAST = 40  # grey levels under the paper that darkest pixel must be: else no ink there
WORD_GAP = 0.6  # times the taller blob's height: blobs closer than this across are one word
WORD_OVERLAP = 0.5  # rows a blob shares with a word, of the shorter's height, to join it
MIN_CONFIDENCE = 50.0  # a word whose least sure character is below this (0-100) is not read
MIN_BLOB_AREA = 4  # pixels: less is noise left by the band's cleaning


def bundled_model_path() -> Path:
    return Path(__file__).parent / "models" / "digits.onnx"


class DigitReader:
    """The network, loaded once (``digit_reader``); ``read`` takes word crops, ``words`` a band."""

    def __init__(self, path: str | Path | None = None, threads: int = 1) -> None:
        self.path = Path(path) if path is not None else bundled_model_path()
        self.session = load_session(self.path, "digit model", threads, bundled=path is None)
        self.input_name = self.session.get_inputs()[0].name

    def read(self, crops: list[np.ndarray]) -> list[tuple[str, float]]:
        """Each word crop's (text, confidence 0-100): the least sure character's probability."""
        if not crops:
            return []
        inputs = [to_input(c) for c in crops]
        width = max(x.shape[1] for x in inputs)
        batch = np.ones((len(inputs), 1, HEIGHT, width), np.float32)
        for i, x in enumerate(inputs):
            batch[i, 0, :, : x.shape[1]] = x
        log_probs = self.session.run(None, {self.input_name: batch})[0]
        return [decode(row[: math.ceil(x.shape[1] / 4)]) for row, x in zip(log_probs, inputs)]

    def words(self, band: np.ndarray) -> list[Word]:
        """The words of a prepared band (dark digits on white), read: Tesseract's contract."""
        boxes = word_boxes(band)
        crops = [word_crop(band, box) for box in boxes]
        return [(text, float(top), float(h), conf, float(left), float(w))
                for (text, conf), (left, top, w, h) in zip(self.read(crops), boxes) if text and conf >= MIN_CONFIDENCE]


@functools.lru_cache(maxsize=2)
def digit_reader(path: str | None = None) -> DigitReader:
    """The bundled reader, loaded once per process."""
    return DigitReader(path)


def to_input(word: np.ndarray) -> np.ndarray:
    """A grey word crop (dark on light) scaled to ``HEIGHT``, in 0..1, its width a multiple of 4
    (white beyond the word): as ``scripts/train_digits.py`` prepares its samples."""
    h, w = word.shape[:2]
    new_w = max(4, int(round(w * HEIGHT / max(h, 1))))
    scaled = cv2.resize(word, (new_w, HEIGHT), interpolation=cv2.INTER_CUBIC if h < HEIGHT else cv2.INTER_AREA)
    out = np.full((HEIGHT, int(math.ceil(new_w / 4) * 4)), 255, np.uint8)
    out[:, :new_w] = scaled
    return out.astype(np.float32) / 255


def decode(log_probs: np.ndarray) -> tuple[str, float]:
    """CTC's best path of one word's (T, classes) log-probabilities: repeats merged, blanks
    dropped; the confidence is the lowest of the kept characters' probabilities, times 100."""
    best = np.argmax(log_probs, axis=1)
    chars, sure, prev = [], [], 0
    for t, k in enumerate(best):
        if k != 0 and k != prev:
            chars.append(ALPHABET[k - 1])
            sure.append(float(np.exp(log_probs[t, k])))
        elif k != 0 and sure:
            sure[-1] = max(sure[-1], float(np.exp(log_probs[t, k])))
        prev = k
    return "".join(chars), 100.0 * min(sure) if sure else 0.0


def word_crop(band: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """The crop the network reads for a word boxed (left, top, width, height) in a band: the box
    with a margin of a sixth of its height above and below and a quarter beside."""
    left, top, w, h = box
    pad_y, pad_x = max(1, int(round(0.15 * h))), max(1, int(round(0.25 * h)))
    return band[max(0, top - pad_y): top + h + pad_y, max(0, left - pad_x): left + w + pad_x]


def word_boxes(band: np.ndarray) -> list[tuple[int, int, int, int]]:
    """(left, top, width, height) of each word in a prepared band: its blobs of ink, joined
    where they overlap along the axis and stand less than ``WORD_GAP`` apart across it (a
    decimal point lies within its digits' rows)."""
    paper = float(np.percentile(band, 75))  # a band is mostly paper
    darkest_near = cv2.erode(band, np.ones((INK_REACH, INK_REACH), np.uint8))
    # ink: half way or more from the paper to the darkest pixel near it, where that is plainly
    # darker than paper (each label by its own contrast: one printed fainter is still found)
    ink = ((band < (darkest_near.astype(np.float32) + paper) / 2) & (darkest_near < paper - INK_CONTRAST)).astype(
        np.uint8)
    n, _, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    blobs = [tuple(int(v) for v in stats[i][:4]) for i in range(1, n) if stats[i][4] >= MIN_BLOB_AREA]
    blobs.sort(key=lambda b: b[0])
    return joined_into_words(blobs, WORD_OVERLAP, WORD_GAP)
