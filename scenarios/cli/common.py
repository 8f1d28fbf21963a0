"""Pieces every command module shares: printing a result, and argparse types."""

from __future__ import annotations

import argparse
import json


def emit(result: dict, as_json: bool, lines: list[str]) -> None:
    """Print `result` as one JSON object, or `lines` for people."""
    print(json.dumps(result) if as_json else "\n".join(lines))


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1, with a message naming the bad value."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value
