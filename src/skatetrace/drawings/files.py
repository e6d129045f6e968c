"""A drawing's file: its bytes, read with errors that name the file, and the drawing's name after it.

Shared by the readers (:mod:`.svg`, :mod:`.points`); :func:`shorten` quotes input briefly in their
error messages.
"""

from __future__ import annotations

import os

from ..errors import DrawingError

__all__ = ["read_bytes", "file_stem", "shorten"]


def read_bytes(file_name: str, kind: str) -> bytes:
    """The bytes of ``file_name``; ``kind`` (``"SVG"``, ``"point list"``) names the file in errors.

    Raises
    ------
    DrawingError
        A missing or unreadable file, or a name that cannot be a file name.
    """
    try:
        with open(file_name, "rb") as handle:
            return handle.read()
    except FileNotFoundError:
        raise DrawingError(f"{kind} file not found: {file_name!r} (current directory {os.getcwd()!r})") from None
    except OSError as exc:
        raise DrawingError(f"cannot read {kind} file {file_name!r}: {exc.strerror or exc}") from exc
    except ValueError:  # a NUL character: no file can have that name
        raise DrawingError(f"{shorten(repr(file_name))} is no file name (it holds a NUL character); give a "
                           f"{kind} file, or its text over more than one line") from None


def file_stem(file_name: str) -> str:
    """The drawing's name after its file: the base name without suffix (``"drawing"`` if empty)."""
    return os.path.splitext(os.path.basename(file_name))[0] or "drawing"


def shorten(text: str, n: int = 60) -> str:
    """``text`` on one line, cut to ``n`` characters with ``...``: input quoted in an error message."""
    text = " ".join(text.split())
    return text if len(text) <= n else text[: n - 3] + "..."
