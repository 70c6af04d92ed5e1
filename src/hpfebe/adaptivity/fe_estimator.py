"""Residual a posteriori error estimate for finite elements (Section 3.3.2).

Indicator (3.100) per cell K, for -div sigma(u) = f with sigma(u) = grad u (Poisson) or
the Hooke stress of linear elasticity (vector fields, :func:`lame_stress`):

    eta_F(K)^2 = h_K^2 || f + div sigma(U) ||^2_{L2(K)}
               + 1/2 sum_{E in dK interior}  h_E || [sigma(U) n] ||^2_{L2(E)}
               + sum_{E in dK cap Gamma_N}   h_E || t_hat - sigma(U) n ||^2_{L2(E)}
               (+ the same with P_n n + P_t t on Gamma_C: pass it as the datum of "C").

The factor 1/2 shares every interior edge between its two cells, so that sum_K eta_F(K)^2
counts it once.  h_K is the cell diameter (longest edge), h_E the edge length.  For P1 and
Q1 (on affine cells) div sigma(U) = 0 in every cell, so the volume term is h_K^2 ||f||^2.
Only degree 1 is accepted (scikit-fem's H1 elements give no second derivatives; the
thesis's h-adaptive FE examples are low order).

Error measure (3.99) without penalty terms: |||u - U|||_F^2 = a(u - U, u - U) =
|| grad (u - U) ||^2_{L2(Omega)} for Poisson, see :func:`energy_error`.

Two bodies in contact (Section 4.2.8, :func:`two_body_indicators`): each body gets its
own indicator (3.100); the datum on Gamma_C ("P_n n + P_t t") is the discrete penalty
traction on the slave, p_n n_m - t_t t_m at the slave contact points (sign convention of
:mod:`hpfebe.contact.two_body`), interpolated linearly along a straight interface
(:func:`contact_traction_datum`), and its negative on the master at the same interface
coordinate.
"""

from __future__ import annotations

import numpy as np
from skfem import Basis, ElementQuad1, ElementTriP1, FacetBasis, Functional, InteriorFacetBasis
from skfem.quadrature import get_quadrature
from skfem.helpers import grad

from ..checks import array, choice, integer
from ..fem.meshes import cell_diameter, facet_containing
from ..constitutive.materials import lame_constants, linear_stress


def _facet_length(mesh, facets) -> np.ndarray:
    f = mesh.facets[:, facets]
    return np.linalg.norm(mesh.p[:, f[0]] - mesh.p[:, f[1]], axis=0)


def lame_stress(E: float, nu: float, plane: str = "strain"):
    """sigma(grad u) of linear elasticity (plane strain or plane stress) as a callable on
    gradient arrays G[i, j] = du_i/dx_j (shape (2, 2, ...))."""
    return hooke_stress(*lame_constants(E, nu, plane))


def hooke_stress(lam: float, mu: float):
    """sigma(grad u) = 2 mu eps + lambda tr(eps) I, eps = sym grad u, as a callable on
    gradient arrays G[i, j] = du_i/dx_j (shape (2, 2, ...))."""
    def sigma(G):
        return linear_stress(0.5 * (G + np.swapaxes(G, 0, 1)), lam, mu)

    return sigma


def _normal_flux(F, n):
    """sigma n: (2, ...) . n -> (...) for scalars, (d, 2, ...) . n -> (d, ...)."""
    if F.ndim == n.ndim:
        return np.sum(F * n, axis=0)
    return np.einsum("ij...,j...->i...", F, n)


def _sq(r):
    r = np.asarray(r)
    return r ** 2 if r.ndim <= 2 else np.sum(r ** 2, axis=0)


