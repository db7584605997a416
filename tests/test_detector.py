"""The ONNX apparatus detector: the bundled model on fresh renders, and bad model files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from streamread.detector import CLASS_NAMES, OnnxDetector, bundled_model_path, letterbox
from streamread.errors import DependencyError, InputError
from streamread.reader import ReaderOptions, read_image
from streamread.synth import render_still

DATA = Path(__file__).resolve().parent / "data"
# seeds far from the training set's (0-3999) and the held-out set's (900000-900399)
FRESH = range(700000, 700024)

needs_model = pytest.mark.skipif(not bundled_model_path().is_file(), reason="bundled model not built")


def _iou(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    return inter / ((a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)


def test_letterbox_keeps_aspect_and_centres() -> None:
    image = np.zeros((100, 200, 3), np.uint8)
    boxed, scale, (px, py) = letterbox(image, 64)
    assert boxed.shape == (64, 64, 3) and scale == pytest.approx(0.32)
    assert (px, py) == (0, 16) and boxed[0, 0, 0] == 114 and boxed[32, 32, 0] == 0


@needs_model
def test_bundled_model_finds_and_names_apparatus() -> None:
    det = OnnxDetector()
    assert det.class_names == CLASS_NAMES
    hits = right = 0
    for seed in FRESH:
        image, truth = render_still(seed)
        found = det.detect_all(image)
        if found and truth.box_xyxy is not None and _iou(found[0].xyxy, truth.box_xyxy) >= 0.5:
            hits += 1
            right += found[0].class_name == truth.kind
    # the benchmark (scripts/bench_detector.py, 400 held-out scenes) gives the figures; this
    # sample only has to show a working model: at least 21 of 24 found and named
    assert hits >= 21 and right >= 21, f"{hits} found, {right} with the right class, of {len(FRESH)}"


@needs_model
def test_detector_class_sets_the_kind_in_auto_mode() -> None:
    image, truth = render_still(1023)  # a syringe the reader reads
    reading = read_image(image, ReaderOptions(apparatus="auto", detector=OnnxDetector()))
    assert reading.calibration is not None and reading.calibration.box_xyxy is not None
    assert reading.apparatus == truth.kind == "syringe"
    assert reading.level == pytest.approx(truth.level_ml, abs=0.5 * truth.minor_ml)


def test_missing_model_is_a_dependency_error(tmp_path: Path) -> None:
    with pytest.raises(DependencyError, match="nope.onnx: expected an ONNX model file"):
        OnnxDetector(tmp_path / "nope.onnx")


def test_not_onnx_is_a_clear_error(tmp_path: Path) -> None:
    fake = tmp_path / "model.onnx"
    fake.write_text("this is not a model")
    with pytest.raises(InputError, match="model.onnx: expected an ONNX model onnxruntime can load"):
        OnnxDetector(fake)


def test_other_layout_is_a_clear_error() -> None:
    with pytest.raises(InputError, match=r"wrong_layout.onnx: expected one input \[1, 3, S, S\] and one output "
                                         r"\[1, 4 \+ classes, N\]"):
        OnnxDetector(DATA / "wrong_layout.onnx")
