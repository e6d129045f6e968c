"""skatetrace: how must a skater move their centre of mass so that the blade traces a figure?

The public API, re-exported explicitly. Names are imported from their modules on first use
(PEP 562), so that ``import skatetrace`` (and the command line) does not pay for the readers of
SVG files and the fitting code when a run needs neither. ``simulate`` and ``verify`` are functions
named like their modules; they are bound at import so that the name always means the function.
"""

from importlib import import_module

from .dynamics.simulate import Controller, Trajectory, simulate  # noqa: F401 (re-exported)
from .verification.verify import VerificationReport, schedule_from_trace, verify  # noqa: F401 (re-exported)

_EXPORTS = {
    "drawings.curves": ("Drawing", "Path"),
    "verification.deviation": ("DeviationCost", "deviation_cost", "segments_target"),
    "errors": ("DrawingError", "FigureFormatError", "FitError", "InfeasibleArcError", "SkatetraceError"),
    "drawings.exact": ("fit_exact_drawing", "fit_exact_path"),
    "drawings.exact_figure": ("figure_from_exact",),
    "drawings.exact_results": ("ExactDrawingFit", "ExactPathFit"),
    "verification.feasibility": ("Feasibility", "HumanLimits", "assess_feasibility"),
    "figures.figure": ("Curve", "Figure", "Join", "figure_from_dict", "load_figure"),
    "drawings.fitting": ("fit_drawing", "fit_path"),
    "drawings.fit_results": ("DrawingFit", "PathFit"),
    "drawings.to_figure": ("figure_from_fit",),
    "figures.geometry": ("Pose", "Segment", "Spiral"),
    "drawings.functions": ("from_function",),
    "drawings.load": ("load_drawing",),
    "drawings.lengths": ("parse_length",),
    "drawings.points": ("read_points",),
    "drawings.svg": ("read_svg",),
    "dynamics.model": ("SleighParams",),
    "figures.patterns": ("pattern", "pattern_names"),
    "dynamics.presets": ("PAPER_PARAMS", "skater_params"),
    "pipeline": ("DefaultReachTrace", "VerifiedTrace", "add_rests", "trace_and_verify", "trace_within_default_reach"),
    "planning.planner": ("plan_figure",),
    "figures.school": ("school_figure", "school_names"),
    "drawings.sources": ("Resolved", "resolve"),
    "tracing.sections": ("FigureTrace", "SectionTrace", "TraceOptions", "TraceStatus", "trace_figure", "trace_section"),
}
_MODULE_OF = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = sorted([*_MODULE_OF, "Controller", "Trajectory", "simulate", "VerificationReport", "schedule_from_trace", "verify"])
__version__ = "0.1.0"


def __getattr__(name: str):
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'skatetrace' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value  # the next lookup is an ordinary attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
