"""Residual a posteriori error estimate for the Galerkin BEM (Section 3.3.3).

Laplace (below), Lame (same indicator with vector residuals), and the contact part of
Section 3.3.5 (end of the module): the datum P_n n + P_t t of (3.107) from the penalty
law of :mod:`hpfebe.constitutive.laws`, the indicator with a weighted consistency term,
|||U|||_B of a discrete penalty solution, and the error |||U_ref - U|||_B against a
reference on a nested finer mesh.

Setting (3.90)/(3.95) without contact: U in V_hp, U = 0 on Gamma_D (the space
H~^(1/2)(Sigma), Sigma = Gamma minus Gamma_D), <S_hat U, V> = <t_hat, V>_{Gamma_N}, and the
traction-like functions (3.104)

    psi = V^-1 (K + 1/2) u,    Psi = i_h V_h^-1 i_h^* (K + 1/2) U     (the Galerkin Psi).

Indicator (3.107) per boundary element I (contact part: the same with P_n n + P_t t in
place of t_hat, pass it as the datum of the label "C"):

    eta_h(I)^2 = h_I || t_hat - S_hat U ||^2_{L2(I cap Gamma_N)}
               + h_I || d/ds (V Psi - (K + 1/2) U) ||^2_{L2(I)}.

Error measure (3.105) without the penalty terms:

    |||u - U|||_B^2 = ||u - U||^2_{H~1/2(Sigma)} + ||psi - Psi||^2_{H^-1/2(Gamma)},

realised as |u - U|_W^2 + ||psi - Psi||_V^2 (equivalent norms: <W.,.> is elliptic on
H~^(1/2)(Sigma) when Gamma_D has positive length, <V.,.> on H^-1/2), each on a richer
space (:mod:`hpfebe.analysis.norms`).

How the functions on Gamma are evaluated (and why).  Both residuals are L2 functions with
logarithmic singularities at the element ends (where Psi and dU/ds jump), so a Galerkin
projection onto a richer discrete space would need the pairing <W U, phi> with
discontinuous phi, which the Maue form does not provide.  Instead they are evaluated
pointwise at quadrature points *on* Gamma through two exact identities of the 2D Laplace
operators, which reduce everything to one weakly singular kernel, grad_x G:

    W U           = - d/ds V (dU/ds)                          (Maue, pointwise),
    d/ds (K + 1/2) U = - (K' - 1/2) (dU/ds)                    (conjugate harmonic),

so that with g[f](x) = PV int grad_x G(x, y) f(y) ds_y  (:mod:`._ongamma`, exact Cauchy
principal value on the element of x, adaptive Gauss on the others), U' = dU/ds in W_hp:

    S_hat U = W U + (K' + 1/2) Psi      = - g[U'] . t + g[Psi] . n + Psi / 2,
    d/ds (V Psi - (K + 1/2) U)          =   g[Psi] . t + g[U'] . n - U' / 2.

Both identities are checked to round-off in tests/adaptivity/test_adaptivity.py (Calderon: W u =
(1/2 - K') psi for an exact harmonic pair).  The L2(I) norms use composite Gauss on a mesh
of I graded geometrically towards both ends (the log singularities); against a rule with
8 grading levels and 8 more points per interval the indicators change by < 0.4 %.

Psi is the operator class's Psi(U): with ``zero_flux=True`` (the default of LaplaceBEM)
it is constrained to zero total flux, so V Psi - (K + 1/2) U is L2-orthogonal to W_hp
only up to a constant; d/ds removes the constant, so the indicator is unaffected.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..analysis.norms import energy_error_dirichlet, energy_error_neumann, neumann_functional
from ..checks import array, callable_returning, real
from ..constitutive.laws import penalty_friction
from ..quadrature import gauss_legendre
from ._ongamma import grad_single_layer_on_gamma


def _call_datum(f, x, n, elem, t):
    """A prescribed traction f(x, n), or f(x, n, elem, t) when it needs the element and
    reference coordinate of the points (e.g. the contact traction P_n n + P_t t computed
    from the discrete solution U at those points)."""
    import inspect

    try:
        nparams = len(inspect.signature(f).parameters)
    except (TypeError, ValueError):
        nparams = 2
    return f(x, n, elem, t) if nparams >= 4 else f(x, n)


def graded_rule(m: int, levels: int = 3, sigma: float = 0.2):
    """Composite Gauss rule on [-1, 1] (points, weights), m points per sub-interval, with
    sub-intervals graded geometrically (ratio ``sigma``, ``levels`` levels) towards both
    ends."""
    xg, wg = gauss_legendre(m)
    d = [sigma ** k for k in range(levels, 0, -1)]  # distances from the end, increasing
    left = [-1.0] + [-1.0 + 2 * s for s in d]
    right = [1.0 - 2 * s for s in d[::-1]] + [1.0]
    br = np.array(left + right)
    pts, wts = [], []
    for a, b in zip(br[:-1], br[1:]):
        pts.append(0.5 * (a + b) + 0.5 * (b - a) * xg)
        wts.append(0.5 * (b - a) * wg)
    return np.concatenate(pts), np.concatenate(wts)


def solve_laplace_mixed(op, flux, dirichlet=("D",)):
    """Primal BEM (3.95) without contact: U in V_hp with U = 0 on ``dirichlet`` elements,
    S_hat U = t_hat weakly on the rest.  ``flux(x, n)`` is the Neumann datum t_hat (its
    values on Gamma_D are not used).  Returns (U, Psi)."""
    V = op.V_space
    if not np.any(op.mesh.where(*dirichlet)):
        raise ValueError(f"dirichlet labels {dirichlet!r} select no element: the pure "
                         "Neumann problem is not handled here")
    free = V.free_dofs(*dirichlet)
    F = neumann_functional(V, flux)
    U = np.zeros(V.ndof)
    U[free] = sla.solve(op.S_hat[np.ix_(free, free)], F[free], assume_a="pos")
    return U, op.Psi(U)


def _residual_points(mesh, nq):
    """(elem, t, w): the graded rule with ``nq`` points (default p_max + 3) on every
    element, w the weights of ds."""
    if nq is None:
        nq = int(mesh.degrees.max()) + 3
    tq, wq = graded_rule(nq)
    ne = mesh.n_elements
    elem = np.repeat(np.arange(ne), len(tq))
    return elem, np.tile(tq, ne), np.tile(wq, ne) * mesh.lengths[elem] / 2.0


def boundary_residuals(op, U, Psi, nq: int | None = None):
    """S_hat U and d/ds (V Psi - (K + 1/2) U) at graded quadrature points of every element.

    Returns dict with elem, t, x, n, w (weights of ds), SU, dres."""
    mesh = op.mesh
    W = op.W_space
    elem, t, w = _residual_points(mesh, nq)
    dU = op.T @ np.asarray(U, dtype=float)        # W_hp coefficients of dU/ds (exact)
    gU = grad_single_layer_on_gamma(W, dU, elem, t)
    gP = grad_single_layer_on_gamma(W, Psi, elem, t)
    tan, nrm = mesh.tangents[elem], mesh.normals[elem]
    Psi_x = W.evaluate(Psi, elem, t)
    dU_x = W.evaluate(dU, elem, t)
    SU = -np.sum(gU * tan, 1) + np.sum(gP * nrm, 1) + 0.5 * Psi_x
    dres = np.sum(gP * tan, 1) + np.sum(gU * nrm, 1) - 0.5 * dU_x
    return dict(elem=elem, t=t, x=mesh.points(elem, t), n=nrm,
                w=w, SU=SU, dres=dres)


def bem_indicators(op, U, Psi, tractions: dict, nq: int | None = None,
                   return_parts: bool = False):
    """eta_h(I) of (3.107) per element (not squared).

    ``tractions`` maps a boundary label to the prescribed traction on it, a callable
    ``f(x, n)`` or ``f(x, n, elem, t)`` (points also given as element index and reference
    coordinate in (-1, 1)): t_hat on "N", P_n n + P_t t on "C".  Elements with other labels (e.g.
    Gamma_D) get only the consistency term h_I ||d/ds (V Psi - (K + 1/2) U)||^2."""
    return _indicators(op.mesh, boundary_residuals(op, U, Psi, nq), tractions, 1,
                       return_parts)


def _indicators(mesh, r, tractions: dict, d: int, return_parts: bool):
    """h_I ||dres||^2_I + h_I ||t_hat - S_hat U||^2_I on the labelled elements, summed per
    element from the residuals ``r`` at quadrature points (d components)."""
    h = mesh.lengths
    ne = mesh.n_elements
    dres = np.asarray(r["dres"]).reshape(len(r["elem"]), d)
    SU = np.asarray(r["SU"]).reshape(len(r["elem"]), d)
    cons = h * np.bincount(r["elem"], r["w"] * np.sum(dres ** 2, 1), minlength=ne)
    trac = np.zeros(ne)
    for label, f in tractions.items():
        on = mesh.labels[r["elem"]] == label
        if not np.any(on):
            continue
        data = np.asarray(_call_datum(f, r["x"][on], r["n"][on], r["elem"][on], r["t"][on]),
                          dtype=float).reshape(-1, d)
        trac += h * np.bincount(r["elem"][on], r["w"][on] * np.sum((data - SU[on]) ** 2, 1),
                                minlength=ne)
    eta = np.sqrt(cons + trac)
    if return_parts:
        return eta, {"traction": np.sqrt(trac), "consistency": np.sqrt(cons)}
    return eta


def error_measure_B(op, U, Psi, u_exact, flux_exact, extra: int = 3) -> float:
    """|||u - U|||_B of (3.105) without contact terms: (|u - U|_W^2 + ||psi - Psi||_V^2)^(1/2)
    with exact trace ``u_exact(x, n)`` and exact Neumann datum ``flux_exact(x, n)``."""
    eu = energy_error_dirichlet(op, U, u_exact, extra=extra)
    ep = energy_error_neumann(op, Psi, flux_exact, extra=extra)
    return float(np.hypot(eu, ep))


# ----------------------------------------------------------------------------- Lame
# For Lame the identities above become longer (Guenter derivatives); instead both
# functions are taken as one-sided limits of the discrete representation
#     w = SL Psi - DL U   (Somigliana, :meth:`LameBEM.displacement_gradient`),
# whose interior traces are, by the jump relations (V t = (K + 1/2) u convention),
#     gamma_0 w = V Psi - (K - 1/2) U = (V Psi - (K + 1/2) U) + U,
#     T w       = (K' + 1/2) Psi + W U = S_hat U,
# so that  d/ds (V Psi - (K + 1/2) U) = grad w . t - dU/ds  and  S_hat U = sigma(w) n,
# evaluated at x - delta h_I n.  delta = 1e-5: the limit error is O(delta log delta) at the
# graded quadrature points (>= 4e-4 h_I from the element ends), while the near-boundary
# quadrature of the potentials loses accuracy below ~1e-6 (measured on a linear field:
# 1e-9 at 1e-4, 6e-6 at 1e-6, 0.2 at 1e-8; on a Kelvin field the result is stable for
# delta in [1e-6, 1e-4]).


def lame_boundary_residuals(op, U, Psi, nq: int | None = None, delta: float = 1e-5):
    """Lame analogue of :func:`boundary_residuals`: SU (n, 2) and dres (n, 2)."""
    mesh = op.mesh
    elem, t, w = _residual_points(mesh, nq)
    tan, nrm = mesh.tangents[elem], mesh.normals[elem]
    x = mesh.points(elem, t)
    xin = x - delta * mesh.lengths[elem, None] * nrm
    G = op.displacement_gradient(xin, U, Psi)                 # (n, i, m) = du_i/dx_m
    div = G[:, 0, 0] + G[:, 1, 1]
    S = op.lam * div[:, None, None] * np.eye(2) + op.mu * (G + np.swapaxes(G, 1, 2))
    dU = (op.T @ np.asarray(U, dtype=float)).reshape(-1, 2)
    dU_x = op.W_space.evaluate(dU, elem, t)                   # (n, 2)
    SU = np.einsum("qij,qj->qi", S, nrm)
    dres = np.einsum("qim,qm->qi", G, tan) - dU_x
    return dict(elem=elem, t=t, x=x, n=nrm, w=w,
                SU=SU, dres=dres)


def solve_lame_mixed(op, traction, dirichlet=("D",), u_dirichlet=None):
    """Primal Lame BEM: U in V_hp^2 with U = I_h u_dirichlet (default 0) on the
    ``dirichlet`` elements, S_hat U = t_hat weakly on the rest; ``traction(x, n)`` returns
    (n, 2).  Returns (U, Psi), interleaved."""
    Vs = op.V_space
    if not np.any(op.mesh.where(*dirichlet)):
        raise ValueError(f"dirichlet labels {dirichlet!r} select no element")
    free = Vs.free_dofs(*dirichlet, components=2)
    fixed = np.setdiff1d(np.arange(2 * Vs.ndof), free)
    F = np.column_stack([neumann_functional(Vs, lambda x, n, c=c: traction(x, n)[:, c])
                         for c in range(2)]).ravel()
    U = np.zeros(2 * Vs.ndof)
    if u_dirichlet is not None:
        g = np.column_stack([Vs.interpolate(lambda x, c=c: u_dirichlet(x)[:, c])
                             for c in range(2)]).ravel()
        U[fixed] = g[fixed]
    S = op.S_hat
    rhs = F[free] - S[np.ix_(free, fixed)] @ U[fixed]
    U[free] = sla.solve(S[np.ix_(free, free)], rhs, assume_a="pos")
    return U, op.Psi(U)


def lame_bem_indicators(op, U, Psi, tractions: dict, nq: int | None = None,
                        return_parts: bool = False, delta: float = 1e-5,
                        residuals: dict | None = None):
    """eta_h(I) of (3.107) for Lame (vector residuals, Euclidean norm); ``tractions`` maps
    labels to callables (x, n) -> (n, 2) or (x, n, elem, t) -> (n, 2) (t_hat on "N",
    P_n n + P_t t on "C", see :func:`bem_indicators`).  ``residuals``: the result of
    ``lame_boundary_residuals(op, U, Psi, nq, delta)`` if already computed (the expensive
    part: potentials at every quadrature point; it does not depend on the data)."""
    r = lame_boundary_residuals(op, U, Psi, nq, delta) if residuals is None else residuals
    return _indicators(op.mesh, r, tractions, 2, return_parts)


def error_measure_B_lame(op, U, Psi, u_exact, traction_exact, extra: int = 3) -> float:
    """|||u - U|||_B (3.105) for Lame: (<W e_u, e_u> + <V e_psi, e_psi>)^(1/2) on the
    space of degree p_I + ``extra`` (exact u interpolated, exact traction projected per
    component; the discrete U, Psi embed exactly)."""
    from ..analysis.norms import _project_W, interpolation_difference
    from ..bem.lame import LameBEM

    hi = LameBEM(op.mesh.with_degrees(op.mesh.degrees + extra), op.E, op.nu, op.plane,
                 scale=op.scale, zero_force=op.zero_force)
    # traction
    ep = np.column_stack([_project_W(hi.W_space, lambda x, n, c=c: traction_exact(x, n)[:, c])
                          for c in range(2)])
    lo_d, hi_d = op.W_space.elem_dofs, hi.W_space.elem_dofs
    mask = lo_d >= 0
    ep[hi_d[:, :lo_d.shape[1]][mask]] -= np.asarray(Psi).reshape(-1, 2)[lo_d[mask]]
    ep = ep.ravel()
    # displacement
    eu = interpolation_difference(op.V_space, hi.V_space, np.asarray(U).reshape(-1, 2),
                                  lambda x, n: u_exact(x)).ravel()
    return float(np.sqrt(max(eu @ hi.W @ eu, 0.0) + max(ep @ hi.V @ ep, 0.0)))


# ----------------------------------------------------------------------------- contact
# Contact part of (3.107) (Section 3.3.5): on Gamma_C the datum of the traction residual
# is the penalty traction on the body, P_n n + P_t t = -p_n n - t_t t, evaluated from U at
# the indicator's quadrature points with the one law of :mod:`hpfebe.constitutive.laws`
# (penetration U_n - g, tangential displacement U_t against a fixed obstacle).

INDICATOR_VARIANTS = ("literal", "balanced")


def contact_traction(op, U, gap, eps_n: float, eps_t: float, mu_f=None, F=None, slip=0.0):
    """The datum P_n n + P_t t of (3.107) as ``f(x, n, elem, t) -> (n, 2)``: the traction
    -p_n n - t_t t of :func:`hpfebe.constitutive.laws.penalty_friction` on the body, from U
    (V_hp^2, interleaved) at the given points; ``gap(x)`` the gap function (constraint
    U_n <= g), Coulomb (``mu_f``) or Tresca (``F``), ``slip`` the accumulated slip (0:
    one load step)."""

    real("eps_n", eps_n, positive=True)
    real("eps_t", eps_t, positive=True)
    mesh = op.mesh
    # g(x) one value per point (a scalar is refused), no NaN (+inf: no obstacle there)
    gap = callable_returning("gap", gap, None, lambda x: (len(x),), allow_inf=True)
    Ul = array("U", U, shape=(op.V_space.ndof * 2,)).reshape(-1, 2)

    def f(x, n, elem, t):
        u = op.V_space.evaluate(Ul, elem, t)
        nn, tt = mesh.normals[elem], mesh.tangents[elem]
        law = penalty_friction(np.sum(u * nn, 1) - gap(x), np.sum(u * tt, 1), slip,
                               eps_n, eps_t, mu_f=mu_f, F=F)
        return -law.p_n[:, None] * nn - law.t_t[:, None] * tt
    return f


def consistency_weight(variant: str, E: float, nu: float, plane: str = "strain") -> float:
    """Weight of the consistency term h_I ||d/ds (V Psi - (K + 1/2) U)||^2 of (3.107) for
    Lame: "literal" 1 (the thesis's formula, a strain beside a traction), "balanced"
    E' (:func:`hpfebe.constitutive.materials.plane_modulus`), which gives both terms the units of
    (traction x length)^2."""
    from ..constitutive.materials import plane_modulus

    if variant == "literal":
        return 1.0
    if variant == "balanced":
        return plane_modulus(E, nu, plane)
    raise ValueError(f"indicator variant must be one of {INDICATOR_VARIANTS}, got "
                     f"{variant!r}")


def lame_contact_indicators(op, U, Psi, gap, eps_n: float, eps_t: float, mu_f=None, F=None,
                            weight: float = 1.0, contact_label: str = "C",
                            tractions: dict | None = None, nq: int | None = None,
                            residuals: dict | None = None):
    """eta_h(I) of (3.107) for a Lame BEM body in penalty contact with a rigid obstacle:
    (h_I ||P_n n + P_t t - S_hat U||^2 + weight^2 h_I ||d/ds (V Psi - (K + 1/2) U)||^2)^(1/2)
    with the datum of :func:`contact_traction` on ``contact_label`` and further data
    ``tractions`` (label -> callable, e.g. t_hat on "N").  ``residuals``: precomputed
    ``lame_boundary_residuals(op, U, Psi, nq)`` (shared by indicator variants that differ
    in ``weight`` only)."""
    weight = real("weight", weight, positive=True)
    data = dict(tractions or {})
    data[contact_label] = contact_traction(op, U, gap, eps_n, eps_t, mu_f=mu_f, F=F)
    _, parts = lame_bem_indicators(op, U, Psi, data, nq=nq, return_parts=True,
                                   residuals=residuals)
    return np.sqrt(parts["traction"] ** 2 + (weight * parts["consistency"]) ** 2)


def norm_B(op, U, Psi, eps_n: float = 0.0, eps_t: float = 0.0, weights=None, p_n=None,
           t_t=None) -> float:
    """|||U|||_B of (3.105) of a discrete penalty solution: (<W U, U> + <V Psi, Psi>
    + eps_n ||p_n||^2_{L2(Gamma_C)} + eps_t ||t_t||^2_{L2(Gamma_C)})^(1/2), the penalty
    terms by the quadrature ``weights`` at the contact points (none if not given)."""
    U = np.asarray(U, dtype=float)
    Psi = np.asarray(Psi, dtype=float)
    n2 = U @ op.W @ U + Psi @ op.V @ Psi
    if weights is not None:
        w = np.asarray(weights, dtype=float)
        n2 = n2 + eps_n * w @ np.asarray(p_n) ** 2 + eps_t * w @ np.asarray(t_t) ** 2
    return float(np.sqrt(n2))


def true_error(op, U, Psi, ref_op, U_ref, Psi_ref) -> float:
    """|||U_ref - U|||_B without the penalty terms, (<W e_u, e_u> + <V e_psi, e_psi>)^(1/2)
    with the operators of ``ref_op``, whose mesh must refine that of ``op`` (the discrete
    (U, Psi), interleaved V_hp^2 x W_hp^2, embed exactly:
    :func:`hpfebe.spaces.prolongate`)."""
    from ..spaces import prolongate

    Uf = prolongate(op.V_space, U, ref_op.V_space, components=2)
    Pf = prolongate(op.W_space, Psi, ref_op.W_space, components=2)
    eu = np.asarray(U_ref, dtype=float) - Uf
    ep = np.asarray(Psi_ref, dtype=float) - Pf
    return float(np.sqrt(max(eu @ ref_op.W @ eu, 0.0) + max(ep @ ref_op.V @ ep, 0.0)))
