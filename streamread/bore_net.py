"""The level indicator found by a small network over the bore: the meniscus where every rule
of ``indicator.find_meniscus`` failed, the stopper's sealing edge where ``find_stopper``'s
did and, more closely, where they agree (``reader._stopper_network``); and, as a check, where
they found one (an indicator the network is sure lies elsewhere makes theirs no reading). One architecture, two bundled models: ``models/meniscus.onnx`` for
cylinders and burettes, ``models/stopper.onnx`` for syringes.

Meniscus.

The rules judge a dark band across the bore by its profile, its arc and its hue, and refuse
when two bands look alike. On a burette, whose dense ticks hide most of the bore's rows, or
where a ring's edge or a label's band rivals the surface, they find none, though a person sees
the liquid's surface at once (dev 1148, 1159, 1280). The bundled ``models/meniscus.onnx``
(trained by ``scripts/train_bore_net.py`` on rendered stills: the tuning set 3000-3599 and
seeds 4000-7999, never the dev or held-out seeds) looks at the whole bore instead:
convolutions over the bore's columns squeeze each row to one vector, dilated convolutions
along the rows give each row about seven divisions of
context above and below (air above, liquid below), and each row gets a score; one more score
says "no surface here". A softmax over the rows and that one gives the meniscus's row and how
sure the network is.

The input is the calibrated strip's bore, cut to the walls with a margin and resampled so that
a division is ``PX_PER_DIVISION`` rows and the bore ``WIDTH`` columns: the network sees every
scale at one size. Five planes: the colour (B, G, R), the grey normalised by the bore's own
median and spread (a dark background, a dim frame), and the print mask (marks and numbers,
which are not the surface).

Stopper. The rules take the darkest bounded run of rows across the bore and its edge facing
the nozzle; a dye as dark as the rubber, a dark background behind the barrel or the rod's
shadow make them miss it or take the wrong run. ``models/stopper.onnx`` sees the same input,
turned so that the nozzle (the scale's zero) is at the top (``nozzle_up``): its row is then
always the top edge of the rubber, whichever way the scale runs in the strip.
"""

from __future__ import annotations

import functools
from pathlib import Path

import cv2
import numpy as np

from streamread.onnxmodel import load_session

PX_PER_DIVISION = 8.0  # rows per scale division in the network's input
WIDTH = 32  # the network's input width: the bore and a margin
MARGIN = 0.15  # share of the bore's width kept outside each wall (the meniscus climbs them)
CONTEXT_DIV = 8.0  # divisions of rows the network also sees beyond the rows it may choose
# the probability, within a division of the chosen row, below which no reading (dev: right
# readings 0.94-1.0 but one, 0.73; held-out 2041, a label's band, 0.69)
MIN_CONFIDENCE = 0.8


MODELS = {"meniscus": "meniscus.onnx", "stopper": "stopper.onnx"}


def bundled_model_path(indicator: str = "meniscus") -> Path:
    return Path(__file__).parent / "models" / MODELS[indicator]


