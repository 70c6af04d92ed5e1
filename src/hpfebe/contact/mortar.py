"""hp-mortar BEM for two-body contact with friction (Sections 4.3.3-4.3.5): the problem
:class:`MortarContact` - gap, frame, the contact QP of body 1, the Neumann problem of
body 2, the mortar transfer - and the solvers acting on it (:mod:`hpfebe.solvers`): the
inner frictionless contact QP by Polyak's projected conjugate gradients
(:mod:`hpfebe.solvers.pcg`), the Uzawa algorithm for given (Tresca) friction (Algorithm
4.4, :func:`hpfebe.solvers.uzawa.tresca_uzawa`), the Dirichlet-to-Neumann algorithm
(Algorithm 4.3, :func:`hpfebe.solvers.dtn.dtn`) with damping omega_D, omega_N
(optionally Aitken-relaxed), the global Uzawa algorithm for Coulomb friction (Algorithm
4.5, :func:`hpfebe.solvers.uzawa.global_uzawa`) and a monolithic semismooth Newton method
(:mod:`hpfebe.solvers.semismooth`).  The indicator eta of Section 4.3.5 and the
hp-refinement rule of Algorithm 4.6 are :mod:`hpfebe.adaptivity.mortar_estimator`; the
model problem of Section 4.3.4 is :mod:`hpfebe.scenes.mortar`.

Discrete setting.  Body i is a :class:`hpfebe.bem.lame.LameBEM` body with unknowns U^i in
V^i_hp^2 (GLL Lagrange basis, interleaved components) and stiffness S_hat^i; its
Dirichlet dofs are eliminated and S_hat condensed onto the contact dofs once per mesh
(:class:`hpfebe.bodies.condensed.CondensedBody`: one Cholesky factorisation of the
rest).  The data transfer is the mortar projection of :mod:`hpfebe.coupling.mortar`
(displacements Q = pi U^2, (4.87)) and its adjoint (tractions).

Constraints (Algorithm 4.3, step 4) are imposed at the Gauss-Lobatto points of
Gamma^1_C, which are the nodes of the GLL basis: in the frame (n_j, t_j) of each contact
node (n_j the outward normal of body 1 given by the scene, t_j = (-n_y, n_x)) the
unknowns are x = (U_n, U_t) and the constraint is U_n - Q_n <= g (gap g measured along
n_j to Gamma^2_C).  The friction functional j(W_t - Q_t) = int F |W_t - Q_t| ds is
integrated by the Gauss-Lobatto rule of each element (weights w_j, lumped), so that
the Tresca conditions hold pointwise at these points: |lambda_j| <= 1 and
lambda_j (U_t - Q_t)_j = |(U_t - Q_t)_j|.

Every outer loop is :func:`hpfebe.solvers.fixed_point` (stopping rule
||x_k - x_{k-1}|| <= TOL ||x_k||, divergence and iteration cap detected there); the inner
solves report a :class:`~hpfebe.solvers.SolverInfo` collected in ``info.steps``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..bem.lame import LameBEM
from ..bodies.condensed import CondensedBody
from ..checks import InputTypeError, array, callable_returning, choice, instance, real
from ..coupling.mortar import MortarProjection
from ..geometry import BoundaryMesh
from ..quadrature import gauss_lobatto
from ..solvers import SolverInfo
from ..solvers.dtn import DtNSettings, DtNState, dtn, transfer_maps
from ..solvers.pcg import BoundQP
from ..solvers.semismooth import SemismoothSettings, semismooth_contact
from ..solvers.uzawa import (GlobalUzawaSettings, UzawaSettings, friction_rhs, global_uzawa,
                             tresca_uzawa)

__all__ = ["MortarContact", "MortarSolution", "node_points", "ray_gap"]


def ray_gap(points, normals, mesh: BoundaryMesh, label: str) -> np.ndarray:
    """Distance g_j >= ... from ``points[j]`` along ``normals[j]`` to the elements of
    ``mesh`` labelled ``label`` (first hit, possibly negative = overlap); +inf where the
    ray misses them (no constraint there)."""
    els = np.flatnonzero(mesh.labels == label)
    a, d = mesh.a[els], mesh.b[els] - mesh.a[els]
    x, nn = np.asarray(points, float), np.asarray(normals, float)
    # x + tau n = a + sigma d  ->  [n, -d] (tau, sigma) = a - x
    det = nn[:, None, 0] * (-d[None, :, 1]) - nn[:, None, 1] * (-d[None, :, 0])
    rx, ry = a[None, :, 0] - x[:, None, 0], a[None, :, 1] - x[:, None, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = (rx * (-d[None, :, 1]) - ry * (-d[None, :, 0])) / det
        sig = (nn[:, None, 0] * ry - nn[:, None, 1] * rx) / det
    ok = (np.abs(det) > 1e-14) & (sig >= -1e-12) & (sig <= 1 + 1e-12)
    tau = np.where(ok, tau, np.inf)
    k = np.argmin(np.abs(tau), axis=1)
    return tau[np.arange(len(x)), k]


def node_points(bem, dofs):
    """The points of the GLL nodes ``dofs`` of the V_hp space of ``bem`` (or any object
    with ``mesh`` and ``V_space``)."""
    mesh, sp_ = bem.mesh, bem.V_space
    xy = np.zeros((sp_.ndof, 2))
    for p in np.unique(mesh.degrees):
        els = np.flatnonzero(mesh.degrees == p)
        xg, _ = gauss_lobatto(int(p) + 1)
        xy[sp_.elem_dofs[els, :int(p) + 1]] = mesh.points(els[:, None], xg[None, :])
    return xy[dofs]


def default_normals(space, dofs, label):
    """Sum of the outward normals of the contact elements sharing each node."""
    mesh = space.mesh
    acc = np.zeros((space.ndof, 2))
    els = np.flatnonzero(mesh.labels == label)
    d = space.elem_dofs[els]
    for k in range(d.shape[1]):                   # local basis index (<= p + 1)
        ok = d[:, k] >= 0
        np.add.at(acc, d[ok, k], mesh.normals[els[ok]])
    return acc[dofs]


def lobatto_weights(mesh, space, dofs, label):
    """w_j = int phi_j ds by the Gauss-Lobatto rule of each contact element."""
    w = np.zeros(space.ndof)
    els = np.flatnonzero(mesh.labels == label)
    for p in np.unique(mesh.degrees[els]):
        e = els[mesh.degrees[els] == p]
        _, wg = gauss_lobatto(int(p) + 1)
        d = space.elem_dofs[e, :int(p) + 1]
        np.add.at(w, d.ravel(), (0.5 * mesh.lengths[e][:, None] * wg[None, :]).ravel())
    return w[dofs]


def two_bodies(a, b, names: str) -> None:
    """ValueError naming ``names`` if ``a`` and ``b`` are one object (a body in contact
    with itself: both copies would overlap in the reference configuration)."""
    if a is b:
        raise ValueError(f"{names} must be two bodies, got the same body twice")


def dirichlet_datum(dirichlet, name: str):
    """(label, (Ux, Uy) as a float array) of a Dirichlet datum (label, (Ux, Uy)): two
    finite real numbers (no strings, no NaN); ValueError naming ``name``."""
    try:
        label, value = dirichlet
        return label, array(name, value, shape=(2,))
    except (TypeError, ValueError) as err:     # InputTypeError is both
        kind = InputTypeError if isinstance(err, TypeError) else ValueError
        raise kind(f"{name} must be (label, (Ux, Uy)) with finite real Ux, Uy, got "
                   f"{dirichlet!r}") from None


def condensed_body(bem, dirichlet, contact, name: str) -> CondensedBody:
    """S_hat of ``bem`` with the Dirichlet datum ``dirichlet`` = (label, (Ux, Uy))
    condensed onto the interleaved ``contact`` dofs (``name``: for the error message)."""
    label, value = dirichlet_datum(dirichlet, name)
    if not np.any(bem.mesh.labels == label):
        raise ValueError(f"{name}: no element labelled {label!r}")
    d = bem.V_space.dofs_on(label)
    fixed = np.column_stack([2 * d, 2 * d + 1]).ravel()
    vals = np.tile(value, d.size)
    return CondensedBody(bem.S_hat, fixed, vals, contact)


def obstacle(Q, nc: int) -> np.ndarray:
    """The obstacle Q of step 4: an interleaved vector on the 2 nc contact dofs of body 1
    (a clear error for one of another length, e.g. a traction on body 2's dofs)."""
    return array("Q", Q, shape=(2 * nc,), finite=False)


def nodal_bound(bound, nc: int):
    """A nodal friction bound (nc,) >= 0 replacing F (a scalar: the same at every
    node), or None."""
    if bound is None:
        return None
    b = array("bound", np.broadcast_to(bound, (nc,)) if np.ndim(bound) == 0 else bound,
              shape=(nc,), finite=False)
    if np.any(b < 0):
        raise ValueError(f"bound must be >= 0, got {b.min()!r}")
    return b


def rho_hint(info: SolverInfo, rho: float, rho_crit: float) -> None:
    """Name the cause of a diverged Uzawa iteration whose step exceeds rho_crit."""
    if rho >= rho_crit:
        info.reason += (f" (the step rho = {rho:.4g} exceeds rho_crit = {rho_crit:.4g} of "
                        "Theorem 3.1.8 for body 1 with no node in contact, e.g. a stamp "
                        "lifted off: take a smaller rho or UzawaSettings(relative=True))")


def contact_normals(normal, outward, points) -> np.ndarray:
    """The normals of the contact nodes: ``outward`` (:func:`default_normals`) if
    ``normal`` is None, else normal(points), checked (:func:`check_outward`)."""
    if normal is None:
        return outward
    if not callable(normal):
        raise InputTypeError(f"normal must be a callable (m, 2) points -> (m, 2) normals, got "
                             f"{normal!r}")
    nrm = array("normal(x)", normal(points), shape=outward.shape)
    check_outward(nrm, outward, points)
    return nrm


def check_outward(normals, outward, points) -> None:
    """ValueError unless every given normal of Gamma^1_C is nonzero and points out of
    body 1, n_j . n_mesh_j > 0 (``outward``: the element normals of the counter-clockwise
    boundary mesh, :func:`default_normals`): the constraint U_n - Q_n <= g of
    Algorithm 4.3 and the gap along n assume the outward normal; an inward one turns
    the obstacle round (measured: converged with 0.09 of penetration)."""
    size = np.linalg.norm(normals, axis=1)
    if np.any(size == 0):
        k = int(np.flatnonzero(size == 0)[0])
        raise ValueError(f"normal(x) must be nonzero, got (0, 0) at the contact node "
                         f"x = {tuple(np.round(points[k], 12))}")
    cos = np.sum(normals * outward, axis=1) / (size * np.linalg.norm(outward, axis=1))
    bad = np.flatnonzero(~(cos > 0))
    if bad.size:
        k = int(bad[0])
        raise ValueError(
            f"normal(x) must be the outward normal of body 1 (n . n_mesh > 0, pointing "
            f"towards body 2), got one pointing into body 1 at {bad.size} of {len(cos)} "
            f"contact nodes (first at x = {tuple(np.round(points[k], 12))}: n = "
            f"{tuple(normals[k])}, n . n_mesh = {cos[k]:.3g}); reverse its sign")


def node_frame(normals):
    """The frame (n, t = (-n_y, n_x)) at the contact nodes of the (unnormalised)
    ``normals`` and the rotation R of an interleaved vector u_c to (u_n, u_t)."""
    nc = len(normals)
    n = normals / np.linalg.norm(normals, axis=1)[:, None]
    t = np.column_stack([-n[:, 1], n[:, 0]])
    R = np.zeros((2 * nc, 2 * nc))
    j = np.arange(nc)
    R[j, 2 * j], R[j, 2 * j + 1] = n[:, 0], n[:, 1]
    R[nc + j, 2 * j], R[nc + j, 2 * j + 1] = t[:, 0], t[:, 1]
    return n, t, R


def global_operators(pr) -> dict:
    """Dense pieces of Algorithm 4.5 on the contact dofs (built once): the lumped
    Gauss-Lobatto pairing Wk = diag(w) x I2 on Gamma^1_C, the traction transfer
    T2 = (B^T D^-T)(free rows of body 2) and H = A1^-1 + Pi A2^-1 Pi^T with
    Pi = D^-1 B (restricted to body 2's free contact dofs): the response of the
    relative displacement U1 - Pi U2 to the nodal traction P is -H Wk P."""
    m, nc = pr.mortar, pr.nc
    Wk = np.repeat(pr.w, 2)
    n2 = pr.c2.size
    Pi = np.column_stack([m.project(e) for e in np.eye(n2)])[:, pr.body2.cpos]
    T2 = Pi.T                                   # B^T D^-T restricted, = Pi^T
    H = np.linalg.inv(pr.body1.A) + Pi @ np.linalg.solve(pr.body2.A, Pi.T)
    sw = np.sqrt(Wk)
    G = sw[:, None] * H * sw[None, :]
    lam_max = np.linalg.eigvalsh(0.5 * (G + G.T))[-1]
    return dict(Wk=Wk, T2=T2, rho_crit=2.0 / lam_max, nc=nc, H=H, Pi=Pi)


@dataclass
class MortarSolution:
    """Result of a mortar contact solve: full boundary displacements U1, U2, the
    friction multiplier lambda and the transferred fields Q (X^1) and P (X^2 dual),
    the frame quantities at the contact nodes of body 1 and the SolverInfo."""

    U1: np.ndarray
    U2: np.ndarray
    lam: np.ndarray
    Q: np.ndarray
    P: np.ndarray
    x: np.ndarray
    info: SolverInfo
    extra: dict = field(default_factory=dict)


def traction_state(pr, P, info, friction: str, mu_f: float) -> MortarSolution:
    """The solution of the nodal contact traction P of :meth:`MortarContact.global_uzawa`
    or :meth:`MortarContact.semismooth_newton`: displacements of the two Neumann
    problems, the multiplier lambda = P_t / b and the tractions in ``extra``."""
    g = pr._global_operators()
    b1, b2, nc = pr.body1, pr.body2, pr.nc
    u1 = b1.solve(-g["Wk"] * P)
    u2c = b2.solve(g["T2"] @ (g["Wk"] * P))
    Q = pr.mortar.project(b2.expand(u2c)[pr.c2])
    pn, pt = pr.frame(P)
    bound = mu_f * pn if friction == "coulomb" else np.full(nc, pr.F)
    lam = np.divide(pt, bound, out=np.zeros(nc), where=bound > 0)
    return MortarSolution(b1.expand(u1), b2.expand(u2c), lam, Q, P,
                          pr.R @ u1, info, extra=dict(pn=pn, pt=pt))


class MortarContact:
    """Two BE bodies in frictional contact through a mortar coupling (Section 4.3.3).

    Parameters
    ----------
    bem1, bem2 : LameBEM of body 1 (contact / mortar side) and body 2 (Neumann side)
    dirichlet1, dirichlet2 : (label, (Ux, Uy)) prescribed displacement on that label
    F : given friction bound (Tresca), >= 0
    normal : callable (m, 2) points -> (m, 2) outward unit normals of body 1 on
        Gamma^1_C (default: the mean of the adjacent element normals)
    label : contact label of both meshes; axis : pairing parameter of the mortar
    gap : callable (m, 2) points of Gamma^1_C -> (m,) initial gap (default: the
        distance along n to Gamma^2_C, :func:`ray_gap`)
    test_space : "full" (test with all of X^1_hp, Phi^1 = D^-1 B Phi^2 as printed in
        (4.87)) or "mortar" (the mortar space M^1_hp of (4.49) with end-point matching,
        (4.50)); see :class:`hpfebe.coupling.mortar.MortarProjection`
    """

    def __init__(self, bem1: LameBEM, bem2: LameBEM, dirichlet1, dirichlet2, F: float,
                 normal=None, label: str = "C", axis=(1.0, 0.0), test_space: str = "full",
                 gap=None):
        instance("bem1", bem1, LameBEM, "a LameBEM (a Lame body)")
        instance("bem2", bem2, LameBEM, "a LameBEM (a Lame body)")
        two_bodies(bem1, bem2, "bem1, bem2")
        self.bem1, self.bem2, self.F = bem1, bem2, real("F", F, nonnegative=True)
        self.mortar = MortarProjection(bem1.mesh, bem2.mesh, label, label, axis,
                                       bem1.V_space, bem2.V_space, test_space)
        m = self.mortar
        self.c1 = np.column_stack([2 * m.dofs1, 2 * m.dofs1 + 1]).ravel()
        self.c2 = np.column_stack([2 * m.dofs2, 2 * m.dofs2 + 1]).ravel()
        self.body1 = condensed_body(bem1, dirichlet1, self.c1, "dirichlet1")
        self.body2 = condensed_body(bem2, dirichlet2, self.c2, "dirichlet2")
        if self.body1.cpos.size != self.c1.size:
            raise ValueError("dirichlet1: the contact nodes of body 1 must not be Dirichlet "
                             "nodes")
        nc = m.dofs1.size
        self.nc, self.points = nc, node_points(bem1, m.dofs1)
        nrm = contact_normals(normal, default_normals(bem1.V_space, m.dofs1, label),
                              self.points)
        self._normal_fn = normal
        self._gap_fn = None if gap is None else callable_returning(   # one per point
            "gap", gap, None, lambda x: (len(x),), allow_inf=True)
        self._set_frame(nrm)
        self.gap = self.gap_at(self.points, self.n)
        self.w = lobatto_weights(bem1.mesh, bem1.V_space, m.dofs1, label)

    def _set_frame(self, normals):
        """The frame (n, t) at the nc contact nodes, the rotation x = R u_c = (U_n, U_t)
        and body 1's condensed quadratic program in it: A = R A_1 R^T (symmetrised
        against round-off), b = R b_1."""
        self.n, self.t, self.R = node_frame(normals)
        R = self.R
        self.A = R @ self.body1.A @ R.T
        self.A = 0.5 * (self.A + self.A.T)
        self.b = R @ self.body1.b

    # the set-up helpers, also for the subclass FEMortarContact
    _node_points = staticmethod(node_points)
    _default_normals = staticmethod(default_normals)
    _lobatto_weights = staticmethod(lobatto_weights)

    def gap_at(self, x, normals) -> np.ndarray:
        """Initial gap at points x of Gamma^1_C: the scene's gap function, or the distance
        along ``normals`` to Gamma^2_C (+inf where the ray misses it)."""
        if self._gap_fn is None:
            return ray_gap(x, normals, self.bem2.mesh, "C")
        return self._gap_fn(np.asarray(x, dtype=float))

    def _normal(self, x) -> np.ndarray:
        """Unit normal of body 1 at points x of Gamma^1_C (the scene's, or the element's)."""
        if self._normal_fn is not None:
            n = np.asarray(self._normal_fn(x), dtype=float)
        else:
            e, _ = self.bem1.mesh.locate(x)
            n = self.bem1.mesh.normals[e]
        return n / np.linalg.norm(n, axis=1)[:, None]

    # ---------------------------------------------------------------- Uzawa step
    @property
    def rho_crit(self) -> float:
        """Largest convergent Uzawa step of Theorem 3.1.8 for the linear (all nodes in
        contact, sticking) model: lambda <- lambda + rho F^2 W^(1/2) C_tt W^(1/2) ...
        contracts iff rho < 2 / (F^2 lambda_max(W^(1/2) C_tt W^(1/2))), C = A^-1 the
        condensed compliance at the contact nodes (tangential block), W = diag(w)."""
        if self.F == 0.0:
            return np.inf
        if not hasattr(self, "_rho_crit"):
            self._rho_crit = 2.0 / (self.F ** 2 * self._weighted_lmax(np.sqrt(self.w)))
        return float(self._rho_crit)

    def _rho_bound(self, rho: float, relative: bool, bound) -> float:
        """The Uzawa step for a nodal friction bound s (Coulomb in DtN): rho itself, or
        rho / (s-weighted largest eigenvalue) as :attr:`rho_crit` with F -> diag(s)."""
        if not relative:
            return float(rho)
        lmax = self._weighted_lmax(np.sqrt(self.w) * np.asarray(bound, dtype=float))
        return float(rho) / lmax if lmax > 0 else float(rho)

    def _weighted_lmax(self, sw) -> float:
        """lambda_max(diag(sw) C_tt diag(sw)), C_tt = (A^-1)_tt (computed once)."""
        if not hasattr(self, "_Ctt"):
            self._Ctt = np.linalg.inv(self.A)[self.nc:, self.nc:]
        T = sw[:, None] * self._Ctt * sw[None, :]
        return np.linalg.eigvalsh(0.5 * (T + T.T))[-1]

    def rho_step(self, rho: float, relative: bool) -> float:
        """The Uzawa step used: ``rho`` itself, or rho * rho_crit / 2 when ``relative``
        (rho = 1 is then the step with the fastest contraction of the stiffest mode)."""
        rho = real("rho", rho, positive=True)
        if not relative or self.F == 0.0:
            return float(rho)
        return float(rho) * 0.5 * self.rho_crit

    # ---------------------------------------------------------------- step 4: contact QP
    def frame(self, v) -> tuple[np.ndarray, np.ndarray]:
        """Normal and tangential components at the contact nodes of an interleaved
        vector on the contact dofs of body 1."""
        try:
            v = np.asarray(v, dtype=float).reshape(self.nc, 2)
        except (TypeError, ValueError):
            raise ValueError(f"v must be {2 * self.nc} numbers (interleaved on the contact "
                             f"dofs of body 1), got {np.shape(v)}") from None
        n, t = self.n, self.t        # (two terms: the same sums as np.sum(v * n, axis=1))
        return v[:, 0] * n[:, 0] + v[:, 1] * n[:, 1], v[:, 0] * t[:, 0] + v[:, 1] * t[:, 1]

    def _unframe(self, v_n, v_t) -> np.ndarray:
        """The interleaved vector with the frame components v_n, v_t (inverse of
        :meth:`frame`)."""
        return (v_n[:, None] * self.n + v_t[:, None] * self.t).ravel()

    def contact_qp(self, Q, lam, x0=None, tol: float = 1e-11, bound=None):
        """Algorithm 4.4 step 2: frictionless contact of body 1 against the obstacle Q
        with the friction load F w lambda (``bound``: a nodal friction bound replacing F,
        e.g. mu_f p_n), by projected CG.  Returns (x, info)."""
        Fw, upper = self._qp_data(obstacle(Q, self.nc), nodal_bound(bound, self.nc))
        qp = self._bound_qp()
        rhs = friction_rhs(qp.b, Fw, np.asarray(lam, dtype=float))
        return qp.solve(rhs, upper, x0, tol)

    def _qp_data(self, Q, bound):
        """The pieces of the contact QP fixed for one obstacle Q and one friction bound:
        the friction weights F w (or s w) and the upper bounds (g + Q_n on U_n, none on
        U_t)."""
        Qn, _ = self.frame(Q)
        F = self.F if bound is None else np.asarray(bound, dtype=float)
        upper = np.concatenate([self.gap + Qn, np.full(self.nc, np.inf)])
        return F * self.w, upper

    def _bound_qp(self) -> BoundQP:
        """The contact QP of body 1 in the node frames (:class:`BoundQP`), built once per
        (A, b) pair (``self.A``, ``self.b`` are read at every call: subclasses may
        replace them)."""
        c = self.__dict__.get("_qp_cache")
        if c is None or c[0] is not self.A or c[1] is not self.b:
            c = self.__dict__["_qp_cache"] = (self.A, self.b, BoundQP.of(self.A, self.b))
        return c[2]

    def uzawa(self, Q, settings: UzawaSettings = UzawaSettings(), lam0=None, x0=None,
              bound=None):
        """Algorithm 4.4 (Uzawa for given friction) against the obstacle Q:
        lambda_{m+1} = P_Lambda(lambda_m + rho F (U_t - Q_t)), stop when
        ||lambda_m - lambda_{m-1}|| <= TOL_U ||lambda_m||
        (:func:`hpfebe.solvers.uzawa.tresca_uzawa`; ``settings``: rho, TOL_U, the cap, the
        CG tolerance; rho relative to rho_crit / 2 if ``settings.relative``,
        :meth:`rho_step`, or with a nodal bound :meth:`_rho_bound`).  Returns (x, lambda,
        info); x = (U_n, U_t) at the contact nodes for the returned lambda.  ``bound``:
        nodal friction bound s_j replacing F (lambda_j += rho s_j (U_t - Q_t)_j).  The QP
        data fixed by Q and the bound are built once per call."""
        uz = instance("settings", settings, UzawaSettings)
        Q, bound = obstacle(Q, self.nc), nodal_bound(bound, self.nc)
        rho = self.rho_step(uz.rho, uz.relative) if bound is None else \
            self._rho_bound(uz.rho, uz.relative, bound)
        F = self.F if bound is None else np.asarray(bound, dtype=float)
        _, Qt = self.frame(Q)
        lam0 = np.zeros(self.nc) if lam0 is None else array("lam0", lam0, shape=(self.nc,))
        Fw, upper = self._qp_data(Q, bound)
        x, lam, info = tresca_uzawa(self._bound_qp(), Fw, rho * F, Qt, upper, lam0, x0, uz)
        if not info.converged and info.reason.startswith("diverged") and bound is None:
            rho_hint(info, rho, self.rho_crit)
        return x, lam, info

    # ---------------------------------------------------------------- DtN
    def dtn(self, settings: DtNSettings, friction: str = "tresca") -> MortarSolution:
        """Algorithm 4.3 (Dirichlet-to-Neumann) with damping omega_D, omega_N in (0, 1],
        by :func:`hpfebe.solvers.dtn.dtn` (its steps, stopping rule and the readings
        ``settings.transfer``, ``settings.aitken`` are described there): step 2 the
        Neumann problem of body 2 under -P_k (:meth:`neumann_step`), step 4 Uzawa
        (Algorithm 4.4) against Q_k, warm-started from the previous DtN iteration
        (:meth:`contact_step`; ``settings.uzawa.relative``: the step rho * rho_crit / 2,
        :meth:`rho_step`), step 5 R1 = S1 U1 - L1 on the contact dofs (:meth:`reaction`).
        Non-convergence (cap, growth, NaN) is reported in ``info.reason``.

        ``friction``: "tresca" - the bound F of j (given friction, (4.55)); "coulomb" -
        the nodal bound F p_n with p_n = max(0, -R1_n / w) of the previous DtN iteration
        (0 in the first one; the per-iteration hook :meth:`_coulomb_bound`)."""
        instance("settings", settings, DtNSettings)
        choice("friction", friction, ("tresca", "coulomb"))
        hook = self._coulomb_bound if friction == "coulomb" else None
        P, info, st = dtn(self, settings, hook)
        load2, _ = transfer_maps(self.mortar, settings.transfer)
        u2c, _, _ = self.neumann_step(load2(P), st)
        x = st.x if st.x is not None else np.zeros(2 * self.nc)
        U1 = self.body1.expand(self.R.T @ x)
        U2 = self.body2.expand(u2c)
        return MortarSolution(U1, U2, st.lam, st.Q, P, x, info)

    def neumann_step(self, load, state: DtNState | None = None):
        """Step 2 of Algorithm 4.3: S2 U2 = L2 - load on Gamma^2_C (body 2 carries the
        functional -load).  Returns (U2 on body 2's free contact dofs, the trace of U2 on
        the dofs c2, None: a linear solve that cannot fail)."""
        b2 = self.body2
        u2c = b2.solve(-load[b2.cpos])
        return u2c, b2.expand(u2c)[self.c2], None

    def contact_step(self, Q, state: DtNState, uz: UzawaSettings):
        """Step 4 of Algorithm 4.3: :meth:`uzawa` against Q, warm-started from the state
        of the previous DtN iteration, with its nodal friction bound (None: F)."""
        return self.uzawa(Q, uz, state.lam, state.x, state.bound)

    def reaction(self, x) -> np.ndarray:
        """Step 5 of Algorithm 4.3: R1 = S1 U1 - L1 on the contact dofs of body 1 for the
        frame unknowns x = (U_n, U_t)."""
        return self.body1.reaction(self.R.T @ x)

    def _coulomb_bound(self, state: DtNState) -> None:
        """DtN hook of ``friction="coulomb"``: the friction bound of the next step 4 is
        F p_n with the nodal pressure p_n = max(0, -R1_n / w) of this iteration."""
        state.bound = self.F * np.maximum(0.0, -self.frame(state.R1)[0] / self.w)

    # ---------------------------------------------------------------- global Uzawa
    def _global_operators(self):
        """The dense pieces of Algorithm 4.5 (:func:`global_operators`), built once."""
        if not hasattr(self, "_glob"):
            self._glob = global_operators(self)
        return self._glob

    def global_uzawa(self, settings: GlobalUzawaSettings) -> MortarSolution:
        """Algorithm 4.5 (Uzawa for the global problem,
        :func:`hpfebe.solvers.uzawa.global_uzawa`) on the nodal contact traction P at the
        Gauss-Lobatto points of Gamma^1_C (force on body 1 = -P): S1 U1 = L1 - <P, .>_1
        and S2 U2 = L2 + pi*<P, .>_1 (two Neumann problems), then P projected pointwise.
        <P, .>_1 is the Gauss-Lobatto (lumped) pairing on Gamma^1_C, the same as the
        friction functional of :meth:`contact_qp`, so that with Tresca friction this is
        the discrete problem DtN solves.  Step: rho * rho_crit / 2 if
        ``settings.relative`` (rho_crit = 2 / lambda_max of the linear response, Theorem
        3.1.8)."""
        instance("settings", settings, GlobalUzawaSettings)
        g = self._global_operators()
        step = settings.rho * 0.5 * g["rho_crit"] if settings.relative else \
            float(settings.rho)
        b1, b2 = self.body1, self.body2

        def response(p):                    # U1 - pi U2 under the nodal traction p
            u1 = b1.solve(-g["Wk"] * p)
            u2c = b2.solve(g["T2"] @ (g["Wk"] * p))
            return u1 - self.mortar.project(b2.expand(u2c)[self.c2])

        P, info = global_uzawa(response, self.frame, self._unframe, self.gap, self.F, step,
                               settings)
        info.counts = dict(rho=step, rho_crit=g["rho_crit"])
        return traction_state(self, P, info, settings.friction, settings.mu_f)

    # ---------------------------------------------------------------- semismooth Newton
    def semismooth_newton(self, settings: SemismoothSettings) -> MortarSolution:
        """Monolithic semismooth Newton (primal-dual active set) for the discrete problem
        of Algorithm 4.5 (beyond the thesis, :mod:`hpfebe.solvers.semismooth`).  The
        displacements are linear in the nodal traction P, d(P) = U1 - pi U2 = d0 - H Wk P
        (:meth:`_global_operators`); in the node frames y = (P_n, P_t) the method solves
        the complementarity functions of the normal contact and the friction law with
        c = rho_crit / 2."""
        instance("settings", settings, SemismoothSettings)
        g = self._global_operators()
        nc, R = self.nc, self.R
        c = 0.5 * g["rho_crit"]
        b1, b2 = self.body1, self.body2
        d0 = R @ (b1.solve(np.zeros(2 * nc)) - g["Pi"] @ b2.solve(np.zeros(b2.cpos.size)))
        G = R @ (g["H"] * g["Wk"][None, :]) @ R.T          # d(local) = d0 - G y
        y, info = semismooth_contact(d0, G, self.gap, self.F, c, settings)
        P = R.T @ y
        info.counts = dict(c=c)
        return traction_state(self, P, info, settings.friction, settings.mu_f)

    # ---------------------------------------------------------------- post-processing
    def norm_W(self, U1, U2) -> float:
        """||U||_W = (<W U1, U1> + <W U2, U2>)^(1/2) (Section 4.3.4)."""
        return float(np.sqrt(U1 @ (self.bem1.W @ U1) + U2 @ (self.bem2.W @ U2)))

    def tresca_residual(self, sol: MortarSolution) -> dict:
        """Tresca conditions at the Gauss-Lobatto points: max |lambda| - 1, the largest
        slip where |lambda| < 1 (must vanish) and the largest violation of
        lambda s = |s| (scaled by max |s|)."""
        _, Qt = self.frame(sol.Q)
        s = sol.x[self.nc:] - Qt
        inner = np.abs(sol.lam) < 1.0 - 1e-9
        sc = max(np.abs(s).max(), 1e-300)
        return dict(lam_excess=float(np.abs(sol.lam).max() - 1.0),
                    stick_slip=float(np.abs(s[inner]).max() if inner.any() else 0.0),
                    complementarity=float(np.abs(sol.lam * s - np.abs(s)).max() / sc),
                    slip_scale=float(sc))