def fe_indicators(basis: Basis, U, f=None, tractions: dict | None = None,
                  return_parts: bool = False, intorder: int | None = None, stress=None,
                  method: str = "auto"):
    """eta_F(K) of (3.100) per cell (not squared) for the solution U in ``basis``.

    ``f(x, y)`` is the volume source (None: zero; shape (d, ...) for vector fields);
    ``tractions`` maps a boundary name of ``basis.mesh.boundaries`` to the prescribed
    traction t_hat(x, y, nx, ny) on it (Neumann, or the contact traction on "C").
    Boundary facets with other names (Dirichlet) carry no term.  ``stress`` maps the
    gradient of U to sigma(U) (default: identity, i.e. Poisson; :func:`lame_stress` for
    elasticity with a vector basis).  ``intorder``: facet quadrature order (default 4).
    ``method``: "cellwise" (P1 triangles only: sigma(U) is constant per cell, so the
    jumps are constant per edge and are integrated in closed form, the boundary terms
    with the facet rule of scikit-fem evaluated by hand; about 20x faster), "quadrature"
    (scikit-fem facet bases, any P1 / Q1 mesh) or "auto" (cellwise where it applies).
    Both give the same indicator to round-off (tests/adaptivity)."""
    mesh = basis.mesh
    elem = basis.elem
    nc = mesh.t.shape[1]
    hK = cell_diameter(mesh)
    U = array("U", U, shape=(basis.N,))
    sig = (lambda G: G) if stress is None else stress
    scalar = getattr(elem, "elem", elem)   # ElementVector wraps the scalar element
    if not isinstance(scalar, (ElementTriP1, ElementQuad1)):
        raise ValueError("basis element must be P1 or Q1 (div sigma(U) = 0 per cell), got "
                         f"{type(scalar).__name__}: scikit-fem's H1 elements provide no "
                         "second derivatives for the volume residual of higher degrees")
    intorder = 4 if intorder is None else integer("intorder", intorder, lo=1)
    choice("method", method, ("auto", "cellwise", "quadrature"))
    cellwise = isinstance(scalar, ElementTriP1)
    if method == "cellwise" and not cellwise:
        raise ValueError("method='cellwise' needs P1 triangles (sigma(U) constant per "
                         f"cell), got {type(scalar).__name__}")
    cellwise = cellwise and method != "quadrature"
    for name in tractions or {}:
        if name not in (mesh.boundaries or {}):
            raise ValueError(f"tractions: boundary {name!r} not in mesh.boundaries "
                             f"({sorted(mesh.boundaries or {})})")

    # volume residual h_K^2 ||f + div sigma(U)||^2 (div sigma(U) = 0 for P1, Q1 on rectangles)
    vol = np.zeros(nc)
    if f is not None:
        @Functional
        def res2(w):
            return _sq(f(w.x[0], w.x[1]))
        vol = hK ** 2 * res2.elemental(basis)

    terms = _cellwise_terms if cellwise else _quadrature_terms
    jump, bnd = terms(basis, U, sig, tractions or {}, intorder)
    eta = np.sqrt(vol + jump + bnd)
    if return_parts:
        return eta, {"volume": np.sqrt(vol), "jump": np.sqrt(jump), "boundary": np.sqrt(bnd)}
    return eta


def _quadrature_terms(basis: Basis, U, sig, tractions: dict, intorder: int):
    """The jump and boundary terms of (3.100) per cell by scikit-fem's facet bases."""
    mesh, elem = basis.mesh, basis.elem
    nc = mesh.t.shape[1]
    # interior jumps: 1/2 h_E ||[sigma(U) n]||^2 to each neighbour
    jump = np.zeros(nc)
    fb0 = InteriorFacetBasis(mesh, elem, side=0, intorder=intorder)
    fb1 = InteriorFacetBasis(mesh, elem, side=1, intorder=intorder)

    @Functional
    def jump2(w):
        return _sq(_normal_flux(sig(grad(w["u0"])) - sig(grad(w["u1"])), w.n))

    j2 = jump2.elemental(fb0, u0=fb0.interpolate(U), u1=fb1.interpolate(U))
    facets = fb0.find
    hE = _facet_length(mesh, facets)
    cells = mesh.f2t[:, facets]
    np.add.at(jump, cells[0], 0.5 * hE * j2)
    np.add.at(jump, cells[1], 0.5 * hE * j2)

    # Neumann / contact boundary terms
    bnd = np.zeros(nc)
    for name, g in tractions.items():
        fb = FacetBasis(mesh, elem, facets=mesh.boundaries[name], intorder=intorder)

        @Functional
        def nres2(w):
            return _sq(g(w.x[0], w.x[1], w.n[0], w.n[1])
                       - _normal_flux(sig(grad(w["u"])), w.n))

        b2 = nres2.elemental(fb, u=fb.interpolate(U))
        fac = fb.find
        np.add.at(bnd, mesh.f2t[0, fac], _facet_length(mesh, fac) * b2)
    return jump, bnd


