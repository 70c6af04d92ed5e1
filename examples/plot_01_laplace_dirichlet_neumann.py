r"""
Laplace BEM: Dirichlet and Neumann problems on your polygon
===========================================================

The Laplace equation in a polygon of your own, solved on the boundary alone
(Sections 1.2-1.4 of the thesis).  For the **Dirichlet problem** the unknown is the
Neumann trace :math:`\psi = \partial_n u` in W_hp, from the first Calderón identity
:math:`V\psi = (K + \tfrac12) g`; for the **Neumann problem** the unknown is the
Dirichlet trace U in V_hp, from the Steklov-Poincaré operator:
:math:`\langle \hat S U, v\rangle = \langle t, v\rangle` (U up to a constant).  We take a harmonic function with inhomogeneous data on every side, refine
uniformly and read off the observed rates.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LaplaceBEM
from hpfebe.analysis import boundary_l2_error, observed_rates

# %%
# The data: :math:`u = \log|x - x_0|` with :math:`x_0` outside the domain is harmonic
# inside; its normal derivative is :math:`(x - x_0)\cdot n / |x - x_0|^2`.  Error functionals such as
# :func:`~hpfebe.analysis.boundary_l2_error` call the exact solution with the points and
# the outward normals there, ``exact(x, n)``; the projection onto W_hp passes the points
# only, and ``mesh.locate`` finds their elements (and so the normals).
x0 = np.array([2.2, 1.9])


def u(x, n=None):
    return 0.5 * np.log(np.sum((x - x0) ** 2, axis=1))


def du_dn(x, n):
    return np.sum((x - x0) * n, axis=1) / np.sum((x - x0) ** 2, axis=1)


# %%
# The domain: any closed polygon, here a "house" with five corners.  ``polygon``
# orients it counter-clockwise, so that the element normals point outwards.
house = [(0, 0), (1, 0), (1, 0.7), (0.5, 1.2), (0, 0.7)]

# %%
# Both problems on a sequence of uniform meshes, degrees p = 1 and 2.
#
# * Dirichlet: ``solve_dirichlet`` returns psi in W_hp (degree p - 1 per element).
# * Neumann: the datum t = du/dn projected onto W_hp; the right-hand side <t, v> for v
#   in V_hp is ``M.T @ t`` (M: test W_hp, trial V_hp).  ``S_hat`` has the constants as
#   kernel, so the mean of U is fixed by a Lagrange multiplier.
results = {}
for p in (1, 2):
    hs, err_d, err_n = [], [], []
    for n in (2, 4, 8, 16):
        mesh = BoundaryMesh.polygon(house, n=n, p=p)
        op = LaplaceBEM(mesh)
        V, W = op.V_space, op.W_space
        psi = op.solve_dirichlet(V.interpolate(u))
        err_d.append(boundary_l2_error(W, psi, du_dn))

        t = W.project(lambda x: du_dn(x, mesh.normals[mesh.locate(x)[0]]))
        c = op.M.T @ W.project(lambda x: np.ones(len(x)))   # U -> int U ds
        A = np.block([[op.S_hat, c[:, None]], [c[None, :], np.zeros((1, 1))]])
        rhs = np.concatenate([op.M.T @ t, [c @ V.interpolate(u)]])
        U = np.linalg.solve(A, rhs)[:-1]
        err_n.append(boundary_l2_error(V, U, u))
        hs.append(mesh.h_max)
    results[p] = (np.array(hs), np.array(err_d), np.array(err_n))
    print(f"p = {p}: Dirichlet (psi) rates {np.round(observed_rates(hs, err_d)[1:], 2)}, "
          f"Neumann (U) rates {np.round(observed_rates(hs, err_n)[1:], 2)}")

# %%
# The L2 errors against h: :math:`\psi` converges like :math:`h^p`, U like
# :math:`h^{p+1}`.
fig, ax = plt.subplots(figsize=(6, 4))
for p, (hs, ed, en) in results.items():
    ax.loglog(hs, ed, "o-", label=f"Dirichlet: psi, p = {p}")
    ax.loglog(hs, en, "s--", label=f"Neumann: U, p = {p}")
ax.set_xlabel("h")
ax.set_ylabel("L2 error on the boundary")
ax.legend()
ax.grid(True, which="both", alpha=0.3)
plt.show()
