"""
Reading controls.csv in pandas
==============================

``skatetrace trace`` writes the controls as a CSV table, one row per sample: the mass position
``(a, b)`` and its rates, the blade's pose, the momenta and the body velocities. This tutorial
runs the command line's own writer into a temporary folder and reads the table with pandas.
"""

# %%
# Write the files, as ``skatetrace trace`` does
# ---------------------------------------------
# :func:`skatetrace.outputs.results.write_results` is the writer the command line uses: it writes
# ``result.json``, ``controls.csv`` and ``report.json`` and returns their paths.
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

import skatetrace as st
from skatetrace.outputs.results import write_results

done = st.trace_and_verify(st.pattern("s-bend"))
out = Path(tempfile.mkdtemp(prefix="skatetrace-tutorial-"))
written = write_results(out, done.trace, done.schedule, done.states, done.report,
                        feasibility=done.feasibility)
print("wrote", ", ".join(p.name for p in written))

# %%
# The table
# ---------
# Columns: ``piece`` (index of the piece within its curve), time ``t``, the mass position ``a``
# (along the blade) and ``b`` (to its left) with their rates ``adot``, ``bdot``, the contact point
# ``x, y`` and heading ``theta``, the momenta ``p1, p2``, the body velocities ``xi1`` (turning rate)
# and ``xi2`` (speed along the blade), and the row's ``curve`` and ``section`` (in skating order).
controls = pd.read_csv(out / "controls.csv")
print(controls.shape)
controls.head()

# %%
# A repeated time marks a jump: the rates jump at a smooth join, and the controls at a cusp. The
# table is dense enough that cubic Hermite interpolation of ``(a, b)`` with their rates reproduces
# the controls (to 1e-11 of their largest value).
jumps = controls[controls["t"].duplicated(keep=False)]
print(f"{len(controls)} rows, {len(jumps) // 2} jumps, duration {controls['t'].iloc[-1]:.3g}")

# %%
# Per piece: how long the blade spends on it, its top speed, and how far the mass goes.
controls["reach"] = (controls["a"] ** 2 + controls["b"] ** 2) ** 0.5
summary = controls.groupby("piece").agg(
    start=("t", "min"), end=("t", "max"), top_speed=("xi2", "max"), largest_reach=("reach", "max"))
summary["duration"] = summary["end"] - summary["start"]
summary

# %%
# Plot the controls and the speed from the table
# ----------------------------------------------
fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
controls.plot(x="t", y=["a", "b"], ax=top, xlabel="", ylabel="mass position (model length)")
controls.plot(x="t", y="xi2", ax=bottom, legend=False, xlabel="model time",
              ylabel="speed along the blade")
fig.tight_layout()
plt.show()

# %%
# The other files: ``result.json`` (the traced figure: sections, phases, residuals, metrics;
# read back with :func:`skatetrace.outputs.results.load_result`) and ``report.json`` (every
# verification and feasibility check). :func:`skatetrace.outputs.results.read_controls` reads the CSV
# into numpy arrays without pandas.
import json
import shutil

report = json.loads((out / "report.json").read_text())
print(report["verdict"])
shutil.rmtree(out)  # the tutorial's temporary folder, not left behind
