"""
Reproducing the paper
=====================

Rhodes & Putkaradze optimise the mass motion of each arc of the double flower with two prescribed
controls, ``a = A cos(wt)`` and ``b = A sin(wt)``, and publish the optimum ``(A*, w*)`` with its
error. :mod:`skatetrace.paper` reproduces their procedures faithfully, then measures any result
with the same yardsticks as the exact engine: above all, does the **full** model, re-simulated
under the same mass motion, stay on the arc? This tutorial does it for arc 1 (Tables 1-2, radius
1.2); ``skatetrace reproduce`` does it for every arc and table, re-runs the optimisation itself,
and writes a report with the errata (a few minutes).
"""

# %%
# The table row, as printed
# -------------------------
# :func:`skatetrace.paper.paper_row` holds the numbers of the LaTeX source with the digits they
# are printed with.
import matplotlib.pyplot as plt

from skatetrace.paper import evaluate_exact_arc, evaluate_paper_arc, paper_row

row = paper_row("main", 1)
print(f"arc {row.arc} (Tables {row.tables}): radius {row.radius}, target length {row.target_length:.4f}")
print(f"published optimum (A*, w*) = {row.published}, published error {row.published_error:g}")

# %%
# The published optimum, evaluated
# --------------------------------
# :func:`~skatetrace.paper.evaluate_paper_arc` integrates the paper's reduced model accurately
# from the table's initial condition, then re-simulates the full five equations under the same
# mass motion and measures how far the blade leaves the circle.
published = evaluate_paper_arc(row, row.published, "published")
print(f"reduced model: length error {published.length_error:+.3g}")
print(f"full dynamics: largest distance from the circle {published.full_deviation:.3g}, "
      f"end speeds {', '.join(f'{v:.3g}' for v in published.full_end_speeds)}")
print("the arc is what it claims:", published.ok)

# %%
# The exact engine on the same arc
# --------------------------------
# :func:`~skatetrace.paper.evaluate_exact_arc` traces the same circle, same length, from rest to
# rest, with one control rate left free and the other fixed by the curvature condition, and
# verifies it by its independent replay.
exact = evaluate_exact_arc(row)
print(f"full dynamics: largest distance from the circle {exact.full_deviation:.1e}, "
      f"end speeds {', '.join(f'{v:.1e}' for v in exact.full_end_speeds)}")
print("the arc is what it claims:", exact.ok)

# %%
# Side by side, as the paper draws them
# -------------------------------------
# :func:`skatetrace.paper.figures.plot_arc` draws the paper's figure for an arc: the trajectory
# (the full-dynamics re-simulation dashed red over the model's path), the speed along the blade
# ``xi2(t)`` and the controls ``a(t)``, ``b(t)``. With two prescribed controls nothing enforces
# the curvature condition, and the full model drifts off the circle; the exact engine's replay
# stays on it.
from skatetrace.paper.figures import plot_arc

plot_arc(row, published, fig=plt.figure(figsize=(9, 6)))
plot_arc(row, exact, fig=plt.figure(figsize=(9, 6)))
plt.show()

# %%
# The whole reproduction, every arc and all six tables, with the re-run optimisations, the
# conditioning of every number and the errata: ``skatetrace reproduce --out rep/`` (it writes
# ``report.md``, ``report.html``, ``reproduction.json`` and the figures).
