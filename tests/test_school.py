"""Tests of skatetrace.figures.school (the compulsory figures) and skatetrace.dynamics.presets (SI parameters)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skatetrace.errors import FigureFormatError
from skatetrace.figures.geometry import Pose, advance, segment_points
from skatetrace.dynamics.model import SleighParams
from skatetrace.dynamics.presets import MOVING_FRACTION, PAPER_PARAMS, SEGMENT_MASS_FRACTIONS, skater_params
from skatetrace.figures.school import BLADE, school_figure, school_names

NAMES = school_names()
HEIGHTS = (1.5, 1.9)
LOOPS = {"loop", "change-loop", "paragraph-loop"}
THREE_LOBES = {"serpentine", "rocker", "counter", "change-three", "change-double-three", "change-loop",
               "change-bracket"}

# (turns, changes of foot, smooth joins), counted from the figures' definitions: every figure changes
# foot once inside the curve (and once more back at the start); a three, bracket, rocker or counter
# is one reversing cusp between two smooth joins (circle -> small arc, small arc -> circle); a loop is
# four smooth joins; a change of edge is one smooth join.
EXPECTED = {
    "circle-eight": (0, 1, 0), "serpentine": (0, 1, 2), "three": (2, 1, 4), "double-three": (4, 1, 8),
    "loop": (0, 1, 8), "bracket": (2, 1, 4), "rocker": (2, 1, 4), "counter": (2, 1, 4),
    "one-foot-eight": (0, 1, 2), "change-three": (2, 1, 6), "change-double-three": (4, 1, 10),
    "change-loop": (0, 1, 10), "change-bracket": (2, 1, 6), "paragraph-three": (4, 1, 10),
    "paragraph-double-three": (8, 1, 18), "paragraph-loop": (0, 1, 18), "paragraph-bracket": (4, 1, 10),
}

# Largest number of inflections in a section (rest to rest), as documented in school.py.
MAX_INFLECTIONS = {name: 1 for name in NAMES} | {"circle-eight": 0, "three": 0, "double-three": 0, "loop": 0,
                                                 "change-bracket": 2, "paragraph-bracket": 3}


def end_pose(placed) -> Pose:
    return Pose(*(float(v) for v in advance(placed.start, placed.segment.curvature, placed.segment.length)))


def radius_of(name: str, height: float) -> float:
    return 0.5 * height if name in LOOPS else 1.5 * height


def lobe_centres(name: str, R: float) -> list[tuple[float, float]]:
    if name in THREE_LOBES:
        return [(-2 * R, 0.0), (0.0, 0.0), (2 * R, 0.0)]
    return [(-R, 0.0), (R, 0.0)]


def cusps(fig):
    """``(join, x, y)`` for every cusp inside the curve."""
    return [(p.join_before, p.start.x, p.start.y) for p in fig.curves[0].layout()
            if p.join_before is not None and p.join_before.is_cusp]


def test_names_are_the_classical_seventeen():
    assert len(NAMES) == 17 and len(set(NAMES)) == 17
    assert NAMES[0] == "circle-eight" and NAMES[-1] == "paragraph-bracket"


# --------------------------------------------------------------------------------------------------
# Geometry of every figure
# --------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("height", HEIGHTS)
@pytest.mark.parametrize("name", NAMES)
def test_figure_is_closed_with_the_intended_joins(name, height):
    fig = school_figure(name, height=height)
    assert len(fig.curves) == 1
    curve = fig.curves[0]
    closure = curve.closure()
    assert closure["closed"], closure
    assert closure["direction_restored"]
    joins = list(curve.joins)
    turns = sum(j.is_cusp and j.reverse for j in joins)
    steps = sum(j.is_cusp and not j.reverse for j in joins)
    smooth = sum(not j.is_cusp for j in joins)
    assert (turns, steps, smooth) == EXPECTED[name]
    assert all(j.pivot == 0.0 for j in joins)
    # a change of foot is a rest point: it starts a new section, as does every turn
    assert len(curve.sections()) == turns + steps + 1


@pytest.mark.parametrize("height", HEIGHTS)
@pytest.mark.parametrize("name", NAMES)
def test_pieces_meet_in_position_and_heading(name, height):
    placed = school_figure(name, height=height).curves[0].layout()
    size = 3.0 * height
    for prev, p in zip(placed, placed[1:]):
        e = end_pose(prev)
        assert math.hypot(e.x - p.start.x, e.y - p.start.y) <= 1e-9 * size
        j = p.join_before
        expected_turn = 0.0 if not j.is_cusp else j.pivot + (math.pi if j.reverse else 0.0)
        assert abs(math.remainder(p.start.heading - e.heading - expected_turn, 2 * math.pi)) <= 1e-9
    # the independent check: going round with advance() alone, joins applied by hand, ends at the start
    pose = placed[0].start
    for p in placed:
        if p.join_before is not None and p.join_before.reverse:
            pose = Pose(pose.x, pose.y, pose.heading + math.pi)
        pose = Pose(*(float(v) for v in advance(pose, p.segment.curvature, p.segment.length)))
    start = placed[0].start
    assert math.hypot(pose.x - start.x, pose.y - start.y) <= 1e-9 * size
    assert abs(math.remainder(pose.heading - start.heading, 2 * math.pi)) <= 1e-9


@pytest.mark.parametrize("height", HEIGHTS)
@pytest.mark.parametrize("name", NAMES)
def test_circles_have_the_intended_size_and_centres(name, height):
    fig = school_figure(name, height=height)
    R = radius_of(name, height)
    assert fig.extra["school"]["radius"] == pytest.approx(R)
    assert 2 * R == pytest.approx(height if name in LOOPS else 3 * height)
    centres = np.array(lobe_centres(name, R))
    n_main = 0
    for p in fig.curves[0].layout():
        k = p.segment.curvature
        if abs(abs(k) * R - 1.0) > 1e-12:
            continue  # a turn's or loop's small arc
        n_main += 1
        cx = p.start.x - math.sin(p.start.heading) / k
        cy = p.start.y + math.cos(p.start.heading) / k
        # every stretch of circle lies on one of the figure's circles, which touch on the long axis
        assert np.min(np.hypot(centres[:, 0] - cx, centres[:, 1] - cy)) <= 1e-9 * R
    assert n_main >= 2
    pts = np.hstack([segment_points(p.start, p.segment, 2001) for p in fig.curves[0].layout()])
    assert np.max(np.abs(pts[1])) == pytest.approx(R, rel=1e-6)  # nothing pokes out across the circles
    lobes = 3 if name in THREE_LOBES else 2
    if name in LOOPS:  # the loops cut the ends of the long axis short
        assert 2 * lobes * R - 2 * BLADE < np.ptp(pts[0]) < 2 * lobes * R
    else:  # a three's cusp cuts the circle short, a bracket's sticks out, by about a turn radius
        rho = fig.extra["school"]["turn_radius"]
        assert abs(np.ptp(pts[0]) - 2 * lobes * R) <= 2 * rho


@pytest.mark.parametrize("height", HEIGHTS)
@pytest.mark.parametrize("name", NAMES)
def test_rest_points_lie_where_the_figure_puts_them(name, height):
    fig = school_figure(name, height=height)
    R = radius_of(name, height)
    centres = lobe_centres(name, R)
    rho = fig.extra["school"]["turn_radius"]
    for join, x, y in cusps(fig):
        if not join.reverse:  # change of foot: where two circles touch
            assert abs(y) <= 1e-9 * R
            assert min(abs(x - (cx + R)) for cx, _ in centres) <= 1e-9 * R
            continue
        if "double-three" in name:
            # two threes divide the circle into thirds: 60 degrees either side of the long axis
            cx = min((c[0] for c in centres), key=lambda c: math.hypot(x - c, y))
            assert abs(abs(math.atan2(y, x - cx)) - math.radians(60.0)) <= 1e-9 or \
                abs(abs(math.atan2(y, x - cx)) - math.radians(120.0)) <= 1e-9
            assert math.hypot(x - cx, y) < R - 0.5 * rho  # a three's cusp points into its circle
            continue
        assert abs(y) <= 1e-9 * R  # on the long axis
        cx = min((c[0] for c in centres), key=lambda c: abs(x - c))
        d = abs(x - cx)
        if name.endswith("three"):
            assert R - 1.5 * rho < d < R - 0.5 * rho  # into the circle
        elif name.endswith("bracket"):
            assert R + 0.5 * rho < d < R + 1.5 * rho  # out of it
        elif name == "rocker":
            assert R - 1.5 * rho < abs(x) < R - 0.5 * rho  # into the middle circle, which it leaves
        elif name == "counter":
            assert R + 0.5 * rho < abs(x) < R + 1.5 * rho  # into the end circle, which it enters
        else:
            pytest.fail(f"unexpected turn in {name}")
    # rest points (with the start, where the figure ends) come in pairs: the figure is symmetric
    start = fig.curves[0].start
    xy = np.array([(x, y) for _, x, y in cusps(fig)] + [(start.x, start.y)])
    twin = np.array([(-x, -y) for x, y in xy]) if name in THREE_LOBES else np.array([(-x, y) for x, y in xy])
    for q in twin:
        assert np.min(np.hypot(*(xy - q).T)) <= 1e-9 * R


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(NAMES), height=st.floats(1.2, 2.2), blade=st.floats(0.12, 0.2),
       turn=st.floats(0.2, 0.8), edge=st.sampled_from(["outside", "inside"]),
       direction=st.sampled_from(["forward", "backward"]), foot=st.sampled_from(["right", "left"]))
def test_any_size_and_variant_closes_with_rest_points_on_the_axis(name, height, blade, turn, edge, direction, foot):
    blade *= height  # 0.28 m is 0.165 of 1.7 m; a loop needs circles of more than about two blades' radius
    fig = school_figure(name, height=height, blade=blade, turn_radius=turn * blade, edge=edge, direction=direction,
                        foot=foot)
    closure = fig.curves[0].closure()
    assert closure["closed"] and closure["direction_restored"], closure
    R = fig.extra["school"]["radius"]
    on_axis = [abs(y) <= 1e-9 * R for join, _, y in cusps(fig) if not ("double-three" in name and join.reverse)]
    assert all(on_axis) and on_axis


@pytest.mark.parametrize("name", sorted(LOOPS))
def test_loop_is_a_blade_wide_and_one_and_a_half_long(name):
    height, blade = 1.7, 0.3
    fig = school_figure(name, height=height, blade=blade)
    placed = fig.curves[0].layout()
    idx = [i for i, p in enumerate(placed) if abs(abs(p.segment.curvature) - 2.0 / blade) < 1e-9]
    assert len(idx) == (4 if name == "paragraph-loop" else 2)
    R = 0.5 * height
    for i in idx:
        half, before = placed[i], placed[i - 1]
        assert half.join_before.kind == "smooth" and placed[i + 1].join_before.kind == "smooth"
        assert abs(half.segment.turn) == pytest.approx(math.pi)
        k = half.segment.curvature
        cx = half.start.x - math.sin(half.start.heading) / k
        assert abs(half.start.y + math.cos(half.start.heading) / k) <= 1e-9  # centred on the long axis
        # the transition arc before the half circle crosses the long axis where the loop closes
        x, y, _ = advance(before.start, before.segment.curvature, np.linspace(0, before.segment.length, 200001))
        j = np.flatnonzero(np.diff(np.sign(y)))
        assert j.size == 1
        x_cross = x[j[0]]
        lobe = min((c[0] for c in lobe_centres(name, R)), key=lambda c: abs(cx - c))
        apex = cx - math.copysign(0.5 * blade, cx - lobe)  # inner end of the loop, nearer the centre
        assert abs(x_cross - apex) == pytest.approx(1.5 * blade, rel=1e-4)
        assert abs(x_cross - lobe) < R  # inside the circle


@pytest.mark.parametrize("name", NAMES)
def test_sections_have_at_most_the_documented_inflections(name):
    worst = 0
    for sec in school_figure(name).curves[0].sections():
        ks = [p.segment.curvature for p in sec.pieces]
        worst = max(worst, sum(a * b < 0 for a, b in zip(ks, ks[1:])))
    assert worst == MAX_INFLECTIONS[name]


# --------------------------------------------------------------------------------------------------
# Variants
# --------------------------------------------------------------------------------------------------
def reflected(placed):
    return flat(placed, -1.0)


def flat(placed, mirror: float = 1.0):
    """Rows (x, y, cos heading, sin heading, curvature, length, direction), reflected in y if ``mirror = -1``."""
    return [(p.start.x, mirror * p.start.y, math.cos(p.start.heading), mirror * math.sin(p.start.heading),
             mirror * p.segment.curvature, p.segment.length, p.direction) for p in placed]


@pytest.mark.parametrize("variant", [{"foot": "left"}, {"edge": "inside"}, {"direction": "backward"},
                                     {"foot": "left", "edge": "inside", "direction": "backward"}])
@pytest.mark.parametrize("name", NAMES)
def test_mirror_variants_are_mirror_images_in_the_long_axis(name, variant):
    base = school_figure(name, height=1.5).curves[0].layout()
    other = school_figure(name, height=1.5, **variant).curves[0].layout()
    np.testing.assert_allclose(np.array(flat(other)), np.array(reflected(base)), atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_two_mirrorings_give_the_same_path_and_edges_follow(name):
    base = school_figure(name)
    same = school_figure(name, foot="left", edge="inside")
    np.testing.assert_allclose(np.array(flat(same.curves[0].layout())), np.array(flat(base.curves[0].layout())),
                               atol=1e-12)
    seq = base.extra["school"]["sequence"]
    assert seq.startswith("RFO") and same.extra["school"]["sequence"].startswith("LFI")
    back = school_figure(name, direction="backward")
    assert back.extra["school"]["start_direction"] == -1 and base.extra["school"]["start_direction"] == 1
    assert back.extra["school"]["sequence"].startswith("RBO")
    assert "backwards" in back.description


def test_edge_sequences_of_well_known_figures():
    seq = {n: school_figure(n).extra["school"]["sequence"] for n in NAMES}
    assert seq["circle-eight"] == "RFO | LFO"
    assert seq["serpentine"] == "RFO change RFI | LFI change LFO"
    assert seq["three"] == "RFO three RBI | LBI three LFO"
    assert seq["bracket"] == "RFO bracket RBI | LBI bracket LFO"
    assert seq["rocker"] == "RFO rocker RBO | LBO rocker LFO"
    assert seq["counter"] == "RFO counter RBO | LBO counter LFO"
    assert seq["paragraph-three"] == "RFO three RBI change RBO three RFI | LFO three LBI change LBO three LFI"


def test_names_are_forgiving_and_params_default_to_the_skater():
    a = school_figure("Circle eight", height=1.6)
    b = school_figure("circle_eight", height=1.6)
    assert a.name == b.name == "circle-eight-RFO"
    assert a.params == skater_params(height=1.6)
    p = SleighParams(M=50.0, m=20.0, I=0.8)
    assert school_figure("three", params=p).params == p
    assert "Wikipedia" in a.provenance and "3" in a.provenance
    assert school_figure("loop").description.startswith("Loop:")


@pytest.mark.parametrize("kwargs, match", [
    ({"name": "triple-axel"}, "valid names are circle-eight, serpentine, three"),
    ({"name": 3}, "valid names are"),
    ({"name": "three", "edge": "flat"}, "valid edges are outside, inside"),
    ({"name": "three", "direction": "sideways"}, "valid directions are forward, backward"),
    ({"name": "three", "foot": "both"}, "valid foots are right, left"),
    ({"name": "three", "height": -1.7}, "height must be a positive length"),
    ({"name": "three", "height": float("nan")}, "height must be a positive length"),
    ({"name": "three", "blade": 0}, "blade must be a positive length"),
    ({"name": "three", "turn_radius": 1.0}, "turn_radius 1 m is too large"),
    ({"name": "loop", "height": 1.0}, "does not fit in a circle of radius 0.5 m"),
])
def test_bad_input_raises_with_the_valid_choices(kwargs, match):
    kwargs = dict(kwargs)
    name = kwargs.pop("name")
    with pytest.raises(FigureFormatError, match=match):
        school_figure(name, **kwargs)


def test_every_valid_name_is_in_the_error_message():
    with pytest.raises(FigureFormatError) as info:
        school_figure("eight")
    assert all(n in str(info.value) for n in NAMES)


# --------------------------------------------------------------------------------------------------
# Presets
# --------------------------------------------------------------------------------------------------
def test_skater_preset_is_plausible_in_si_units():
    p = skater_params()
    assert p.M + p.m == pytest.approx(60.0)
    assert 30.0 < p.M < 50.0 and 15.0 < p.m < 25.0  # kg
    assert 0.2 < p.I < 1.5  # kg m^2: below a standing body's ~1 kg m^2, the limbs being in m
    assert 0.05 < p.length_scale < 0.15  # m
    assert sum(SEGMENT_MASS_FRACTIONS[k] * n for k, n in (("head_neck", 1), ("trunk", 1), ("arm", 2), ("leg", 2))) \
        == pytest.approx(1.0)
    assert 0.3 <= MOVING_FRACTION <= 0.4
    # the moving mass is well clear of the curvature condition's singular set on the figures' circles
    assert p.length_scale < school_figure("three").extra["school"]["turn_radius"]


def test_skater_preset_scales_like_a_body():
    p, q = skater_params(60.0, 1.7), skater_params(120.0, 1.7)
    assert (q.M, q.m, q.I) == pytest.approx((2 * p.M, 2 * p.m, 2 * p.I))
    assert q.length_scale == pytest.approx(p.length_scale)
    tall = skater_params(60.0, 3.4)
    assert tall.I == pytest.approx(4 * p.I) and tall.M == pytest.approx(p.M)
    assert skater_params(radius=0.2).I == pytest.approx(0.5 * p.M * 0.04)
    assert skater_params(moving_fraction=0.3).m == pytest.approx(18.0)


def test_units_are_documented():
    import skatetrace.dynamics.presets as presets

    doc = (presets.__doc__ or "") + (skater_params.__doc__ or "")
    for word in ("kg m^2", "kg", "metres", "m/s", "seconds"):
        assert word in doc
    assert PAPER_PARAMS == SleighParams() and PAPER_PARAMS.length_scale == 1.0


@pytest.mark.parametrize("kwargs, match", [
    ({"body_mass": 0.0}, "body_mass must be a positive number"),
    ({"height": -1.0}, "height must be a positive number"),
    ({"body_mass": True}, "body_mass must be a positive number"),
    ({"moving_fraction": 0.0}, "moving_fraction must lie strictly between 0 and 1"),
    ({"moving_fraction": 1.0}, "moving_fraction must lie strictly between 0 and 1"),
    ({"radius": float("inf")}, "radius must be a positive number"),
])
def test_bad_presets_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        skater_params(**kwargs)


# --------------------------------------------------------------------------------------------------
# End to end: trace with the SI skater and replay (the other figures take minutes each; see the
# issue's report for the full table)
# --------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_circle_eight_traces_and_verifies_in_si_units():
    from skatetrace.tracing.sections import TraceOptions, trace_figure
    from skatetrace.verification.verify import verify

    fig = school_figure("circle-eight", height=1.7)
    tr = trace_figure(fig, fig.params, TraceOptions(speed=2.0))  # a glide at 2 m/s
    assert tr.success, tr.message
    assert len(tr.sections) == 2
    # two circles of 16 m at 2 m/s, plus the launch and stop of each: seconds, not hours or microseconds
    assert 2 * 2 * math.pi * 2.55 / 2.0 < tr.duration < 60.0
    rep = verify(tr)
    assert rep.success, rep.message
    assert rep.max_deviation <= 1e-6 * fig.size()
