"""Linear elasticity on a FE body (scikit-fem), the building block of Chapter 4's FE bodies.

Lowest-order spaces of Section 4.2.3: R_1(K) = P_1 on triangles, Q_1 on quadrilaterals,
vector valued.  Stiffness  a(u, v) = (sigma(u), eps(v)),  sigma = 2 mu eps + lambda tr(eps) I
with (lambda, mu) from :func:`hpfebe.constitutive.materials.lame_constants` (plane strain, or plane stress
with the modified lambda*).

Dof numbering is scikit-fem's: ``basis.nodal_dofs[c, i]`` is component c (0 = x, 1 = y) at
vertex i (interleaved, 2 i + c, for these elements).

A body is built from a mesh whose boundary facets carry labels (``mesh.boundaries``, the
labelled meshes of :mod:`hpfebe.fem.meshes`, also as an :class:`~hpfebe.fem.meshes.FEDomain`;
:func:`~hpfebe.fem.meshes.refine_labelled` keeps the labels); :func:`rectangle_mesh`
labels the four sides of a rectangle "left", "right", "bottom", "top" by position.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    ElementQuad1,
    ElementTriP1,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshQuad,
    MeshTri,
    asm,
)
from skfem.models.elasticity import linear_elasticity

from ..checks import choice, integer, real
from ..constitutive.materials import lame_constants
from .meshes import FEDomain

KINDS = ("quad", "tri")


def rectangle_mesh(
    x0: float, x1: float, y0: float, y1: float, nx: int, ny: int, kind: str = "quad"
):
    """Uniform mesh of [x0, x1] x [y0, y1] with nx x ny cells (``kind="tri"``: each cell
    split into two triangles), boundary facets labelled "left", "right", "bottom", "top"."""
    choice("kind", kind, KINDS)
    nx, ny = integer("nx", nx, lo=1), integer("ny", ny, lo=1)
    x0, x1, y0, y1 = (real(k, v) for k, v in zip(("x0", "x1", "y0", "y1"), (x0, x1, y0, y1)))
    if not (x1 > x0):
        raise ValueError(f"x1 must exceed x0, got x0={x0!r}, x1={x1!r}")
    if not (y1 > y0):
        raise ValueError(f"y1 must exceed y0, got y0={y0!r}, y1={y1!r}")
    xs = np.linspace(x0, x1, int(nx) + 1)
    ys = np.linspace(y0, y1, int(ny) + 1)
    cls = MeshQuad if kind == "quad" else MeshTri
    mesh = cls.init_tensor(xs, ys)
    tol = 1e-10 * max(x1 - x0, y1 - y0)
    return mesh.with_boundaries(
        {
            "left": lambda x: np.abs(x[0] - x0) < tol,
            "right": lambda x: np.abs(x[0] - x1) < tol,
            "bottom": lambda x: np.abs(x[1] - y0) < tol,
            "top": lambda x: np.abs(x[1] - y1) < tol,
        }
    )


def p1_stiffness(mesh, basis, lam: float, mu: float) -> sp.csr_matrix:
    """The stiffness matrix of linear elasticity for P1 triangles in closed form (the
    strains are constant per cell): K_e[(i, a), (j, b)] = |K| (mu d_ab grad l_i . grad l_j
    + mu d_a l_j d_b l_i + lambda d_a l_i d_b l_j), l_i the barycentric coordinates,
    local dof 2 i + a as scikit-fem's ElementVector(ElementTriP1); the matrix of
    scikit-fem's quadrature assembly to round-off, about 10x faster (tests/fem)."""
    P = mesh.p[:, mesh.t]                                   # (2, 3, nc)
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    det = e1[0] * e2[1] - e1[1] * e2[0]
    # grad l_1 = (e2_y, -e2_x) / det, grad l_2 = (-e1_y, e1_x) / det, l_0 = 1 - l_1 - l_2
    g1 = np.array([e2[1], -e2[0]]) / det
    g2 = np.array([-e1[1], e1[0]]) / det
    G = np.stack([-g1 - g2, g1, g2], axis=1)                # (2 comps, 3 nodes, nc)
    area = 0.5 * np.abs(det)
    dots = np.einsum("aic,ajc->ijc", G, G)                  # grad l_i . grad l_j
    eye = np.eye(2)
    Ke = (mu * eye[None, :, None, :, None] * dots[:, None, :, None, :]
          + mu * np.einsum("ajc,bic->iajbc", G, G)
          + lam * np.einsum("aic,bjc->iajbc", G, G)) * area   # (3, 2, 3, 2, nc)
    Ke = Ke.reshape(6, 6, -1)
    dofs = basis.element_dofs                               # (6, nc)
    rows = np.broadcast_to(dofs[:, None, :], Ke.shape)
    cols = np.broadcast_to(dofs[None, :, :], Ke.shape)
    return sp.coo_matrix((Ke.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(basis.N, basis.N)).tocsr()


class ElasticBody:
    """A linearly elastic FE body: mesh, vector P1/Q1 basis, stiffness matrix ``K``.

    Parameters: ``mesh`` (skfem MeshTri or MeshQuad with labelled ``boundaries``, or an
    :class:`~hpfebe.fem.meshes.FEDomain`), ``E`` (Young's modulus), ``nu`` (Poisson
    ratio), ``plane`` ("strain" or "stress").
    """

    def __init__(self, mesh, E: float, nu: float, plane: str = "strain",
                 assembly: str = "quadrature"):
        if assembly not in ("quadrature", "closed_form"):
            raise ValueError("assembly must be 'quadrature' or 'closed_form', got "
                             f"{assembly!r}")
        if isinstance(mesh, FEDomain):
            mesh = mesh.mesh
        if isinstance(mesh, MeshQuad):
            elem = ElementQuad1()
        elif isinstance(mesh, MeshTri):
            elem = ElementTriP1()
        else:
            raise ValueError(f"mesh must be a skfem MeshTri or MeshQuad, got {type(mesh).__name__}")
        self.mesh = mesh
        self.E, self.nu, self.plane = float(E), float(nu), plane
        self.lam, self.mu = lame_constants(E, nu, plane)
        self.basis = Basis(mesh, ElementVector(elem))
        if assembly == "closed_form" and isinstance(mesh, MeshTri):
            self.K = p1_stiffness(mesh, self.basis, self.lam, self.mu)
        else:
            self.K = asm(linear_elasticity(self.lam, self.mu), self.basis).tocsr()

    # ------------------------------------------------------------------ geometry / dofs
    @property
    def ndofs(self) -> int:
        return self.basis.N

    @property
    def nodal_dofs(self) -> np.ndarray:
        """(2, n_vertices) dof indices, row c = component c."""
        return self.basis.nodal_dofs

    def boundary_labels(self) -> list:
        return sorted((self.mesh.boundaries or {}).keys())

    def boundary_facets(self, label: str) -> np.ndarray:
        b = self.mesh.boundaries or {}
        if label not in b:
            raise ValueError(f"boundary label must be one of {sorted(b)}, got {label!r}")
        return np.asarray(b[label], dtype=np.int64)

    def boundary_vertices(self, label: str) -> np.ndarray:
        return np.unique(self.mesh.facets[:, self.boundary_facets(label)])

    def dofs_on(self, labels, component: Optional[int] = None) -> np.ndarray:
        """Dofs of the vertices on the boundary part(s) ``labels`` (str or list);
        ``component`` 0 / 1 for one component, None for both."""
        if isinstance(labels, str):
            labels = [labels]
        verts = np.unique(np.concatenate([self.boundary_vertices(lb) for lb in labels]))
        return self._vertex_dofs(verts, component)

    def vertex_at(self, point: Sequence[float]) -> int:
        """Index of the mesh vertex at ``point`` (ValueError if there is none)."""
        p = np.asarray(point, dtype=float).reshape(2, 1)
        d = np.linalg.norm(self.mesh.p - p, axis=0)
        i = int(np.argmin(d))
        scale = float(np.ptp(self.mesh.p, axis=1).max())
        if d[i] > 1e-10 * scale:
            raise ValueError(f"point must be a mesh vertex, got {tuple(p.ravel())!r}")
        return i

    def dofs_at(self, point: Sequence[float], component: Optional[int] = None) -> np.ndarray:
        return self._vertex_dofs(np.array([self.vertex_at(point)]), component)

    def _vertex_dofs(self, verts: np.ndarray, component: Optional[int]) -> np.ndarray:
        nd = self.nodal_dofs
        if component is None:
            return np.sort(nd[:, verts].ravel())
        if component not in (0, 1):
            raise ValueError(f"component must be 0, 1 or None, got {component!r}")
        return nd[component, verts]

    def dof_coordinates(self) -> np.ndarray:
        """(ndofs, 2) coordinates of the vertex of every dof."""
        xy = np.empty((self.ndofs, 2))
        for c in (0, 1):
            xy[self.nodal_dofs[c]] = self.mesh.p.T
        return xy

    def nodal_displacement(self, u: np.ndarray) -> np.ndarray:
        """(2, n_vertices) displacement at the vertices from the dof vector ``u``."""
        return np.asarray(u)[self.nodal_dofs]

    def outward_normals(self, facets: np.ndarray) -> np.ndarray:
        """(2, n) unit outward normals of the boundary facets ``facets``."""
        p = self.mesh.p
        a, b = p[:, self.mesh.facets[0, facets]], p[:, self.mesh.facets[1, facets]]
        t = b - a
        n = np.vstack([t[1], -t[0]]) / np.linalg.norm(t, axis=0)
        elem = self.mesh.f2t[0, facets]
        centroid = p[:, self.mesh.t[:, elem]].mean(axis=1)
        flip = np.sum(n * (0.5 * (a + b) - centroid), axis=0) < 0
        n[:, flip] *= -1.0
        return n

    # ------------------------------------------------------------------ loads
    def traction_load(self, label: str, traction) -> np.ndarray:
        """Load vector  int_{Gamma_label} t . v ds  for a traction ``t``: a constant
        (tx, ty) or a callable (x, y) -> (tx, ty) evaluated at the quadrature points."""
        facets = self.boundary_facets(label)
        fb = FacetBasis(self.mesh, self.basis.elem, facets=facets, intorder=2)
        if callable(traction):
            func = traction
        else:
            tc = np.asarray(traction, dtype=float)
            if tc.shape != (2,):
                raise ValueError(f"traction must be a pair (tx, ty) or callable, got {traction!r}")
            func = None

        @LinearForm
        def load(v, w):
            if func is None:
                tx, ty = tc[0], tc[1]
            else:
                tx, ty = func(w.x[0], w.x[1])
            return tx * v[0] + ty * v[1]

        return asm(load, fb)

    def energy_norm(self, u: np.ndarray) -> float:
        return float(np.sqrt(max(u @ (self.K @ u), 0.0)))
