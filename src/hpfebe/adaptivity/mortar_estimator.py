"""The hp-adaptive mortar contact of Section 4.3.5: the residual indicator of the two BE
bodies of a :class:`hpfebe.contact.mortar.MortarContact` solution, the h-or-p decision
of Algorithm 4.6 (:func:`hp_refine`) and the algorithm on both bodies (:func:`hp_adapt`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..checks import array, instance, integer, real
from ..geometry import BoundaryMesh
from ..quadrature import gauss_legendre
from .adaptive import adapt
from .bem_estimator import lame_bem_indicators

if TYPE_CHECKING:  # annotations only: adaptivity sits above contact, contact never imports it
    from ..contact.mortar import MortarContact, MortarSolution


def mortar_indicators(pr: MortarContact, sol: MortarSolution, nq: int | None = None,
                      return_parts: bool = False):
    """The indicator eta = (eta_C^2 + eta_N^2 + eta_S^2)^(1/2) of Section 4.3.5, one
    value per element of each mesh: (eta1, eta2).

    With the nodal contact traction P of the solution (force on body 1 = -P, on body 2
    = +P at the paired point) as the datum on Gamma_C and t_hat = 0 on Gamma_N:

    * eta_N^2 + third term of eta_C^2: (h_I / p_I) ||datum - S_hat U||^2_{L2(I)},
    * eta_S^2: (h_I / p_I) h_I ||d/ds (V Psi - (K + 1/2) U)||^2_{L2(I)} (the derivative
      form of :func:`hpfebe.adaptivity.bem_estimator.lame_bem_indicators`, Section 3.3.3,
      instead of the L2 norm of the residual itself),
    * on Gamma^1_C also (h_I / p_I) ||[P]||^2 + (h_I / p_I)^-1 ||[U_n]_+||^2 with
      [P] = Psi^1 + Psi^2 (paired point; zero for equal and opposite tractions) and
      [U_n]_+ = max(0, (U^1 - U^2) . n - g) (paired point, gap along n).
    """
    m = pr.mortar
    b1, b2 = pr.bem1, pr.bem2
    P = np.zeros((b1.V_space.ndof, 2))
    P[m.dofs1] = sol.P.reshape(-1, 2)
    zero = lambda x, n: np.zeros((len(x), 2))  # noqa: E731

    def datum1(x, n, elem, t):
        return -b1.V_space.evaluate(P, elem, t)

    def datum2(x, n, elem, t):
        e1, t1, inside = m.locate(m.parameter(x), 1)
        out = np.zeros((len(x), 2))
        if inside.any():
            out[inside] = b1.V_space.evaluate(P, e1[inside], t1[inside])
        return out

    U1, U2 = sol.U1, sol.U2
    Psi1, Psi2 = b1.Psi(U1), b2.Psi(U2)
    eta1, parts1 = lame_bem_indicators(b1, U1, Psi1, {"N": zero, "C": datum1}, nq,
                                       return_parts=True)
    eta2, parts2 = lame_bem_indicators(b2, U2, Psi2, {"C": datum2}, nq, return_parts=True)
    eta1 = eta1 ** 2 / b1.mesh.degrees
    eta2 = eta2 ** 2 / b2.mesh.degrees
    # jump terms on Gamma^1_C
    mesh = b1.mesh
    els = np.flatnonzero(mesh.labels == "C")
    q = int(mesh.degrees.max()) + 3 if nq is None else integer("nq", nq, lo=1)
    tq, wq = (np.asarray(v, float) for v in gauss_legendre(q))
    elem = np.repeat(els, q)
    t = np.tile(tq, els.size)
    w = np.tile(wq, els.size) * mesh.lengths[elem] / 2.0
    x = mesh.points(elem, t)
    e2, t2, inside = m.locate(m.parameter(x), 2)
    u1 = b1.V_space.evaluate(U1.reshape(-1, 2), elem, t)
    ps1 = b1.W_space.evaluate(Psi1.reshape(-1, 2), elem, t)
    u2, ps2 = np.zeros_like(u1), np.zeros_like(u1)
    u2[inside] = b2.V_space.evaluate(U2.reshape(-1, 2), e2[inside], t2[inside])
    ps2[inside] = b2.W_space.evaluate(Psi2.reshape(-1, 2), e2[inside], t2[inside])
    nrm = pr._normal(x)
    g = pr.gap_at(x, nrm)
    pen = np.where(inside & np.isfinite(g), np.maximum(0.0, np.sum((u1 - u2) * nrm, 1) - g), 0.0)
    jump = np.sum((ps1 + ps2) ** 2, 1)
    hp = mesh.lengths / mesh.degrees
    jP = hp * np.bincount(elem, w * jump, minlength=mesh.n_elements)
    jU = np.bincount(elem, w * pen ** 2, minlength=mesh.n_elements) / hp
    eta1 = np.sqrt(eta1 + jP + jU)
    eta2 = np.sqrt(eta2)
    if return_parts:
        return (eta1, eta2), dict(jump_P=np.sqrt(jP), penetration=np.sqrt(jU),
                                  residual1=parts1, residual2=parts2)
    return eta1, eta2


def hp_refine(mesh: BoundaryMesh, marked, eta, h_fraction: float = 0.9) -> BoundaryMesh:
    """Algorithm 4.6 on the marked elements (marked: eta_I >= q1 eta_max): h-refine
    (bisect) where eta_I >= ``h_fraction`` eta_max, raise p by one on the others."""
    instance("mesh", mesh, BoundaryMesh)
    marked = array("marked", marked, shape=(mesh.n_elements,), dtype=bool)
    # a NaN would make eta >= h_fraction * max(eta) false everywhere: no h-refinement
    eta = array("eta (indicators)", eta, shape=(mesh.n_elements,))
    if np.any(eta < 0):
        raise ValueError(f"eta (indicators) must be non-negative, got {eta.min()!r}")
    h_fraction = real("h_fraction", h_fraction, lo=0.0, hi=1.0, lo_open=True)
    h = marked & (eta >= h_fraction * eta.max())
    p = marked & ~h
    out = mesh.raise_degree(p) if p.any() else mesh
    return out.refine(h) if h.any() else out


def hp_adapt(meshes, solve, n_steps: int, q1: float = 0.85, q2: float = 0.9):
    """Algorithm 4.6 on both bodies of a mortar contact problem through
    :func:`hpfebe.adaptivity.adapt`: ``solve(meshes)`` returns ((problem, solution),
    (ndof1, ndof2)) as ``adapt`` expects; the indicator :func:`mortar_indicators`;
    marking eta_I >= q1 eta_max per body; h-refinement (bisection) where eta_I >= q2
    eta_max, else p + 1 (:func:`hp_refine`); ``n_steps`` solves.  Returns (the
    :class:`~hpfebe.adaptivity.AdaptiveHistory`, the number of bisections and degree
    raises per refinement of each body: dicts body, n_h, n_p)."""
    q1 = real("q1", q1, lo=0.0, hi=1.0, lo_open=True)
    q2 = real("q2", q2, lo=0.0, hi=1.0, lo_open=True)
    store, counts = {}, []

    def estimate(meshes, state):
        store["eta"] = mortar_indicators(*state)
        return store["eta"]

    def refiner(k):
        def refine(mesh, marked):
            eta = store["eta"][k]
            nh = int(np.sum(marked & (eta >= q2 * eta.max())))
            counts.append(dict(body=k + 1, n_h=nh, n_p=int(marked.sum()) - nh))
            return hp_refine(mesh, marked, eta, q2)
        return refine

    hist = adapt(tuple(meshes), solve, estimate, n_steps=n_steps, theta=q1, marking="max",
                 refine=[refiner(0), refiner(1)])
    return hist, counts
