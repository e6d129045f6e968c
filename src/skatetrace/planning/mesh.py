"""Mesh refinement of the planning program: where the collocation misses the dynamics, split the interval.

The error of an interval is measured against the compiled integrator: from the planned state at
its start, under the planned control (``u`` linear across the interval), how far is the state at
its end from the planned one, relative to the reach (for ``a, b``), the momenta's scale and the
section's length. Intervals above the tolerance are split into as many pieces as the defect's
fifth-order fall asks for (at most four; the new nodes' guesses interpolate the old interval,
exact for ``u``), and the program is solved again from that guess.
"""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.integrator import integrate_legs
from ..dynamics.model import SleighParams
from .collocation import ProgramSolution, SectionSpec
from .finish import _legs_from, _pieces

__all__ = ["interval_errors", "refined"]

#: At most this many pieces out of one interval per round.
_MAX_PARTS = 4


def interval_errors(sol: ProgramSolution, specs: list[SectionSpec], M: float, m: float, I: float,
                    reach: float) -> list[np.ndarray]:
    """Per section, the defect of each collocation interval (see the module docstring)."""
    params = SleighParams(M=M, m=m, I=I)
    out = []
    for spec, times, X in zip(specs, sol.times, sol.states):
        ends, coeffs = _pieces(spec.pieces)
        scale = np.array([max(np.max(np.abs(X[0])), 1e-3), max(np.max(np.abs(X[1])), 1e-3), reach, reach,
                          spec.length])
        err = np.empty(times.size - 1)
        for k in range(times.size - 1):
            h = times[k + 1] - times[k]
            j, kap, sw = _legs_from(ends, coeffs, X[4, k])
            y = X[:5, k].copy()
            y[4] = 0.0
            alpha = (X[5, k + 1] - X[5, k]) / h if h > 0 else 0.0
            with np.errstate(all="ignore"):
                r = integrate_legs(params, y, kap, sw, alpha, h, rtol=1e-10, atol=1e-12, beta=X[5, k])
            if r.status != 0 or not np.all(np.isfinite(r.y)):
                err[k] = np.inf
                continue
            end = X[:5, k + 1].copy()
            end[4] -= X[4, k]
            err[k] = float(np.max(np.abs(r.y - end) / scale))
        out.append(err)
    return out


def refined(sol: ProgramSolution, errors: list[np.ndarray], tol: float):
    """``(meshes, guess, n_split)``: the intervals with an error above ``tol`` halved, and the guess on them."""
    meshes, times_out, states_out, controls_out = [], [], [], []
    n_split = 0
    for sec_mesh, times, X, W, err in zip(sol.meshes, sol.times, sol.states, sol.controls, errors):
        new_sec, t_new, x_new, w_new = [], [times[:1]], [X[:, :1]], []
        i = 0
        for nodes in sec_mesh:
            N = nodes.size - 1
            new_nodes = [nodes[0]]
            for q in range(N):
                k = i + q
                if err[k] > tol:
                    # the defect falls like h^5 (Radau, degree 3): enough pieces to meet tol at once;
                    # an integration that diverged over the interval (an infinite defect: a planned
                    # drawing's, vivus-hi-there at 6 m) gets the most
                    ratio = err[k] / tol
                    parts = _MAX_PARTS if not math.isfinite(ratio) else int(min(_MAX_PARTS, max(2, math.ceil(ratio ** 0.2))))
                    n_split += 1
                    for f in np.arange(1, parts) / parts:
                        new_nodes.append(nodes[q] + f * (nodes[q + 1] - nodes[q]))
                        t_new.append([times[k] + f * (times[k + 1] - times[k])])
                        x_new.append((1.0 - f) * X[:, k:k + 1] + f * X[:, k + 1:k + 2])
                        w_new.append([W[k]])
                new_nodes.append(nodes[q + 1])
                t_new.append(times[k + 1:k + 2])
                x_new.append(X[:, k + 1:k + 2])
                w_new.append([W[k]])
            new_sec.append(np.array(new_nodes))
            i += N
        meshes.append(new_sec)
        times_out.append(np.concatenate(t_new))
        states_out.append(np.hstack(x_new))
        controls_out.append(np.concatenate(w_new))
    guess = ProgramSolution(success=True, status="refined", message="refined", times=tuple(times_out),
                            states=tuple(states_out), controls=tuple(controls_out), meshes=tuple(meshes))
    return meshes, guess, n_split
