r"""
Meshes from a gmsh file
=======================

:func:`hpfebe.io.read_fe_mesh` reads the triangles of a gmsh ``.msh`` file (MSH 2.2 or
4.1) into a scikit-fem mesh whose ``boundaries`` are the file's physical groups;
:func:`hpfebe.io.read_boundary_mesh` reads its boundary lines into a
:class:`~hpfebe.BoundaryMesh` labelled by the same groups, the lines chained into closed
curves and oriented (outer boundary counter-clockwise, the hole clockwise) whatever
their direction in the file.

The file ``data/plate_with_hole.msh`` is a plate :math:`[0, 2] \times [0, 1]` with a
hole of radius 0.25 and four physical groups of lines, made with gmsh's Python API:

.. code-block:: python

   occ = gmsh.model.occ
   occ.cut([(2, occ.addRectangle(0, 0, 0, 2, 1))], [(2, occ.addDisk(0.7, 0.5, 0, 0.25, 0.25))])
   occ.synchronize()
   # physical groups of curves "clamped" (x = 0), "load" (x = 2), "free", "hole"
   # and of the surface "plate", then
   gmsh.model.mesh.generate(2)
   gmsh.write("plate_with_hole.msh")
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import scipy.sparse.linalg as spla

from hpfebe import ElasticBody
from hpfebe.io import read_boundary_mesh, read_fe_mesh
from hpfebe.scenes import E, NU

try:
    path = Path(__file__).with_name("data") / "plate_with_hole.msh"
except NameError:                      # run line by line, without __file__
    path = Path("data") / "plate_with_hole.msh"

# %%
# The FE mesh and its named boundaries (facet indices per group).
mesh = read_fe_mesh(path)
print({name: len(facets) for name, facets in mesh.boundaries.items()})

# %%
# The boundary mesh: one element per line of the file, p = 2 on the hole and 1
# elsewhere (a degree per group); two closed curves.
bmesh = read_boundary_mesh(path, p={"clamped": 1, "load": 1, "free": 1, "hole": 2})
print(f"{bmesh.n_elements} elements on {bmesh.n_curves} curves, "
      f"perimeter {bmesh.lengths.sum():.4f} (exact {6 + 0.5 * np.pi:.4f})")

# %%
# Plane-strain elasticity on the FE mesh: clamped at x = 0, pulled at x = 2 by the
# traction (E / 1000, 0); the Dirichlet dofs are removed from the system.
body = ElasticBody(mesh, E, NU)
f = body.traction_load("load", (E / 1000, 0.0))
fixed = body.dofs_on("clamped")
free = np.setdiff1d(np.arange(body.ndofs), fixed)
u = np.zeros(body.ndofs)
u[free] = spla.spsolve(body.K[free][:, free].tocsc(), f[free])
disp = body.nodal_displacement(u)
print(f"largest displacement {np.abs(disp).max():.2e}")

# %%
# Left: the deformed FE mesh (displacements scaled by 50) coloured by :math:`|u|`.
# Right: the boundary mesh with its element normals, which point out of the plate, so
# into the hole.
fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
xd = mesh.p + 50 * disp
tc = a1.tripcolor(xd[0], xd[1], mesh.t.T, np.hypot(*disp), shading="gouraud")
a1.triplot(xd[0], xd[1], mesh.t.T, "w-", lw=0.2)
a1.set_aspect("equal")
a1.set_title("FE: deformed (x50)")
fig.colorbar(tc, ax=a1)
mid = 0.5 * (bmesh.a + bmesh.b)
for name in ("clamped", "load", "free", "hole"):
    on = bmesh.labels == name
    a2.quiver(mid[on, 0], mid[on, 1], bmesh.normals[on, 0], bmesh.normals[on, 1],
              color=f"C{['clamped', 'load', 'free', 'hole'].index(name)}", scale=25,
              label=name)
a2.set_aspect("equal")
a2.set_title("BoundaryMesh: labels and outward normals")
a2.legend(loc="upper right", fontsize=8)
plt.show()
