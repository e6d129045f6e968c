"""Feedback: a tracking law that holds the blade on the figure, and replays of it under perturbations."""

from .closed_loop import LoopRun, Plant, run_loop
from .lqr import TrackingGains, TrackingLaw, default_gains, design
from .reference import Reference, references

__all__ = ["LoopRun", "Plant", "Reference", "TrackingGains", "TrackingLaw", "default_gains", "design",
           "references", "run_loop"]
