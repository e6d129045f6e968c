"""
A school figure for a given skater
==================================

The school figures (circle eight, serpentine, three, loop, ...) are built exactly from arcs,
sized for a skater: a circle is three heights across, a loop one blade wide. Everything is in SI
units: metres, seconds, kilograms. This tutorial traces the *loop* for a 1.60 m, 52 kg skater.
"""

# %%
# The skater and the figure
# -------------------------
# :func:`skatetrace.skater_params` turns a height and a body mass into the sleigh's parameters:
# the moving mass ``m`` stands for the arms, the free leg and the head (34 % of the body), the
# sleigh ``M`` for the rest, and ``I`` is the inertia of the trunk about the blade.
import matplotlib.pyplot as plt

import skatetrace as st

height, body_mass = 1.60, 52.0  # m, kg
params = st.skater_params(body_mass=body_mass, height=height)
print(f"M = {params.M:.1f} kg, m = {params.m:.1f} kg, I = {params.I:.3f} kg m^2")
print("school figures:", ", ".join(st.school_names()))

figure = st.school_figure("loop", height=height, params=params)
print(figure.name, "-", figure.extra["school"]["sequence"])

# %%
# Trace, verify, and ask whether a person could do it
# ---------------------------------------------------
# Figures in metres are skated at 2 m/s by default on the command line; here we say so through
# :class:`skatetrace.TraceOptions`. The feasibility limits are those of this skater
# (:meth:`skatetrace.HumanLimits.for_skater`).
options = st.TraceOptions(speed=2.0)
limits = st.HumanLimits.for_skater(height=height, body_mass=body_mass)
done = st.trace_and_verify(figure, params, options, limits=limits)

print(done.message)
print(f"largest deviation {done.report.max_deviation:.1e} m (tolerance {done.report.tolerance:.1e} m)")
print(done.verdict)
for check in done.feasibility.checks:
    print(("ok    " if check.passed else "BEYOND"), check.phrase())

# %%
# The blade's path and the mass's path
# ------------------------------------
# First the replayed blade path over the figure; then where the moving mass goes in the
# blade's frame (``a`` along the blade, ``b`` to its left), one colour per section.
from skatetrace.outputs.plotting import plot_figure, plot_mass_path

fig, ax = plt.subplots(figsize=(8, 4.5))
plot_figure(done.trace, done.report, ax=ax, unit="m")
fig, ax = plt.subplots(figsize=(8, 5))
plot_mass_path(done.trace, done.report, ax=ax, unit="m")
plt.show()

# %%
# Try another figure or skater: ``st.school_figure("three", height=1.75)`` (each traces in a few
# seconds), or the same from the command line:
# ``skatetrace trace school:loop --height 1.6 --body-mass 52 --out out/``.
