"""The paper's own procedures, reproduced faithfully as documented baselines.

Rhodes & Putkaradze, "Trajectory tracing in figure skating" (``shared/reference``):

- :mod:`~skatetrace.paper.tables`: Tables 1-6 as data (:func:`paper_rows`);
- :mod:`~skatetrace.paper.controls`: the two control families and eq. (b_diff_eq) as printed;
- :mod:`~skatetrace.paper.reduced`: the model reduced to circular arcs, integrated forward and
  backward until the speed vanishes (readings of the ambiguous parts are options);
- :mod:`~skatetrace.paper.procedure`: the BFGS optimisation with BDF inside, from the printed guesses;
- :mod:`~skatetrace.paper.evaluate`: accurate evaluation and full-dynamics re-simulation of any
  parameter set, and the exact engine on the same arc;
- :mod:`~skatetrace.paper.report`: ``skatetrace reproduce``, the side-by-side report and errata;
- :mod:`~skatetrace.paper.figures`: every kind of figure the paper shows.
"""

from .controls import CircularControl, HarmonicControl, b_rate_printed, control_from_params
from .evaluate import ArcEvaluation, evaluate_exact_arc, evaluate_paper_arc, full_replay, singular_distances
from .procedure import ProcedureResult, paper_cost, run_procedure
from .reduced import PAPER_SOLVER, TIGHT_SOLVER, HalfArc, ReducedArc, ReducedOptions, integrate_reduced
from .tables import METHODS, PaperRow, paper_row, paper_rows

__all__ = [
    "ArcEvaluation", "CircularControl", "HalfArc", "HarmonicControl", "METHODS", "PAPER_SOLVER", "PaperRow",
    "ProcedureResult", "ReducedArc", "ReducedOptions", "TIGHT_SOLVER", "b_rate_printed", "control_from_params",
    "evaluate_exact_arc", "evaluate_paper_arc", "full_replay", "integrate_reduced", "paper_cost", "paper_row",
    "paper_rows", "run_procedure", "singular_distances",
]
