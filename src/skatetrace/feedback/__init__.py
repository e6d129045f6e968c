"""Feedback: a tracking law that holds the blade on the figure, and replays of it under perturbations."""

from .closed_loop import LoopRun, Plant, loop_sections, run_loop
from .lqr import TrackingGains, TrackingLaw, default_gains, design, robust_gains
from .reference import Reference, references
from .robustness import Perturbation, RobustnessReport

# ``robustness`` (the study) is not re-exported: the name stays the submodule's
__all__ = ["LoopRun", "Perturbation", "Plant", "Reference", "RobustnessReport", "TrackingGains", "TrackingLaw",
           "default_gains", "design", "loop_sections", "references", "robust_gains", "run_loop"]
