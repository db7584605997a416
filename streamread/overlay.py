"""An annotated picture of what the reader saw: marks, numbers read, corrected values, fit, indicator, reading.

Everything is drawn in the input image's pixels (the strip coordinates mapped back).
"""

from __future__ import annotations

import cv2
import numpy as np

from streamread.apparatus import format_value
from streamread.types import Reading

MAJOR = (0, 0, 255)
MEDIUM = (0, 165, 255)
MINOR = (255, 128, 0)
READ_OK = (0, 200, 0)
READ_BAD = (0, 0, 200)
INDICATOR = (255, 0, 255)


def draw_overlay(image: np.ndarray, reading: Reading) -> np.ndarray:
    out = image.copy()
    h, w = out.shape[:2]
    scale = max(0.4, min(w, h) / 900)
    cal = reading.calibration
    if cal is not None:
        up = cal.upright
        corners = up.to_input(np.array([[0, 0], [up.strip_wh[0], 0], [up.strip_wh[0], up.strip_wh[1]],
                                        [0, up.strip_wh[1]]]))
        cv2.polylines(out, [corners.astype(np.int32)], True, (200, 200, 200), 1, cv2.LINE_AA)
        fit = cal.fit
        for m in cal.marks.marks:
            a, b = up.to_input(np.array([[m.x0_up, m.y_up], [m.x1_up, m.y_up]]))
            color = MAJOR if m.tier == "major" else MEDIUM if m.tier == "medium" else MINOR
            cv2.line(out, tuple(np.round(a).astype(int)), tuple(np.round(b).astype(int)), color, 1, cv2.LINE_AA)
            if m.tier == "major":
                value = fit.value_at(m.y_up)
                p = up.to_input(np.array([[m.x1_up + 4, m.y_up]]))[0]
                cv2.putText(out, format_value(round(value / fit.minor_ml) * fit.minor_ml), tuple(np.round(p).astype(int)),
                            cv2.FONT_HERSHEY_SIMPLEX, 0.4 * scale, MAJOR, 1, cv2.LINE_AA)
        for r in cal.reads:
            if r.value is None:
                continue
            ok = abs(fit.value_at(r.y_up) - r.value) <= 0.3 * fit.minor_ml
            x0 = min(m.x0_up for m in cal.marks.marks)
            p = up.to_input(np.array([[x0 - 40, r.y_up]]))[0]
            cv2.putText(out, f"[{r.text}]", tuple(np.round(p).astype(int)), cv2.FONT_HERSHEY_SIMPLEX, 0.4 * scale,
                        READ_OK if ok else READ_BAD, 1, cv2.LINE_AA)
    if reading.indicator is not None and cal is not None:
        ind = reading.indicator
        l, r = cal.bore_x_up
        a, b = cal.upright.to_input(np.array([[l, ind.y_up], [r, ind.y_up]]))
        cv2.line(out, tuple(np.round(a).astype(int)), tuple(np.round(b).astype(int)), INDICATOR, 1, cv2.LINE_AA)
    if reading.indicator_px is not None:
        cv2.circle(out, tuple(np.round(reading.indicator_px).astype(int)), 4, INDICATOR, 1, cv2.LINE_AA)
    text = (f"{reading.apparatus}: {reading.level:.3f} +- {reading.sigma:.3f} {reading.unit}"
            if reading.level is not None else f"no reading: {reading.error}")
    cv2.rectangle(out, (0, 0), (w, int(24 * scale) + 6), (255, 255, 255), -1)
    cv2.putText(out, text, (5, int(20 * scale)), cv2.FONT_HERSHEY_SIMPLEX, 0.6 * scale, (0, 0, 0), 1, cv2.LINE_AA)
    return out
