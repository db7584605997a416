"""One small error hierarchy: every failure a user can cause is a ``StreamreadError``.

The CLI turns these into one clear line and a non-zero exit; anything else is a bug
and keeps its traceback.
"""

from __future__ import annotations


class StreamreadError(Exception):
    """Base of every error the user can cause or fix."""


class InputError(StreamreadError):
    """An input (file, device, argument) is missing, unreadable or of the wrong kind."""


class ConfigError(StreamreadError):
    """A profile, calibration or option has a wrong type, value or missing key."""


class DependencyError(StreamreadError):
    """A system dependency (tesseract binary, model file) is missing; says how to install it."""


def expected(what: str, name: object, wanted: str, got: object) -> str:
    """Message naming the argument, the expected and the actual value."""
    return f"{what} {name!s}: expected {wanted}, got {got!s}"
