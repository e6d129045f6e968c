"""The tracking laws of a figure as data: ``feedback.json`` (schema ``skatetrace.feedback/1``) and back.

A law is ``u = u_r(t) - K(t) (z - z_r(t))`` per section (:class:`~skatetrace.feedback.lqr.TrackingLaw`).
The reference ``(z_r, u_r)`` is the section's rows of ``controls.csv``; this file holds the rest:
the model the law was designed for, the weights, and the gains ``K`` at section times ``t`` (linear
between them: :meth:`~skatetrace.feedback.lqr.TrackingLaw.thinned`). Reading it back against the
same ``controls.csv`` gives the same law, to the bit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..dynamics.model import SleighParams
from .lqr import TrackingGains, TrackingLaw
from .reference import Reference

__all__ = ["FEEDBACK_SCHEMA", "STATE", "laws_from_dict", "laws_to_dict"]

FEEDBACK_SCHEMA = "skatetrace.feedback/1"
#: The state the gains multiply, in their columns' order.
STATE = ("p1", "p2", "theta", "x", "y", "a", "b")


def laws_to_dict(laws, params: SleighParams, gains: TrackingGains, start_times) -> dict[str, Any]:
    """``feedback.json``'s content for one law per section (``None`` where a section was not traced).

    Parameters
    ----------
    laws : sequence of TrackingLaw or None
    params : SleighParams
        The model the laws were designed for.
    gains : TrackingGains
        Their weights.
    start_times : sequence of float
        Each section's start in the figure's time (``result.json``'s ``start_time``).
    """
    sections = []
    for si, (law, t0) in enumerate(zip(laws, start_times)):
        if law is None:
            sections.append({"section": si, "traced": False})
            continue
        sections.append({"section": si, "traced": True, "success": bool(law.success), "message": law.message,
                         "start_time": float(t0), "t": law.t.tolist(), "K": law.K.tolist()})
    return {
        "schema": FEEDBACK_SCHEMA,
        "law": "u = u_r(t) - K(t) (z - z_r(t)), per section, t from the section's start",
        "state": list(STATE),
        "rates": ["adot", "bdot"],
        "reference": "the section's rows of controls.csv; between rows the cubic Hermite interpolant with the "
                     "model's derivatives",
        "measurement": "the momenta p1, p2 are the model's for the measured motion (blade speed and turning "
                       "rate, mass position and rates)",
        "model": params.to_dict(),
        "gains": gains.to_dict(),
        "sections": sections,
    }


def _fail(message: str):
    raise ValueError(f"feedback.json: {message}")


def laws_from_dict(data: Any, refs, params: SleighParams) -> list[TrackingLaw | None]:
    """The laws of ``feedback.json``'s content ``data``, about the references ``refs`` (one per section).

    Raises
    ------
    ValueError
        If ``data`` is not ``skatetrace.feedback/1``, was designed for another model, or does not
        match ``refs`` (another number of sections, other row times, gains of the wrong shape or
        not finite).
    """
    if not isinstance(data, dict) or data.get("schema") != FEEDBACK_SCHEMA:
        _fail(f"expected schema {FEEDBACK_SCHEMA!r}, got {data.get('schema') if isinstance(data, dict) else data!r}")
    model = data.get("model")
    if not isinstance(model, dict) or any(not math.isclose(float(model.get(k, math.nan)), getattr(params, k),
                                                           rel_tol=1e-12) for k in ("M", "m", "I")):
        _fail(f"designed for the model {model!r}, not the figure's {params.to_dict()}; design the law again")
    records = data.get("sections")
    if not isinstance(records, list) or len(records) != len(refs):
        _fail(f"holds {len(records) if isinstance(records, list) else 'no'} sections, the figure has {len(refs)}")
    return [_law(si, rec, ref, params) for si, (rec, ref) in enumerate(zip(records, refs))]


def _law(si: int, rec: Any, ref: Reference | None, params: SleighParams) -> TrackingLaw | None:
    if not isinstance(rec, dict):
        _fail(f"section {si} is not an object")
    if not rec.get("traced", False):
        if ref is not None:
            _fail(f"section {si} has no law but is traced in controls.csv")
        return None
    if ref is None:
        _fail(f"section {si} has a law but no rows in controls.csv")
    try:
        t = np.asarray(rec["t"], dtype=float)
        K = np.asarray(rec["K"], dtype=float)
    except (KeyError, TypeError, ValueError) as exc:
        _fail(f"section {si}: cannot read its gains ({type(exc).__name__} {exc})")
    if t.ndim != 1 or t.size < 2 or K.shape != (t.size, 2, len(STATE)):
        _fail(f"section {si}: {t.size} times and gains of shape {K.shape}, expected at least two times and "
              f"gains of shape (times, 2, {len(STATE)})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(K))):
        _fail(f"section {si}: a time or a gain is not finite")
    slack = 1e-9 * max(ref.duration, 1e-300)
    if np.any(np.diff(t) < 0) or abs(t[0]) > slack or abs(t[-1] - ref.duration) > slack:
        _fail(f"section {si}: its times must rise from 0 to the section's duration {ref.duration!r} in "
              f"controls.csv, got {t[0]!r} to {t[-1]!r}")
    return TrackingLaw(reference=ref, t=t, K=K, success=bool(rec.get("success", True)),
                       message=str(rec.get("message", "")), params=params)
