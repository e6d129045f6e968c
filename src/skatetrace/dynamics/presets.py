"""Model parameters for a real skater, in SI units, and the paper's dimensionless ones.

The sleigh model (:class:`~skatetrace.dynamics.model.SleighParams`) splits the skater into

- the *sleigh*, mass ``M``: the part of the body carried rigidly by the blade, with its centre of
  mass over the blade's contact point and moment of inertia ``I`` about the vertical axis there;
- the *moving mass* ``m``: a point mass at ``(a, b)`` in the blade's frame, standing for the parts of
  the body the skater moves relative to the blade to steer (arms, free leg, head and lean).

Units
-----
:func:`skater_params` returns ``M`` and ``m`` in kg and ``I`` in kg m^2. Lay figures out in metres
(as :mod:`skatetrace.figures.school` does) and give ``TraceOptions(speed=...)`` in m/s; every time is then
in seconds, the mass position ``(a, b)`` in metres, its rates in m/s, ``p1`` in kg m^2/s and
``p2`` in kg m/s. The motion depends on the masses only through the ratios ``M : m : I`` (scaling
all three by one factor scales the momenta, not the motion), so the one length the model owns is
``sqrt(I / (M + m))`` (:attr:`SleighParams.length_scale`), about 0.09 m for the default skater: the
figures' circles (metres) and turns (a fraction of a blade) are many such lengths.

:data:`PAPER_PARAMS` are the paper's ``M = 2, m = 1, I = 3`` in unstated consistent units
(dimensionless): its length scale is 1, and with a speed of 1 one time unit is the time to glide one
length unit.
"""

from __future__ import annotations

import math

from .model import SleighParams

__all__ = ["PAPER_PARAMS", "SEGMENT_MASS_FRACTIONS", "MOVING_FRACTION", "TRUNK_RADIUS_PER_HEIGHT", "REACH_PER_HEIGHT",
           "IMPULSE_TIME", "skater_params", "skater_reach"]

PAPER_PARAMS = SleighParams(M=2.0, m=1.0, I=3.0)
"""The paper's parameters ``M = 2, m = 1, I = 3`` (dimensionless, length scale 1)."""

#: Segment masses as fractions of body mass, Dempster's (1955) cadaver data as tabulated in
#: D. A. Winter, *Biomechanics and Motor Control of Human Movement* (anthropometry chapter).
#: "arm" is upper arm + forearm + hand, "leg" is thigh + shank + foot; they sum to 1.
SEGMENT_MASS_FRACTIONS = {"head_neck": 0.081, "trunk": 0.497, "arm": 0.050, "leg": 0.161}

#: Moving mass as a fraction of body mass: both arms, the free leg and the head and neck, which a
#: skater moves relative to the skating leg to steer (0.342 with the fractions above).
MOVING_FRACTION = (2 * SEGMENT_MASS_FRACTIONS["arm"] + SEGMENT_MASS_FRACTIONS["leg"]
                   + SEGMENT_MASS_FRACTIONS["head_neck"])

#: Radius of the cylinder standing for the sleigh (trunk and skating leg) per unit of height:
#: 0.15 m for a skater 1.7 m tall, about half the width of the hips.
TRUNK_RADIUS_PER_HEIGHT = 0.15 / 1.7


#: The planner's default reach per unit of height: the length of the trunk, from the hip to the
#: shoulder (0.818 H - 0.530 H = 0.288 H in Drillis and Contini's segment proportions, as tabulated
#: in Winter's anthropometry chapter). The moving mass (arms, free leg, head) then stays within the
#: trunk's length of the skating leg: a comfortable range, well inside the 0.5 H beyond which the
#: feasibility check (:mod:`skatetrace.verification.feasibility`) calls a motion impossible.
REACH_PER_HEIGHT = 0.288

