"""Benchmark: bounded-reach planning of the school figures for a 1.7 m skater, against today's manoeuvres.

Run: python bench/bench_planning.py [NAME ...] [--reach R] [--markdown]
     (default: all seventeen school figures at R = 0.5 m; "paper-arc" is the paper's first arc,
     r = 1.2 over 198 degrees, in model units at reach 1)

Per figure, with the launch-glide-stop manoeuvres (``before``) and planned within the reach
(``after``), both replayed and assessed from their exported rows: the mass's largest distance from
the blade, the largest jump of its position on the ice at a cusp, the peak force on it, its speed
relative to the stopped blade at the cusps, the largest impulse there, the effort (the integral of
the squared force), the figure's duration, the largest Newton residual, the replay's deviation
against its tolerance, both verdicts, and the planning time as a multiple of the double flower's
warm trace-and-verify in the same run. ``--markdown`` prints the table of the README and the
guide. Nothing is asserted about time.
"""

from __future__ import annotations

import argparse
import time

import skatetrace as st
from skatetrace.figures.figure import figure_from_dict
from skatetrace.verification.feasibility import HumanLimits

PAPER_ARC = {"schema": "skatetrace.figure/1", "name": "paper arc 1", "params": {"M": 2, "m": 1, "I": 3},
             "curves": [{"pieces": [{"type": "arc", "radius": 1.2, "sweep_deg": 198}]}]}


def _case(name: str, reach: float):
    if name == "paper-arc":
        return figure_from_dict(PAPER_ARC), st.PAPER_PARAMS, 1.0, 1.0, None
    fig = st.school_figure(name, height=1.7)
    return fig, fig.params, 2.0, reach, HumanLimits.for_skater(1.7, 60.0)


def _baseline() -> float:
    """The double flower's warm trace-and-verify, in s (the unit of the time column)."""
    fig = st.pattern("double-flower")
    st.trace_and_verify(fig, st.PAPER_PARAMS)  # warm the compiled code
    t0 = time.perf_counter()
    st.trace_and_verify(fig, st.PAPER_PARAMS)
    return time.perf_counter() - t0


def measure(name: str, reach: float) -> dict:
    """Today's manoeuvres and the plan within ``reach`` for one figure, as one row."""
    fig, params, speed, reach, limits = _case(name, reach)
    before = st.trace_and_verify(fig, params, st.TraceOptions(speed=speed), limits=limits)
    t0 = time.perf_counter()
    after = st.trace_and_verify(fig, params, st.TraceOptions(speed=speed, reach=reach), limits=limits)
    seconds = time.perf_counter() - t0
    c0 = {c.name: c.value for c in before.feasibility.checks}
    c1 = {c.name: c.value for c in after.feasibility.checks}
    i0, i1 = before.feasibility.info, after.feasibility.info
    return {
        "figure": name, "reach": reach, "seconds": seconds,
        "reach_before": c0["reach"], "reach_after": c1["reach"],
        "jump_before": c0["cusp_jump"], "jump_after": c1["cusp_jump"],
        "force_before": i0["peak_force_on_mass"], "force_after": i1["peak_force_on_mass"],
        "accel_after": c1["mass_acceleration"],
        "cusp_mass_speed": i1["max_cusp_mass_speed"], "cusp_impulse": i1["max_cusp_impulse"],
        "effort_before": i0["effort"], "effort_after": i1["effort"],
        "duration_before": sum(s.duration for s in before.trace.sections if s.phases),
        "duration_after": sum(s.duration for s in after.trace.sections if s.phases),
        "residual": max((max(s.residuals.values()) for s in after.trace.sections if s.residuals), default=float("nan")),
        "deviation": after.report.max_deviation, "tolerance": after.report.tolerance,
        # the replay's largest speed at a cusp as a fraction of its section's fastest motion (verdict: 1e-8)
        "cusp_rest": max((max(s["start_speed"], s["end_speed"]) / s["speed_scale"] for s in after.report.sections
                          if s.get("traced")), default=0.0),
        "verified": bool(after.success), "feasible": bool(after.feasibility.feasible),
        "verdict": after.verdict, "message": after.message,
    }


def _verified(r: dict) -> str:
    """The replay's verdict in a few words: yes, or no and why."""
    if r["verified"]:
        return "yes"
    if r["deviation"] > r["tolerance"]:
        return f"no: the replay strays {r['deviation'] / r['tolerance']:.2g} x its tolerance"
    if r["cusp_rest"] > 1e-8:
        return f"no: the replay at a cusp moves at {r['cusp_rest']:.2g} of its fastest motion (limit 1e-8)"
    return f"no: {r['message'][:60]}"


def markdown(rows: list[dict]) -> str:
    """The table of the README and the guide."""
    head = ("| figure | reach before → after (m) | cusp jump before → after (m) | peak force (N) | peak accel (m/s²) "
            "| cusp mass speed (m/s) "
            "| cusp impulse (N s) | duration (s) | residual | verified | plan time (× flower) |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        if not r["duration_after"] > 0:  # nothing planned: no motion to measure
            lines.append(f"| {r['figure']} | {r['reach_before']:.3g} → – | {r['jump_before']:.3g} → – | – | – | – | – | – | – "
                         f"| no: {r['message'][:60]} | {r['ratio']:.0f} |")
            continue
        lines.append(
            f"| {r['figure']} | {r['reach_before']:.3g} → {r['reach_after']:.3g} | {r['jump_before']:.3g} → "
            f"{r['jump_after']:.1g} | {r['force_after']:.3g} | {r['accel_after']:.3g} | {r['cusp_mass_speed']:.3g} | "
            f"{r['cusp_impulse']:.3g} | {r['duration_after']:.1f} | {r['residual']:.0e} | {_verified(r)} | "
            f"{r['ratio']:.0f} |")
    return "\n".join(lines)


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--reach", type=float, default=0.5)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    names = args.names or st.school_names()
    base = _baseline()
    print(f"double flower warm trace-and-verify: {base:.3f} s (the unit of 'x flower')")
    print(f"{'figure':24s} {'x flower':>8s} {'s':>6s} {'reach':>13s} {'jump':>17s} {'force':>13s} {'cusp v':>7s} "
          f"{'impulse':>8s} {'effort':>19s} {'residual':>8s} {'deviation/tol':>13s} verdict")
    rows = []
    for name in names:
        row = measure(name, args.reach)
        row["ratio"] = row["seconds"] / base
        rows.append(row)
        print(f"{name:24s} {row['ratio']:8.0f} {row['seconds']:6.1f} {row['reach_before']:6.3g}>{row['reach_after']:<6.3g} "
              f"{row['jump_before']:8.2g}>{row['jump_after']:<8.1g} {row['force_before']:6.3g}>{row['force_after']:<6.3g} "
              f"{row['cusp_mass_speed']:7.3g} {row['cusp_impulse']:8.3g} {row['effort_before']:9.3g}>{row['effort_after']:<9.3g} "
              f"{row['residual']:8.0e} {row['deviation'] / row['tolerance']:13.2g} {row['verdict']}", flush=True)
    if args.markdown:
        print(markdown(rows))
    return rows


if __name__ == "__main__":
    main()
