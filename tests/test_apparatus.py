"""The catalogue's graduation layouts are those of real apparatus."""

from __future__ import annotations

import pytest

from streamread.apparatus import CATALOGUE, format_value, get_spec
from streamread.errors import InputError


def test_syringe_5ml_layout() -> None:
    spec = get_spec("syringe_5ml")
    g = spec.graduation
    values = [g.value_ml(t) for t in g.ticks]
    assert values[0] == 0.0 and values[-1] == 5.0 and len(values) == 26  # every 0.2 ml
    assert [g.label(t) for t in g.ticks if g.label(t)] == ["1", "2", "3", "4", "5"]
    assert all(g.tier(t) == "major" for t in g.ticks if g.value_ml(t) in (1.0, 2.0, 3.0))
    assert g.tier(1) == "minor"
    assert spec.mm_per_ml == pytest.approx(8.75, abs=0.05)  # BD 5 ml bore


def test_burette_increases_downward() -> None:
    spec = get_spec("burette_50ml")
    assert spec.increases_downward
    assert spec.y_mm(10.0) < spec.y_mm(0.0)
    assert spec.value_at(spec.y_mm(12.3)) == pytest.approx(12.3)
    assert spec.graduation.label(0) == "0" and spec.graduation.label(10) == "1"


def test_cylinder_250_labels_every_20_from_30() -> None:
    g = get_spec("cylinder_250ml").graduation
    labels = [g.label(t) for t in g.ticks if g.label(t)]
    assert labels[0] == "30" and labels[-1] == "250" and len(labels) == 12
    assert g.tier(10) == "major" and g.label(10) is None  # 20 ml: long mark, no number


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_model_has_a_readable_layout(name: str) -> None:
    spec = CATALOGUE[name]
    g = spec.graduation
    assert sum(1 for t in g.ticks if g.label(t)) >= 5
    assert 0.5 <= spec.division_mm <= 3.0  # a human can see one division on the real thing


def test_format_value() -> None:
    assert [format_value(v) for v in (1.0, 0.5, 0.05, 250.0, 0.0)] == ["1", "0.5", "0.05", "250", "0"]


def test_unknown_apparatus_names_the_choices() -> None:
    with pytest.raises(InputError, match="syringe_5ml"):
        get_spec("syringe_7ml")
