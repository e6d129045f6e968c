"""Where a section's glide may be placed: its segments, the mass's position at the apex, and the legs either side.

The launch-glide-stop tracer (:func:`~skatetrace.tracing.sections.trace_section`) tries the glide on
each segment of a section in turn, longest first, and at each candidate position of the mass
(:func:`glide_candidates`); the launch runs backwards from the apex and the stop forwards from it,
over the legs :func:`legs_from_apex` cuts from the section's segments.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..dynamics.model import SleighParams, singular_point
from ..figures.geometry import shifted_polynomial

__all__ = ["APEX_CLEARANCE", "apex_singular_distance", "auto_maneuver_length", "glide_candidates", "legs_from_apex",
           "line_apex"]

if TYPE_CHECKING:  # pragma: no cover - for the annotations only (sections imports this module)
    from .sections import TraceOptions

#: A glide's apex nearer than this many singular limits (``TraceOptions.singular_limit``) to the
#: singular point of the apex's curvature is not solved. Its launch and stop both start there, and
#: while the ramp is weak the mass hovers about the singular point, where the control rates grow
#: as one over the distance: on a gently curved arc of resvg-path-m-a-trimmed (the apex ``(0, 0)``
#: 1.3 limits away) each integration took some 28,000 steps, 28 ms, and 330 of them were 3.5 of the
#: drawing's 4.4 s of tracing, for no section traced. No trace kept has come near: over 316
#: distinct sections of the school figures (1.5 to 1.9 m), the examples and the paper's figures,
#: and the 57 corpus drawings at 6 m, the kept apexes were 22 limits or more from it (measured
#: 2026-11-29, every placement solved as before).
APEX_CLEARANCE = 10.0


def apex_singular_distance(params: SleighParams, kappa: float, glide_ab: tuple[float, float]) -> float:
    """How far the apex ``glide_ab`` is from the singular point ``(0, -kappa I / M)`` of its curvature ``kappa``."""
    sa, sb = singular_point(params, kappa)
    return math.hypot(glide_ab[0] - sa, glide_ab[1] - sb)


def auto_maneuver_length(params: SleighParams, kappa: float, length: float) -> float:
    """The length a launch or a stop takes by default: half the segment, at most its radius (a line: one model length)."""
    cap = 1.0 / abs(kappa) if kappa != 0.0 else params.length_scale
    return min(0.5 * length, cap)


def line_apex(params: SleighParams, ell: float) -> float:
    """Fore-aft mass position ``a`` for an apex on the blade's axis before a launch over ``ell``.

    Such a launch moves the mass back by about ``(M + m) ell / m``, which must not reach ``a = 0``
    (the singular point of a line), so the apex sits twice that far ahead plus one model length.
    """
    return 2.0 * (params.M + params.m) / params.m * ell + params.length_scale


def glide_candidates(params: SleighParams, segs, g: int, ell: float,
                     options: TraceOptions) -> list[tuple[tuple[float, float], bool]]:
    """Mass positions ``((a, b), steady)`` to try at the apex on segment ``g``, most natural first.

    ``steady`` apexes are glides: the mass locked at ``(0, b)`` on an arc or anywhere on a line
    keeps the sleigh on the curve at constant speed, so a long segment simply glides longer. At a
    smooth join from curvature k1 to k2 the control rates jump by ``D (k1 - k2) xi2 / |c|`` along
    ``c``; with the mass at ``(0, b)`` the jump moves the mass backwards (speeding the sleigh up)
    iff ``b - b*`` has the sign of ``k1 - k2``, where ``b* = -k2 I / M`` is the singular point of
    the new curvature, so those positions are tried next. Last, on a gently curved arc, where a
    stop driven from ``a = 0`` needs lateral excursions of about ``2 / |k|``, the line's apex
    ``(a, 0)`` is tried as an instant (not a glide): the launch runs straight into the stop.

    A spiral (varying curvature) has no glide: every apex on it is an instant at its middle, at
    ``(0, b)`` for ``b = 0`` and on both sides of the singular point ``b* = -k I / M`` of the
    curvature ``k`` there, then at the line's apex.
    """
    seg = segs[g]
    scale = params.length_scale
    if not seg.constant:
        kg = float(seg.curvature_at(0.5 * seg.length))
        bstar = -kg * params.I / params.M
        out = [0.0] + [bstar + d * scale for d in (1.0, -1.0, 2.5, -2.5)]
        steady = False
    else:
        kg = seg.coefficients[0]
        base = line_apex(params, ell)
        if kg == 0.0:
            return [((base, 0.0), True), ((2.0 * base, 0.0), True), ((4.0 * base, 0.0), True)]
        if options.glide_lateral is not None:
            return [((0.0, options.glide_lateral), True)]
        out = [0.0]
        # the curvature on the other side of the nearest join that changes it
        after = next((s.coefficients[0] for s in segs[g + 1:] if s.coefficients[0] != kg), None)
        before = next((float(s.curvature_at(s.length)) for s in reversed(segs[:g])
                       if float(s.curvature_at(s.length)) != kg), None)
        for k2 in (after, before):
            if k2 is None:
                continue
            bstar = -k2 * params.I / params.M
            sgn = math.copysign(1.0, kg - k2)
            out += [bstar + sgn * d * scale for d in (1.0, 1.5, 2.5)]
        steady = True
    seen: list[float] = []
    for b in out:
        if all(abs(b - c) > 1e-12 for c in seen):
            seen.append(b)
    instant = line_apex(params, 0.5 * seg.length)
    return [((0.0, b), steady) for b in seen] + [((instant, 0.0), False), ((2.0 * instant, 0.0), False)]


def legs_from_apex(segs, g: int, ell_g: float) -> tuple[list, list]:
    """Legs ``[(coefficients, length), ...]`` of the launch and the stop from an apex on segment ``g``.

    The launch's legs run backwards along the curve from ``ell_g`` into segment ``g`` (a curvature
    polynomial of the distance back from the apex), the stop's forwards from ``ell_g`` before its end.
    """
    seg = segs[g]
    L = seg.length
    before = [(shifted_polynomial(seg.coefficients, ell_g, -1.0), ell_g)]
    before += [(shifted_polynomial(s.coefficients, s.length, -1.0), s.length) for s in reversed(segs[:g])]
    after = [(shifted_polynomial(seg.coefficients, L - ell_g, 1.0), ell_g)]
    after += [(s.coefficients, s.length) for s in segs[g + 1:]]
    return before, after
