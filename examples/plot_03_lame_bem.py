r"""
Lamé BEM: tractions from displacements, stresses inside
=======================================================

Plane-strain linear elasticity with the boundary element method (the Lamé case of
Sections 1.2-1.4).  For a prescribed boundary displacement U in V_hp^2 the traction
:math:`\psi = \sigma(u) n` in W_hp^2 solves :math:`V\psi = (K + \tfrac12) U`; Somigliana's identity (1.2)
then gives the displacement and the stress at any interior point.  Vector fields
interleave their components: dof ``2 d + c``.

The exact solution :math:`u = \nabla\phi`, :math:`\phi = e^x \sin y` harmonic, is
divergence free and harmonic, so it solves the Navier equations for any Lamé constants;
its stress is :math:`\sigma = 2\mu\,\varepsilon(u) = 2\mu \nabla^2\phi`.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LameBEM, lame_constants
from hpfebe.analysis import boundary_l2_error, observed_rates
from hpfebe.scenes import E, NU

lam, mu = lame_constants(E, NU, "strain")


def displacement(x):
    return np.exp(x[:, 0])[:, None] * np.column_stack([np.sin(x[:, 1]), np.cos(x[:, 1])])


def stress(x):
    ex, s, c = np.exp(x[:, 0]), np.sin(x[:, 1]), np.cos(x[:, 1])
    eps = np.empty((len(x), 2, 2))
    eps[:, 0, 0], eps[:, 1, 1] = ex * s, -ex * s
    eps[:, 0, 1] = eps[:, 1, 0] = ex * c
    return 2 * mu * eps                           # tr eps = 0


def traction(c):
    return lambda x, n: np.einsum("kij,kj->ki", stress(x), n)[:, c]


# %%
# A trapezoid, uniform refinement, p = 1 and 2 (the traction has degree p - 1).  ``interpolate`` is scalar: interpolate each
# component and interleave.
corners = [(0, 0), (2, 0), (1.5, 1), (0.3, 1)]
curves = {}
for p in (1, 2):
    hs, errs = [], []
    for n in (1, 2, 4, 8):
        mesh = BoundaryMesh.polygon(corners, n=n, p=p)
        op = LameBEM(mesh, E, NU, plane="strain")
        V, W = op.V_space, op.W_space
        U = np.column_stack([V.interpolate(lambda x: displacement(x)[:, c])
                             for c in (0, 1)]).ravel()
        psi = op.Psi(U)                           # tractions, W_hp^2 interleaved
        comp = psi.reshape(-1, 2)
        errs.append(np.hypot(*(boundary_l2_error(W, comp[:, c], traction(c))
                               for c in (0, 1))))
        hs.append(mesh.h_max)
    curves[p] = (hs, errs)
    print(f"p = {p}: traction L2 errors {np.array(errs)}, "
          f"rates {np.round(observed_rates(hs, errs)[1:], 2)}")

# %%
# The stress inside from Somigliana's identity, on the finest mesh, against the exact
# :math:`\sigma_{xx} = 2\mu e^x \sin y`.
xs, ys = np.meshgrid(np.linspace(0.35, 1.45, 23), np.linspace(0.1, 0.9, 17))
pts = np.column_stack([xs.ravel(), ys.ravel()])
pts = pts[(pts[:, 0] > 0.3 * pts[:, 1] + 0.1) & (pts[:, 0] < 2 - 0.5 * pts[:, 1] - 0.1)]
sig = op.stress(pts, U, psi)
rel = np.abs(sig[:, 0, 0] - stress(pts)[:, 0, 0]).max() / np.abs(stress(pts)[:, 0, 0]).max()
print(f"max relative error of sigma_xx inside: {rel:.1e}")

fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8))
for p, (hs, errs) in curves.items():
    a1.loglog(hs, errs, "o-", label=f"p = {p}")
a1.set_xlabel("h")
a1.set_ylabel("traction L2 error")
a1.legend()
a1.grid(True, which="both", alpha=0.3)
sc = a2.scatter(pts[:, 0], pts[:, 1], c=sig[:, 0, 0], s=18)
a2.plot(*np.vstack([corners, corners[:1]]).T, "k-")
a2.set_aspect("equal")
a2.set_title(r"$\sigma_{xx}$ from Somigliana's identity")
fig.colorbar(sc, ax=a2)
plt.show()
