"""Exact integration of the normal penalty term (U_n - g_h)_+ on the contact elements of a
BE body against a rigid obstacle (Section 3.2, the discrete form (3.57)-(3.58)).

g is replaced by its nodal interpolant g_h in V_hp, so that the penetration
U_n - g_h is a polynomial of degree p_I on each contact element; its real roots split
the element and Gauss rules with p_I + 1 points on the positive pieces integrate
(U_n - g_h)_+ v_n, its derivative and (U_n - g_h)_+^2 exactly.  The points depend on U:
:meth:`ExactPositivePart.points` gives them for the current iterate, and the contact
problem (:class:`hpfebe.contact.two_body.TwoBodyContact` with ``quadrature="exact"``)
evaluates the one penalty law of :mod:`hpfebe.constitutive.laws` there.
"""

from __future__ import annotations

import numpy as np

from ..quadrature import gauss_legendre, gauss_lobatto
from ..spaces import lagrange_values


def gap_nodes(mesh, elems, gap) -> list:
    """The gap g at the GLL nodes of every contact element (its interpolant g_h)."""
    out = []
    for e in elems:
        p = int(mesh.degrees[e])
        xg, _ = gauss_lobatto(p + 1)
        pts = mesh.points(np.full(p + 1, e), xg)
        if callable(gap):
            gv = np.asarray(gap(pts), dtype=float)
            if gv.size == 1:
                gv = np.full(p + 1, float(gv.ravel()[0]))
            elif gv.size != p + 1:
                raise ValueError(f"gap(x) must return one value per point, got shape "
                                 f"{gv.shape} for {p + 1} points")
            gv = gv.reshape(p + 1)
        else:
            try:
                gv = np.full(p + 1, float(gap))
            except (TypeError, ValueError):
                raise ValueError(f"gap must be a float or a callable, got {gap!r}") from None
        if not np.all(np.isfinite(gv)):
            raise ValueError("gap must be finite on Gamma_C")
        out.append(gv)
    return out


def positive_pieces(p: int, w_nodes: np.ndarray) -> list:
    """Sub-intervals of [-1, 1] where the degree-p polynomial with GLL nodal values
    w_nodes is positive (exact roots)."""
    xg, _ = gauss_lobatto(p + 1)
    if np.all(w_nodes <= 0) and p == 1:
        return []
    # monomial coefficients by interpolation at the GLL nodes
    c = np.linalg.solve(np.vander(xg, p + 1), w_nodes)
    roots = np.roots(c) if np.any(c[:-1] != 0) else np.array([])
    r = np.sort(np.real(roots[(np.abs(np.imag(roots)) < 1e-12)]))
    br = np.concatenate([[-1.0], r[(r > -1) & (r < 1)], [1.0]])
    return [(a, b) for a, b in zip(br[:-1], br[1:])
            if b - a > 0 and np.polyval(c, 0.5 * (a + b)) > 0]


class ExactPositivePart:
    """The contact elements ``elems`` of a BE body (V_hp^2 interleaved) with the nodal
    gap g_h: nodal penetrations and the U-dependent Gauss points of the positive pieces."""

    def __init__(self, mesh, space, elems, gap):
        self.mesh, self.space = mesh, space
        self.elems = np.asarray(elems)
        self.g_nodes = gap_nodes(mesh, self.elems, gap)

    def nodal_penetration(self, U) -> list:
        """U_n - g_h at the GLL nodes of every contact element."""
        out = []
        for e, gn in zip(self.elems, self.g_nodes):
            p = int(self.mesh.degrees[e])
            d = self.space.elem_dofs[e, :p + 1]
            n = self.mesh.normals[e]
            out.append(U[2 * d] * n[0] + U[2 * d + 1] * n[1] - gn)
        return out

    def key(self, U) -> bytes:
        """The nodal contact pattern (for cycling detection)."""
        return np.signbit(np.concatenate(self.nodal_penetration(U))).tobytes()

    def points(self, U) -> dict:
        """Gauss points of the positive pieces: element ids, parameters s in [0, 1],
        weights of ds, g_h at the points, and the number of elements in contact."""
        ids, ss, ws, gs = [], [], [], []
        n_active = 0
        for e, gn, w in zip(self.elems, self.g_nodes, self.nodal_penetration(U)):
            p = int(self.mesh.degrees[e])
            pieces = positive_pieces(p, w)
            n_active += bool(pieces)
            xq, wq = gauss_legendre(p + 1)
            for a, b in pieces:
                t = a + (b - a) * 0.5 * (xq + 1.0)
                ids.append(np.full(t.size, e))
                ss.append(0.5 * (t + 1.0))
                ws.append(wq * (b - a) * 0.5 * self.mesh.lengths[e] * 0.5)
                gs.append(lagrange_values(p, t) @ gn)
        cat = (lambda v, dt=float: np.concatenate(v) if v else np.zeros(0, dtype=dt))
        return dict(ids=cat(ids, np.int64), s=cat(ss), weights=cat(ws), g0=cat(gs),
                    n_active=n_active)

    def pressure(self, U, eps: float):
        """(p_eps(elem, t) callable, (x, p) at the GLL nodes of Gamma_C), p_eps =
        (1/eps)(U_n - g_h)_+ >= 0."""
        pen = dict(zip(self.elems.tolist(), self.nodal_penetration(U)))

        def p_eps(elem, t):
            if elem not in pen:
                raise ValueError(f"elem {elem} is not a contact element")
            p = int(self.mesh.degrees[elem])
            return np.maximum(lagrange_values(p, np.atleast_1d(t)) @ pen[elem], 0.0) / eps

        xs = [self.mesh.points(np.full(len(w), e), gauss_lobatto(len(w))[0])
              for e, w in pen.items()]
        ps = [np.maximum(w, 0.0) / eps for w in pen.values()]
        return p_eps, (np.vstack(xs), np.concatenate(ps))
