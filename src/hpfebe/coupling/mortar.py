"""Mortar projection between two non-matching contact meshes (Section 4.3.3, (4.50),
(4.87)).

For a function Phi^2 in X^2_hp (traces of V^2_hp on Gamma^2_C) its mortar projection
Phi^1 = pi^1_hp Phi^2 in X^1_hp (traces of V^1_hp on Gamma^1_C = the mortar space M^1_hp)
is defined by (4.87)

    int_{Gamma_C} Phi^1 Psi^1 ds = int_{Gamma_C} Phi^2 Psi^1 ds    for all Psi^1 in M^1_hp,

algebraically Phi^1 = D^-1 B Phi^2 with the mass matrix D of M^1_hp and the mixed mass
matrix B; tractions (functionals on X^1_hp) are transferred by the adjoint
pi^1*_hp R = B^T D^-T R.

The two contact boundaries are different curves (body 1's arc and body 2's straight
side, with a gap between them); a point of Gamma^1_C is paired with the point of
Gamma^2_C having the same parameter s = x . ``axis`` (default: the x-coordinate, i.e. the
projection along the normal of a horizontal Gamma^2_C).  Both contact zones must be
graphs over s.  Gamma_C in (4.87) is Gamma^1_C with its arc length ds: the integrals are
taken on the common refinement of the two meshes in s (all element end points of both
zones), on every piece by Gauss-Legendre with max(p1, p2) + 1 points, which is exact:
on a piece both element maps are affine in s, ds/d s is constant, so the
integrand is a polynomial of degree p1 + p2 <= 2 max(p1, p2) in s.  (The closed-curve
:func:`hpfebe.geometry.common_refinement` does not fit: the two zones are open pieces of
two different boundaries; the refinement here is the merge of their break points in s.)

Scalar dofs: ``dofs1`` / ``dofs2``, the dofs of the two :class:`ContinuousSpace` whose
basis functions do not vanish on the contact elements (closure, end points included).
Vector fields are interleaved (2 d + c) and transferred component by component.
The traces of Q1 bodies on rectangles are P1 boundary meshes through their boundary
vertices (:func:`fe_trace_mesh`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..checks import array, choice, instance
from ..geometry import BoundaryMesh
from ..quadrature import gauss_legendre, gauss_lobatto
from ..spaces import ContinuousSpace

SIDES = ("bottom", "right", "top", "left")


def fe_trace_mesh(mesh, contact: str):
    """The boundary of a rectangle FE mesh (labelled "bottom", "right", "top", "left",
    :func:`hpfebe.fem.elasticity.rectangle_mesh`) as a P1 :class:`BoundaryMesh` through
    its boundary vertices, the side ``contact`` labelled "C", and the FE vertex of every
    dof of the :class:`ContinuousSpace` on it.  Returns (boundary mesh, space, vertex)."""
    if contact not in SIDES:
        raise ValueError(f"contact must be one of {SIDES}, got {contact!r}")
    b = mesh.boundaries or {}
    if any(s not in b for s in SIDES):
        raise ValueError(f"mesh must have the boundaries {SIDES}, got {sorted(b)}")
    lo, hi = mesh.p.min(axis=1), mesh.p.max(axis=1)
    corners = [(lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1])]
    n = [len(b[s]) for s in SIDES]
    labels = ["C" if s == contact else s for s in SIDES]
    bm = BoundaryMesh.polygon(corners, n=n, labels=labels, p=1)
    space = ContinuousSpace(bm)
    used = np.unique(bm.elements)                     # vertex dofs in ContinuousSpace order
    pts = bm.nodes[used]
    d = np.linalg.norm(pts[:, None, :] - mesh.p.T[None, :, :], axis=2)
    vertex = np.argmin(d, axis=1)
    scale = float(np.max(hi - lo))
    if d[np.arange(len(pts)), vertex].max() > 1e-9 * scale:
        raise ValueError("mesh must be a uniform rectangle mesh (its boundary vertices "
                         "equally spaced on every side)")
    return bm, space, vertex


def _zone(mesh: BoundaryMesh, label: str, axis: np.ndarray, name: str):
    instance(name, mesh, BoundaryMesh)
    els = np.flatnonzero(mesh.labels == label)
    if els.size == 0:
        raise ValueError(f"label{name[-1]}: mesh {name} has no element labelled {label!r}, "
                         "the mortar space has no support")
    sa, sb = mesh.a[els] @ axis, mesh.b[els] @ axis
    if np.any(np.abs(sb - sa) <= 1e-12 * mesh.scale):
        raise ValueError(f"{name}: the contact zone {label!r} is not a graph over the axis "
                         "(an element is perpendicular to it)")
    lo, hi = np.minimum(sa, sb), np.maximum(sa, sb)
    order = np.argsort(lo)
    if np.any(lo[order][1:] < hi[order][:-1] - 1e-12 * mesh.scale):
        raise ValueError(f"{name}: the contact zone {label!r} is not a graph over the axis "
                         "(elements overlap in the parameter)")
    return els, sa, sb, lo, hi


def _check_cover(s0: float, s1: float, lo2, hi2, label1: str, label2: str) -> None:
    """ValueError unless Gamma^2_C covers Gamma^1_C along the axis: (4.87) pairs every
    point of Gamma^1_C with a point of Gamma^2_C, and a point of Gamma^1_C without a
    partner would get the obstacle of a zero Phi^2 (measured: 9-47 % wrong at the
    uncovered nodes of a stamp shifted by 0.5 or overhanging the work piece, with every
    solver reporting converged).  Tolerance: 1e-9 of the length of Gamma^1_C in s."""
    tol = 1e-9 * (s1 - s0)
    a, b = float(lo2.min()), float(hi2.max())
    if s0 >= a - tol and s1 <= b + tol:
        return
    gaps = [f"[{s0:.6g}, {min(a, s1):.6g}]"] if s0 < a - tol else []
    gaps += [f"[{max(b, s0):.6g}, {s1:.6g}]"] if s1 > b + tol else []
    raise ValueError(
        f"mesh2: Gamma^2_C (label2 {label2!r}, on [{a:.6g}, {b:.6g}] along the axis) must "
        f"cover Gamma^1_C (label1 {label1!r} of mesh1, on [{s0:.6g}, {s1:.6g}]); the "
        f"part{'s' if len(gaps) > 1 else ''} {' and '.join(gaps)} of Gamma^1_C ha"
        f"{'ve' if len(gaps) > 1 else 's'} no partner on Gamma^2_C.  Label only the "
        "covered elements of mesh1 as the contact zone, or exchange the bodies (the "
        "mortar side must be the shorter one)")


class MortarProjection:
    """Mortar projection pi^1_hp: X^2_hp -> X^1_hp (4.87) and its adjoint.

    Parameters
    ----------
    mesh1, mesh2
        BoundaryMesh of body 1 (mortar side) and body 2
    label1, label2
        contact labels of the two meshes
    axis
        unit vector; the parameter s = x . axis pairs the points of the two zones
    space1, space2
        the ContinuousSpace of each mesh (default: built on the mesh)

    Attributes: ``dofs1``, ``dofs2`` (scalar contact dofs), ``D`` (n1 x n1), ``B``
    (n1 x n2), ``M2`` (n2 x n2, mass matrix of X^2_hp), sparse; ``overlap`` =
    (s_min, s_max) of the common part; ``P`` the dense projection matrix when
    ``test_space="mortar"`` (the mortar space M^1_hp of (4.49) with end-point matching,
    (4.50)), else None (test space all of X^1_hp, D^-1 B as printed in (4.87)).
    """

    def __init__(self, mesh1: BoundaryMesh, mesh2: BoundaryMesh, label1: str = "C",
                 label2: str = "C", axis=(1.0, 0.0), space1: ContinuousSpace | None = None,
                 space2: ContinuousSpace | None = None, test_space: str = "full"):
        self.test_space = choice("test_space", test_space, ("full", "mortar"))
        axis = array("axis", axis, shape=(2,))
        if np.linalg.norm(axis) == 0:
            raise ValueError(f"axis must be a nonzero 2-vector, got {axis!r}")
        axis = axis / np.linalg.norm(axis)
        self.axis = axis
        self.space1 = space1 if space1 is not None else ContinuousSpace(mesh1)
        self.space2 = space2 if space2 is not None else ContinuousSpace(mesh2)
        for k, (sp_, m) in enumerate(((self.space1, mesh1), (self.space2, mesh2)), 1):
            if sp_.mesh is not m:
                raise ValueError(f"space{k} must be built on mesh{k}")
        e1, sa1, sb1, lo1, hi1 = _zone(mesh1, label1, axis, "mesh1")
        e2, sa2, sb2, lo2, hi2 = _zone(mesh2, label2, axis, "mesh2")
        s_min, s_max = max(lo1.min(), lo2.min()), min(hi1.max(), hi2.max())
        tol = 1e-12 * max(mesh1.scale, mesh2.scale)
        if s_max <= s_min + tol:
            raise ValueError(f"mesh2: the contact zones do not overlap (mesh1 on "
                             f"[{lo1.min():.6g}, {hi1.max():.6g}], mesh2 on "
                             f"[{lo2.min():.6g}, {hi2.max():.6g}] along the axis)")
        _check_cover(lo1.min(), hi1.max(), lo2, hi2, label1, label2)
        self.overlap = (float(s_min), float(s_max))
        self.mesh1, self.mesh2 = mesh1, mesh2
        self.dofs1 = self.space1.dofs_on(label1)
        self.dofs2 = self.space2.dofs_on(label2)
        p1 = int(mesh1.degrees[e1].max())
        p2 = int(mesh2.degrees[e2].max())
        nq = max(p1, p2) + 1          # exact for D (degree 2 p1) and B (p1 + p2)
        tq, wq = (np.asarray(v, float) for v in gauss_legendre(nq))
        # D: on the elements of zone 1 (mass matrix of M^1_hp)
        t = np.broadcast_to(tq, (e1.size, nq))
        P1 = self.space1.trace_matrix(np.repeat(e1, nq), t.ravel())
        w = (0.5 * mesh1.lengths[e1])[:, None] * wq[None, :]
        D = P1.T @ sp.diags(w.ravel()) @ P1
        self.D = sp.csr_matrix(D[self.dofs1][:, self.dofs1])
        # M2: mass matrix of X^2_hp on the elements of zone 2 (L2 pairing on Gamma^2_C)
        t2q = np.broadcast_to(tq, (e2.size, nq))
        P2 = self.space2.trace_matrix(np.repeat(e2, nq), t2q.ravel())
        w2 = (0.5 * mesh2.lengths[e2])[:, None] * wq[None, :]
        self.M2 = sp.csr_matrix((P2.T @ sp.diags(w2.ravel()) @ P2)[self.dofs2][:, self.dofs2])
        # B: on the common refinement of both zones in s, restricted to the overlap
        brk = np.unique(np.concatenate([lo1, hi1, lo2, hi2]))
        brk = brk[(brk >= s_min - tol) & (brk <= s_max + tol)]
        brk = np.clip(brk, s_min, s_max)
        keep = np.concatenate([[True], np.diff(brk) > tol])
        brk = brk[keep]
        a, b = brk[:-1], brk[1:]
        mid = 0.5 * (a + b)
        k1 = self._owner(mid, lo1, hi1, "mesh1")
        k2 = self._owner(mid, lo2, hi2, "mesh2")
        s = (0.5 * (a + b))[:, None] + (0.5 * (b - a))[:, None] * tq[None, :]   # (npc, nq)
        t1 = 2.0 * (s - sa1[k1][:, None]) / (sb1 - sa1)[k1][:, None] - 1.0
        t2 = 2.0 * (s - sa2[k2][:, None]) / (sb2 - sa2)[k2][:, None] - 1.0
        jac = mesh1.lengths[e1[k1]] / np.abs(sb1 - sa1)[k1]                   # ds / d s
        wB = (0.5 * (b - a) * jac)[:, None] * wq[None, :]
        Q1 = self.space1.trace_matrix(np.repeat(e1[k1], nq), np.clip(t1, -1, 1).ravel())
        Q2 = self.space2.trace_matrix(np.repeat(e2[k2], nq), np.clip(t2, -1, 1).ravel())
        B = Q1.T @ sp.diags(wB.ravel()) @ Q2
        self.B = sp.csr_matrix(B[self.dofs1][:, self.dofs2])
        self._lu = spla.splu(sp.csc_matrix(self.D))
        self.pieces = np.column_stack([a, b])
        self._zones = ((e1, sa1, sb1, lo1, hi1), (e2, sa2, sb2, lo2, hi2))
        self.P = self._mortar_matrix() if test_space == "mortar" else None

    def _mortar_matrix(self) -> np.ndarray:
        """The projection (4.50) with the mortar space M^1_hp of (4.49) as test space:
        pi Phi = Phi at the two end points of Gamma_C (the paired points of Gamma^2_C)
        and int (Phi - pi Phi) Psi ds = 0 for the Psi of N^1_hp whose degree on the two
        end elements is p_I - 1.  A Psi of M^1_hp is the N^1_hp function c = E m whose
        end-point coefficient is the extrapolation of its other GLL values on the end
        element (Lagrange polynomial of degree p - 1).  Returns the dense matrix of
        Phi^2 (on dofs2) -> Phi^1 (on dofs1)."""
        e1, sa1, sb1, lo1, hi1 = self._zones[0]
        if e1.size < 2:
            raise ValueError("mesh1: test_space='mortar' needs at least two contact "
                             "elements on mesh1 (the end elements lose one degree)")
        pos = -np.ones(self.space1.ndof, dtype=np.int64)
        pos[self.dofs1] = np.arange(self.dofs1.size)
        n1 = self.dofs1.size
        ends, rows = [], []
        for k, s_end in ((np.argmin(lo1), lo1.min()), (np.argmax(hi1), hi1.max())):
            el = e1[k]
            p = int(self.mesh1.degrees[el])
            tn, _ = gauss_lobatto(p + 1)
            kb = 0 if abs(sa1[k] - s_end) <= abs(sb1[k] - s_end) else p
            others = np.array([j for j in range(p + 1) if j != kb])
            # Lagrange polynomials of degree p - 1 on the other nodes, at t_kb
            ell = np.array([np.prod([(tn[kb] - tn[m]) / (tn[j] - tn[m])
                                     for m in others if m != j]) for j in others])
            d = self.space1.elem_dofs[el]
            ends.append(pos[d[kb]])
            rows.append((pos[d[others]], ell))
        ends = np.array(ends)
        interior = np.setdiff1d(np.arange(n1), ends)
        E = np.zeros((n1, interior.size))
        E[interior, np.arange(interior.size)] = 1.0
        col = -np.ones(n1, dtype=np.int64)
        col[interior] = np.arange(interior.size)
        for eb, (od, ell) in zip(ends, rows):
            E[eb, col[od]] += ell
        # end-point values: Phi^2 at the paired points of the overlap's ends
        s_ends = np.clip([lo1.min(), hi1.max()], *self.overlap)
        e2, t2, _ = self.locate(s_ends, 2)
        T = self.space2.trace_matrix(e2, t2).toarray()[:, self.dofs2]
        D, B = self.D.toarray(), self.B.toarray()
        K = E.T @ D[:, interior]
        P = np.zeros((n1, self.dofs2.size))
        P[ends] = T
        P[interior] = np.linalg.solve(K, E.T @ (B - D[:, ends] @ T))
        return P

    def parameter(self, points) -> np.ndarray:
        """The pairing parameter s = x . axis of points."""
        return np.asarray(points, dtype=float) @ self.axis

    def locate(self, s, side: int):
        """(elem, t, inside) of the points with parameter ``s`` on the contact zone of
        mesh ``side`` (1 or 2); ``inside`` False (elem -1) outside the zone."""
        if side not in (1, 2):
            raise ValueError(f"side must be 1 or 2, got {side!r}")
        e, sa, sb, lo, hi = self._zones[side - 1]
        s = np.atleast_1d(np.asarray(s, dtype=float))
        order = np.argsort(lo)
        k = order[np.clip(np.searchsorted(lo[order], s, side="right") - 1, 0, len(lo) - 1)]
        tol = 1e-12 * (hi.max() - lo.min())
        inside = (s >= lo[k] - tol) & (s <= hi[k] + tol)
        t = np.clip(2.0 * (s - sa[k]) / (sb[k] - sa[k]) - 1.0, -1.0, 1.0)
        return np.where(inside, e[k], -1), np.where(inside, t, np.nan), inside

    @staticmethod
    def _owner(s, lo, hi, name):
        order = np.argsort(lo)
        k = np.searchsorted(lo[order], s, side="right") - 1
        k = order[np.clip(k, 0, len(lo) - 1)]
        if np.any((s < lo[k]) | (s > hi[k])):
            raise ValueError(f"{name}: the contact zone has a hole inside the overlap")
        return k

    # ------------------------------------------------------------------ transfer
    def _apply(self, v, n_in, op):
        v = np.asarray(v, dtype=float)
        if v.ndim != 1 or v.size not in (n_in, 2 * n_in):
            raise ValueError(f"vector must have {n_in} (scalar) or {2 * n_in} (interleaved "
                             f"2-component) entries, got shape {v.shape}")
        comps = v.size // n_in
        out = op(v.reshape(n_in, comps))
        return np.asarray(out).ravel()

    def project(self, phi2) -> np.ndarray:
        """pi^1_hp Phi^2 = D^-1 B Phi^2 (coefficients on ``dofs1``) of Phi^2 given by its
        coefficients on ``dofs2`` (scalar, or interleaved vector)."""
        if self.P is not None:
            return self._apply(phi2, self.dofs2.size, lambda V: self.P @ V)
        return self._apply(phi2, self.dofs2.size, lambda V: self._lu.solve(self.B @ V))

    def riesz(self, r1) -> np.ndarray:
        """The function R in X^1_hp with int R Psi ds = r1(Psi) for all Psi in X^1_hp:
        D^-1 r1 (scalar or interleaved)."""
        return self._apply(r1, self.dofs1.size, lambda V: self._lu.solve(V))

    def pair2(self, phi2) -> np.ndarray:
        """The functional W -> int Phi^2 W ds on X^2_hp of a function Phi^2: M2 Phi^2."""
        return self._apply(phi2, self.dofs2.size, lambda V: self.M2 @ V)

    def adjoint(self, r1) -> np.ndarray:
        """pi^1*_hp R = B^T D^-T R of a functional R on X^1_hp (values on ``dofs1``),
        a functional on X^2_hp (values on ``dofs2``)."""
        if self.P is not None:
            return self._apply(r1, self.dofs1.size, lambda V: self.P.T @ V)
        BT = self._transpose_B()
        return self._apply(r1, self.dofs1.size, lambda V: BT @ self._lu.solve(V, trans="T"))

    def _transpose_B(self):
        """B^T (the sparse matrix ``self.B.T``), formed once per B: the adjoint is applied
        in every DtN iteration and forming the transpose costs more than the product."""
        cached = self.__dict__.get("_BT")
        if cached is None or cached[0] is not self.B:
            cached = self.__dict__["_BT"] = (self.B, self.B.T)
        return cached[1]
