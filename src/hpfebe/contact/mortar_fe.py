"""Mortar contact of two FE bodies, the second one elastoplastic (Section 4.4, thesis
lines 20355-20460; Algorithm 4.3 with Remark 4.3.5): an elastic FE body 1 (the stamp,
contact / mortar side) and a J2 elastoplastic FE body 2 (the work piece,
:class:`hpfebe.fem.plastic_body.ElastoPlasticFE`, Neumann side).

The machinery is that of the hp-mortar BEM (:mod:`hpfebe.contact.mortar`):
:class:`FEMortarContact` is a :class:`~hpfebe.contact.mortar.MortarContact` whose body 1
is the FE stiffness of the stamp condensed onto its contact dofs
(:class:`~hpfebe.bodies.condensed.CondensedBody`, one Cholesky factorisation, built once
and reused by every DtN iteration and every damping pair), so the frictional contact
problem of step 4 (Uzawa, Algorithm 4.4, with Polyak's projected CG for the inner QP),
the reaction of step 5, the frame, the gap and the Lobatto weights are inherited
unchanged, and the DtN iteration is the one of :func:`hpfebe.solvers.dtn.dtn`.  The traces of the
Q1 bodies on their boundaries are the continuous P1 spaces of
:class:`~hpfebe.spaces.ContinuousSpace` on a :class:`~hpfebe.geometry.BoundaryMesh`
through the FE boundary vertices (:func:`hpfebe.coupling.mortar.fe_trace_mesh`), and the
data transfer is the mortar projection (4.87) of :class:`hpfebe.coupling.mortar.MortarProjection`.

What differs from the BEM version is step 2: the Neumann problem of body 2 is the
elastoplastic one (Remark 4.3.5: the nonlinearities are separated),

    f_int(U^2_k) = -P_k on Gamma^2_C,   U^2_k = u_D on Gamma^2_D,                   (4.88)

one backward-Euler step (4.38)-(4.43) from the committed (virgin) history of the work
piece, solved by :func:`hpfebe.solvers.newton` on the body's
:class:`~hpfebe.fem.plastic_body.DisplacementSteps` problem (consistent tangent,
Armijo line search; each Newton system by the banded Cholesky factorisation of the
symmetric positive definite tangent, :class:`~hpfebe.contact.band_solve.BandSteps`,
15-18x faster than SuperLU on the Section 4.4 work piece), warm-started from the
previous DtN iterate.  The history is not committed during the DtN iteration (its
iterates are not load increments), so every DtN iteration and every damping pair solves
the same one-step problem.

:meth:`FEMortarContact.monolithic` (beyond the thesis) solves the same discrete problem
at once: the stamp, the work piece and the nodal contact forces by a semismooth Newton
method on the complementarity functions of the normal contact and the Tresca law
(:class:`MonolithicKKT`).  The scene of Section 4.4 is :mod:`hpfebe.scenes.section44`.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..bodies.condensed import CondensedBody
from ..checks import instance, integer, real, tolerance
from ..constitutive.j2 import dev, tensor_norm
from ..coupling.mortar import SIDES, MortarProjection, fe_trace_mesh
from ..fem.elasticity import ElasticBody
from ..fem.plastic_body import ElastoPlasticFE
from .band_solve import BandSteps, spd_band_solve
from ..solvers import Iterate, SingularStep, SolverInfo, newton
from ..solvers.dtn import DtNSettings, DtNState, dtn, transfer_maps
from .mortar import MortarContact, MortarSolution, dirichlet_datum, ray_gap, two_bodies

def _vector_dofs(body, vertex) -> np.ndarray:
    """Interleaved FE dofs (x, y of each vertex in turn) of the vertices ``vertex``."""
    return np.asarray(body.nodal_dofs)[:, np.asarray(vertex, dtype=np.int64)].T.ravel()


def _dirichlet(body, spec, name):
    label, value = dirichlet_datum(spec, name)
    if label not in SIDES:
        raise ValueError(f"{name}: label must be one of {SIDES}, got {label!r}")
    fixed = body.dofs_on(label)
    comp = np.zeros(body.ndofs, dtype=np.int64)
    comp[body.nodal_dofs[1]] = 1
    return fixed, value[comp[fixed]]


# --------------------------------------------------------------------------- problem
@dataclass(frozen=True)
class NeumannSettings:
    """Newton for step 2 of Algorithm 4.3 on the elastoplastic body 2, (4.88): stop at
    ||R||_inf <= ``tol`` x (force scale + :attr:`FEMortarContact.newton_floor`), at most
    ``max_iter`` iterations."""

    tol: float = 1e-8
    max_iter: int = 30

    def __post_init__(self):
        object.__setattr__(self, "tol", tolerance("newton tol", self.tol))
        object.__setattr__(self, "max_iter", integer("newton max_iter", self.max_iter,
                                                     lo=1))


class FEMortarContact(MortarContact):
    """An elastic FE stamp (body 1) and an elastoplastic FE work piece (body 2) coupled
    by the mortar projection (Section 4.4).

    Parameters
    ----------
    stamp : :class:`~hpfebe.fem.elasticity.ElasticBody` on a rectangle mesh
    work : :class:`~hpfebe.fem.plastic_body.ElastoPlasticFE` on a rectangle mesh
    dirichlet1, dirichlet2 : (side, (ux, uy)) prescribed displacement of each body
    F : given friction bound (Tresca, traction units), >= 0
    contact1, contact2 : the side of each body on Gamma_C (the stamp's other free sides
        are traction free; Gamma^2_C covers Gamma^1_C along the x axis)
    """

    def __init__(self, stamp: ElasticBody, work: ElastoPlasticFE, dirichlet1, dirichlet2,
                 F: float, contact1: str = "bottom", contact2: str = "top"):
        instance("stamp", stamp, ElasticBody)
        instance("work", work, ElastoPlasticFE)
        two_bodies(stamp, work.elastic, "stamp, work (its elastic body)")
        self.stamp, self.work, self.F = stamp, work, real("F", F, nonnegative=True)
        self.mesh1, space1, vert1 = fe_trace_mesh(stamp.mesh, contact1)
        self.mesh2, space2, vert2 = fe_trace_mesh(work.mesh, contact2)
        try:
            self.mortar = m = MortarProjection(self.mesh1, self.mesh2, "C", "C",
                                               (1.0, 0.0), space1, space2, "full")
        except ValueError as err:
            raise ValueError(f"stamp, work: the stamp's side {contact1!r} must lie on the "
                             f"work piece's side {contact2!r} along x: {err}") from None
        self.c1 = _vector_dofs(stamp, vert1[m.dofs1])    # FE dofs of body 1 on Gamma^1_C
        self.c2 = _vector_dofs(work.elastic, vert2[m.dofs2])  # ... of body 2 on Gamma^2_C
        # the tangential component of an interleaved vector on Gamma^2_C (a straight side)
        self.t2 = 0 if contact2 in ("top", "bottom") else 1
        fixed1, vals1 = _dirichlet(stamp, dirichlet1, "dirichlet1")
        self.fixed2, self.values2 = _dirichlet(work.elastic, dirichlet2, "dirichlet2")
        if np.intersect1d(fixed1, self.c1).size or np.intersect1d(self.fixed2, self.c2).size:
            raise ValueError("dirichlet1/dirichlet2: the contact side must not be a "
                             "Dirichlet side")
        # the stamp's stiffness condensed onto Gamma^1_C: assembled and factorised once
        self.body1 = CondensedBody(stamp.K.toarray(), fixed1, vals1, self.c1)
        self.nc = m.dofs1.size
        ns = SimpleNamespace(mesh=self.mesh1, V_space=space1)
        self.points = self._node_points(ns, m.dofs1)
        nrm = self._default_normals(space1, m.dofs1, "C")
        self._normal_fn, self._gap_fn = None, None
        self._set_frame(nrm)
        self.gap = self.gap_at(self.points, self.n)
        self.w = self._lobatto_weights(self.mesh1, space1, m.dofs1, "C")
        # body 2's Neumann problem (4.88): prescribed sides, load on Gamma^2_C
        self.steps2 = BandSteps(work, self.fixed2, self.values2, extrapolate=False)
        # the data's force scale: body 2's prescribed displacement, the other dofs held
        K2D = self.work.K.tocsc()[:, self.fixed2]
        self.data_force2 = float(np.abs(K2D @ self.values2).max(initial=0.0))
        # the mortar projection as a matrix on interleaved vectors (2 nc x 2 n2c)
        Pi = spla.splu(sp.csc_matrix(m.D)).solve(m.B.toarray())     # D^-1 B, (4.87)
        self.Pi = np.kron(Pi, np.eye(2))

    # ---------------------------------------------------------------- overrides
    def gap_at(self, x, normals) -> np.ndarray:
        """Initial gap along ``normals`` from x to Gamma^2_C (the straight side of the
        work piece; +inf where the ray misses it)."""
        return ray_gap(x, normals, self.mesh2, "C")

    def _normal(self, x) -> np.ndarray:
        e, _ = self.mesh1.locate(x)
        return self.mesh1.normals[e]

    def _global_operators(self):
        raise ValueError("body 2 is elastoplastic: the linear global operators of "
                         "Algorithm 4.5 do not exist; use dtn or monolithic")

    def norm_W(self, U1, U2) -> float:
        raise ValueError("norm_W needs BE bodies; FE bodies have no W")

    # ---------------------------------------------------------------- step 2
    def neumann(self, P, u0=None, tol: float = 1e-8, max_iter: int = 30):
        """Step 2 of Algorithm 4.3 for the elastoplastic body 2: f_int(U2) = -P on
        Gamma^2_C (P: a functional on the contact dofs of body 2, i.e. the force on body
        1 transferred by the adjoint mortar projection), U2 prescribed on its Dirichlet
        side; one step from the committed history, Newton from ``u0`` (default: the
        elastic solution, :meth:`elastic_start`) until ||R||_inf <= tol x (force scale +
        :attr:`newton_floor`).  Returns (U2 on all FE dofs, SolverInfo)."""
        st = self.steps2
        f = np.zeros(self.work.ndofs)
        f[self.c2] = -np.asarray(P, dtype=float)
        st.f_ext = f
        x0 = self.elastic_start(f) if u0 is None else np.asarray(u0, dtype=float)
        it, info = newton(st.problem(1.0), st.start(x0, 1.0), tol, max_iter,
                          atol=tol * self.newton_floor, norm=np.inf)
        return it.x, info

    @property
    def force_floor(self) -> float:
        """:attr:`J2Material.stress_floor` (sigma_Y, at most 1e-3 E) x the shortest cell
        edge of body 2: the nodal force of a yield-level traction, the absolute floor of
        the Newton stopping test (times its tolerance; at a stress-free state, e.g. the
        rigid lift of the first DtN iteration, the relative test alone would ask for
        round-off).  Uncapped, sigma_Y = 4e12 gave a floor above every force of the
        Section 4.4 scene: Newton accepted its start and DtN 'converged' to a work
        piece that never deformed."""
        h = self.__dict__.get("_h_min")
        if h is None:           # the mesh is fixed: its shortest edge once (every Newton)
            p, f = self.work.mesh.p, self.work.mesh.facets
            h = self._h_min = float(np.linalg.norm(p[:, f[0]] - p[:, f[1]], axis=0).min())
        return self.work.material.stress_floor * h

    @property
    def newton_floor(self) -> float:
        """The absolute floor of the Newton tests (times their tolerance):
        :attr:`force_floor` capped by ``data_force2`` (the forces of body 2's prescribed
        displacement), scale-free as the displacement goes to 0 (the floor alone
        accepted the rigid start of a lift of 1e-14); on Section 4.4 it is force_floor."""
        return min(self.force_floor, self.data_force2)

    def elastic_start(self, f_ext) -> np.ndarray:
        """The linear elastic response of body 2 to the prescribed values and the load
        ``f_ext`` (the elastic predictor of its Newton iteration; a start with the
        prescribed values beside zeros would put the first iterate far into the plastic
        range)."""
        st = self.steps2
        if not hasattr(self, "_K2"):
            K = self.work.K.tocsc()
            self._K2 = (spla.splu(K[st.free][:, st.free]), K[st.free][:, st.fixed])
        lu, KfD = self._K2
        u = np.zeros(self.work.ndofs)
        u[st.fixed] = st.values
        u[st.free] = lu.solve(np.asarray(f_ext)[st.free] - KfD @ st.values)
        return u

    # ---------------------------------------------------------------- DtN
    def neumann_step(self, load, state: DtNState | None = None):
        """Step 2 of Algorithm 4.3 as :func:`hpfebe.solvers.dtn.dtn` calls it:
        :meth:`neumann` under the functional ``load``, warm-started from ``state.u2``,
        with the Newton settings ``state.data["newton"]`` (default
        :class:`NeumannSettings`).  Returns (U2 on all FE dofs, its values on the dofs
        c2, the Newton SolverInfo - one that did not converge named "Neumann problem
        (Newton)": it ends the DtN iteration with its reason)."""
        u0, newton = (None, None) if state is None else (state.u2, state.data.get("newton"))
        newton = NeumannSettings() if newton is None else newton
        u2, info = self.neumann(load, u0, newton.tol, newton.max_iter)
        if not info.converged:
            info = SolverInfo(False, f"Neumann problem (Newton): {info.reason}",
                              steps=[info])
        return u2, u2[self.c2], info

    def dtn(self, settings: DtNSettings, newton: NeumannSettings = NeumannSettings(),
            coupling_tol: float = 1e-3, F: float | None = None, hook=None
            ) -> MortarSolution:
        """Algorithm 4.3 with the elastoplastic Neumann problem (Remark 4.3.5), by
        :func:`hpfebe.solvers.dtn.dtn` (its steps, the stopping rule and the readings
        ``settings.transfer`` are described there - the fixed point of "function" is not
        the consistent discrete problem; the settings of Section 4.4:
        :func:`hpfebe.scenes.section44.dtn_settings`): step 2 f_int(U2_k) = L2 - P_k
        (:meth:`neumann_step`, Newton ``newton``), step 4 the stamp's frictional contact
        problem against Q_k with given friction F (Uzawa, Algorithm 4.4,
        ``settings.uzawa``: step rho - absolute unless ``relative`` -; multiplier and QP
        warm-started from the last DtN iteration; :meth:`contact_step`), step 5 R1 =
        S1 U1 - L1 on Gamma^1_C (:meth:`reaction`), step 6 as printed
        (``settings.relaxation`` "convex").  Step 7 stops at ||P_{k+1} - P_k||_2 <= TOL
        ||P_{k+1}||_2; the thesis divides by ||P_k||, the previous iterate: the two
        thresholds differ by a factor 1 + O(TOL), the counts are the same (measured on
        Table 4.2, every reading recorded by a ``hook``).  Converged only if also the
        obstacle matches the work piece, ||Q_n - (pi U2)_n||_inf <= ``coupling_tol``
        ||(pi U2)_n||_inf (``info.backward_error``), and the work piece's equilibrium
        residual under P (:meth:`kkt_residual`, ``equilibrium2``) is <= ``coupling_tol``.

        ``newton``: step 2 to ||R||_inf <= tol x (force scale + :attr:`newton_floor`);
        the thesis's TOL_N = 1e-4 in this norm leaves the Neumann solutions too inexact
        for TOL_DtN = 1e-6 (the DtN increments stagnate at ~4e-5), hence the default
        1e-8 (Newton converges quadratically: one more iteration).  ``F``: a given
        friction bound replacing the scene's (e.g. 0: frictionless).  ``hook``: called
        with the :class:`~hpfebe.solvers.dtn.DtNState` after every DtN iteration (P_k,
        P_k+1, U2_k-1 - None in the first -, U2_k), e.g. the readings of the stopping
        rule, :class:`hpfebe.scenes.section44.DtNReadings`.

        ``info.steps[k]``: the inner SolverInfo of DtN iteration k + 1, its ``counts``
        the Uzawa and Newton iterations; ``info.counts["relative_increments"]``: the
        quantity of the stopping test, ||P_k+1 - P_k|| / ||P_k+1||, per iteration (the
        run stopped at a looser TOL is its first entry <= TOL), ``P_norms`` the
        ||P_k+1||.  ``extra``: the FE vectors ``u1``, ``u2``, the force of step 2 on
        body 2 ``force2`` and the work piece's stress fields (:meth:`work_fields`)."""
        bound = None
        if F is not None:
            bound = np.full(self.nc, real("F", F, nonnegative=True))
        coupling_tol = real("coupling_tol", coupling_tol, positive=True)
        norms = []

        def iteration(st: DtNState) -> SolverInfo:
            """The inner SolverInfo of one DtN iteration (Newton of step 2, Uzawa of
            step 4), ||P_k+1|| and the caller's hook."""
            ninfo, uinfo = st.neumann_info, st.contact_info
            inner = SolverInfo(uinfo.converged, uinfo.reason, uinfo.iterations,
                               steps=[ninfo, uinfo],
                               counts=dict(uzawa=uinfo.iterations,
                                           newton=ninfo.iterations))
            if not uinfo.converged:
                inner.reason = f"Uzawa: {uinfo.reason}"
            norms.append(float(np.linalg.norm(st.P_new)))
            if hook is not None:
                hook(st)
            return inner

        P, info, st = dtn(self, settings, iteration, bound=bound, data=dict(newton=newton))
        rho = self.rho_step(settings.uzawa.rho, settings.uzawa.relative)
        return self._dtn_solution(P, info, st, norms, rho, settings.transfer, newton,
                                  coupling_tol)

    def _dtn_solution(self, P, info: SolverInfo, st: DtNState, norms: list, rho: float,
                      transfer: str, newton: NeumannSettings,
                      coupling_tol: float) -> MortarSolution:
        """The end of :meth:`dtn`: iteration counts, U2 of the final P, and the backward
        error of the transfer (a converged P must make the obstacle Q the work piece)."""
        m = self.mortar
        load2, _ = transfer_maps(m, transfer)
        info.counts = dict(
            uzawa_first=info.steps[0].counts.get("uzawa", 0) if info.steps else 0,
            uzawa_total=int(sum(s.counts.get("uzawa", 0) for s in info.steps)),
            newton_total=int(sum(s.counts.get("newton", 0) for s in info.steps)),
            rho=rho, relative_increments=[
                r / max(n, np.finfo(float).tiny) for r, n in zip(info.residuals, norms)],
            P_norms=norms)
        u2 = st.u2 if st.u2 is not None else self.elastic_start(np.zeros(self.work.ndofs))
        if info.converged:                       # U2 of the final P (step 2 once more)
            u2, ninfo = self.neumann(load2(P), u2, newton.tol, newton.max_iter)
            if not ninfo.converged:
                info.converged, info.reason = False, f"final Neumann solve: {ninfo.reason}"
        x = st.x if st.x is not None else np.zeros(2 * self.nc)
        info.backward_error = contact_backward_error(self, x, st.R1, m.project(u2[self.c2]))
        if info.converged and info.backward_error > coupling_tol:
            info.converged = False
            info.reason = (f"no solution: P stopped changing but the stamp's contact "
                           f"conditions against the work piece's (pi U2)_n are violated "
                           f"by {info.backward_error:.1e} (relative) > coupling_tol = "
                           f"{coupling_tol:g}")
        u1 = self.body1.expand(self.R.T @ x)
        sol = MortarSolution(u1[self.c1], u2[self.c2], st.lam, st.Q, P, x, info,
                             extra=dict(u1=u1, u2=u2, force2=load2(P),
                                        fields=self.work_fields(u2)))
        # backward error of step 2, independent of the Newton test and its floor: the
        # returned U2 must carry the returned P
        eq = self.kkt_residual(sol)["equilibrium2"] if info.converged else np.nan
        if info.converged and not eq <= coupling_tol:
            info.converged = False
            info.reason = (f"no solution: the work piece's equilibrium residual {eq:.1e} "
                           f"(relative) > coupling_tol = {coupling_tol:g}")
        return sol

    # ---------------------------------------------------------------- monolithic
    def monolithic(self, tol: float = 1e-10, max_iter: int = 60,
                   c: float | None = None) -> MortarSolution:
        """(Beyond the thesis) the discrete problem of :meth:`dtn` solved at once by a
        semismooth Newton method (:func:`hpfebe.solvers.newton`, line search on
        1/2 |F|^2) on the KKT system :class:`MonolithicKKT`.  c: the complementarity
        constant (default the mean diagonal of A1).  Stop: ||F||_inf <= tol x (force
        scale + min(force_floor, the data's force scale ``kkt.data_scale``)).  The
        solution is kept per (tol, max_iter, c) and returned again (the same object): the
        problem does not change - the DtN runs commit no history - and Table 4.2's
        claims ask for it twice (the tangential share, the monolithic claim)."""
        tol, max_iter = tolerance("tol", tol), integer("max_iter", max_iter, lo=1)
        memo = self.__dict__.setdefault("_monolithic", {})
        key = (tol, max_iter, c)
        if key not in memo:
            memo[key] = _monolithic_solve(self, tol, max_iter, c)
        return memo[key]

    # ---------------------------------------------------------------- post-processing
    def work_fields(self, u2) -> dict:
        """The work piece's stress at U2 (one step from the committed history, nothing
        committed): ||dev sigma|| (Frobenius norm of the 3 x 3 deviator), ||eps_p|| and
        the element means (``*_mean``)."""
        _, _, rm = self.work.response(np.asarray(u2, dtype=float))
        fe = self.work
        out = {"dev_sigma_norm": tensor_norm(dev(rm.sigma)).reshape(fe.nel, fe.nq),
               "eps_p_norm": tensor_norm(rm.state.eps_p).reshape(fe.nel, fe.nq)}
        w = fe.dx / fe.dx.sum(axis=1, keepdims=True)
        for k in list(out):
            out[k + "_mean"] = (out[k] * w).sum(axis=1)
        return out

    def kkt_residual(self, sol: MortarSolution) -> dict:
        """Backward errors of a solution: the work piece's equilibrium under the
        transferred force (||f_int + P||_inf / max |f_int| on its free dofs; P the
        force of step 2, ``extra["force2"]``) and the
        Tresca conditions (:meth:`tresca_residual`)."""
        u2 = sol.extra["u2"]
        f, _ = self.work.internal_force(u2)
        r = f.copy()
        r[self.c2] += sol.extra.get("force2", sol.P)
        free = self.steps2.free
        scale = max(float(np.abs(f).max()), float(np.abs(r - f).max())) + self.newton_floor
        out = dict(equilibrium2=float(np.abs(r[free]).max() / max(scale, 1e-300)))
        out.update(self.tresca_residual(sol))
        return out


def _monolithic_solve(pr: "FEMortarContact", tol: float, max_iter: int,
                      c: float | None) -> MortarSolution:
    """:meth:`FEMortarContact.monolithic` itself (not memoised)."""
    st2 = pr.steps2
    st2.f_ext = np.zeros(pr.work.ndofs)
    st2.problem(1.0)
    c = real("c", np.mean(np.diag(pr.body1.A)) if c is None else c, positive=True)
    kkt = MonolithicKKT(pr, c)
    it, info = newton(kkt, kkt.start(), tol, max_iter,
                      atol=tol * min(pr.force_floor, kkt.data_scale), norm=np.inf)
    u1c, u2, y = kkt.split(it.x)
    info.counts = dict(c=c, unknowns=int(it.x.size))
    nc, bound = pr.nc, pr.F * pr.w
    x = pr.R @ u1c
    Q = pr.Pi @ u2[pr.c2]
    lam = np.divide(y[nc:], bound, out=np.zeros(nc), where=bound > 0)
    P = -pr.mortar.adjoint(pr.R.T @ y)
    return MortarSolution(u1c, u2[pr.c2], lam, Q, P, x, info,
                          extra=dict(u1=pr.body1.expand(u1c), u2=u2, y=y,
                                     fields=pr.work_fields(u2)))


def contact_backward_error(pr: "FEMortarContact", x, R1, Q_true) -> float:
    """Backward error of the transfer (step 3) of :meth:`FEMortarContact.dtn`: the
    normal contact conditions of the stamp's x = (U_n, U_t) and nodal force
    y_n = -R1_n >= 0 against the returned work piece's obstacle Q* = pi U2 (not the
    damped Q of the last step 3), max_j |min(y_j / c, g_j + Q*_n,j - U_n,j)| / max |Q*_n|
    (c of :meth:`FEMortarContact.monolithic`; nodes without a gap skipped): zero iff
    y >= 0, slack >= 0, y x slack = 0.  In contact (y_j / c above the mismatch) it is
    |Q_n - Q*_n|, the former measure, which called the P = 0 of a correct lift-off 'no
    solution'.  Q_t enters only through the slip direction where the stamp slides."""
    qs = pr.frame(Q_true)[0]
    y = np.zeros(pr.nc) if R1 is None else -pr.frame(R1)[0]
    c = float(np.mean(np.diag(pr.body1.A)))
    closed = np.isfinite(pr.gap)
    slack = np.where(closed, pr.gap, 0.0) + qs - x[:pr.nc]
    r = np.where(closed, np.minimum(y / c, slack), 0.0)
    return float(np.abs(r).max(initial=0.0) / max(np.abs(qs).max(initial=0.0), 1e-300))


# --------------------------------------------------------------------------- monolithic
class MonolithicKKT:
    """(Beyond the thesis) the discrete problem of :meth:`FEMortarContact.dtn` at once,
    as a Newton problem (:class:`hpfebe.solvers.NewtonProblem`, semismooth).  Unknowns:
    the stamp's contact values u1 (condensed), the work piece's free dofs u2 and the
    nodal contact forces y = (y_n, y_t) on body 1 in the node frames (force on body 1 =
    -R^T y, on body 2 = +pi^T R^T y):

        A1 u1 - b1 + R^T y = 0,   f_int(u2) - pi^T R^T y = 0 (free dofs),
        y_n - max(0, y_n + c (d_n - g)) = 0,
        y_t - clip(y_t + c d_t, -F w, F w) = 0,     d = R (u1 - pi u2|Gamma_C),

    the KKT conditions of step 4 (projected CG + Uzawa) and the equilibrium of step 2
    at a DtN fixed point; c > 0 the complementarity constant.  The work piece's
    prescribed values are those of ``pr.steps2`` (its load set to zero first)."""

    def __init__(self, pr: "FEMortarContact", c: float):
        nc, R, free2 = pr.nc, pr.R, pr.steps2.free
        n1, nf = 2 * nc, free2.size
        self.pr, self.c, self.nc, self.R, self.free2 = pr, c, nc, R, free2
        self.A1, self.b1 = pr.body1.A, pr.body1.b
        pos2 = -np.ones(pr.work.ndofs, dtype=np.int64)
        pos2[free2] = np.arange(nf)
        # d = R u1 - R Pi u2[c2]: the columns of c2 among the free dofs of body 2
        RPi = sp.csr_matrix(R @ pr.Pi)
        self.G2 = sp.csr_matrix((RPi.data, pos2[pr.c2][RPi.indices], RPi.indptr),
                                shape=(n1, nf))
        self.Rs = sp.csr_matrix(R)
        self.closed = np.isfinite(pr.gap)
        self.gap = np.where(self.closed, pr.gap, 0.0)
        self.bound = pr.F * pr.w
        self.u2_0 = pr.elastic_start(pr.steps2.f_ext)
        # the force scale of the data (:attr:`FEMortarContact.newton_floor`): body 2's
        # prescribed displacement, body 1's load, an initial overlap times c
        over = np.where(self.closed, np.maximum(0.0, -self.gap), 0.0)
        self.data_scale = max(pr.data_force2, float(np.abs(self.b1).max(initial=0.0)),
                              c * float(over.max(initial=0.0)))
        self.sl = (slice(0, n1), slice(n1, n1 + nf), slice(n1 + nf, 2 * n1 + nf))

    def start(self) -> np.ndarray:
        """z_0: the stamp and the forces zero, the work piece's elastic response."""
        z0 = np.zeros(self.sl[2].stop)
        z0[self.sl[1]] = self.u2_0[self.free2]
        return z0

    def split(self, z):
        """(u1, the work piece's full displacement u2, y) of the unknowns z."""
        u2 = self.u2_0.copy()
        u2[self.free2] = z[self.sl[1]]
        return z[self.sl[0]], u2, z[self.sl[2]]

    def evaluate(self, z) -> Iterate:
        nc, c, bound = self.nc, self.c, self.bound
        u1, u2, y = self.split(z)
        f2, T2 = self.pr.work.internal_force(u2)
        d = self.R @ u1 - self.G2 @ z[self.sl[1]]
        zn = np.where(self.closed, y[:nc] + c * (d[:nc] - self.gap), -1.0)
        zt = y[nc:] + c * d[nc:]
        r = np.concatenate([self.A1 @ u1 - self.b1 + self.R.T @ y,
                            f2[self.free2] - self.G2.T @ y,
                            y[:nc] - np.maximum(0.0, zn),
                            y[nc:] - np.clip(zt, -bound, bound)])
        act, stick = zn > 0, np.abs(zt) < bound
        scale = max(float(np.abs(f2).max(initial=0.0)), 1e-300)
        return Iterate(z, r, 0.5 * float(r @ r), scale,
                       key=(act.tobytes(), stick.tobytes()), data=(act, stick, T2))

    def step(self, it: Iterate) -> np.ndarray:
        act, stick, T2 = it.data
        keep = np.concatenate([act, stick])      # rows -c dd; others dy
        Kd = sp.diags(np.where(keep, -self.c, 0.0))
        Ky = sp.diags(np.where(keep, 0.0, 1.0))
        J = sp.bmat([[sp.csr_matrix(self.A1), None, self.Rs.T],
                     [None, T2[self.free2][:, self.free2], -self.G2.T],
                     [Kd @ self.Rs, -(Kd @ self.G2), Ky]], format="csc")
        try:        # minimum degree on J + J^T: 1.8x faster than COLAMD here (measured)
            dz = spla.splu(J, permc_spec="MMD_AT_PLUS_A").solve(-it.residual)
        except RuntimeError as e:
            raise SingularStep(f"singular Newton matrix: {e}") from None
        if not np.all(np.isfinite(dz)):
            raise SingularStep("singular Newton matrix: non-finite step")
        return dz

    def slope(self, it: Iterate, dz) -> float:
        return -2.0 * it.merit


__all__ = ["FEMortarContact", "MonolithicKKT", "NeumannSettings", "spd_band_solve"]
