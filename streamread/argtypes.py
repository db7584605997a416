"""Argument types shared by the command line (``cli.py``) and the Rerun flags (``sink.py``)."""

from __future__ import annotations

import argparse


def at_least_one(text: str) -> int:
    """A whole number >= 1, or argparse's usage error naming the value given."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value
