"""Saved calibrations (``--calibration FILE``): a fixed camera setup starts without OCR.

The file is JSON: the apparatus kind, the frame size it was made on, the strip rotation, the
marks, the numbers read, the corrected fit, the bore, and the print signature the per-frame
check matches against. Loading validates every field and names the file and the key when one
is wrong; the first frames then confirm the calibration against the camera (a moved camera
falls back to OCR as usual).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import numpy as np

from streamread.errors import ConfigError, InputError, expected
from streamread.registration import Signature
from streamread.types import Calibration, Mark, Marks, OcrRead, ScaleFit, Upright

FORMAT = "streamread-calibration/1"
KINDS = ("syringe", "measuring_cylinder", "burette")


def save_calibration(path: str | Path, calibration: Calibration, signature: Signature,
                     frame_wh: tuple[int, int]) -> Path:
    path = Path(path)
    fit = calibration.fit
    data = {
        "format": FORMAT,
        "apparatus": calibration.apparatus,
        "frame_wh": list(frame_wh),
        "upright": {"angle_deg": calibration.upright.angle_deg,
                    "to_upright": calibration.upright.to_upright.tolist(),
                    "strip_wh": list(calibration.upright.strip_wh)},
        "marks": {"spacing_up": calibration.marks.spacing_up,
                  "marks": [asdict(m) for m in calibration.marks.marks]},
        "reads": [asdict(r) for r in calibration.reads],
        "fit": {"slope": fit.slope, "offset": fit.offset, "residual_px": fit.residual_px, "minor_ml": fit.minor_ml,
                "mark_y_up": list(fit.mark_y_up), "mark_values": list(fit.mark_values)},
        "bore_x_up": list(calibration.bore_x_up),
        "box_xyxy": None if calibration.box_xyxy is None else list(calibration.box_xyxy),
        "signature": _signature_to_json(signature),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    tmp.replace(path)  # never a half-written calibration
    return path


def _signature_to_json(signature: Signature) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in fields(Signature):
        value = getattr(signature, f.name)
        if isinstance(value, np.ndarray):
            out[f.name] = {"array": value.tolist(), "dtype": str(value.dtype)}
        elif isinstance(value, tuple):
            out[f.name] = list(value)
        elif isinstance(value, (np.floating, np.integer, np.bool_)):
            out[f.name] = value.item()
        else:
            out[f.name] = value
    return out


def _signature_from_json(r: _Reader, obj: dict[str, Any]) -> Signature:
    values: dict[str, Any] = {}
    template = {f.name: f.type for f in fields(Signature)}
    for name, kind in template.items():
        where = f"signature.{name}"
        if name not in obj:
            raise r.fail(where, "present", "missing")
        v = obj[name]
        if kind == "np.ndarray":
            if not isinstance(v, dict) or "array" not in v or v.get("dtype") not in ("float32", "float64", "bool"):
                raise r.fail(where, "an array with a dtype", type(v).__name__)
            try:
                values[name] = np.asarray(v["array"], dtype=v["dtype"])
            except (TypeError, ValueError):
                raise r.fail(where, f"a list of {v['dtype']}", "other values") from None
        elif "tuple" in str(kind):
            if v is None and "None" in str(kind):
                values[name] = None
            elif isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v):
                values[name] = (int(v[0]), int(v[1]))
            else:
                raise r.fail(where, "two numbers", v)
        elif kind == "bool":
            if not isinstance(v, bool):
                raise r.fail(where, "true or false", v)
            values[name] = v
        elif kind == "int":
            if not isinstance(v, int) or isinstance(v, bool):
                raise r.fail(where, "an integer", v)
            values[name] = v
        else:
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise r.fail(where, "a number", v)
            values[name] = float(v)
    return Signature(**values)


class _Reader:
    """Typed access to the JSON with errors that name the file and the key."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, key: str, wanted: str, got: object) -> ConfigError:
        return ConfigError(expected("calibration", f"{self.path} key {key!r}", wanted, got))

    def get(self, obj: Any, key: str, kind: type | tuple[type, ...], where: str = "") -> Any:
        name = f"{where}.{key}" if where else key
        if not isinstance(obj, dict) or key not in obj:
            raise self.fail(name, "present", "missing")
        value = obj[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or isinstance(value, bool):
            raise self.fail(name, getattr(kind, "__name__", str(kind)), type(value).__name__)
        if isinstance(value, float) and not math.isfinite(value):
            raise self.fail(name, "a finite number", value)
        return value

    def numbers(self, obj: Any, key: str, where: str = "", length: int | None = None) -> list[float]:
        values = self.get(obj, key, list, where)
        try:
            out = [float(v) for v in values]
        except (TypeError, ValueError):
            raise self.fail(f"{where}.{key}" if where else key, "a list of numbers", values) from None
        if length is not None and len(out) != length:
            raise self.fail(f"{where}.{key}" if where else key, f"{length} numbers", len(out))
        return out


def load_calibration(path: str | Path, kind: str | None = None) -> tuple[Calibration, Signature, tuple[int, int]]:
    """Read a saved calibration; ``kind`` (when the user named the apparatus) must match it."""
    path = Path(path)
    if not path.is_file():
        raise InputError(expected("calibration", path, "an existing calibration file", "no such file"))
    try:
        data = json.loads(path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(expected("calibration", path, "a JSON calibration written by streamread", exc)) from None
    r = _Reader(path)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise r.fail("format", repr(FORMAT), repr(got))
    apparatus = r.get(data, "apparatus", str)
    if apparatus not in KINDS:
        raise r.fail("apparatus", " | ".join(KINDS), repr(apparatus))
    if kind is not None and kind != apparatus:
        raise ConfigError(expected("calibration", path, f"a calibration of a {kind} (--apparatus)",
                                   f"one of a {apparatus}"))
    try:
        w, h = (int(v) for v in r.numbers(data, "frame_wh", length=2))
        up = r.get(data, "upright", dict)
        matrix = np.array(r.get(up, "to_upright", list, "upright"), dtype=float)
        if matrix.shape != (2, 3):
            raise r.fail("upright.to_upright", "a 2x3 matrix", f"shape {matrix.shape}")
        sw, sh = (int(v) for v in r.numbers(up, "strip_wh", "upright", length=2))
        upright = Upright(angle_deg=r.get(up, "angle_deg", float, "upright"), to_upright=matrix, strip_wh=(sw, sh))
        mk = r.get(data, "marks", dict)
        mark_list = [Mark(y_up=r.get(m, "y_up", float, "marks"), x0_up=r.get(m, "x0_up", float, "marks"),
                          x1_up=r.get(m, "x1_up", float, "marks"), thickness_up=r.get(m, "thickness_up", float, "marks"),
                          tier=r.get(m, "tier", str, "marks"), grid_index=r.get(m, "grid_index", int, "marks"))
                     for m in r.get(mk, "marks", list, "marks")]
        if any(m.tier not in ("major", "medium", "minor") for m in mark_list):
            raise r.fail("marks.marks.tier", "major | medium | minor", sorted({m.tier for m in mark_list}))
        if len(mark_list) < 3:
            raise r.fail("marks.marks", "at least 3 marks", len(mark_list))
        marks = Marks(marks=tuple(mark_list), spacing_up=r.get(mk, "spacing_up", float, "marks"))
        reads = tuple(OcrRead(y_up=r.get(o, "y_up", float, "reads"), text=r.get(o, "text", str, "reads"),
                              value=None if o.get("value") is None else r.get(o, "value", float, "reads"),
                              confidence=r.get(o, "confidence", float, "reads"))
                      for o in r.get(data, "reads", list))
        f = r.get(data, "fit", dict)
        fit = ScaleFit(slope=r.get(f, "slope", float, "fit"), offset=r.get(f, "offset", float, "fit"),
                       residual_px=r.get(f, "residual_px", float, "fit"), minor_ml=r.get(f, "minor_ml", float, "fit"),
                       mark_y_up=tuple(r.numbers(f, "mark_y_up", "fit")),
                       mark_values=tuple(r.numbers(f, "mark_values", "fit")))
        bore = r.numbers(data, "bore_x_up", length=2)
        box = data.get("box_xyxy")
        box_xyxy = None if box is None else tuple(r.numbers(data, "box_xyxy", length=4))
        calibration = Calibration(apparatus=apparatus, upright=upright, marks=marks, reads=reads, fit=fit,
                                  bore_x_up=(bore[0], bore[1]), box_xyxy=box_xyxy)  # type: ignore[arg-type]
        signature = _signature_from_json(r, r.get(data, "signature", dict))
        if signature.x_profile.ndim != 1 or signature.comb_y.shape != signature.is_major.shape:
            raise r.fail("signature", "profiles of matching shapes", "mismatched arrays")
    except ValueError as exc:  # a dataclass refused a value
        raise ConfigError(expected("calibration", path, "consistent values", exc)) from None
    return calibration, signature, (w, h)
