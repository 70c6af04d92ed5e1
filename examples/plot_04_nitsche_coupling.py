r"""
Nitsche FE/BE coupling on your own geometry
===========================================

The Poisson interface problem of Chapter 2: finite elements in :math:`\Omega_1`,
boundary elements in :math:`\Omega_2`, coupled weakly across the interface
:math:`\Gamma_I` by Nitsche's method (2.3)-(2.4) with the penalty
:math:`\lambda_{Nit} h_1^{-1} p_1^\alpha [U]`.  The two meshes need not match on
:math:`\Gamma_I`.

Here :math:`\Omega = [0, 2] \times [-1, 1]` with a boundary element inclusion
:math:`\Omega_2 = [0.5, 1.5] \times [-0.5, 0.5]`, Dirichlet data on :math:`x = 0` and
Neumann data elsewhere, and the exact solution :math:`u = \sin(x)\, e^{-y}` (harmonic,
zero on :math:`x = 0`).
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe.analysis import observed_rates
from hpfebe.coupling import InterfaceProblem, NitscheFEBE, be_trace_energy_error, fe_errors

TOL = 1e-10


def u(x, y):
    return np.sin(x) * np.exp(-y)


def grad_u(x, y):
    return np.cos(x) * np.exp(-y), -np.sin(x) * np.exp(-y)


def in_omega2(x, y):
    return (np.abs(x - 1.0) < 0.5) & (np.abs(y) < 0.5)


def fe_label(x, y):
    """Labels of the FE boundary facets (at their midpoints): D, I (on dOmega2) or N."""
    lab = np.full(np.shape(x), "N", dtype="<U1")
    on_vertical = (np.abs(np.abs(x - 1.0) - 0.5) < TOL) & (np.abs(y) <= 0.5 + TOL)
    on_horizontal = (np.abs(np.abs(y) - 0.5) < TOL) & (np.abs(x - 1.0) <= 0.5 + TOL)
    lab[on_vertical | on_horizontal] = "I"
    lab[np.abs(x) < TOL] = "D"
    return lab


# %%
# The problem: geometry (the FE mesh is a tensor grid on the blocks ``xbreaks`` x
# ``ybreaks`` outside :math:`\Omega_2`), the BE polygon :math:`\partial\Omega_2`
# (counter-clockwise, every side on the interface), the data.
problem = InterfaceProblem(
    name="inclusion", u=u, grad_u=grad_u, f=None,
    xbreaks=(0.0, 0.5, 1.5, 2.0), ybreaks=(-1.0, -0.5, 0.5, 1.0),
    in_omega1=lambda x, y: ~in_omega2(x, y), in_omega2=in_omega2, fe_label=fe_label,
    be_vertices=((0.5, -0.5), (1.5, -0.5), (1.5, 0.5), (0.5, 0.5)),
    be_labels=("I", "I", "I", "I"),
)

# %%
# h-version with p = 1 and non-matching meshes (BE mesh finer than the FE mesh),
# :math:`\lambda_{Nit} = 10`: the FE energy error and the BE part of the energy norm.
hs, fe_h1, be_energy = [], [], []
for h_inv in (2, 4, 8):
    model = NitscheFEBE(problem, fe_h_inv=h_inv, be_h_inv=h_inv + 1, p_fe=1)
    sol = model.solve(lambda_nit=10.0)
    fe_h1.append(fe_errors(model, sol)["h1"])
    be_energy.append(be_trace_energy_error(model, sol))
    hs.append(1.0 / h_inv)
print("FE H1 errors", np.array(fe_h1), "rates", np.round(observed_rates(hs, fe_h1)[1:], 2))
print("BE energy errors", np.array(be_energy), "rates",
      np.round(observed_rates(hs, be_energy)[1:], 2))

# %%
# The FE solution on the last mesh (Q1: the first dofs are the vertex values) and the
# boundary element trace on :math:`\partial\Omega_2`.
mesh = model.fe.mesh
fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
tri = np.vstack([mesh.t[[0, 1, 2]].T, mesh.t[[0, 2, 3]].T])     # quads split for plotting
pc = a1.tripcolor(mesh.p[0], mesh.p[1], tri, sol.U1[:mesh.p.shape[1]], shading="gouraud")
be = model.be_mesh
a1.plot(*np.vstack([be.nodes[be.elements[:, 0]], be.nodes[be.elements[:1, 0]]]).T, "w-")
a1.set_aspect("equal")
a1.set_title("U1 (FE) and the BE inclusion")
fig.colorbar(pc, ax=a1)
a2.loglog(hs, fe_h1, "o-", label="FE: H1 seminorm")
a2.loglog(hs, be_energy, "s-", label="BE: energy norm of the trace")
a2.set_xlabel("h")
a2.legend()
a2.grid(True, which="both", alpha=0.3)
plt.show()
