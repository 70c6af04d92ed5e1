r"""
Adaptive refinement driven by a residual estimator
==================================================

The mixed Laplace problem on an L-shape whose solution
:math:`u = r^{2/3}\sin(2\theta/3)` is singular at the reentrant corner, solved by the
boundary element method.  The residual indicator :math:`\eta_h(I)` of (3.107) (without
contact terms: the Neumann residual and the consistency term) drives Algorithm 3.2:
solve, estimate, mark the elements with :math:`\eta(I) \ge 0.9 \max \eta`, bisect them.
Adaptive refinement recovers the convergence rate that the corner singularity costs
uniform refinement.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LaplaceBEM, adapt
from hpfebe.adaptivity import bem_indicators, error_measure_B, solve_laplace_mixed
from hpfebe.analysis import fitted_rate


def theta(x):
    return np.mod(np.arctan2(x[:, 1], x[:, 0]), 2 * np.pi)


def u(x, n=None):
    r = np.hypot(x[:, 0], x[:, 1])
    return r ** (2 / 3) * np.sin(2 * theta(x) / 3)


def flux(x, n):
    r = np.maximum(np.hypot(x[:, 0], x[:, 1]), 1e-300)
    c, th = (2 / 3) * r ** (-1 / 3), theta(x)
    grad = np.column_stack([-c * np.sin(th / 3), c * np.cos(th / 3)])
    return np.sum(grad * n, axis=1)


# %%
# The L-shape [-1, 1]^2 minus the fourth quadrant, u = 0 on the two sides at the
# reentrant corner (0, 0) ("D"), the Neumann datum du/dn on the rest.
corners = [(0, 0), (1, 0), (1, 1), (-1, 1), (-1, -1), (0, -1)]
mesh0 = BoundaryMesh.polygon(corners, n=1, p=1, labels=["D", "N", "N", "N", "N", "D"])


def solve(mesh):
    op = LaplaceBEM(mesh)
    U, Psi = solve_laplace_mixed(op, flux)
    return (op, U, Psi), op.S_hat.shape[0]


def estimate(mesh, state):
    op, U, Psi = state
    return bem_indicators(op, U, Psi, {"N": flux})


def error(mesh, state):
    op, U, Psi = state
    return error_measure_B(op, U, Psi, u, flux)


# %%
# The adaptive loop against uniform refinement (``marking="uniform"``); right, the
# last adaptive mesh.
runs = {"adaptive": adapt(mesh0, solve, estimate, n_steps=14, error=error),
        "uniform": adapt(mesh0, solve, estimate, n_steps=6, marking="uniform", error=error)}
fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
for name, history in runs.items():
    dof = np.array([r["ndof"] for r in history.records])
    err = np.array([r["error"] for r in history.records])
    eta = np.array([r["eta"] for r in history.records])
    print(f"{name:9s}: error ~ DOF^{fitted_rate(dof, err, last=4):.2f}, "
          f"efficiency eta/error {np.round(eta / err, 2)}")
    a1.loglog(dof, err, "o-", label=f"{name}: error")
    a1.loglog(dof, eta, "x--", label=f"{name}: estimator")
a1.set_xlabel("degrees of freedom")
a1.set_ylabel(r"$|||u - U|||_B$")
a1.legend()
mesh = runs["adaptive"].mesh                 # right: the elements shrink towards (0, 0)
a2.plot(*np.vstack([corners, corners[:1]]).T, "k-", lw=0.5)
a2.plot(mesh.nodes[:, 0], mesh.nodes[:, 1], "r.", ms=4)
a2.set_aspect("equal")
a2.set_title(f"adaptive mesh: {mesh.n_elements} elements")
plt.show()
