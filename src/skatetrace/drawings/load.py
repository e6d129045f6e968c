"""Any drawing file, read by the reader its suffix names: SVG or a point list.

The one place that maps file types to readers (:mod:`.svg`, :mod:`.points`).
"""

from __future__ import annotations

import os
import pathlib

from .curves import Drawing
from .points import POINT_SUFFIXES, read_points
from .svg import SVG_SUFFIXES, read_svg
from ..errors import DrawingError

__all__ = ["load_drawing"]


def load_drawing(path: str | os.PathLike) -> Drawing:
    """Read a drawing file, its type chosen by the suffix.

    Parameters
    ----------
    path : str or os.PathLike
        ``.svg`` (:func:`~skatetrace.drawings.svg.read_svg`), or ``.csv``, ``.txt``, ``.dat``
        (:func:`~skatetrace.drawings.points.read_points`); the suffix's case is ignored.

    Returns
    -------
    Drawing

    Raises
    ------
    DrawingError
        An unsupported suffix (the message lists the supported ones), or any error of the reader.

    Examples
    --------
    >>> load_drawing("figure.dxf")
    Traceback (most recent call last):
    ...
    skatetrace.errors.DrawingError: cannot load 'figure.dxf': unsupported file type '.dxf'; supported: .svg (SVG drawing), .csv, .txt, .dat (point lists)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise DrawingError(f"load_drawing expects a file name, got {type(path).__name__}")
    file_name = os.fspath(path)
    suffix = os.path.splitext(file_name)[1].lower()
    if suffix in SVG_SUFFIXES:
        return read_svg(pathlib.Path(file_name))
    if suffix in POINT_SUFFIXES:
        return read_points(pathlib.Path(file_name))
    raise DrawingError(f"cannot load {file_name!r}: unsupported file type {suffix or '(no suffix)'!r}; supported: "
                       f"{', '.join(SVG_SUFFIXES)} (SVG drawing), {', '.join(POINT_SUFFIXES)} (point lists)")
