"""Profiles: the calib/ files are the documented defaults; a broken profile is one clear error."""

from __future__ import annotations

from pathlib import Path

import pytest

from streamread.errors import ConfigError, InputError
from streamread.profile import default_profile, load_profile

CALIB = Path(__file__).resolve().parents[1] / "calib"


@pytest.mark.parametrize("kind", ["syringe", "measuring_cylinder", "burette"])
def test_calib_files_are_the_defaults(kind: str) -> None:
    assert load_profile(CALIB / f"{kind}.toml") == default_profile(kind)


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "p.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(("line", "wrong", "message"), [
    ("aspect_min = 2.5", 'aspect_min = "wide"', r"marks\.aspect_min: expected a number"),
    ("rings = true", "rings = 1", r"marks\.rings: expected true or false, got 1"),
])
def test_wrong_type_names_the_key(tmp_path: Path, line: str, wrong: str, message: str) -> None:
    text = (CALIB / "burette.toml").read_text().replace(line, wrong)
    with pytest.raises(ConfigError, match=message):
        load_profile(_write(tmp_path, text))


def test_missing_key_names_the_key(tmp_path: Path) -> None:
    text = "\n".join(line for line in (CALIB / "syringe.toml").read_text().splitlines() if not line.startswith("jump"))
    with pytest.raises(ConfigError, match=r"grouping\.jump: expected a value, got missing"):
        load_profile(_write(tmp_path, text))


def test_bad_indicator_type(tmp_path: Path) -> None:
    text = (CALIB / "syringe.toml").read_text().replace('type = "stopper"', 'type = "float"')
    with pytest.raises(ConfigError, match="indicator.type"):
        load_profile(_write(tmp_path, text))


def test_bad_network_choice(tmp_path: Path) -> None:
    text = (CALIB / "syringe.toml").read_text().replace('network = "fallback"', 'network = "always"')
    with pytest.raises(ConfigError, match="ocr.network: expected fallback or off, got 'always'"):
        load_profile(_write(tmp_path, text))


def test_not_toml_and_missing(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="valid TOML"):
        load_profile(_write(tmp_path, "kind = = 3"))
    with pytest.raises(InputError, match="no such file"):
        load_profile(tmp_path / "none.toml")
