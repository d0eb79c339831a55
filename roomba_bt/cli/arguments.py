"""Argument types shared by the commands: bad values become argparse's usage error (exit 2)
with what was found and what is allowed, never a traceback from deep inside."""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from roomba_bt.oi.encode import BAUD_CODES


def baud_rate(text: str) -> int:
    """One of the rates the OI's Baud command (129) knows: 300 .. 115200."""
    allowed = ", ".join(str(rate) for rate in BAUD_CODES)
    try:
        rate = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: {allowed}") from None
    if rate not in BAUD_CODES:
        raise argparse.ArgumentTypeError(f"found {rate}; allowed: {allowed}")
    return rate


def seconds(text: str) -> float:
    """A time in seconds, 0 or more (``0.1``)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {text!r}; allowed: seconds, 0 or more") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"found {text}; allowed: seconds, 0 or more")
    return value


def output_file(text: str) -> str:
    """A file to write (--record, --plot): its directory must exist and be writable, checked
    before anything runs, so that a long run does not end in ``No such file or directory``."""
    folder = Path(text).resolve().parent
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"found {text!r}: there is no directory {folder}")
    if not os.access(folder, os.W_OK):
        raise argparse.ArgumentTypeError(f"found {text!r}: directory {folder} is not writable")
    return text


def plot_file(text: str) -> str:
    """A PNG to draw (--plot): as :func:`output_file`, and matplotlib (an optional extra) must
    be installed."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise argparse.ArgumentTypeError(
            "--plot needs matplotlib, an optional extra: pip install 'roomba-bt[plot]'"
        ) from None
    return output_file(text)
