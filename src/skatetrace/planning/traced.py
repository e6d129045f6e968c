"""A planned section as the tracer's :class:`~skatetrace.tracing.sections.SectionTrace`: its phases, metrics and link.

:mod:`skatetrace.planning.planner` finishes each planned section exactly
(:func:`~skatetrace.planning.finish.finish_section`); here the finish becomes a section trace like
the tracer's own, with the tracer's metrics, how it meets the section before, and the reach
certified between samples.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..dynamics.model import SleighParams
from ..tracing.maneuver import _singular_distances
from ..tracing.sections import SectionTrace, TraceOptions, TraceStatus, _Phase, _with_metrics
from .finish import RestState

__all__ = ["failed", "link_metrics", "section_trace"]


def link_metrics(link: str, arrived: RestState | None, start: RestState, params: SleighParams,
                 options: TraceOptions) -> dict:
    """How the section meets the previous one: the kind, the impulse on the mass (N s) and the jump of its position."""
    if arrived is None:  # a curve's first section, or one after a section that could not be finished
        unknown = 0.0 if link == "start" else math.nan
        return {"link": link, "link_impulse": unknown, "link_jump": unknown}
    dv = math.hypot(start.adot - arrived.adot, start.bdot - arrived.bdot) * options.speed
    return {"link": link, "link_impulse": float(params.m * dv),
            "link_jump": float(math.hypot(start.a - arrived.a, start.b - arrived.b))}


def failed(sec, ci, params, options, status, message) -> SectionTrace:
    """Section ``sec`` of curve ``ci`` not planned (``status``, saying why in ``message``), without controls."""
    return SectionTrace(success=False, status=status, message=message, curve_index=ci, section=sec, params=params,
                        speed=options.speed, glide={"segment": 0, "a": math.nan, "b": math.nan, "length": 0.0,
                                                    "kappa": math.nan, "speed": options.speed})


def section_trace(fin, sec, ci, params, options, spec, link: dict) -> SectionTrace:
    """The exact finish ``fin`` of section ``sec`` (curve ``ci``, program section ``spec``) as a section trace.

    Its metrics are the tracer's, with the reach certified between samples and the ``link`` to the
    section before (:func:`link_metrics`); a finish that did not converge is ``RESIDUAL``, and one
    whose exact motion leaves ``options.reach`` is ``INFEASIBLE``, saying so.
    """
    if not fin.success:
        return failed(sec, ci, params, options, TraceStatus.RESIDUAL, fin.message)
    phases = tuple(_Phase("plan", t0, t1, man, s0, 0.0, j) for t0, t1, man, s0, j in fin.intervals)
    glide = {"segment": 0, "a": fin.start.a, "b": fin.start.b, "length": 0.0,
             "kappa": spec.pieces[0].coefficients[0], "speed": options.speed, "planned": True}
    residuals = {k: abs(v) for k, v in fin.residuals.items()}
    trace = SectionTrace(success=True, status=TraceStatus.SUCCESS, message="planned and finished exactly",
                         curve_index=ci, section=sec, params=params, speed=options.speed, glide=glide, phases=phases,
                         residuals=residuals, nfev=fin.nfev)
    trace = _with_metrics(trace, _singular_distance(trace), options)
    reach = _certified_reach(trace)
    metrics = dict(trace.metrics, reach=reach, **link)
    if trace.success and reach > options.reach:
        return dataclasses.replace(trace, success=False, status=TraceStatus.INFEASIBLE, metrics=metrics,
                                   message=f"the exact motion reaches {reach:.4g} > reach {options.reach:.4g}")
    return dataclasses.replace(trace, metrics=metrics)


def _samples(trace: SectionTrace, n: int = 20001):
    """``n`` times spread over the section, its breakpoints among them, and the motion there."""
    t = np.unique(np.concatenate([np.linspace(0.0, trace.duration, n), trace.breakpoints()]))
    return t, trace.evaluate(t, geometry=False)


def _singular_distance(trace: SectionTrace) -> float:
    """Closest approach of the mass to the singular point, leg by leg as the tracer measures it."""
    return min(_singular_distances(trace.params, ph.maneuver.legs)[0] for ph in trace.phases)


def _certified_reach(trace: SectionTrace) -> float:
    """Largest distance of the mass from the contact point, bounded between the samples.

    Between samples ``dt`` apart the distance changes at most at the mass's speed relative to the
    blade, so it exceeds the larger sampled end by at most ``dt / 2`` times that speed's maximum
    over the interval; the larger speed at the two ends stands for it with half as much again.
    """
    t, v = _samples(trace)
    r = np.hypot(v["a"], v["b"])
    speed = np.hypot(v["adot"], v["bdot"])
    dt = np.diff(t)
    bound = np.maximum(r[:-1], r[1:]) + 0.5 * dt * np.maximum(speed[:-1], speed[1:]) * 1.5
    return float(max(np.max(r), np.max(bound) if bound.size else 0.0))