def _outward_normals(mesh, facets: np.ndarray) -> np.ndarray:
    """(2, nf) unit normals of ``facets`` pointing out of their cell f2t[0]."""
    a, b = mesh.p[:, mesh.facets[0, facets]], mesh.p[:, mesh.facets[1, facets]]
    d = b - a
    n = np.array([d[1], -d[0]]) / np.linalg.norm(d, axis=0)
    # the vertex of the cell opposite the facet lies on the inner side
    tri = mesh.t[:, mesh.f2t[0, facets]]
    inner = mesh.p[:, tri].sum(axis=1) - a - b
    flip = np.einsum("ij,ij->j", n, inner - 0.5 * (a + b)) > 0
    n[:, flip] *= -1.0
    return n


def _cellwise_terms(basis: Basis, U, sig, tractions: dict, intorder: int):
    """The jump and boundary terms of (3.100) per cell for P1 triangles: sigma(U) is one
    value per cell, so on an interior edge E the jump is constant and
    h_E ||[sigma n]||^2_{L2(E)} = h_E^2 |[sigma n]|^2; the boundary terms with the
    datum at the points of scikit-fem's facet rule of order ``intorder`` (the rule of
    :func:`_quadrature_terms`, whose sums these are to round-off)."""
    mesh = basis.mesh
    nc = mesh.t.shape[1]
    S = sig(basis.interpolate(U).grad[..., 0])        # (2, 2, nc) or (2, nc)
    f2t = mesh.f2t
    inner = np.flatnonzero(f2t[1] >= 0)
    n = _outward_normals(mesh, inner)
    hE = _facet_length(mesh, inner)
    J = _normal_flux(S[..., f2t[0, inner]] - S[..., f2t[1, inner]], n)
    j2 = (np.sum(J ** 2, axis=0) if S.ndim == 3 else J ** 2) * hE ** 2
    jump = np.zeros(nc)
    np.add.at(jump, f2t[0, inner], 0.5 * j2)
    np.add.at(jump, f2t[1, inner], 0.5 * j2)

    bnd = np.zeros(nc)
    X, W = get_quadrature(mesh.brefdom, intorder)
    for name, g in tractions.items():
        fac = mesh.normalize_facets(mesh.boundaries[name])
        cell, nb, L = f2t[0, fac], _outward_normals(mesh, fac), _facet_length(mesh, fac)
        a = mesh.p[:, mesh.facets[0, fac]]
        d = mesh.p[:, mesh.facets[1, fac]] - a
        x = a[:, :, None] + d[:, :, None] * X[0]          # (2, nf, nq) as FacetBasis
        nq = np.broadcast_to(nb[:, :, None], x.shape)
        sn = _normal_flux(S[..., cell], nb)[..., None]
        r2 = _sq(g(x[0], x[1], nq[0], nq[1]) - sn)         # (nf, nq)
        np.add.at(bnd, cell, L * (r2 @ W) * L)
    return jump, bnd


def energy_error(basis: Basis, U, grad_u) -> float:
    """|||u - U|||_F = ||grad(u - U)||_{L2} (3.99 without penalty terms, Poisson);
    ``grad_u(x, y)`` returns the pair (u_x, u_y)."""
    @Functional
    def e2(w):
        gx, gy = grad_u(w.x[0], w.x[1])
        gu = grad(w["u"])
        return (gx - gu[0]) ** 2 + (gy - gu[1]) ** 2

    return float(np.sqrt(e2.assemble(basis, u=basis.interpolate(np.asarray(U, float)))))


def energy_error_elasticity(basis: Basis, U, grad_u, stress) -> float:
    """a(u - U, u - U)^(1/2) = (int sigma(e) : grad e)^(1/2) for elasticity;
    ``grad_u(x, y)`` returns the 2 x 2 array G[i, j] = du_i/dx_j."""
    @Functional
    def e2(w):
        G = np.asarray(grad_u(w.x[0], w.x[1])) - grad(w["u"])
        return np.einsum("ij...,ij...->...", stress(G), G)

    return float(np.sqrt(e2.assemble(basis, u=basis.interpolate(np.asarray(U, float)))))


