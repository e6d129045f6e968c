"""skatetrace: how must a skater move their centre of mass so that the blade traces a figure?

The public API, re-exported explicitly.
"""

from .curves import Drawing, Path
from .deviation import DeviationCost, deviation_cost, segments_target
from .exact import ExactDrawingFit, ExactPathFit, figure_from_exact, fit_exact_drawing, fit_exact_path
from .errors import DrawingError, FigureFormatError, FitError, InfeasibleArcError, SkatetraceError
from .figure import Curve, Figure, Join, figure_from_dict, load_figure
from .fitting import DrawingFit, PathFit, figure_from_fit, fit_drawing, fit_path
from .inputs import from_function, load_drawing, parse_length, read_points, read_svg
from .geometry import Pose, Segment, Spiral
from .model import SleighParams
from .patterns import pattern, pattern_names
from .presets import PAPER_PARAMS, skater_params
from .rests import VerifiedTrace, add_rests, trace_and_verify
from .school import school_figure, school_names
from .simulate import Trajectory, simulate
from .sources import Resolved, resolve
from .tracing import FigureTrace, SectionTrace, TraceOptions, TraceStatus, trace_figure, trace_section
from .verify import VerificationReport, schedule_from_trace, verify

__all__ = [
    "Curve", "DeviationCost", "Figure", "FigureFormatError", "FigureTrace", "InfeasibleArcError", "Join", "Pose",
    "SectionTrace", "Segment", "SkatetraceError", "SleighParams", "TraceOptions", "TraceStatus",
    "VerificationReport", "figure_from_dict", "load_figure", "pattern", "pattern_names",
    "Drawing", "DrawingError", "DrawingFit", "FitError", "PAPER_PARAMS", "Path", "PathFit", "Resolved",
    "figure_from_fit", "fit_drawing", "fit_path", "from_function", "load_drawing", "parse_length", "read_points",
    "read_svg", "resolve", "school_figure", "school_names", "skater_params",
    "Trajectory", "deviation_cost", "schedule_from_trace", "segments_target", "simulate", "trace_figure", "trace_section", "verify",
    "VerifiedTrace", "add_rests", "trace_and_verify",
    "Spiral", "ExactDrawingFit", "ExactPathFit", "figure_from_exact", "fit_exact_drawing", "fit_exact_path",
]
__version__ = "0.1.0"
