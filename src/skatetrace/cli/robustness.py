"""The ``skatetrace robustness`` command: a traced figure replayed on perturbed sleighs, open loop against closed loop.

It reads the output folder of ``skatetrace trace`` (:func:`~skatetrace.outputs.traced.load_traced`),
designs the tracking law of each section (:func:`~skatetrace.feedback.robustness.lqr_laws`), runs
the study (:func:`~skatetrace.feedback.robustness.robustness`), prints a table and writes
``robustness.json`` and ``robustness.png`` into the folder. Exit codes: 0 the study ran (whatever
the numbers), 1 it could not run as asked (no traced section, or a law that could not be
designed: the files are still written), 2 a usage error.
"""

from __future__ import annotations

import math
import time

from ..errors import SkatetraceError
from ..feedback.lqr import ROBUST_RATE_WEIGHT, robust_gains
from .values import angle, duration, fraction, length_or_zero

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The ``robustness`` subcommand and its options, on the subparsers ``sub``."""
    r = sub.add_parser("robustness", help="replay a traced figure on perturbed sleighs (parameter error, start error, "
                                          "delay, noise) in open and closed loop: how far the blade strays")
    r.add_argument("source", help="the output folder of 'skatetrace trace' (or its result.json); robustness.json "
                                  "and robustness.png are written there")
    r.add_argument("--param-error", default="5%",
                   help="each of M, m, I multiplied by its own 1 + U(-e, e): e as 5%% or 0.05 (default 5%%; "
                        "below 100%%)")
    r.add_argument("--initial-error",
                   help="LENGTH,ANGLE: each curve starts this far off (random direction; m, cm, mm, or a plain number "
                        "in the figure's units) and its heading this much off either way (deg or rad); default "
                        "1mm,0.5deg for figures in metres, 1e-4 of the figure's size and 0.5deg in model units")
    r.add_argument("--delay", help="age of the state the controller sees: 10ms, 0.01s or 0.01 (the figure's time "
                                   "unit); default 10ms, 0.01 in model units")
    r.add_argument("--noise", default="0", help="standard deviation of the measured position, a length as for "
                                                "--initial-error (default 0)")
    r.add_argument("--trials", type=int, default=32, help="number of perturbed sleighs (default 32, at most 10000)")
    r.add_argument("--seed", type=int, default=0, help="seed of the perturbations: the same seed, the same sleighs "
                                                       "(default 0)")
    r.add_argument("--steps", type=int, default=4000,
                   help="Runge-Kutta steps per section (default 4000; more where the delay asks for them)")
    r.add_argument("--rate-weight", type=float, default=ROBUST_RATE_WEIGHT,
                   help="cost of the mass rates in the tracking law, relative to Bryson's rule (default "
                        f"{ROBUST_RATE_WEIGHT:g}: a slow law that a model error does not destabilise; the verification's "
                        "law uses 100)")
    r.add_argument("--no-plots", action="store_true", help="skip robustness.png")


def _perturbation(args, traced):
    """The options as a Perturbation, the issue's scenario where they are not given."""
    from ..feedback.robustness import default_perturbation

    unit = traced.unit
    changes = dict(param_error=fraction(args.param_error, "--param-error"),
                   noise=length_or_zero(args.noise, unit, "--noise"), trials=args.trials, seed=args.seed)
    if args.initial_error is not None:
        parts = args.initial_error.split(",")
        if len(parts) != 2:
            raise SkatetraceError(f"--initial-error must be LENGTH,ANGLE, e.g. 1mm,0.5deg (or 0,0 for none), got "
                                  f"{args.initial_error!r}")
        changes.update(position_error=length_or_zero(parts[0], unit, "--initial-error"),
                       angle_error=angle(parts[1], "--initial-error"))
    if args.delay is not None:
        changes["delay"] = duration(args.delay, unit, "--delay")
    return default_perturbation(traced.size, unit, **changes)  # a bad --trials or --seed: ValueError, exit 2


