r"""
Hertz contact: a BE half-disk on a rigid flat
=============================================

A half-disk of radius R (boundary elements, plane strain) pressed onto a rigid flat,
frictionless, with the normal penalty law (4.19) :math:`p_n = -\varepsilon_n^{-1} g_n`
(Section 3.2 for one body against a rigid obstacle).  The computed pressure is compared
with Hertz's: for a cylinder on a rigid plane under the force F per unit depth,

.. math::

   a = \sqrt{\frac{4 F R}{\pi E^*}}, \qquad p(x) = p_0 \sqrt{1 - x^2/a^2}, \qquad
   p_0 = \frac{2F}{\pi a}, \qquad E^* = \frac{E}{1 - \nu^2}.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import BoundaryMesh, LameBEM, RigidObstacle, TwoBodyContact
from hpfebe.scenes import E, NU

# %%
# The half-disk: its curved side "C" meshed finer towards the bottom point (0, -R),
# where contact happens, and the flat top "top".  ``polygon`` closes the curve from the
# last vertex back to the first.
R, n_arc = 1.0, 96
s = np.linspace(-1.0, 1.0, n_arc + 1)
theta = 1.5 * np.pi + 0.5 * np.pi * np.sign(s) * s ** 2
arc = R * np.column_stack([np.cos(theta), np.sin(theta)])
mesh = BoundaryMesh.polygon(arc, n=[1] * n_arc + [8], p=1, labels=["C"] * n_arc + ["top"])
disk = LameBEM(mesh, E, NU, plane="strain")

# %%
# The rigid flat y = -R touches the disk at its bottom point: the gap along the
# vertical is g(x) = y + R (a fine approximation of the normal gap where the contact
# is, a << R).  The top is moved down by delta in four load steps; a stiff penalty
# (eps_n = 1e-3 / E) keeps the penetration far below the displacement.
flat = RigidObstacle(gap=lambda x: x[:, 1] + R)
problem = TwoBodyContact(disk, flat, "C", eps_n=1e-3 / E)
top = problem.dofs_on("slave", "top")
top_y = problem.dofs_on("slave", "top", 1)
delta = 2e-2
result = problem.solve(None, top, np.where(np.isin(top, top_y), -delta, 0.0),
                       load_factors=np.linspace(0.25, 1.0, 4))
print(result.converged, result.reason, "Newton iterations per step:", result.iterations)

# %%
# Hertz's half-width and peak pressure for the computed force, against ours.
F = result.total_forces()[0]                  # normal force per unit depth
E_star = E / (1 - NU ** 2)
a = np.sqrt(4 * F * R / (np.pi * E_star))
p0 = 2 * F / (np.pi * a)
# The pressure at the contact points oscillates between the two Gauss points of an
# element (a P1 displacement against a curved boundary approximated by straight
# elements); its mean per element, weighted by the quadrature weights, follows Hertz.
x, p = result.points[:, 0], result.p_n
w, e = result.weights, result.elements
on = np.bincount(e, weights=w) > 0
p_elem = np.bincount(e, weights=w * p)[on] / np.bincount(e, weights=w)[on]
x_elem = np.bincount(e, weights=w * x)[on] / np.bincount(e, weights=w)[on]
print(f"F = {F:.1f}; half-width: Hertz {a:.4f}, computed {np.abs(x[p > 0]).max():.4f}; "
      f"peak pressure: Hertz {p0:.0f}, element means {p_elem.max():.0f} "
      f"({100 * (p_elem.max() / p0 - 1):+.1f} %)")

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(x, p, ".", color="0.7", label="at the contact points")
ax.plot(x_elem, p_elem, "o", label="element means")
xs = np.linspace(-a, a, 201)
ax.plot(xs, p0 * np.sqrt(1 - (xs / a) ** 2), "k-", label="Hertz")
ax.set_xlim(-2 * a, 2 * a)
ax.set_xlabel("x")
ax.set_ylabel("contact pressure $p_n$")
ax.legend()
plt.show()