#: The time over which a cusp's impulse counts as delivered in the effort (s, or the model's time
#: unit): an impulse ``J`` spread evenly over ``IMPULSE_TIME`` adds ``|J|^2 / IMPULSE_TIME`` to the
#: integral of the squared force. The least-effort planner penalises the mass's velocity jumps by
#: the same, and the feasibility report measures them so (``cusp_effort``).
IMPULSE_TIME = 0.1


def skater_reach(height: float = 1.7) -> float:
    """The planner's default reach in m for a skater ``height`` m tall (:data:`REACH_PER_HEIGHT` x height).

    >>> round(skater_reach(1.7), 3)
    0.49
    """
    if not (_is_number(height) and math.isfinite(height) and height > 0):
        raise ValueError(f"height must be a positive length in m, got {height!r}")
    return REACH_PER_HEIGHT * float(height)


def skater_params(body_mass: float = 60.0, height: float = 1.7, *, moving_fraction: float = MOVING_FRACTION,
                  radius: float | None = None) -> SleighParams:
    """Sleigh parameters of a skater in SI units (kg, kg m^2).

    Parameters
    ----------
    body_mass : float
        Whole body mass in kg (default 60 kg).
    height : float
        Standing height in m (default 1.7 m); sets the default ``radius``.
    moving_fraction : float
        Fraction of the body mass that moves relative to the blade, the moving mass ``m``.
        Default :data:`MOVING_FRACTION` (0.342): two arms (0.050 each), the free leg (0.161) and
        the head and neck (0.081), from :data:`SEGMENT_MASS_FRACTIONS`. Must lie in (0, 1).
    radius : float, optional
        Radius in m of the vertical cylinder that stands for the sleigh (trunk and skating leg).
        Default ``TRUNK_RADIUS_PER_HEIGHT * height`` (0.15 m at 1.7 m).

    Returns
    -------
    SleighParams
        ``M = (1 - moving_fraction) body_mass`` (kg), ``m = moving_fraction body_mass`` (kg) and
        ``I = M radius^2 / 2`` (kg m^2).

    Raises
    ------
    ValueError
        If a value is not positive and finite, or ``moving_fraction`` is not in (0, 1).

    Notes
    -----
    Assumptions, all rough: the segment mass fractions are Dempster's (1955) as tabulated by Winter
    (see :data:`SEGMENT_MASS_FRACTIONS`); the moving mass is a point (its own inertia about its
    centre is neglected); the rest of the body is a uniform vertical cylinder about the vertical axis
    through the blade's contact point. There is no parallel-axis term because the model puts the
    sleigh's centre of mass over the contact point. For a 60 kg, 1.7 m skater this gives
    ``M = 39.5 kg``, ``m = 20.5 kg`` and ``I = 0.44 kg m^2``; the whole standing body's moment of
    inertia about its long axis is of the order of 1 kg m^2, of which the arms, free leg and head,
    here in the moving mass, carry a good part.

    Examples
    --------
    >>> p = skater_params()
    >>> round(p.M, 2), round(p.m, 2), round(p.I, 3)
    (39.48, 20.52, 0.444)
    >>> round(p.length_scale, 3)  # metres
    0.086
    >>> skater_params(moving_fraction=1.2)
    Traceback (most recent call last):
    ...
    ValueError: moving_fraction must lie strictly between 0 and 1, got 1.2
    """
    for name, value in (("body_mass", body_mass), ("height", height)):
        if not (_is_number(value) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value!r}")
    if not (_is_number(moving_fraction) and 0.0 < moving_fraction < 1.0):
        raise ValueError(f"moving_fraction must lie strictly between 0 and 1, got {moving_fraction!r}")
    if radius is None:
        radius = TRUNK_RADIUS_PER_HEIGHT * height
    elif not (_is_number(radius) and math.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be a positive number (metres), got {radius!r}")
    m = moving_fraction * body_mass
    M = body_mass - m
    return SleighParams(M=M, m=m, I=0.5 * M * radius * radius)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
