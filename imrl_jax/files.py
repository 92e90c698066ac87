"""A user's file read safely: a size limit before reading, UTF-8, one line naming the file when it cannot be."""

from __future__ import annotations

import os

#: The source tree the package lives in (its docs/ and experiments/ when run from a clone).
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def named(what: str) -> str:
    """``what: `` to begin an error's line, or nothing."""
    return f"{what}: " if what else ""


def read_text(path: str, what: str, limit: int, error: type[Exception]) -> str:
    """The UTF-8 text of ``path``, at most ``limit`` bytes of it read (raises ``error``, naming
    ``what`` and the file: too large, not UTF-8, unreadable)."""
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)  # never more: a device or a huge file is refused, not read whole
    except OSError as failure:
        raise error(f"{named(what)}cannot read {path} ({failure.strerror or failure})") from None
    if len(data) > limit:
        raise error(f"{named(what)}{path} is larger than the limit of {limit:,} bytes (is it the right file?)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as failure:
        raise error(f"{named(what)}{path} is not UTF-8 text (byte {failure.start:,})") from None
