"""Apparatus detection with a YOLO-format ONNX model on onnxruntime (calibration time only).

The layout is the one Ultralytics v8/v11 exports: one input ``[1, 3, S, S]`` (RGB, 0-1,
letterboxed: resized to fit and padded with grey 114, centred) and one output
``[1, 4 + classes, N]``: for each of N candidates the box centre, width and height in input
pixels, then one score per class (already sigmoid). Boxes are kept above a score threshold,
suppressed per class (NMS) and mapped back to the image.

Class names come from the model's metadata (``names``, as Ultralytics writes it:
``{0: 'syringe', 1: 'measuring_cylinder', 2: 'burette'}``) or a sidecar ``MODEL.names.txt``
(one name per line). The bundled model was trained on the project's synthetic renders
(``scripts/train_detector.py``); a user can pass their own (``--detector THEIR.onnx``).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import cv2
import numpy as np

from streamread.errors import InputError, expected
from streamread.onnxmodel import load_session

CLASS_NAMES = ("syringe", "measuring_cylinder", "burette")
LAYOUT = "one input [1, 3, S, S] and one output [1, 4 + classes, N] (the Ultralytics YOLOv8/11 export)"
PAD_VALUE = 114


def bundled_model_path() -> Path:
    return Path(str(resources.files("streamread") / "models" / "apparatus.onnx"))


def letterbox(image: np.ndarray, size: int) -> tuple[np.ndarray, float, tuple[int, int]]:
    """Resize to fit a ``size`` square keeping the aspect, pad with grey; (image, scale, (pad_x, pad_y))."""
    h, w = image.shape[:2]
    scale = min(size / h, size / w)
    nw, nh = max(1, int(round(w * scale))), max(1, int(round(h * scale)))
    resized = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR)
    px, py = (size - nw) // 2, (size - nh) // 2
    out = np.full((size, size) + image.shape[2:], PAD_VALUE, image.dtype)
    out[py:py + nh, px:px + nw] = resized
    return out, scale, (px, py)


@dataclass(frozen=True)
class Detection:
    xyxy: tuple[float, float, float, float]
    class_name: str
    score: float


def _names_from(path: Path, metadata: dict[str, str], n_classes: int) -> tuple[str, ...]:
    sidecar = path.with_suffix(".names.txt")
    if sidecar.is_file():
        names = tuple(line.strip() for line in sidecar.read_text().splitlines() if line.strip())
    elif "names" in metadata:
        try:
            parsed = ast.literal_eval(metadata["names"])
        except (ValueError, SyntaxError):
            raise InputError(expected("detector", path, "metadata 'names' as a dict or list", metadata["names"])) from None
        names = tuple(parsed[i] for i in sorted(parsed)) if isinstance(parsed, dict) else tuple(parsed)
    elif n_classes == len(CLASS_NAMES):
        names = CLASS_NAMES
    else:
        raise InputError(expected("detector", path, f"class names (metadata 'names' or {sidecar.name})",
                                  f"none for {n_classes} classes"))
    if len(names) != n_classes:
        raise InputError(expected("detector", path, f"{n_classes} class names (from the output shape)",
                                  f"{len(names)} names"))
    return tuple(str(n) for n in names)


class OnnxDetector:
    """Finds apparatus boxes; implements the reader's ``Detector`` interface."""

    def __init__(self, path: str | Path | None = None, score_min: float = 0.6, iou_max: float = 0.5,
                 threads: int = 1, agnostic: bool = True) -> None:
        self.path = Path(path) if path is not None else bundled_model_path()
        self.session = load_session(self.path, "detector", threads, bundled=path is None)
        inputs, outputs = self.session.get_inputs(), self.session.get_outputs()
        if len(inputs) != 1 or len(outputs) != 1:
            raise InputError(expected("detector", self.path, LAYOUT, f"{len(inputs)} inputs, {len(outputs)} outputs"))
        shape_in, shape_out = inputs[0].shape, outputs[0].shape
        if len(shape_in) != 4 or not isinstance(shape_in[2], int) or shape_in[2] != shape_in[3] \
                or shape_in[1] not in (3, "3"):
            raise InputError(expected("detector", self.path, LAYOUT, f"input shape {shape_in}"))
        if len(shape_out) != 3 or not isinstance(shape_out[1], int) or shape_out[1] < 5:
            raise InputError(expected("detector", self.path, LAYOUT, f"output shape {shape_out}"))
        self.size = int(shape_in[2])
        self.input_name = inputs[0].name
        meta = self.session.get_modelmeta().custom_metadata_map
        self.class_names = _names_from(self.path, meta, int(shape_out[1]) - 4)
        self.score_min, self.iou_max = score_min, iou_max
        # one apparatus is one box: boxes of different classes over the same glass compete
        # (Ultralytics' agnostic NMS); per-class NMS keeps a "syringe" and a "cylinder" there
        self.agnostic = agnostic

    def detect_all(self, image: np.ndarray) -> list[Detection]:
        boxed, scale, (px, py) = letterbox(image, self.size)
        blob = cv2.cvtColor(boxed, cv2.COLOR_BGR2RGB).astype(np.float32).transpose(2, 0, 1)[None] / 255.0
        out = self.session.run(None, {self.input_name: blob})[0]
        if out.ndim != 3 or out.shape[1] != 4 + len(self.class_names):
            raise InputError(expected("detector", self.path, LAYOUT, f"an output of shape {out.shape}"))
        pred = out[0].T  # [N, 4 + C]
        scores = pred[:, 4:]
        cls = scores.argmax(axis=1)
        best = scores[np.arange(len(scores)), cls]
        keep = best >= self.score_min
        if not keep.any():
            return []
        pred, cls, best = pred[keep], cls[keep], best[keep]
        cx, cy, w, h = pred[:, 0], pred[:, 1], pred[:, 2], pred[:, 3]
        x0 = (cx - w / 2 - px) / scale
        y0 = (cy - h / 2 - py) / scale
        x1 = (cx + w / 2 - px) / scale
        y1 = (cy + h / 2 - py) / scale
        found: list[Detection] = []
        ih, iw = image.shape[:2]
        groups = [np.arange(len(cls))] if self.agnostic else [np.nonzero(cls == c)[0] for c in np.unique(cls)]
        for idx in groups:
            rects = [[float(x0[i]), float(y0[i]), float(x1[i] - x0[i]), float(y1[i] - y0[i])] for i in idx]
            kept = cv2.dnn.NMSBoxes(rects, [float(best[i]) for i in idx], self.score_min, self.iou_max)
            for k in np.asarray(kept).reshape(-1):
                i = idx[int(k)]
                box = (float(np.clip(x0[i], 0, iw - 1)), float(np.clip(y0[i], 0, ih - 1)),
                       float(np.clip(x1[i], 0, iw - 1)), float(np.clip(y1[i], 0, ih - 1)))
                found.append(Detection(box, self.class_names[int(cls[i])], float(best[i])))
        return sorted(found, key=lambda d: -d.score)

    def detect(self, image: np.ndarray) -> list[tuple[tuple[float, float, float, float], str, float]]:
        return [(d.xyxy, d.class_name, d.score) for d in self.detect_all(image)]
