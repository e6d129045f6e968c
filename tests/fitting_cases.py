"""Curves the arc-fitting tests share (test_splitting, test_fitting, test_to_figure, ...), and small measures."""

import math

import numpy as np

from skatetrace.drawings.curves import BezierPiece, EllipticArcPiece, FunctionPiece, Path


def sine_piece(analytic=True):
    if analytic:
        return FunctionPiece(lambda u: (u, np.sin(u)), 0.0, 2 * math.pi, lambda u: (np.ones_like(u), np.cos(u)),
                             lambda u: (np.zeros_like(u), -np.sin(u)))
    return FunctionPiece(lambda u: (u, np.sin(u)), 0.0, 2 * math.pi)


def ellipse_quarter():
    return Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, math.pi / 2),), name="ellipse-quarter")


def bezier_spiral():
    # Curvature of one sign, monotone on [0, 1] (checked in test_reference_spirals_are_single_spans).
    return Path((BezierPiece(((0.0, 0.0), (1.0, 0.0), (2.0, 0.2), (2.8, 0.8))),), name="bezier-spiral")


def size_of(path):
    pts = path.points(513)
    return float(max(np.ptp(pts[0]), np.ptp(pts[1])))


def heading_gap(a, b):
    return abs(math.remainder(a - b, 2 * math.pi))
