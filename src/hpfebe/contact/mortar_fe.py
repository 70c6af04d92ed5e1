"""Mortar contact of two FE bodies, the second one elastoplastic (Section 4.4, thesis
lines 20355-20460; Algorithm 4.3 with Remark 4.3.5): an elastic FE body 1 (the stamp,
contact / mortar side) and a J2 elastoplastic FE body 2 (the work piece,
:class:`hpfebe.fem.plastic_body.ElastoPlasticFE`, Neumann side).

The machinery is that of the hp-mortar BEM (:mod:`hpfebe.contact.mortar`):
:class:`FEMortarContact` is a :class:`~hpfebe.contact.mortar.MortarContact` whose body 1
is the FE stiffness of the stamp condensed onto its contact dofs
(:class:`~hpfebe.contact.mortar.CondensedBody`, one Cholesky factorisation, built once
and reused by every DtN iteration and every damping pair), so the frictional contact
problem of step 4 (Uzawa, Algorithm 4.4, with Polyak's projected CG for the inner QP),
the frame, the gap and the Lobatto weights are inherited unchanged.  The traces of the
Q1 bodies on their boundaries are the continuous P1 spaces of
:class:`~hpfebe.spaces.ContinuousSpace` on a :class:`~hpfebe.geometry.BoundaryMesh`
through the FE boundary vertices (:func:`fe_trace_mesh`), and the data transfer is the
mortar projection (4.87) of :class:`hpfebe.coupling.mortar.MortarProjection`.

What differs from the BEM version is step 2: the Neumann problem of body 2 is the
elastoplastic one (Remark 4.3.5: the nonlinearities are separated),

    f_int(U^2_k) = -P_k on Gamma^2_C,   U^2_k = u_D on Gamma^2_D,                   (4.88)

one backward-Euler step (4.38)-(4.43) from the committed (virgin) history of the work
piece, solved by :func:`hpfebe.solvers.nonlinear.newton` on the body's
:class:`~hpfebe.fem.plastic_body.DisplacementSteps` problem (consistent tangent,
Armijo line search; each Newton system by the banded Cholesky factorisation of the
symmetric positive definite tangent, :class:`_BandSteps`, 15-18x faster than SuperLU on the
Section 4.4 work piece), warm-started from the previous DtN iterate.  The history is not
committed during the DtN iteration (its iterates are not load increments), so every
DtN iteration and every damping pair solves the same one-step problem.

:meth:`FEMortarContact.monolithic` (beyond the thesis) solves the same discrete problem
at once: the stamp, the work piece and the nodal contact forces by a semismooth Newton
method on the complementarity functions of the normal contact and the Tresca law.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg import lapack

from ..coupling.mortar import MortarProjection
from ..fem.elasticity import ElasticBody
from ..fem.plastic_body import DisplacementSteps, ElastoPlasticFE
from ..constitutive.j2 import dev, tensor_norm
from ..geometry import BoundaryMesh
from ..solvers import Iterate, SingularStep, SolverInfo, fixed_point, newton
from ..spaces import ContinuousSpace
from .mortar import (CondensedBody, MortarContact, MortarSolution, _check_omega,
                     _check_pos, ray_gap)

SIDES = ("bottom", "right", "top", "left")

#: Readings of the DtN stopping rule (Algorithm 4.3, step 7: "stop if ||P^k - P^k-1|| <=
#: TOL_DtN ||P^k-1||"), recorded per iteration by :meth:`FEMortarContact.dtn` in
#: ``info.counts["readings"]``: the quantity (P: the transferred traction functional on
#: Gamma^2_C; U2: the work piece's displacement of step 2), the norm (l2 / max of the
#: coefficient vector, L2(Gamma_C) of the function M2^-1 P, the elastic energy norm of
#: U2, U2 on Gamma^2_C) and the reference (the previous iterate - the printed rule -, the
#: new one - :func:`hpfebe.solvers.nonlinear.fixed_point`'s -, or the first nonzero P).
#: "P_n_l2_prev": the normal components of P alone (a test on the contact pressure).
#: "P_t_l2_prev" is no reading but a bound: the tangential components of P's increment
#: alone, relative to ||P^k-1|| (<= P_l2_prev: the printed rule cannot stop before it
#: falls below TOL).  Where the stamp slides, step 6 relaxes the tangential traction
#: alone (R1_t = F w lambda, |lambda| = 1, does not change), so this quantity contracts by
#: exactly 1 - omega_N per iteration.
READINGS = ("P_l2_prev", "P_l2_new", "P_max_prev", "P_L2gamma_prev", "P_l2_first",
            "U2_l2_prev", "U2_max_prev", "U2_energy_prev", "U2_contact_prev", "P_n_l2_prev",
            "P_t_l2_prev")


# --------------------------------------------------------------------------- traces
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


def _vector_dofs(body, vertex) -> np.ndarray:
    """Interleaved FE dofs (x, y of each vertex in turn) of the vertices ``vertex``."""
    return np.asarray(body.nodal_dofs)[:, np.asarray(vertex, dtype=np.int64)].T.ravel()


def _dirichlet(body, spec, name):
    try:
        label, value = spec
        value = np.asarray(value, dtype=float).reshape(2)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be (label, (ux, uy)), got {spec!r}") from None
    if label not in SIDES:
        raise ValueError(f"{name}: label must be one of {SIDES}, got {label!r}")
    fixed = body.dofs_on(label)
    comp = np.zeros(body.ndofs, dtype=np.int64)
    comp[body.nodal_dofs[1]] = 1
    return fixed, value[comp[fixed]]


# --------------------------------------------------------------------------- solves
class _BandPattern:
    """The lower band storage (LAPACK) of a square CSR sparsity pattern (``indptr``,
    ``indices``, sorted), with the position of the mirror entry (j, i) of every lower
    entry (i, j): :meth:`solve` checks the symmetry of given values and solves by the
    banded Cholesky factorisation.  ``ok`` is False (no band solve) for a structurally
    non-symmetric pattern or a band of more than ``max_fill`` n^2 entries."""

    def __init__(self, indptr, indices, n: int, max_fill: float = 0.25):
        row = np.repeat(np.arange(n), np.diff(indptr))
        col = np.asarray(indices, dtype=np.int64)
        d = row - col
        self.n, self.bw = n, int(np.abs(d).max(initial=0))
        self.low = np.flatnonzero(d >= 0)
        self.dl, self.cl = d[self.low], col[self.low]
        key = row * n + col                              # sorted: row-major, cols sorted
        mkey = col[self.low] * n + row[self.low]
        pos = np.minimum(np.searchsorted(key, mkey), max(key.size - 1, 0))
        self.mirror = pos
        self.ok = bool((self.bw + 1) * n <= max_fill * n * n + n and key.size and
                       np.array_equal(key[pos], mkey))

    def solve(self, data, b):
        """x = A^-1 b for the matrix of this pattern with the values ``data``; None if it
        is not symmetric (relative 1e-12) or not positive definite."""
        if not self.ok:
            return None
        v = data[self.low]
        if np.abs(v - data[self.mirror]).max(initial=0.0) > \
                1e-12 * np.abs(v).max(initial=0.0):
            return None
        ab = np.zeros((self.bw + 1, self.n))
        ab[self.dl, self.cl] = v
        _, x, info = lapack.dpbsv(ab, np.asarray(b, dtype=float), lower=1)
        return x if info == 0 and np.all(np.isfinite(x)) else None


def spd_band_solve(A, b, max_fill: float = 0.25):
    """x = A^-1 b for a symmetric positive definite sparse ``A`` whose entries lie in a
    narrow band around the diagonal (a tensor FE mesh in its natural numbering), by the
    banded Cholesky factorisation of LAPACK (dpbsv): O(n bw^2) flops, about 13x faster
    than SuperLU on the work piece's tangent of Section 4.4 (n = 3844, bandwidth 65;
    measured 1.7 ms against 22 ms).  Returns None - the caller falls back to a general
    sparse solve - if the band would hold more than ``max_fill`` n^2 entries, ``A`` is
    not symmetric (relative 1e-12) or not positive definite."""
    A = sp.csr_matrix(A)
    if A.shape[0] != A.shape[1]:
        return None
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    return _BandPattern(A.indptr, A.indices, A.shape[0], max_fill).solve(A.data, b)


class _BandSteps(DisplacementSteps):
    """:class:`~hpfebe.fem.plastic_body.DisplacementSteps` whose Newton step solves the
    (symmetric positive definite) consistent tangent on the free dofs by the banded
    Cholesky factorisation (:class:`_BandPattern`, built once for the tangent's
    sparsity pattern: the free-free block is gathered from the tangent's values by a
    fixed index), SuperLU where that declines."""

    def _free_block(self, T):
        """(values of T[free][:, free] in CSR order, its :class:`_BandPattern`); the
        gather index and the pattern cached for T's sparsity pattern."""
        T = sp.csr_matrix(T)
        c = self.__dict__.get("_band")
        if c is None or not (np.array_equal(c[0], T.indptr) and
                             np.array_equal(c[1], T.indices)):
            pos = sp.csr_matrix((np.arange(T.nnz, dtype=float), T.indices, T.indptr),
                                shape=T.shape)[self.free][:, self.free]
            pos.sort_indices()
            pattern = _BandPattern(pos.indptr, pos.indices, self.free.size)
            c = self.__dict__["_band"] = (T.indptr.copy(), T.indices.copy(),
                                          pos.data.astype(np.int64), pattern)
        return T.data[c[2]], c[3]

    def step(self, it: Iterate) -> np.ndarray:
        T = self.tangent(it)
        if sp.issparse(T) and T.format == "csr" and T.has_canonical_format:
            vals, pattern = self._free_block(T)
            d = pattern.solve(vals, -it.residual)
        else:
            d = spd_band_solve(T[self.free][:, self.free], -it.residual)
        if d is None:
            return super().step(it)
        dx = np.zeros_like(it.x)
        dx[self.free] = d
        return dx


