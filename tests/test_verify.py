"""Measuring a replay against the figure: where the blade's speed jumps with the control rates."""

import importlib

import numpy as np

from skatetrace.model import SleighParams

verify_module = importlib.import_module("skatetrace.verify")  # the package exports the function as verify


def _circle_replay(params, times, speeds):
    """A replay on the unit circle whose speed jumps at the repeated time (both limits sampled)."""
    phi = np.empty(times.size)
    acc, last = 0.0, times[0]
    for i, (t, v) in enumerate(zip(times, speeds)):
        acc += v * (t - last)
        last = t
        phi[i] = acc
    I, Mm = params.I, params.M + params.m
    # mass at the contact point, at rest relative to the blade: xi1 = p1 / I, xi2 = p2 / (M + m)
    state = np.vstack([I * speeds, Mm * speeds, phi + np.pi / 2, np.cos(phi), np.sin(phi)])
    n = times.size
    return verify_module.Replay(t=times, state=state, controls=np.zeros((4, n)), section=np.zeros(n, int),
                                piece=np.zeros(n, int))


def test_figure_to_replay_uses_the_velocity_on_each_side_of_a_jump():
    params = SleighParams()
    left = np.linspace(0.0, 1.0, 11)
    right = np.linspace(1.0, 1.5, 16)
    times = np.concatenate([left, right])
    speeds = np.concatenate([np.full(left.size, 1.0), np.full(right.size, 3.0)])
    rep = _circle_replay(params, times, speeds)
    end = 1.0 + 3.0 * 0.5
    ang = np.linspace(0.0, end, 400)
    points = np.vstack([np.cos(ang), np.sin(ang)])
    d = verify_module._figure_to_replay(points, rep, np.ones(times.size, bool), params)
    # cubic Hermite interpolation of a circle in 0.1-radian steps is off by about 0.1**4 / 384 = 2.6e-7
    assert d.max() < 1e-6, d.max()
    # the same replay interpolated with the left-hand speed past the jump strays by far more
    bad = _circle_replay(params, np.delete(times, 11), np.delete(speeds, 11))
    assert verify_module._figure_to_replay(points, bad, np.ones(times.size - 1, bool), params).max() > 1e-4


def test_figure_to_replay_sees_past_a_run_of_repeated_rows():
    # a replay chunk of zero length (many rows at one instant) must not hide the intervals around it
    params = SleighParams()
    times = np.concatenate([np.linspace(0.0, 1.0, 11), np.full(20, 1.0), np.linspace(1.0, 2.0, 11)])
    speeds = np.ones(times.size)
    rep = _circle_replay(params, times, speeds)
    ang = np.linspace(0.0, 2.0, 400)
    d = verify_module._figure_to_replay(np.vstack([np.cos(ang), np.sin(ang)]), rep, np.ones(times.size, bool), params)
    assert d.max() < 1e-6, d.max()
