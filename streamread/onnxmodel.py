"""Loading an ONNX model for onnxruntime on the CPU, with the errors a user can act on: the
apparatus detector and the digit reader both go through here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from streamread.errors import DependencyError, InputError, expected


def load_session(path: Path, what: str, threads: int = 1, bundled: bool = False) -> Any:
    """An ``onnxruntime.InferenceSession`` of the model at ``path`` (``what`` names it in
    errors: "detector", "digit model"); ``bundled``: the path is the install's own model."""
    if not path.is_file():
        hint = " (the bundled model is missing from this install: reinstall streamread)" if bundled else ""
        raise DependencyError(expected(what, path, "an ONNX model file", "no such file") + hint)
    try:
        import onnxruntime as ort
    except ImportError:
        raise DependencyError("onnxruntime is not installed: pip install onnxruntime") from None
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3
    try:
        return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # noqa: BLE001 - onnxruntime raises its own types for a bad file
        first = str(exc).strip().splitlines()[0][:160] if str(exc).strip() else type(exc).__name__
        raise InputError(expected(what, path, "an ONNX model onnxruntime can load", first)) from None
