"""Ground truth carried by every render: what a perfect reader would report and where.

Pixel coordinates follow OpenCV (pixel centres at integers, x right, y down).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from streamread.apparatus import Kind, Tier

PointPx = tuple[float, float]


@dataclass(frozen=True)
class MarkTruth:
    """One graduation mark: its value and where its visible stroke lies in the image."""

    value_ml: float
    tier: Tier
    label: str | None
    center_px: PointPx
    ends_px: tuple[PointPx, PointPx]
    in_frame: bool


@dataclass(frozen=True)
class SceneTruth:
    """Everything the renderer knows about one image or frame."""

    apparatus: str
    kind: Kind
    minor_ml: float
    level_ml: float
    indicator_px: PointPx
    indicator_line_px: tuple[PointPx, PointPx]
    indicator_in_frame: bool
    box_xyxy: tuple[float, float, float, float] | None
    axis_px: tuple[PointPx, PointPx]
    axis_values_ml: tuple[float, float]
    marks: tuple[MarkTruth, ...]
    px_per_division: float
    occluded: bool = False

    def __post_init__(self) -> None:
        if self.minor_ml <= 0:
            raise ValueError(f"truth: expected minor_ml > 0, got {self.minor_ml}")

    @property
    def visible(self) -> bool:
        """The level can be read by eye: indicator in frame and nothing in front of it."""
        return self.indicator_in_frame and not self.occluded

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)