def _text(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else "inf"


def _describe(p, unit: str) -> str:
    length, time_unit = ("m", "s") if unit == "m" else ("model units", "time units")
    return (f"{p.trials} trials (seed {p.seed}): M, m, I each within ±{100 * p.param_error:.3g} %; each curve "
            f"starts {p.position_error:.3g} {length} off, heading ±{math.degrees(p.angle_error):.3g}°; "
            f"delay {p.delay:.3g} {time_unit}; position noise {p.noise:.3g} {length}")


def _trace_verdict(folder) -> str:
    """Both verdicts of the trace in ``folder`` (verified, humanly feasible), from its ``report.json``."""
    import json

    try:
        verdict = json.loads((folder / "report.json").read_text(encoding="utf-8")).get("verdict")
    except (OSError, ValueError, AttributeError):
        verdict = None
    return verdict if isinstance(verdict, str) else "no verdict (report.json missing or unreadable)"


def _table(report, unit: str) -> list[str]:
    from ..feedback.robustness import quantiles

    length, speed = ("m", "m/s") if unit == "m" else ("model length", "model length/time")
    lines = [f"largest deviation of each trial's blade from the figure ({length}), over the trials; blade speed "
             f"at the rests ({speed})",
             f"{'':12} {'p50':>9} {'p95':>9} {'max':>9} {'p95/size':>9} {'max/size':>9} {'diverged':>9} "
             f"{'cusp speed':>11} {'mass reach':>11}"]
    for name, fam in (("open loop", report.open_loop), ("closed loop", report.closed_loop)):
        dev = quantiles(fam.deviation)
        cells = [dev["p50"], dev["p95"], dev["max"], dev["p95"] / report.figure_size, dev["max"] / report.figure_size]
        lines.append(f"{name:12} {' '.join(f'{_text(v):>9}' for v in cells)} {f'{fam.diverged}/{fam.trials}':>9} "
                     f"{_text(quantiles(fam.cusp_speed)['max']):>11} {_text(quantiles(fam.mass_reach)['max']):>11}")
    lines.append(f"mass reach: the moving mass's largest distance from the blade ({length}), what a skater would "
                 "have to reach in that loop")
    return lines


def _write(report, traced, laws, gains, plots: bool) -> list[str]:
    from ..feedback.export import laws_to_dict
    from ..outputs.files import atomic_write, dumps_json, write_atomically
    from ..outputs.folder import adopt

    data = {**report.to_dict(), "figure": traced.name, "unit": traced.unit}
    path = traced.folder / "robustness.json"
    atomic_write(path, dumps_json(data))
    written = [path]
    path = traced.folder / "feedback.json"
    atomic_write(path, dumps_json(laws_to_dict(laws, traced.params, gains, traced.start_times), indent=None))
    written.append(path)
    if plots:
        from ..outputs.plotting import robustness_figure

        fig = robustness_figure(report, traced.sections, name=traced.name, unit=traced.unit)
        path = traced.folder / "robustness.png"
        write_atomically(path, lambda tmp: fig.savefig(tmp, format="png", dpi=110))
        written.append(path)
    for p in written:
        adopt(p)  # the study is of the run in the folder: the next run there replaces or removes it
    return [p.name for p in written]


def run(args) -> int:
    """Run ``skatetrace robustness``; returns the exit code."""
    from ..feedback.robustness import MAX_STEPS, lqr_laws, robustness
    from ..outputs.folder import check_finished, check_output_file
    from ..outputs.traced import load_traced
    from .commands import _progress_bar  # already loaded: this command runs from it

    t0 = time.perf_counter()
    check_finished(args.source)
    traced = load_traced(args.source)
    perturbation = _perturbation(args, traced)
    if not (math.isfinite(args.rate_weight) and args.rate_weight > 0):
        raise SkatetraceError(f"--rate-weight must be a positive finite number, got {args.rate_weight}")
    if not 1 <= args.steps <= MAX_STEPS:
        raise SkatetraceError(f"--steps must be a whole number from 1 to {MAX_STEPS}, got {args.steps}")
    check_output_file(traced.folder / "robustness.json", label="robustness", suffixes=(".json",),
                      create_parent=False)
    print(f"robustness of {traced.name}: {traced.traced} of {len(traced.sections)} section(s) traced, figure "
          f"{traced.size:.4g} {'m' if traced.unit == 'm' else 'model units'} across")
    print(f"the trace studied: {_trace_verdict(traced.folder)}")
    print(f"perturbation: {_describe(perturbation, traced.unit)}")
    t1 = time.perf_counter()
    laws, law = lqr_laws(traced.references, traced.params, traced.size, args.rate_weight)
    designed = time.perf_counter() - t1
    print(f"law: {law['name']} ({law['about']}), designed in {designed:.1f} s; {args.steps} Runge-Kutta steps per "
          "section")
    report = robustness(traced.references, traced.sections, traced.params, laws, perturbation, size=traced.size,
                        steps=args.steps, law=law, progress=_progress_bar("replaying open, then closed loop"))
    if report.replayed == 0:
        print(f"nothing written: {report.message}")
        return 1
    for line in _table(report, traced.unit):
        print(line)
    print("(inf: the statistic reaches a trial whose replay diverged)")
    if not report.success:
        print(f"note: {report.message}")
    names = _write(report, traced, laws, robust_gains(traced.size, args.rate_weight), not args.no_plots)
    print(f"{report.status.name.lower().replace('_', ' ')}: open loop {report.open_loop.seconds:.1f} s, closed loop "
          f"{report.closed_loop.seconds:.1f} s; wrote {', '.join(names)} to {traced.folder}/ in "
          f"{time.perf_counter() - t0:.1f} s")
    return 0 if report.success else 1