# --------------------------------------------------------------------------- problem
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
        if not isinstance(stamp, ElasticBody):
            raise ValueError(f"stamp must be an ElasticBody, got {type(stamp).__name__}")
        if not isinstance(work, ElastoPlasticFE):
            raise ValueError(f"work must be an ElastoPlasticFE, got {type(work).__name__}")
        if not np.isfinite(F) or F < 0:
            raise ValueError(f"F must be >= 0, got {F!r}")
        self.stamp, self.work, self.F = stamp, work, float(F)
        self.mesh1, space1, vert1 = fe_trace_mesh(stamp.mesh, contact1)
        self.mesh2, space2, vert2 = fe_trace_mesh(work.mesh, contact2)
        self.mortar = m = MortarProjection(self.mesh1, self.mesh2, "C", "C", (1.0, 0.0),
                                           space1, space2, "full")
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
        self.steps2 = _BandSteps(work, self.fixed2, self.values2, extrapolate=False)
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
        :attr:`force_floor`).  Returns (U2 on all FE dofs, SolverInfo)."""
        st = self.steps2
        f = np.zeros(self.work.ndofs)
        f[self.c2] = -np.asarray(P, dtype=float)
        st.f_ext = f
        x0 = self.elastic_start(f) if u0 is None else np.asarray(u0, dtype=float)
        it, info = newton(st.problem(1.0), st.start(x0, 1.0), tol, max_iter,
                          atol=tol * self.force_floor, norm=np.inf)
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
        p = self.work.mesh.p
        f = self.work.mesh.facets
        h = float(np.linalg.norm(p[:, f[0]] - p[:, f[1]], axis=0).min())
        return self.work.material.stress_floor * h

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
    def dtn(self, omega_D: float, omega_N: float, rho: float = 8.264e5, tol: float = 1e-6,
            tol_U: float = 1e-6, max_iter: int = 200, max_uzawa: int = 2000,
            divergence: float = 1e6, rho_relative: bool = False,
            newton_tol: float = 1e-8, newton_max_iter: int = 30,
            coupling_tol: float = 1e-3, transfer: str = "functional",
            F: float | None = None) -> MortarSolution:
        """Algorithm 4.3 with the elastoplastic Neumann problem (Remark 4.3.5):

        2. f_int(U2_k) = L2 - P_k (:meth:`neumann`, Newton, tolerance ``newton_tol``),
        3. Q_k = (1 - omega_D) Q_{k-1} + omega_D D^-1 B U2_k,
        4. the stamp's frictional contact problem against Q_k with given friction F
           (Uzawa, Algorithm 4.4, step ``rho`` - absolute unless ``rho_relative``,
           tolerance ``tol_U``; multiplier and QP warm-started from the last DtN
           iteration),
        5. R1 = S1 U1 - L1 on Gamma^1_C,
        6. P_{k+1} = (1 - omega_N) P_k + omega_N B^T D^-T R1,
        7. stop if ||P_{k+1} - P_k||_2 <= TOL ||P_{k+1}||_2 (:func:`fixed_point`; the
           thesis divides by ||P_k||, the previous iterate: the two thresholds differ by
           a factor 1 + O(TOL), the counts are the same - measured on Table 4.2, every
           reading in ``info.counts["readings"]``, :data:`READINGS`; growth of the
           increment by ``divergence``, a failed Newton or Uzawa solve or ``max_iter``
           end it with the reason); converged only if also the obstacle matches the
           work piece, ||Q_n - (pi U2)_n||_inf <= ``coupling_tol`` ||(pi U2)_n||_inf
           (``info.backward_error``) and the work piece's equilibrium residual under P
           (:meth:`kkt_residual`, ``equilibrium2``) is <= ``coupling_tol``.

        ``newton_tol``: the Newton tolerance of step 2 (||R||_inf <= newton_tol x (force
        scale + :attr:`force_floor`)); the thesis's TOL_N = 1e-4 in this norm leaves
        the Neumann solutions too inexact for TOL_DtN = 1e-6 (the DtN increments
        stagnate at ~4e-5), hence the default 1e-8 (Newton converges quadratically:
        one more iteration).

        ``transfer``: "functional" (consistent: P = B^T D^-T R1 is the force on body 2)
        or "function" (the literal reading of steps 5-6 and (4.88), as
        :meth:`MortarContact.dtn`: R1 = D^-1 r1 and P functions, the load of step 2 the
        L2 pairing M2 P; its fixed point is not the consistent discrete problem).

        ``F``: a given friction bound replacing the scene's (e.g. 0: frictionless).

        ``info.steps[k]``: the inner SolverInfo of DtN iteration k + 1, its ``counts``
        the Uzawa and Newton iterations; ``info.counts["relative_increments"]``: the
        quantity of the stopping test, ||P_k+1 - P_k|| / ||P_k+1||, per iteration (the
        run stopped at a looser TOL is its first entry <= TOL), ``P_norms`` the
        ||P_k+1||.  ``extra``: the FE vectors ``u1``, ``u2``, the force of step 2 on
        body 2 ``force2`` and the work piece's stress fields (:meth:`work_fields`)."""
        _check_omega("omega_D", omega_D)
        _check_omega("omega_N", omega_N)
        _check_pos("rho", rho)
        if transfer not in ("functional", "function"):
            raise ValueError(f"transfer must be 'functional' or 'function', got "
                             f"{transfer!r}")
        rho = self.rho_step(rho, rho_relative)
        bound = None
        if F is not None:
            if not (np.isfinite(F) and F >= 0):
                raise ValueError(f"F must be >= 0, got {F!r}")
            bound = np.full(self.nc, float(F))
        m = self.mortar
        load2 = m.pair2 if transfer == "function" else (lambda P: P)
        to_P = (lambda R1: m.adjoint(m.riesz(R1))) if transfer == "function" else m.adjoint
        st = dict(Q=np.zeros(2 * self.nc), lam=np.zeros(self.nc), x=None, u2=None, pn=[],
                  first=None, readings={k: [] for k in READINGS})

        def update(P):
            u2, ninfo = self.neumann(load2(P), st["u2"], newton_tol, newton_max_iter)
            if not ninfo.converged:
                return P, SolverInfo(False, f"Neumann problem (Newton): {ninfo.reason}",
                                     steps=[ninfo])
            u2_old, st["u2"] = st["u2"], u2
            Q = (1.0 - omega_D) * st["Q"] + omega_D * m.project(u2[self.c2])
            x, lam, uinfo = self.uzawa(Q, rho, tol_U, max_uzawa, st["lam"], st["x"],
                                       bound=bound)
            st.update(Q=Q, lam=lam, x=x)
            R1 = self.body1.reaction(self.R.T @ x)
            inner = SolverInfo(uinfo.converged, uinfo.reason, uinfo.iterations,
                               steps=[ninfo, uinfo],
                               counts=dict(uzawa=uinfo.iterations,
                                           newton=ninfo.iterations))
            if not uinfo.converged:
                inner.reason = f"Uzawa: {uinfo.reason}"
            P_new = (1.0 - omega_N) * P + omega_N * to_P(R1)
            st["pn"].append(float(np.linalg.norm(P_new)))
            if st["first"] is None:
                st["first"] = P_new
            self._record_readings(st["readings"], P, P_new, st["first"], u2_old, u2)
            return P_new, inner

        P, info = fixed_point(update, np.zeros(self.c2.size), tol, max_iter, norm=2,
                              divergence=divergence)
        return self._dtn_solution(P, info, st, rho, load2, newton_tol, newton_max_iter,
                                  coupling_tol)

    def _dtn_solution(self, P, info: SolverInfo, st: dict, rho: float, load2, newton_tol,
                      newton_max_iter, coupling_tol) -> MortarSolution:
        """The end of :meth:`dtn`: iteration counts, U2 of the final P, and the backward
        error of the transfer (a converged P must make the obstacle Q the work piece)."""
        m = self.mortar
        info.counts = dict(
            uzawa_first=info.steps[0].counts.get("uzawa", 0) if info.steps else 0,
            uzawa_total=int(sum(s.counts.get("uzawa", 0) for s in info.steps)),
            newton_total=int(sum(s.counts.get("newton", 0) for s in info.steps)),
            rho=rho, relative_increments=[
                r / max(n, np.finfo(float).tiny) for r, n in zip(info.residuals, st["pn"])],
            readings=st["readings"], P_norms=st["pn"])
        u2 = st["u2"] if st["u2"] is not None else self.elastic_start(
            np.zeros(self.work.ndofs))
        if info.converged:                       # U2 of the final P (step 2 once more)
            u2, ninfo = self.neumann(load2(P), u2, newton_tol, newton_max_iter)
            if not ninfo.converged:
                info.converged, info.reason = False, f"final Neumann solve: {ninfo.reason}"
        # backward error of the transfer: at a fixed point Q_n = (pi U2)_n (step 3; the
        # tangential Q_t enters only through the slip direction where the stamp slides);
        # a P that stops changing because the stamp has lost contact (P = 0 twice) is no
        # solution
        qn, pn = self.frame(st["Q"])[0], self.frame(m.project(u2[self.c2]))[0]
        info.backward_error = float(np.abs(qn - pn).max() / max(np.abs(pn).max(), 1e-300))
        if info.converged and info.backward_error > coupling_tol:
            info.converged = False
            info.reason = (f"no solution: P stopped changing but the obstacle Q_n differs "
                           f"from (pi U2)_n by {info.backward_error:.1e} (relative) > "
                           f"coupling_tol = {coupling_tol:g}")
        x = st["x"] if st["x"] is not None else np.zeros(2 * self.nc)
        u1 = self.body1.expand(self.R.T @ x)
        sol = MortarSolution(u1[self.c1], u2[self.c2], st["lam"], st["Q"], P, x, info,
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

    def _record_readings(self, out: dict, P_old, P_new, P_first, u2_old, u2) -> None:
        """Append the relative increment of DtN iteration k under every reading of the
        stopping rule (:data:`READINGS`) to ``out`` (inf where the reference is zero or
        not yet defined: the first iteration has P_0 = 0 and no previous U2)."""
        def rel(num, den):
            return float(num / den) if den > 0 else np.inf

        dP = P_new - P_old
        if not hasattr(self, "_m2_lu"):
            self._m2_lu = spla.splu(sp.csc_matrix(self.mortar.M2))
            self._K2e = self.work.K.tocsr()

        def l2_gamma(v):                    # ||M2^-1 v||_L2(Gamma_C) of a functional v
            V = v.reshape(-1, 2)
            return float(np.sqrt(max((self._m2_lu.solve(V) * V).sum(), 0.0)))

        def energy(v):
            return float(np.sqrt(max(v @ (self._K2e @ v), 0.0)))

        out["P_l2_prev"].append(rel(np.linalg.norm(dP), np.linalg.norm(P_old)))
        out["P_l2_new"].append(rel(np.linalg.norm(dP), np.linalg.norm(P_new)))
        out["P_max_prev"].append(rel(np.abs(dP).max(), np.abs(P_old).max()))
        out["P_L2gamma_prev"].append(rel(l2_gamma(dP), l2_gamma(P_old)))
        out["P_l2_first"].append(rel(np.linalg.norm(dP), np.linalg.norm(P_first)))
        out["P_t_l2_prev"].append(rel(np.linalg.norm(dP.reshape(-1, 2)[:, self.t2]),
                                      np.linalg.norm(P_old)))
        out["P_n_l2_prev"].append(rel(np.linalg.norm(dP.reshape(-1, 2)[:, 1 - self.t2]),
                                      np.linalg.norm(P_old.reshape(-1, 2)[:, 1 - self.t2])))
        if u2_old is None:
            for k in ("U2_l2_prev", "U2_max_prev", "U2_energy_prev", "U2_contact_prev"):
                out[k].append(np.inf)
            return
        dU = u2 - u2_old
        out["U2_l2_prev"].append(rel(np.linalg.norm(dU), np.linalg.norm(u2_old)))
        out["U2_max_prev"].append(rel(np.abs(dU).max(), np.abs(u2_old).max()))
        out["U2_energy_prev"].append(rel(energy(dU), energy(u2_old)))
        out["U2_contact_prev"].append(rel(np.linalg.norm(dU[self.c2]),
                                          np.linalg.norm(u2_old[self.c2])))

    # ---------------------------------------------------------------- monolithic
    def monolithic(self, tol: float = 1e-10, max_iter: int = 60,
                   c: float | None = None) -> MortarSolution:
        """(Beyond the thesis) the discrete problem of :meth:`dtn` solved at once by a
        semismooth Newton method (:func:`hpfebe.solvers.nonlinear.newton`, line search on
        1/2 |F|^2).  Unknowns: the stamp's contact values u1 (condensed), the work
        piece's free dofs u2 and the nodal contact forces y = (y_n, y_t) on body 1 in
        the node frames (force on body 1 = -R^T y, on body 2 = +pi^T R^T y):

            A1 u1 - b1 + R^T y = 0,   f_int(u2) - pi^T R^T y = 0 (free dofs),
            y_n - max(0, y_n + c (d_n - g)) = 0,
            y_t - clip(y_t + c d_t, -F w, F w) = 0,     d = R (u1 - pi u2|Gamma_C),

        the KKT conditions of step 4 (projected CG + Uzawa) and the equilibrium of step
        2 at a DtN fixed point.  c: the complementarity constant (default the mean
        diagonal of A1).  Stop: ||F||_inf <= tol x force scale."""
        nc, R, A1, b1 = self.nc, self.R, self.body1.A, self.body1.b
        st2 = self.steps2
        st2.f_ext = np.zeros(self.work.ndofs)
        st2.problem(1.0)
        free2 = st2.free
        n1, nf = 2 * nc, free2.size
        pos2 = -np.ones(self.work.ndofs, dtype=np.int64)
        pos2[free2] = np.arange(nf)
        # d = R u1 - R Pi u2[c2]: the columns of c2 among the free dofs of body 2
        RPi = sp.csr_matrix(R @ self.Pi)
        G2 = sp.csr_matrix((RPi.data, pos2[self.c2][RPi.indices], RPi.indptr),
                           shape=(n1, nf))
        Rs = sp.csr_matrix(R)
        c = float(np.mean(np.diag(A1))) if c is None else float(c)
        _check_pos("c", c)
        closed = np.isfinite(self.gap)
        gap = np.where(closed, self.gap, 0.0)
        bound = self.F * self.w
        u2_full0 = self.elastic_start(st2.f_ext)
        sl1, sl2, sly = slice(0, n1), slice(n1, n1 + nf), slice(n1 + nf, 2 * n1 + nf)

        def split(z):
            u2 = u2_full0.copy()
            u2[free2] = z[sl2]
            return z[sl1], u2, z[sly]

        class Problem:
            def evaluate(_, z):
                u1, u2, y = split(z)
                f2, T2 = self.work.internal_force(u2)
                d = R @ u1 - G2 @ z[sl2]
                zn = np.where(closed, y[:nc] + c * (d[:nc] - gap), -1.0)
                zt = y[nc:] + c * d[nc:]
                r = np.concatenate([A1 @ u1 - b1 + R.T @ y, f2[free2] - G2.T @ y,
                                    y[:nc] - np.maximum(0.0, zn),
                                    y[nc:] - np.clip(zt, -bound, bound)])
                act, stick = zn > 0, np.abs(zt) < bound
                scale = max(float(np.abs(f2).max(initial=0.0)), 1e-300)
                return Iterate(z, r, 0.5 * float(r @ r), scale,
                               key=(act.tobytes(), stick.tobytes()), data=(act, stick, T2))

            def step(_, it):
                act, stick, T2 = it.data
                keep = np.concatenate([act, stick])      # rows -c dd; others dy
                Kd = sp.diags(np.where(keep, -c, 0.0))
                Ky = sp.diags(np.where(keep, 0.0, 1.0))
                J = sp.bmat([[sp.csr_matrix(A1), None, Rs.T],
                             [None, T2[free2][:, free2], -G2.T],
                             [Kd @ Rs, -(Kd @ G2), Ky]], format="csc")
                try:
                    dz = spla.splu(J).solve(-it.residual)
                except RuntimeError as e:
                    raise SingularStep(f"singular Newton matrix: {e}") from None
                if not np.all(np.isfinite(dz)):
                    raise SingularStep("singular Newton matrix: non-finite step")
                return dz

            def slope(_, it, dz):
                return -2.0 * it.merit

        z0 = np.zeros(2 * n1 + nf)
        z0[sl2] = u2_full0[free2]
        it, info = newton(Problem(), z0, tol, max_iter, atol=tol * self.force_floor,
                          norm=np.inf)
        u1c, u2, y = split(it.x)
        info.counts = dict(c=c, unknowns=int(z0.size))
        x = R @ u1c
        Q = self.Pi @ u2[self.c2]
        lam = np.divide(y[nc:], bound, out=np.zeros(nc), where=bound > 0)
        P = -self.mortar.adjoint(R.T @ y)
        return MortarSolution(u1c, u2[self.c2], lam, Q, P, x, info,
                              extra=dict(u1=self.body1.expand(u1c), u2=u2, y=y,
                                         fields=self.work_fields(u2)))

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
        out = dict(equilibrium2=float(np.abs(r[free]).max() / max(np.abs(f).max(), 1e-300)))
        out.update(self.tresca_residual(sol))
        return out


def section44_scene(stamp_cells=(10, 20), work_cells=(61, 31), E: float = 266926.0,
                    nu: float = 0.29, sigma_Y: float = 4.0, H: float = 450.0,
                    theta: float = 1.0, F: float = 0.22, lift: float = 1e-4,
                    formulation: str = "bbar") -> FEMortarContact:
    """The mortar scene of Section 4.4: Q1 stamp [-1/2, 1/2] x [0, 2] (``stamp_cells`` =
    (nx, ny)), top fixed, on the J2 (sigma_Y, hardening H, isotropic share theta) Q1
    work piece [-2, 2] x [-2, 0] (``work_cells``) whose bottom is displaced by
    (0, ``lift``); plane strain, Tresca friction F on the stamp's bottom."""
    from ..fem.elasticity import rectangle_mesh
    from ..constitutive.j2 import J2Material

    for name, cells in (("stamp_cells", stamp_cells), ("work_cells", work_cells)):
        if len(cells) != 2 or any(int(k) != k or k < 1 for k in cells):
            raise ValueError(f"{name} must be two positive integers, got {cells!r}")
    stamp = ElasticBody(rectangle_mesh(-0.5, 0.5, 0.0, 2.0, *map(int, stamp_cells)), E, nu)
    work = ElastoPlasticFE(rectangle_mesh(-2.0, 2.0, -2.0, 0.0, *map(int, work_cells)),
                           J2Material(E, nu, sigma_Y, H, theta), formulation)
    return FEMortarContact(stamp, work, ("top", (0.0, 0.0)), ("bottom", (0.0, lift)), F)


__all__ = ["FEMortarContact", "READINGS", "fe_trace_mesh", "section44_scene",
           "spd_band_solve"]
