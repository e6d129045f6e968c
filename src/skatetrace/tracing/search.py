"""The search over a section's glide placements: solved in order, the one whose mass stays nearest kept.

:func:`~skatetrace.tracing.sections.trace_section` hands :func:`search_placements` its placements
(:mod:`~skatetrace.tracing.placements`) in order and a function that traces the section with the
glide at one of them. The first placement that works and up to ``TraceOptions.search`` after it
are compared by their reach (the largest ``|a|, |b|`` of the mass), then by the mass's peak
kinetic energy. A placement sure to reach farther than the best so far is not solved (its apex
alone reaches farther), or not launched (its stop alone does: :class:`Attempt`). A long search
runs in batches side by side (:func:`~skatetrace.processes.evaluated_ahead`) with the same answer,
and the same integrations counted, as one after another.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, NamedTuple

from ..processes import evaluated_ahead

__all__ = ["Attempt", "Searched", "search_placements"]

if TYPE_CHECKING:  # pragma: no cover - for the annotations only (sections imports this module)
    from .sections import SectionTrace, TraceOptions


class Attempt(NamedTuple):
    """A placement solved by the ``solve`` of :func:`search_placements`.

    ``trace`` is the section traced with the glide there, or None where its stop alone reaches
    farther than the ``bound`` it was solved with (see :func:`outreaches`): the launch was not
    solved, since the section cannot win. ``nfev`` counts the integrations of the whole attempt,
    ``deferred`` says whether it failed for want of the stops' full-accuracy fallbacks;
    ``stop_reach`` and ``stop_nfev`` are the stop's reach (the largest ``|a|, |b|`` where the
    section's peaks are looked for) and its integrations, where the stop was found (``stop_reach``
    NaN where it was not).
    """

    trace: SectionTrace | None
    nfev: int
    deferred: bool = False
    stop_reach: float = math.nan
    stop_nfev: int = 0


@dataclass(frozen=True, slots=True)
class Searched:
    """Where a search of glide placements ended (:func:`search_placements`).

    ``best`` is the placement kept (None if none worked), ``first_failure`` the first that failed,
    ``deferred`` whether any failed for want of the stops' fallbacks, and ``settled`` the failures
    that did not (by their index in the order of the search, without their controls), which a
    search with the fallbacks would find again.
    """

    best: SectionTrace | None
    first_failure: SectionTrace | None
    attempts: int
    nfev: int
    deferred: bool
    settled: dict[int, SectionTrace]


def search_placements(placements: Iterator, solve: Callable[..., Attempt], options: TraceOptions,
                      settled: dict[int, SectionTrace]) -> Searched:
    """Solve ``placements`` in order until the search has its answer, and say what it found.

    The first placement that works and up to ``options.search`` tried after it are compared (the
    first alone with ``options.placement="first"``); at most ``options.max_placements`` are tried
    while none works. ``solve(placement, bound)`` gives an :class:`Attempt`; ``bound`` is the
    reach of the best placement so far (infinite before one works), beyond which the attempt may
    stop after its stop. The placements whose index is in ``settled`` are taken from it instead
    (their integrations counted where they were solved).

    An attempt solved in a batch side by side was given the bound known when the batch began. Where
    its stop reaches farther than the best found since, it is counted as one after another would
    have solved it, its stop alone: the search and its integrations do not depend on the batches.
    """
    nfev = attempts = extra = 0
    first_failure = best = None
    deferred = False
    failed: dict[int, SectionTrace] = {}

    def wanted(item) -> bool:
        """Whether the search below would solve ``item`` if it came next (it only ever wants fewer)."""
        if best is None:
            return attempts < options.max_placements
        return extra < options.search and not _cannot_win(item[1][4], best[0])

    def solved(item) -> Attempt:
        index, placement = item
        return Attempt(settled[index], 0) if index in settled else solve(placement, _bound(best))

    # The placements are solved in order; a long search (a section of a hundred pieces may try a
    # hundred placements before one works) goes on in batches side by side, the same answers.
    for (index, placement), done in evaluated_ahead(solved, enumerate(placements), wanted, workers=options.workers):
        if best is None and attempts >= options.max_placements:
            break
        if best is not None:
            if extra >= options.search:
                break
            extra += 1
            if _cannot_win(placement[4], best[0]):
                continue  # counted as tried: the same placements are searched as without the shortcut
        attempt, used, skipped, stop_reach, stop_nfev = done
        attempts += 1
        if best is not None and outreaches(stop_reach, _bound(best)):
            nfev += stop_nfev  # one after another, the launch would not have been solved
            continue
        if attempt is None:  # pragma: no cover - solve stops short only beyond the bound it was given
            raise RuntimeError(f"a placement was given up at a reach of {stop_reach!r}, within the best's")
        nfev += used
        if not attempt.success:
            first_failure = first_failure or attempt
            deferred = deferred or skipped
            if not skipped:  # kept without its controls (a failure is reported by its reason alone)
                failed[index] = replace(attempt, phases=())
        elif options.placement == "first":
            best = ((), attempt)
            break
        else:
            key = (_reach(attempt), attempt.metrics["peak_mass_kinetic_energy"])
            if best is None or _improves(key, best[0]):
                best = (key, attempt)
    return Searched(best=None if best is None else best[1], first_failure=first_failure, attempts=attempts,
                    nfev=nfev, deferred=deferred, settled=failed)


# Placement keys this close (relative) are a tie, kept by the first placement: mirror-image
# placements (a section symmetric under b -> -b, or two equal segments) have the same key but for
# the rounding of their solves.
_KEY_TIE = 1e-12


def _improves(key: tuple[float, float], best: tuple[float, float]) -> bool:
    """Whether placement ``key`` (reach, peak kinetic energy) beats ``best``: less reach, then less energy."""
    for new, old in zip(key, best):
        if abs(new - old) > _KEY_TIE * max(abs(old), abs(new)):
            return new < old
    return False


def _bound(best) -> float:
    """The reach of the best placement so far (``(key, trace)`` or None), infinite before one works."""
    return math.inf if best is None else best[0][0]


def outreaches(reach: float, bound: float) -> bool:
    """Whether a section whose mass reaches ``reach`` somewhere is sure to reach farther than ``bound``, the best's.

    ``reach`` is the largest ``|a|, |b|`` at some of the states where the section's peaks are
    looked for; the margin covers the rounding of those states' times (see :func:`_cannot_win`).
    False for a NaN ``reach``.
    """
    return reach > bound * (1.0 + 1e-9)


def _cannot_win(glide_ab: tuple[float, float], best_key: tuple[float, float]) -> bool:
    """Whether a placement with its apex at ``glide_ab`` is sure to reach farther than the best so far.

    The apex is a sampled state of every trace through it (a phase boundary), so the reach of such
    a trace is at least ``max(|a|, |b|)`` there. The margin covers the rounding of section times
    when the apex is evaluated; a placement within it is solved, never skipped.
    """
    return outreaches(max(abs(glide_ab[0]), abs(glide_ab[1])), best_key[0])


def _reach(trace: SectionTrace) -> float:
    """Largest distance of the mass from the contact point along the blade or across it."""
    return max(trace.metrics["max_abs_a"], trace.metrics["max_abs_b"])
