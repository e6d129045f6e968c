"""Exact distances to arcs and lines: as the centre-based formula where it is accurate, and well
conditioned where it is not (radii of 1e14)."""

import numpy as np

from skatetrace.drawings import arc_distances
from skatetrace.figures.geometry import Pose, Segment, distance_to_segment


def test_robust_segment_distance():
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(2, 500))
    pose = Pose(0.1, -0.2, 0.7)
    for k in (0.0, 1.0, -2.0, 0.3, 5.0):
        seg = Segment(k, 2.5)
        assert np.allclose(arc_distances._seg_dist(pts, pose, k, 2.5), distance_to_segment(pts, pose, seg), atol=1e-12)
    # For a radius of 1e14 the centre-based formula loses every digit; ours matches the line's.
    far = arc_distances._seg_dist(pts, pose, 1e-14, 2.5)
    assert np.allclose(far, arc_distances._seg_dist(pts, pose, 0.0, 2.5), atol=1e-12)
