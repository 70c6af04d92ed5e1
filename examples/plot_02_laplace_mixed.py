r"""
Laplace BEM: a mixed problem with inhomogeneous data
====================================================

Dirichlet data on part of the boundary, Neumann data on the rest, neither zero, on an
L-shaped polygon.  With the discrete Steklov-Poincare operator ``S_hat``
(Section 1.4) the mixed problem reads: find U in V_hp with U = g on
:math:`\Gamma_D` and

.. math::

   \langle \hat S U, v\rangle = \langle t, v\rangle_{\Gamma_N}
   \quad \text{for all } v \in V_{hp} \text{ vanishing on } \Gamma_D,


the symmetric formulation of Section 1.3 with the unknown flux on Gamma_D eliminated.
The Dirichlet values enter by lifting: U = U_D + U_0, U_D the interpolant of g at the
Dirichlet dofs.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LaplaceBEM
from hpfebe.analysis import boundary_l2_error, observed_rates


def u(x, n=None):                      # harmonic: exp(x) sin(y)
    return np.exp(x[:, 0]) * np.sin(x[:, 1])


def du_dn(x, n):
    grad = np.exp(x[:, 0])[:, None] * np.column_stack([np.sin(x[:, 1]), np.cos(x[:, 1])])
    return np.sum(grad * n, axis=1)


# %%
# An L-shape; the labels say which sides carry Dirichlet ("D") and Neumann ("N") data.
corners = [(-1, -1), (0, -1), (0, 0), (1, 0), (1, 1), (-1, 1)]
labels = ["D", "N", "N", "D", "N", "N"]


def solve_mixed(n, p):
    mesh = BoundaryMesh.polygon(corners, n=n, p=p, labels=labels)
    op = LaplaceBEM(mesh)
    V, W = op.V_space, op.W_space
    D = V.dofs_on("D")                          # dofs touching Gamma_D (closure)
    free = np.setdiff1d(np.arange(op.S_hat.shape[0]), D)
    U = np.zeros(op.S_hat.shape[0])
    U[D] = V.interpolate(u)[D]                  # the Dirichlet lift

    def t_on_N(x):                              # Neumann datum, zero on Gamma_D
        e = mesh.locate(x)[0]
        return np.where(mesh.labels[e] == "N", du_dn(x, mesh.normals[e]), 0.0)

    rhs = op.M.T @ W.project(t_on_N) - op.S_hat @ U
    U[free] = np.linalg.solve(op.S_hat[np.ix_(free, free)], rhs[free])
    return mesh, boundary_l2_error(V, U, u), op.S_hat.shape[0]


# %%
# h-version for p = 1, 2, 3: the observed rates of the boundary L2 error of U.
fig, ax = plt.subplots(figsize=(6, 4))
for p in (1, 2, 3):
    hs, errs, dofs = [], [], []
    for n in (1, 2, 4, 8):
        mesh, err, ndof = solve_mixed(n, p)
        hs.append(mesh.h_max), errs.append(err), dofs.append(ndof)
    print(f"p = {p}: errors {np.array(errs)}, rates {np.round(observed_rates(hs, errs)[1:], 2)}")
    ax.loglog(dofs, errs, "o-", label=f"p = {p}")
ax.set_xlabel("degrees of freedom")
ax.set_ylabel(r"$\|u - U\|_{L^2(\Gamma)}$")
ax.set_title("mixed problem on an L-shape")
ax.legend()
ax.grid(True, which="both", alpha=0.3)
plt.show()
