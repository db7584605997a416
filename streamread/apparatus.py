"""Catalogue of graduated apparatus: graduation layouts and tube geometry.

Both the renderer (to draw them) and the reader (to know what a division is worth
and which way the numbers run) use this one table, so a layout is written once.

Geometry is in millimetres along the apparatus axis (``y_mm``, upward when the
apparatus stands upright, 0 at the volume zero) and across it (``x_mm``, 0 on the
axis). Values are integers of "ticks" (minor divisions) so that no float rounding
decides whether a mark is a major one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from streamread.errors import InputError, expected

Kind = Literal["syringe", "measuring_cylinder", "burette"]
Tier = Literal["major", "medium", "minor"]
KINDS: tuple[Kind, ...] = ("syringe", "measuring_cylinder", "burette")


@dataclass(frozen=True)
class Graduation:
    """Where the marks are and which carry numbers, in ticks of one minor division."""

    minor_ml: float
    first_tick: int
    last_tick: int
    major_every: int
    medium_every: int = 0
    label_every: int = 0
    label_phase: int = 0
    label_zero: bool = False

    def __post_init__(self) -> None:
        if self.minor_ml <= 0:
            raise ValueError(expected("graduation", "minor_ml", "> 0", self.minor_ml))
        if self.last_tick <= self.first_tick:
            raise ValueError(expected("graduation", "last_tick", f"> {self.first_tick}", self.last_tick))
        if self.major_every <= 0:
            raise ValueError(expected("graduation", "major_every", "> 0", self.major_every))

    @property
    def ticks(self) -> range:
        return range(self.first_tick, self.last_tick + 1)

    def value_ml(self, tick: int) -> float:
        return round(tick * self.minor_ml, 6)

    def is_labelled(self, tick: int) -> bool:
        if self.label_every <= 0 or (tick == 0 and not self.label_zero):
            return False
        return (tick - self.label_phase) % self.label_every == 0

    def tier(self, tick: int) -> Tier:
        if tick % self.major_every == 0 or self.is_labelled(tick):
            return "major"
        if self.medium_every and tick % self.medium_every == 0:
            return "medium"
        return "minor"

    def label(self, tick: int) -> str | None:
        """The number printed beside the mark, as a human writes it ("0.5", "1", "10")."""
        if not self.is_labelled(tick):
            return None
        return format_value(self.value_ml(tick))

    @property
    def first_ml(self) -> float:
        return self.value_ml(self.first_tick)

    @property
    def last_ml(self) -> float:
        return self.value_ml(self.last_tick)


def format_value(value: float) -> str:
    """Shortest decimal text of a scale value: 1.0 -> "1", 0.50 -> "0.5"."""
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


@dataclass(frozen=True)
class ApparatusSpec:
    """One apparatus model: what it is, its scale, and its tube."""

    name: str
    kind: Kind
    capacity_ml: float
    graduation: Graduation
    inner_radius_mm: float
    wall_mm: float
    increases_downward: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(expected("apparatus", "kind", " | ".join(KINDS), self.kind))
        if self.inner_radius_mm <= 0 or self.wall_mm <= 0:
            raise ValueError(expected("apparatus", "inner_radius_mm/wall_mm", "> 0", self.inner_radius_mm))

    @property
    def mm_per_ml(self) -> float:
        """Axial length of one millilitre in a tube of this bore."""
        return 1000.0 / (math.pi * self.inner_radius_mm**2)

    @property
    def outer_radius_mm(self) -> float:
        return self.inner_radius_mm + self.wall_mm

    @property
    def minor_ml(self) -> float:
        return self.graduation.minor_ml

    def y_mm(self, value_ml: float) -> float:
        """Axial position of a scale value (0 at the volume zero, up positive)."""
        sign = -1.0 if self.increases_downward else 1.0
        return sign * value_ml * self.mm_per_ml

    def value_at(self, y_mm: float) -> float:
        sign = -1.0 if self.increases_downward else 1.0
        return sign * y_mm / self.mm_per_ml

    @property
    def division_mm(self) -> float:
        return self.minor_ml * self.mm_per_ml


def _syringe(name: str, capacity: float, inner_d: float, minor: float, major_ml: float,
             label_ml: float, medium_ml: float = 0.0) -> ApparatusSpec:
    per = lambda ml: int(round(ml / minor))  # noqa: E731 - ticks in a value
    return ApparatusSpec(
        name=name, kind="syringe", capacity_ml=capacity, inner_radius_mm=inner_d / 2, wall_mm=1.0,
        graduation=Graduation(minor_ml=minor, first_tick=0, last_tick=per(capacity),
                              major_every=per(major_ml), medium_every=per(medium_ml) if medium_ml else 0,
                              label_every=per(label_ml)),
    )


def _cylinder(name: str, capacity: float, inner_d: float, minor: float, first: float, major_ml: float,
              label_ml: float, medium_ml: float = 0.0, label_phase_ml: float = 0.0) -> ApparatusSpec:
    per = lambda ml: int(round(ml / minor))  # noqa: E731
    return ApparatusSpec(
        name=name, kind="measuring_cylinder", capacity_ml=capacity, inner_radius_mm=inner_d / 2, wall_mm=1.4,
        graduation=Graduation(minor_ml=minor, first_tick=per(first), last_tick=per(capacity),
                              major_every=per(major_ml), medium_every=per(medium_ml) if medium_ml else 0,
                              label_every=per(label_ml), label_phase=per(label_phase_ml)),
    )


def _burette(name: str, capacity: float, inner_d: float) -> ApparatusSpec:
    return ApparatusSpec(
        name=name, kind="burette", capacity_ml=capacity, inner_radius_mm=inner_d / 2, wall_mm=1.2,
        increases_downward=True,
        graduation=Graduation(minor_ml=0.1, first_tick=0, last_tick=int(round(capacity * 10)),
                              major_every=10, medium_every=5, label_every=10, label_zero=True),
    )


# Bores and layouts follow common catalogue items (BD Luer-Lok syringes, ISO 4788 class B
# cylinders, ISO 385 burettes); what matters for reading is the layout and the aspect.
CATALOGUE: dict[str, ApparatusSpec] = {
    spec.name: spec
    for spec in (
        _syringe("syringe_1ml", 1.0, 4.78, minor=0.01, major_ml=0.1, label_ml=0.1, medium_ml=0.05),
        _syringe("syringe_3ml", 3.0, 8.66, minor=0.1, major_ml=0.5, label_ml=0.5),
        _syringe("syringe_5ml", 5.0, 12.06, minor=0.2, major_ml=1.0, label_ml=1.0),
        _syringe("syringe_10ml", 10.0, 14.5, minor=0.2, major_ml=1.0, label_ml=1.0),
        _cylinder("cylinder_10ml", 10.0, 13.2, minor=0.2, first=1.0, major_ml=1.0, label_ml=1.0),
        _cylinder("cylinder_50ml", 50.0, 22.0, minor=1.0, first=5.0, major_ml=10.0, label_ml=10.0, medium_ml=5.0),
        _cylinder("cylinder_100ml", 100.0, 27.0, minor=1.0, first=10.0, major_ml=10.0, label_ml=10.0, medium_ml=5.0),
        _cylinder("cylinder_250ml", 250.0, 37.0, minor=2.0, first=20.0, major_ml=10.0, label_ml=20.0,
                  label_phase_ml=10.0),
        _burette("burette_25ml", 25.0, 8.4),
        _burette("burette_50ml", 50.0, 11.2),
    )
}


def get_spec(name: str) -> ApparatusSpec:
    """The catalogue entry, or an error that lists the known names."""
    try:
        return CATALOGUE[name]
    except KeyError:
        raise InputError(expected("apparatus", repr(name), "one of " + ", ".join(CATALOGUE), "an unknown name")) from None

