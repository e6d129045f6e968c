"""Benchmark: arcs used by the greedy and the minimum-count arc-spline fits, their time and certified bounds.

Run: python bench/bench_fit.py [--quick] [--tol T ...]

For each reference curve (an ellipse, a cubic Bézier S-curve, a sine wave, a lemniscate given as a
parametric function, an Euler spiral, and two dense polylines: a circle drawn as 2,500 lines and a
sine wave as 2,000, which greedy alone fitted with a piece per line) and each tolerance (relative to the curve's size), fits the curve
with ``method="greedy"`` and ``method="min"`` and prints the segments each uses, the time each takes and
the certified Hausdorff bound as a fraction of the tolerance. ``--quick`` runs one curve at one tolerance.
Timings are never asserted.
"""

import argparse
import math
import sys
import time
import warnings

import numpy as np
from scipy.special import fresnel

from skatetrace.drawings.curves import BezierPiece, EllipticArcPiece, FunctionPiece, LinePiece, Path
from skatetrace.drawings.fitting import fit_path


def _sine():
    return Path((FunctionPiece(lambda u: (u, np.sin(u)), 0.0, 2 * math.pi,
                               lambda u: (np.ones_like(u), np.cos(u)),
                               lambda u: (np.zeros_like(u), -np.sin(u))),), name="sine")


def _lemniscate():
    def fn(u):
        d = 1.0 + np.sin(u) ** 2
        return np.cos(u) / d, np.sin(u) * np.cos(u) / d

    return Path((FunctionPiece(fn, 0.0, 2 * math.pi),), closed=True, name="lemniscate")


def _euler_spiral():
    def fn(u):
        s, c = fresnel(u)
        return c, s

    return Path((FunctionPiece(fn, 0.2, 2.0, lambda u: (np.cos(0.5 * math.pi * u * u), np.sin(0.5 * math.pi * u * u)),
                               lambda u: (-math.pi * u * np.sin(0.5 * math.pi * u * u),
                                          math.pi * u * np.cos(0.5 * math.pi * u * u))),), name="euler-spiral")


def _polyline(x, y, closed: bool, name: str) -> Path:
    pts = list(zip(x.tolist(), y.tolist()))
    ends = pts[1:] + pts[:1] if closed else pts[1:]
    return Path(tuple(LinePiece(a, b) for a, b in zip(pts, ends)), closed=closed, name=name)


def _polygon_circle(n: int = 2500) -> Path:
    th = 2 * math.pi * np.arange(n) / n
    return _polyline(np.cos(th), np.sin(th), True, f"circle-{n}-gon")


def _polyline_sine(n: int = 2000) -> Path:
    u = np.linspace(0.0, 2 * math.pi, n)
    return _polyline(u, np.sin(u), False, f"sine-{n}-lines")


CURVES = {
    "ellipse": lambda: Path((EllipticArcPiece((0.0, 0.0), 2.0, 1.0, 0.0, 0.0, 2 * math.pi),), closed=True,
                            name="ellipse"),
    "bezier-s": lambda: Path((BezierPiece(((0.0, 0.0), (1.0, 1.0), (2.0, -1.0), (3.0, 0.0))),), name="bezier-s"),
    "sine": _sine,
    "lemniscate": _lemniscate,
    "euler-spiral": _euler_spiral,
    "circle-2500-gon": _polygon_circle,
    "sine-2000-lines": _polyline_sine,
}


def _size(path: Path) -> float:
    pts = path.points(513)
    return float(max(np.ptp(pts[0]), np.ptp(pts[1])))


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one curve (ellipse), one tolerance (1e-2)")
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4],
                    help="tolerances relative to the curve's size (default: 1e-2 1e-3 1e-4)")
    args = ap.parse_args(argv)
    names = ["ellipse"] if args.quick else list(CURVES)
    tols = [1e-2] if args.quick else args.tol
    rows = []
    print(f"{'curve':>15} {'tol/size':>8} {'greedy':>6} {'g time s':>8} {'g bound/tol':>11} "
          f"{'min':>5} {'m time s':>8} {'m bound/tol':>11} {'min/greedy':>10}")
    for name in names:
        path = CURVES[name]()
        size = _size(path)
        for rel in tols:
            tol = rel * size
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                t0 = time.perf_counter()
                g = fit_path(path, tol, method="greedy")
                t1 = time.perf_counter()
                m = fit_path(path, tol, method="min")
                t2 = time.perf_counter()
            row = {"curve": name, "tol_rel": rel, "tol": tol, "size": size,
                   "greedy_segments": g.n_segments, "greedy_s": t1 - t0, "greedy_bound": g.hausdorff,
                   "greedy_success": g.success, "greedy_certificates": g.certificates,
                   "min_segments": m.n_segments, "min_s": t2 - t1, "min_bound": m.hausdorff,
                   "min_success": m.success, "min_certificates": m.certificates,
                   "curve_length": g.curve_length, "greedy_length_error": g.spline_length - g.curve_length}
            rows.append(row)
            print(f"{name:>15} {rel:>8.0e} {g.n_segments:>6d} {t1 - t0:>8.3f} {g.hausdorff / tol:>11.3f} "
                  f"{m.n_segments:>5d} {t2 - t1:>8.3f} {m.hausdorff / tol:>11.3f} "
                  f"{m.n_segments / g.n_segments:>10.2f}")
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
