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
"""

from __future__ import annotations

import numpy as np
from skfem import Basis, ElementQuad1, ElementTriP1, FacetBasis, Functional, InteriorFacetBasis
from skfem.helpers import grad


def _cell_diameter(mesh) -> np.ndarray:
    p, t = mesh.p, mesh.t
    nv = t.shape[0]
    h = np.zeros(t.shape[1])
    for i in range(nv):
        for j in range(i + 1, nv):
            h = np.maximum(h, np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0))
    return h


def _facet_length(mesh, facets) -> np.ndarray:
    f = mesh.facets[:, facets]
    return np.linalg.norm(mesh.p[:, f[0]] - mesh.p[:, f[1]], axis=0)


def lame_stress(E: float, nu: float, plane: str = "strain"):
    """sigma(grad u) of linear elasticity (plane strain or plane stress) as a callable on
    gradient arrays G[i, j] = du_i/dx_j (shape (2, 2, ...))."""
    if not (np.isfinite(E) and E > 0):
        raise ValueError(f"E must be positive, got {E!r}")
    if not (-1.0 < nu < 0.5):
        raise ValueError(f"nu must lie in (-1, 0.5), got {nu!r}")
    if plane not in ("strain", "stress"):
        raise ValueError(f"plane must be 'strain' or 'stress', got {plane!r}")
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    if plane == "stress":
        lam = 2 * lam * mu / (lam + 2 * mu)

    def sigma(G):
        eps = 0.5 * (G + np.swapaxes(G, 0, 1))
        tr = eps[0, 0] + eps[1, 1]
        eye = np.eye(2).reshape((2, 2) + (1,) * (G.ndim - 2))
        return lam * tr * eye + 2 * mu * eps

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
                  return_parts: bool = False, intorder: int | None = None, stress=None):
    """eta_F(K) of (3.100) per cell (not squared) for the solution U in ``basis``.

    ``f(x, y)`` is the volume source (None: zero; shape (d, ...) for vector fields);
    ``tractions`` maps a boundary name of ``basis.mesh.boundaries`` to the prescribed
    traction t_hat(x, y, nx, ny) on it (Neumann, or the contact traction on "C").
    Boundary facets with other names (Dirichlet) carry no term.  ``stress`` maps the
    gradient of U to sigma(U) (default: identity, i.e. Poisson; :func:`lame_stress` for
    elasticity with a vector basis).  ``intorder``: facet quadrature order (default 4)."""
    mesh = basis.mesh
    elem = basis.elem
    nc = mesh.t.shape[1]
    hK = _cell_diameter(mesh)
    U = np.asarray(U, dtype=float)
    if U.shape != (basis.N,):
        raise ValueError(f"U must have {basis.N} entries (basis.N), got shape {U.shape}")
    sig = (lambda G: G) if stress is None else stress
    scalar = getattr(elem, "elem", elem)   # ElementVector wraps the scalar element
    if not isinstance(scalar, (ElementTriP1, ElementQuad1)):
        raise ValueError("basis element must be P1 or Q1 (div sigma(U) = 0 per cell), got "
                         f"{type(scalar).__name__}: scikit-fem's H1 elements provide no "
                         "second derivatives for the volume residual of higher degrees")
    if intorder is None:
        intorder = 4

    # volume residual h_K^2 ||f + div sigma(U)||^2 (div sigma(U) = 0 for P1, Q1 on rectangles)
    vol = np.zeros(nc)
    if f is not None:
        @Functional
        def res2(w):
            return _sq(f(w.x[0], w.x[1]))
        vol = hK ** 2 * res2.elemental(basis)

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
    for name, g in (tractions or {}).items():
        if name not in (mesh.boundaries or {}):
            raise ValueError(f"tractions: boundary {name!r} not in mesh.boundaries "
                             f"({sorted(mesh.boundaries or {})})")
        fb = FacetBasis(mesh, elem, facets=mesh.boundaries[name], intorder=intorder)

        @Functional
        def nres2(w):
            return _sq(g(w.x[0], w.x[1], w.n[0], w.n[1])
                       - _normal_flux(sig(grad(w["u"])), w.n))

        b2 = nres2.elemental(fb, u=fb.interpolate(U))
        fac = fb.find
        np.add.at(bnd, mesh.f2t[0, fac], _facet_length(mesh, fac) * b2)

    eta = np.sqrt(vol + jump + bnd)
    if return_parts:
        return eta, {"volume": np.sqrt(vol), "jump": np.sqrt(jump), "boundary": np.sqrt(bnd)}
    return eta


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
