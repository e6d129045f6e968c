"""skatetrace: how must a skater move their centre of mass so that the blade traces a figure?

The public API, re-exported explicitly.
"""

from .deviation import DeviationCost, deviation_cost, segments_target
from .errors import FigureFormatError, InfeasibleArcError, SkatetraceError
from .figure import Curve, Figure, Join, figure_from_dict, load_figure
from .geometry import Pose, Segment
from .model import SleighParams
from .patterns import pattern, pattern_names
from .simulate import Trajectory, simulate
from .tracing import FigureTrace, SectionTrace, TraceOptions, TraceStatus, trace_figure, trace_section
from .verify import VerificationReport, schedule_from_trace, verify

__all__ = [
    "Curve", "DeviationCost", "Figure", "FigureFormatError", "FigureTrace", "InfeasibleArcError", "Join", "Pose",
    "SectionTrace", "Segment", "SkatetraceError", "SleighParams", "TraceOptions", "TraceStatus",
    "VerificationReport", "figure_from_dict", "load_figure", "pattern", "pattern_names",
    "Trajectory", "deviation_cost", "schedule_from_trace", "segments_target", "simulate", "trace_figure", "trace_section", "verify",
]
__version__ = "0.1.0"
