"""Adaptive sampling of controls for cubic Hermite interpolation."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from skatetrace.dynamics.controls import sample_adaptively, sample_intervals


def _fn(t):
    return np.sin(3 * t), 5 * np.cos(t), 3 * np.cos(3 * t), -5 * np.sin(t)


@pytest.mark.parametrize("value_tol, rate_tol", [(1e-11, 1e-9), (1e-12, 1e-10), (1e-8, 1e-6)])
def test_sampling_meets_its_relative_tolerances_everywhere(value_tol, rate_tol):
    t = sample_adaptively(_fn, 0.0, 10.0, value_tol=value_tol, rate_tol=rate_tol)
    assert np.all(np.diff(t) > 0) and t[0] == 0.0 and t[-1] == 10.0
    a, b, ad, bd = _fn(t)
    tt = np.linspace(0.0, 10.0, 200_001)
    ref = _fn(tt)
    sa, sb = CubicHermiteSpline(t, a, ad), CubicHermiteSpline(t, b, bd)
    v_scale, r_scale = 5.0, 5.0  # largest |a|, |b| and largest rate
    # the checks sit at u = 1/2 (values) and u = 1/4 (rates, 97 % of the largest error), and rates
    # are not refined below the rounding of (y1 - y0) / h: allow 10 %
    assert max(np.abs(sa(tt) - ref[0]).max(), np.abs(sb(tt) - ref[1]).max()) <= 1.1 * value_tol * v_scale
    rate_err = max(np.abs(sa.derivative()(tt) - ref[2]).max(), np.abs(sb.derivative()(tt) - ref[3]).max())
    assert rate_err <= 1.1 * rate_tol * r_scale
    # and it does not oversample: the rate error is within a factor 10 of what was asked
    assert rate_err > 0.1 * rate_tol * r_scale or t.size <= 16


def test_sampling_stops_at_the_rounding_floor_of_noisy_controls():
    # values with rounding-level noise cannot satisfy a rate tolerance below eps / h: no runaway
    # (before the floor, halving went on until the intervals were a few ulps long)
    rng = np.random.default_rng(0)

    def noisy(t):
        a = np.sin(t) * (1 + 1e-15 * rng.standard_normal(t.size))
        return a, a, np.cos(t), np.cos(t)

    t = sample_adaptively(noisy, 0.0, 1.0, value_tol=1e-15, rate_tol=1e-15)
    assert t.size < 20_000


def test_sampling_terminates_at_a_kink_of_the_values():
    # values with kinks that the smooth rates do not show (as between two steps of an ODE solver's
    # dense output): a tent 1e-9 high and 2e-4 wide, whose slopes differ from the rates by 1e-5;
    # halving stops at min_step, so the tent costs at most its width / min_step points
    def kinked(t):
        a = np.sin(t) + 1e-9 * np.maximum(0.0, 1.0 - np.abs(t - 0.3) / 1e-4)
        return a, a, np.cos(t), np.cos(t)

    smooth = sample_adaptively(lambda t: (np.sin(t), np.sin(t), np.cos(t), np.cos(t)), 0.0, 1.0)
    t = sample_adaptively(kinked, 0.0, 1.0, min_step=1e-7)
    assert t.size <= smooth.size + 2e-4 / 1e-7
    assert np.min(np.diff(t)) >= 1e-7


def test_many_spans_at_once_sample_as_each_alone():
    # spans of very different scales (each keeps its own relative tolerance) and a jump at every
    # breakpoint: the span before it sees the left value, marked by `left`
    bounds = np.array([0.0, 0.7, 2.0, 2.05, 6.0])
    gain = np.array([1.0, 1e3, 1e-4, 2.0])

    def fn(t, left):
        after = np.searchsorted(bounds, t, side="right") - 1
        before = np.searchsorted(bounds, t, side="left") - 1  # a span's end belongs to that span
        k = np.clip(np.where(left, before, after), 0, bounds.size - 2)
        a, b, ad, bd = _fn(t)
        return gain[k] * a, gain[k] * b, gain[k] * ad, gain[k] * bd

    spans = sample_intervals(fn, bounds)
    assert len(spans) == 4
    for k, (lo, hi) in enumerate(zip(bounds[:-1], bounds[1:])):
        alone = sample_adaptively(lambda t, _k=k: tuple(gain[_k] * v for v in _fn(t)), lo, hi)
        np.testing.assert_array_equal(spans[k], alone)


def test_a_scale_floor_samples_tiny_spans_to_the_others_scale():
    # three spans: values of scale 5, 2.5 and 5e-6 (the mass passing through the contact point)
    bounds = np.array([0.0, 4.0, 7.0, 10.0])
    gain = np.array([1.0, 0.5, 1e-6])

    def fn(t, left):
        after = np.searchsorted(bounds, t, side="right") - 1
        before = np.searchsorted(bounds, t, side="left") - 1
        k = np.clip(np.where(left, before, after), 0, bounds.size - 2)
        return tuple(gain[k] * v for v in _fn(t))

    alone = sample_intervals(fn, bounds)
    floored = sample_intervals(fn, bounds, scale_floor=1e-2)
    # spans above the floor (0.5 >= 1e-2 of 1) are sampled exactly as alone
    for k in (0, 1):
        np.testing.assert_array_equal(floored[k], alone[k])
    # the tiny span is sampled to 1e-2 of the largest scale, not to its own: far fewer points
    assert floored[2].size < alone[2].size / 5
    t = floored[2]
    a, b, ad, bd = (gain[2] * v for v in _fn(t))
    tt = np.linspace(7.0, 10.0, 100_001)
    ref = [gain[2] * v for v in _fn(tt)]
    sa, sb = CubicHermiteSpline(t, a, ad), CubicHermiteSpline(t, b, bd)
    err = max(np.abs(sa(tt) - ref[0]).max(), np.abs(sb(tt) - ref[1]).max())
    assert err <= 1.1 * 1e-11 * 1e-2 * 5.0  # value_tol times the floor's share of the largest |a|, |b|
    assert err > 1.1 * 1e-11 * gain[2] * 5.0  # and beyond what the span alone was held to


def test_a_span_of_zero_length_is_sampled_without_warnings():
    # a planned piece of no duration puts two breakpoints at one time
    import warnings

    bounds = np.array([0.0, 1.0, 1.0, 2.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spans = sample_intervals(lambda t, left: _fn(t), bounds)
    assert len(spans) == 3
    assert np.all(spans[1] == 1.0)
    np.testing.assert_array_equal(spans[0], sample_adaptively(_fn, 0.0, 1.0))


def test_a_span_of_a_few_ulps_is_not_split_forever():
    # Two breakpoints apart by round-off, the values stepping inside (two pieces finished apart):
    # every midpoint rounds onto an end of the span, so no split can help.
    lo = 10.0
    hi = lo + 8 * np.spacing(lo)
    calls = []

    def fn(t, left):
        calls.append(t.size)
        a, b, ad, bd = _fn(t)
        return a + 1e-9 * (t > lo + 4 * np.spacing(lo)), b, ad, bd

    spans = sample_intervals(fn, np.array([0.0, lo, hi, 20.0]), value_tol=1e-14, rate_tol=1e-12)
    assert len(spans) == 3
    assert np.all((spans[1] >= lo) & (spans[1] <= hi)) and spans[1].size <= 16  # left as first sampled
    assert len(calls) < 100


def test_steps_within_round_off_are_not_distinct():
    from skatetrace.dynamics.controls import distinct_steps

    t = np.array([0.0, 1.0, 1.0, 1.0 + 4e-13, 2.0, 3.0])
    np.testing.assert_array_equal(distinct_steps(t), [True, False, False, True, True])
    assert distinct_steps([5.0]).size == 0 and distinct_steps([]).size == 0
    # the round-off scales with the times: 1e-9 apart is one time at t = 1e4, two at t = 1
    assert not distinct_steps([1e4, 1e4 + 1e-9])[0] and distinct_steps([1.0, 1.0 + 1e-9])[0]