def bore_input(strip_bgr: np.ndarray, masked: np.ndarray, bore: tuple[float, float], d: float,
               rows: tuple[int, int]) -> tuple[np.ndarray, float, int]:
    """The network's input for strip rows ``rows`` (first, last, inclusive) of the bore between
    ``bore``'s walls, a division being ``d`` px: a (5, H, WIDTH) float32 array, the rows per
    strip px, and the strip row of the input's first row. ``strip_bgr`` may be grey (H, W)."""
    n, w = masked.shape
    left, right = bore
    margin = MARGIN * (right - left)
    x0, x1 = max(0, int(np.floor(left - margin))), min(w, int(np.ceil(right + margin)) + 1)
    r0, r1 = max(0, rows[0]), min(n, rows[1] + 1)
    colour = strip_bgr[r0:r1, x0:x1]
    if colour.ndim == 2:
        colour = cv2.cvtColor(np.ascontiguousarray(colour), cv2.COLOR_GRAY2BGR)
    scale = PX_PER_DIVISION / d
    out_h = max(8, int(round((r1 - r0) * scale)))
    shrink = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
    colour = cv2.resize(np.ascontiguousarray(colour), (WIDTH, out_h), interpolation=shrink).astype(np.float32)
    mask = cv2.resize(np.ascontiguousarray(masked[r0:r1, x0:x1]), (WIDTH, out_h),
                      interpolation=cv2.INTER_AREA).astype(np.float32) / 255
    grey = colour.mean(axis=2)
    middle = grey[:, WIDTH // 4: 3 * WIDTH // 4]
    centre = float(np.median(middle))
    spread = float(np.median(np.abs(middle - centre))) * 1.4826 + 4.0
    planes = [colour[:, :, c] / 255 - 0.5 for c in range(3)]
    planes += [np.clip((grey - centre) / spread, -4, 4) / 4, mask]
    return np.stack(planes).astype(np.float32), out_h / (r1 - r0), r0


class BoreNet:
    """One of the networks, loaded once (``meniscus_net``, ``stopper_net``)."""

    def __init__(self, path: str | Path | None = None, threads: int = 1, indicator: str = "meniscus") -> None:
        self.path = Path(path) if path is not None else bundled_model_path(indicator)
        self.session = load_session(self.path, f"{indicator} model", threads, bundled=path is None)
        self.input_name = self.session.get_inputs()[0].name

    def scores(self, planes: np.ndarray) -> tuple[np.ndarray, float]:
        """Each input row's score and the "no surface" score (logits)."""
        rows, none = self.session.run(None, {self.input_name: planes[None]})
        return rows[0].astype(np.float64), float(none.reshape(-1)[0])

    def locate(self, strip_bgr: np.ndarray, masked: np.ndarray, bore: tuple[float, float], d: float,
               allowed: tuple[int, int], min_confidence: float = MIN_CONFIDENCE,
               turned: bool = False) -> tuple[float, float] | None:
        """The indicator's strip row within ``allowed`` (first, last) and the probability that it
        lies within a division of it; None where the network sees none there (under
        ``min_confidence``). ``turned``: the input upside down (``nozzle_up``)."""
        if d <= 0 or allowed[1] <= allowed[0]:
            return None
        context = int(round(CONTEXT_DIV * d))
        planes, scale, first = bore_input(strip_bgr, masked, bore, d, (allowed[0] - context, allowed[1] + context))
        if turned:
            logits, none = self.scores(np.ascontiguousarray(planes[:, ::-1]))
            logits = logits[::-1]  # the input's rows are symmetric about its middle: row i is row n-1-i turned
        else:
            logits, none = self.scores(planes)
        rows = first + (np.arange(len(logits)) + 0.5) / scale - 0.5  # each input row's strip row
        logits = np.where((rows >= allowed[0]) & (rows <= allowed[1]), logits, -np.inf)
        top = max(float(logits.max()), none)
        weights = np.exp(logits - top)
        total = weights.sum() + np.exp(none - top)
        best = int(np.argmax(logits))
        apart = np.abs(np.arange(len(logits)) - best)
        confidence = float(weights[apart <= PX_PER_DIVISION].sum() / total)
        if confidence < min_confidence:
            return None
        close = apart <= 2
        row = float((weights[close] * rows[close]).sum() / weights[close].sum())
        return row, confidence


def nozzle_up(slope: float) -> bool:
    """Whether a syringe's strip must be turned for the stopper network, which sees the nozzle
    (value zero) at the top: values fall with the strip's rows where the slope is negative."""
    return slope < 0


@functools.lru_cache(maxsize=2)
def meniscus_net(path: str | None = None) -> BoreNet:
    """The bundled meniscus network, loaded once per process."""
    return BoreNet(path, indicator="meniscus")


@functools.lru_cache(maxsize=2)
def stopper_net(path: str | None = None) -> BoreNet:
    """The bundled stopper network, loaded once per process."""
    return BoreNet(path, indicator="stopper")