# --------------------------------------------------------------------------- two bodies
def contact_traction_datum(mesh, label: str, points, tractions, axis: int = 0):
    """The datum t(x, y, nx, ny) -> (2, ...) of (3.100) on the straight contact boundary
    ``label`` of ``mesh`` (along the coordinate x_axis): the tractions (n, 2) at those of
    the ``points`` (n, 2) lying on facets labelled ``label``, interpolated linearly in
    x_axis (constant beyond the first and the last point) and zero outside the extent of
    those facets."""
    if axis not in (0, 1):
        raise ValueError(f"axis must be 0 or 1, got {axis!r}")
    facets = np.asarray((mesh.boundaries or {}).get(label, ()), dtype=np.int64)
    if facets.size == 0:
        raise ValueError(f"label {label!r} names no facets of mesh.boundaries "
                         f"({sorted(mesh.boundaries or {})})")
    pts = np.asarray(points, dtype=float)
    tr = np.asarray(tractions, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or tr.shape != pts.shape:
        raise ValueError(f"points and tractions must both have shape (n, 2), got "
                         f"{pts.shape} and {tr.shape}")
    on = facet_containing(mesh, facets, pts.T) >= 0
    if not on.any():
        raise ValueError(f"no point lies on the facets labelled {label!r}")
    order = np.argsort(pts[on, axis])
    xs, tr = pts[on, axis][order], tr[on][order]
    ends = mesh.p[axis, mesh.facets[:, facets]]
    lo, hi = float(ends.min()), float(ends.max())
    tol = 1e-12 * max(1.0, hi - lo)

    def datum(x, y, nx, ny):
        s = x if axis == 0 else y
        inside = (s >= lo - tol) & (s <= hi + tol)
        return np.array([np.where(inside, np.interp(s, xs, tr[:, c]), 0.0) for c in (0, 1)])

    return datum


def _zero_traction(x, y, nx, ny):
    return np.zeros((2,) + np.shape(x))


def two_body_indicators(problem, result, contact=("C", "C"), free=((), ()), axis: int = 0,
                        intorder: int | None = None):
    """(eta_s, eta_m): indicator (3.100) per cell of the slave and of the master FE body
    of a :class:`hpfebe.contact.two_body.TwoBodyContact` solution ``result``.

    Datum on the slave facets labelled ``contact[0]``: the penalty traction
    p_n n_m - t_t t_m at the slave contact points of positive weight, interpolated by
    :func:`contact_traction_datum` (straight interface along x_axis); on the master facets
    labelled ``contact[1]``: its negative at the same x_axis.  The facets labelled in
    ``free[0]`` / ``free[1]`` are traction free; the others (Dirichlet) carry no term.
    Stress: Hooke's law with each body's Lame constants."""
    if len(contact) != 2 or len(free) != 2:
        raise ValueError(f"contact and free must be (slave, master) pairs, got {contact!r}, "
                         f"{free!r}")
    S, M = problem.slave, problem.master
    for name, body in (("slave", S), ("master", M)):
        if not hasattr(body, "basis"):
            raise ValueError(f"the {name} must be an FE body (ElasticBody), got "
                             f"{type(body).__name__}")
    w = np.asarray(result.weights)
    traction = (result.p_n[:, None] * problem.normals - result.t_t[:, None] * problem.tangents)
    sel = w > 0
    f = contact_traction_datum(S.mesh, contact[0], result.points[sel], traction[sel], axis)

    def on_master(x, y, nx, ny):
        return -f(x, y, nx, ny)

    out = []
    for body, u, lab, g, fr in ((S, result.u_slave, contact[0], f, free[0]),
                                (M, result.u_master, contact[1], on_master, free[1])):
        fr = (fr,) if isinstance(fr, str) else tuple(fr)
        tractions = {lab: g, **{name: _zero_traction for name in fr}}
        out.append(fe_indicators(body.basis, u, stress=hooke_stress(body.lam, body.mu),
                                 tractions=tractions, intorder=intorder))
    return out[0], out[1]
