r"""
Laplace BEM: a mixed problem with inhomogeneous data
====================================================

Dirichlet data g on part of the boundary, Neumann data t on the rest, neither zero, on an
L-shaped polygon.  With the discrete Steklov-Poincaré operator ``S_hat``
(Section 1.4) the mixed problem reads: find U in V_hp with U = g on
:math:`\Gamma_D` and

.. math::

   \langle \hat S U, v\rangle = \langle t, v\rangle_{\Gamma_N}
   \quad \text{for all } v \in V_{hp} \text{ vanishing on } \Gamma_D,

the symmetric formulation of Section 1.3 with the unknown flux on Gamma_D eliminated.
:func:`hpfebe.bem.solve_mixed` solves it: the Dirichlet values enter by lifting
(U = I_h g at the dofs of Gamma_D), the flux on all of Gamma is
:math:`\Psi = V^{-1}(K + \tfrac12) U`.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LaplaceBEM
from hpfebe.analysis import boundary_l2_error, observed_rates
from hpfebe.bem import MixedData, solve_mixed
from hpfebe.io import interior_vtu


def u(x, n=None):                      # harmonic: exp(x) sin(y)
    return np.exp(x[:, 0]) * np.sin(x[:, 1])


def du_dn(x, n):
    grad = np.exp(x[:, 0])[:, None] * np.column_stack([np.sin(x[:, 1]), np.cos(x[:, 1])])
    return np.sum(grad * n, axis=1)


# %%
# An L-shape; the labels say which sides carry Dirichlet ("D") and Neumann ("N") data.
corners = [(-1, -1), (0, -1), (0, 0), (1, 0), (1, 1), (-1, 1)]
labels = ["D", "N", "N", "D", "N", "N"]


def solve(n, p):
    mesh = BoundaryMesh.polygon(corners, n=n, p=p, labels=labels)
    op = LaplaceBEM(mesh)
    sol = solve_mixed(op, MixedData(dirichlet=("D",), g=u, t=du_dn))
    return mesh, boundary_l2_error(op.V_space, sol.U, u), sol.U.size


# %%
# h-version for p = 1, 2, 3: the observed rates of the boundary L2 error of U.
fig, ax = plt.subplots(figsize=(6, 4))
for p in (1, 2, 3):
    hs, errs, dofs = [], [], []
    for n in (1, 2, 4, 8):
        mesh, err, ndof = solve(n, p)
        hs.append(mesh.h_max), errs.append(err), dofs.append(ndof)
    print(f"p = {p}: errors {np.array(errs)}, rates {np.round(observed_rates(hs, errs)[1:], 2)}")
    ax.loglog(dofs, errs, "o-", label=f"p = {p}")
ax.set_xlabel("degrees of freedom")
ax.set_ylabel(r"$\|u - U\|_{L^2(\Gamma)}$")
ax.set_title("mixed problem on an L-shape")
ax.legend()
ax.grid(True, which="both", alpha=0.3)

# %%
# The potential inside, by the representation formula of the Cauchy data (U, Psi) at the
# vertices of a generated sampling mesh (:func:`hpfebe.io.interior_vtu`; write it for
# ParaView with :func:`hpfebe.io.write_interior_vtu`).
mesh = BoundaryMesh.polygon(corners, n=4, p=2, labels=labels)
op = LaplaceBEM(mesh)
sol = solve_mixed(op, MixedData(g=u, t=du_dn))
inside = interior_vtu(op, sol.U, sol.Psi, h=0.1)
xy, tri = inside.points[:, :2], inside.cells[0].data
err = np.abs(inside.point_data["potential"] - u(xy)).max()
print(f"{len(xy)} sampling vertices, max |u - u_h| inside: {err:.1e}")
fig2, a2 = plt.subplots(figsize=(6, 5))
tp = a2.tripcolor(xy[:, 0], xy[:, 1], tri, inside.point_data["potential"], shading="gouraud")
a2.triplot(xy[:, 0], xy[:, 1], tri, lw=0.2, color="w")
a2.set_aspect("equal")
a2.set_title("potential inside (representation formula)")
fig2.colorbar(tp, ax=a2)
plt.show()
