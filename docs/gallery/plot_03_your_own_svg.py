"""
Your own drawing (SVG)
======================

Any curve can be traced once it is turned into pieces the engine traces exactly: arcs and lines
(fitted within a certified distance of the drawing) or, in exact mode, curvature splines. This
tutorial writes a small SVG, reads it, fits it and traces it.
"""

# %%
# A drawing
# ---------
# An S-shaped stroke of two cubic Bézier curves, written to a temporary file (any SVG path, shape
# or group works; :func:`skatetrace.read_svg` also takes the SVG text directly).
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import skatetrace as st

SVG = """<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 12 8">
  <path id="s-curve" d="M 1 6 C 4 9, 6 6, 6 4 C 6 2, 8 -1, 11 2" fill="none" stroke="black"/>
</svg>"""

with tempfile.TemporaryDirectory(prefix="skatetrace-tutorial-") as folder:  # removed when read
    (Path(folder) / "s-curve.svg").write_text(SVG)
    drawing = st.load_drawing(Path(folder) / "s-curve.svg")
print(f"{drawing.name}: {len(drawing.paths)} path(s), {drawing.size():.3g} units across")

# %%
# Fit by arcs and lines
# ---------------------
# :func:`skatetrace.fit_drawing` splits the drawing at its corners and inflections and fits each
# smooth run by arcs and lines. ``hausdorff`` is a *certified* bound on the distance between the
# drawing and the fit, not a sampled estimate.
tol = 1e-3 * drawing.size()
fit = st.fit_drawing(drawing, tol)
print(fit.message)
print(f"{fit.n_arcs} arcs, {fit.n_lines} lines, distance to the drawing <= {fit.hausdorff:.2e} (tolerance {tol:.2e})")

from skatetrace.outputs.plotting import plot_fit

fig, ax = plt.subplots(figsize=(7, 5))
plot_fit(drawing, fit, ax=ax)

# %%
# Trace the fitted figure
# -----------------------
# :func:`skatetrace.figure_from_fit` turns the fit into a figure (one curve per path, starting and
# ending at rest). Tracing it is the same call as for a built-in figure.
figure = st.figure_from_fit(fit, name="s-curve")
done = st.trace_and_verify(figure)
print(done.message)
print(f"largest deviation from the fitted pieces {done.report.max_deviation:.1e}; "
      f"from the drawing at most {fit.hausdorff + done.report.max_deviation:.1e}")

from skatetrace.outputs.plotting import plot_figure

fig, ax = plt.subplots(figsize=(7, 5))
plot_figure(done.trace, done.report, ax=ax)
plt.show()

# %%
# The command line does the same with ``skatetrace trace my-drawing.svg --size 6m --tol 1mm``
# (``--size`` scales the drawing to metres, ``--exact`` traces curvature splines instead of arcs).
# The repository's ``examples/`` folder has more drawings: ``three-turn.svg``,
# ``figure-eight.svg``, ``serpentine.svg`` and a point list, ``points-eight.csv``.
