"""Two elastic bodies in penalty contact with Coulomb friction on non-matching meshes
(Chapter 4, Section 4.2: master-slave gap (4.18), constitutive laws (4.19)-(4.20), the
return map of Section 4.2.5, Newton with load increments, Algorithm 4.1, block systems
(4.27) FE/BE and (4.33) BE/BE).

Bodies.  Each body is either a P1/Q1 finite element body
(:class:`hpfebe.fem.elasticity.ElasticBody`) or a Galerkin boundary element body
(:class:`hpfebe.bem.lame.LameBEM` on a labelled :class:`hpfebe.geometry.BoundaryMesh`).
The contact code below is written once; what depends on the discretisation (stiffness,
contact segments, traces at the contact points, boundary conditions and loads) comes
from a body adapter (:mod:`hpfebe.contact.bem_body`).  A BE body's unknowns are its
boundary displacement in V_hp^2 (interleaved components), its stiffness the dense
discrete Steklov-Poincare operator S_hat, its traces the GLL Lagrange basis of degree p.

Unknowns and block structure.  One dof vector U = (U^s, U^m): the slave body's dofs first,
then the master's (offset = the slave's ndofs), as in (4.27)/(4.33).  The Newton matrix is

    [ K^s + C_ss    -C_sm     ]
    [ -C_ms         K^m + C_mm]   (signs absorbed in the coupling matrices below),

K^b the FE stiffness (sparse) or S_hat (dense, stored as a fully populated block of the
one sparse matrix, so that FE blocks stay sparse), C the linearised contact terms
(sparse); each Newton system is solved by a sparse LU (scipy.sparse.linalg.splu).

Contact points. The thesis evaluates the gap at slave points x^s and leaves the
integration of the contact terms open. Ours (segment-based Gauss-point-to-segment):
every slave facet of Gamma_C^s is split where master vertices of Gamma_C^m project onto
it, and each piece gets ``nq`` Gauss-Legendre points, so that both traces (linear on the
piece) and the contact integrands are integrated exactly for a flat interface: this is
what makes the contact patch test pass to rounding on non-matching meshes. With
``split=False`` the Gauss points of the whole slave facets are used (plain GPTS); the
master forces are then integrated inexactly across master kinks and the patch test fails
at the percent level (5-7 % pressure error on the 4-vs-5 element test). The split is
exact for straight interfaces; on a polygonal master it still puts a break at every
master vertex. Every contact point x^s is projected onto the master polyline Gamma_C^m
(closest point, vectorised: all points against all master segments, parameter clipped to
the segment). Corners: the nearest segment wins; when two segments are equally near (a
point in the exterior cone of a convex corner, or exactly above a shared vertex) the one
on which the unclipped projection parameter lies inside [0, 1] (or the least outside) is
taken, and its normal is used - Wriggers' "nearest segment" rule. A point in the
exterior cone of a corner projects onto the corner vertex (with the normal of the chosen
segment). Points whose projection falls beyond the ends of the master polyline (clipped
onto an end vertex, a vertex of one master facet only) are flagged ``outside`` and carry
no contact.

Small deformation (what Section 4.2.5 linearises: g_n(U_n) = ([U_n] - g)_+ with the normal
fixed): the projection, the master normal n_m (outward of the master body) and tangent
t_m = (n_m,y, -n_m,x) (n_m turned clockwise by 90 degrees: +x on the top side of a lower
body) are computed once, in the reference configuration, and kept fixed.  With
x_m = the projection and N_m the master shape functions at it,

    g_n = (x_s + u_s - x_m - u_m) . n_m     (signed normal gap; penetration  g_n < 0),
    g_t = (u_s - u_m) . t_m                 (relative tangential displacement).

Constitutive laws (signs: p_n >= 0 is the contact pressure, the negative of the thesis's
P_n in (4.19); t_t is the friction traction with the sign of the elastic slip, the
negative of P_t in (4.20)):

    p_n   = (1/eps_n) (-g_n)_+ ,
    t_try = (g_t - g_t^p) / eps_t            (trial, g_t^p the slip of the last step),
    t_t   = t_try                 if |t_try| <= mu_f p_n      (stick)
          = mu_f p_n sign(t_try)  otherwise                   (slip; open: p_n = 0),

and after a converged load step the slip is updated, g_t^p <- g_t - eps_t t_t (backward
Euler).  The traction exerted on the slave body is  p_n n_m - t_t t_m , on the master
its negative.  Weak form: with the internal contact force
f_c(U) . V = sum_q w_q [ -p_n dg_n(V) + t_t dg_t(V) ] (w_q the quadrature weights),

    R(U) = F_ext - K U - f_c(U) = 0   on the free dofs.

Consistent linearisation (4.35) and Section 4.2.5, pointwise, with the active indicator
H = [g_n <= 0] (g_n = 0 counts as active: sign(0) := 1 in Remark 4.2.2, so bodies that
touch in the reference state get contact stiffness in the first Newton step):

    d(-p_n) = (H / eps_n) dg_n,
    d t_t   = (1/eps_t) dg_t                               (stick),
            = -mu_f sign(t_try) (H / eps_n) dg_n           (slip),

so the tangent  K + G_n^T W_n G_n + G_t^T (W_t G_t + W_tn G_n)  (G_n, G_t the sparse maps
U -> dg_n, dg_t at the points, W diagonal) is the exact (generalised) derivative of
R; it is non-symmetric in slip.  Points with g_n > 0 are open: p_n = t_t = 0 (their
slip follows the relative motion, g_t^p <- g_t).  With mu_f = 0 (frictionless) the
tangential terms vanish and active points are reported as SLIP (t_t = 0 = mu_f p_n).
Semismooth Newton: in the piecewise linear setting it terminates once the active and
stick/slip sets are right (the last step drops the residual to rounding); changes of
those sets may take a few non-monotone iterations - or cycle forever between two sets
(measured: the Figure 4.13 scene on its initial mesh h = 1/2 with P1 triangles).
Globalisation (``line_search=True``, off by default so that the plain iteration of the
thesis is what runs unless asked for): Armijo backtracking alpha = 1, 1/2, 1/4, ... on
the merit ||R_free||_2, accepting ||R(U + alpha dU)|| <= (1 - 1e-4 alpha) ||R(U)||.
Justification: R is piecewise linear in U and dU solves the Newton system of the current
piece, so for small alpha ||R(U + alpha dU)|| = (1 - alpha) ||R(U)|| (when U is interior
to its piece; on a kink the one-sided derivative of the new piece enters): the search
succeeds, the residual decreases strictly, and a state once left cannot be met again
with the same residual - no cycle; near the solution the full step is accepted and the
finite termination is kept.  Below ``min_step`` the last trial step is taken.  Non-
symmetric in slip, the problem has no energy, hence the residual as merit.

Algorithm 4.1: for every load factor lambda_j the external load F_ext(lambda_j) and the
Dirichlet values (both arrays scaled by lambda, or callables of lambda) are applied, the
start iterate is the last converged state with the new Dirichlet values, and Newton
iterates until ||R_free||_2 <= atol + rtol * ref, ref = max(||F_ext,free||_2,
||R^(0)_free||_2) of that step.  Failure (max_iter, non-finite residual or singular
system: a linear solve whose relative residual exceeds 1e-6, e.g. a body held only by
contact that has lost it) stops the loading and is reported (``converged=False`` and
``reason``); the returned state is the last iterate of the failed step.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..bem.lame import LameBEM
from ..fem.elasticity import ElasticBody
from ..quadrature import gauss_legendre
from .bem_body import make_adapter

OPEN, STICK, SLIP = 0, 1, 2
STATE_NAMES = {OPEN: "open", STICK: "stick", SLIP: "slip"}


def _positive(name: str, value) -> float:
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def project_onto_polyline(points: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Closest-point projection of ``points`` (n, 2) onto the segments a[k] -> b[k] (m, 2).

    Returns (seg, s, excess, dist): the chosen segment per point, the clipped parameter
    s in [0, 1] (x_m = a + s (b - a)), how far the unclipped parameter lies outside
    [0, 1] (0 for an interior projection) and the distance.  Ties between equally near
    segments (corners) go to the segment with the smallest excess."""
    P = np.asarray(points, dtype=float)[:, None, :]
    A, B = np.asarray(a, dtype=float)[None], np.asarray(b, dtype=float)[None]
    d = B - A
    L2 = np.sum(d * d, axis=2)
    s_raw = np.sum((P - A) * d, axis=2) / L2
    s = np.clip(s_raw, 0.0, 1.0)
    excess = np.abs(s_raw - s)
    dist = np.linalg.norm(P - (A + s[..., None] * d), axis=2)
    scale = np.sqrt(L2.max())
    dmin = dist.min(axis=1, keepdims=True)
    near = dist <= dmin + 1e-10 * scale
    key = np.where(near, excess, np.inf)
    seg = np.argmin(key, axis=1)
    i = np.arange(P.shape[0])
    return seg, s[i, seg], excess[i, seg], dist[i, seg]


@dataclass
class StepRecord:
    """Diagnostics of one load step: load factor, Newton iterations, residual norms
    ||R_free||_2 of every iterate (index 0 = start iterate), outcome, contact state
    counts of the last iterate and the Newton step lengths (all 1 without line search)."""

    load_factor: float
    iterations: int
    residuals: list
    converged: bool
    reason: str
    n_stick: int = 0
    n_slip: int = 0
    n_open: int = 0
    step_lengths: list = None


@dataclass
class TwoBodyResult:
    """Outcome of :meth:`TwoBodyContact.solve`.

    U : the global dof vector (slave dofs first); u_slave, u_master : its two parts
    converged, reason : "converged", or why the loading stopped ("max_iter in step j",
        "non-finite residual in step j", "singular Newton matrix in step j")
    steps : one StepRecord per attempted load step
    points : (n, 2) slave contact points (reference); weights : quadrature weights
        (0 for points outside the master)
    g_n, g_t, p_n, t_t : gap, relative tangential displacement, pressure and friction
        traction at the points (last iterate); state : OPEN / STICK / SLIP codes;
        slip : accumulated slip g_t^p after the last converged step
    """

    U: np.ndarray
    u_slave: np.ndarray
    u_master: np.ndarray
    converged: bool
    reason: str
    steps: list
    points: np.ndarray
    weights: np.ndarray
    g_n: np.ndarray
    g_t: np.ndarray
    p_n: np.ndarray
    t_t: np.ndarray
    state: np.ndarray
    slip: np.ndarray

    @property
    def residual_histories(self) -> list:
        return [s.residuals for s in self.steps]

    @property
    def iterations(self) -> list:
        return [s.iterations for s in self.steps]

    @property
    def state_names(self) -> list:
        return [STATE_NAMES[int(k)] for k in self.state]


class TwoBodyContact:
    """Slave and master elastic bodies (FE or BE) in frictional penalty contact.

    Parameters
    ----------
    slave, master : :class:`hpfebe.fem.elasticity.ElasticBody` (FE) or
        :class:`hpfebe.bem.lame.LameBEM` (BE)
    slave_boundary, master_boundary : labels (str or list) of Gamma_C^s, Gamma_C^m
        (FE: facet labels of the mesh; BE: element labels of the boundary mesh)
    eps_n, eps_t : penalty parameters (> 0); 1/eps are the contact stiffnesses
    mu_f : Coulomb friction coefficient (>= 0; 0 = frictionless: no tangential terms)
    nq : Gauss points per integration piece (>= 1; 2 integrates the P1/Q1 trace
        products exactly; with a BE body at least p_max + 1 are taken)
    split : split the slave segments at the projections of the master vertices
    """

    def __init__(
        self,
        slave: Union[ElasticBody, LameBEM],
        master: Union[ElasticBody, LameBEM],
        slave_boundary: Union[str, Sequence[str]],
        master_boundary: Union[str, Sequence[str]],
        eps_n: float,
        eps_t: float = 1.0,
        mu_f: float = 0.0,
        nq: int = 2,
        split: bool = True,
    ):
        if not isinstance(slave, (ElasticBody, LameBEM)):
            raise ValueError(f"slave must be an ElasticBody or a LameBEM, got {type(slave).__name__}")
        if not isinstance(master, (ElasticBody, LameBEM)):
            raise ValueError(f"master must be an ElasticBody or a LameBEM, got {type(master).__name__}")
        self.eps_n = _positive("eps_n", eps_n)
        self.eps_t = _positive("eps_t", eps_t)
        mu = float(mu_f)
        if not (np.isfinite(mu) and mu >= 0):
            raise ValueError(f"mu_f must be non-negative and finite, got {mu_f!r}")
        self.mu_f = mu
        if int(nq) != nq or nq < 1:
            raise ValueError(f"nq must be a positive integer, got {nq!r}")
        self.nq = int(nq)
        self.split = bool(split)
        self.slave, self.master = slave, master
        self.adapters = {"slave": make_adapter(slave), "master": make_adapter(master)}
        sa, ma = self.adapters["slave"], self.adapters["master"]
        self.offset = sa.ndofs
        self.ndofs = sa.ndofs + ma.ndofs
        # (4.27) / (4.33): FE blocks sparse, a BE block (dense S_hat) stored inside
        self.K = sp.block_diag([sa.K, ma.K], format="csr")
        self._build_contact(slave_boundary, master_boundary)

    # ------------------------------------------------------------------ geometry
    def _build_contact(self, slave_boundary, master_boundary) -> None:
        S, M = self.adapters["slave"], self.adapters["master"]
        ssg = S.segments(slave_boundary)
        msg = M.segments(master_boundary)
        fs, xa, xb = ssg["ids"], ssg["a"], ssg["b"]
        A, B, ma, mb = msg["a"], msg["b"], msg["va"], msg["vb"]
        # integration segments: every slave segment is split where a master vertex
        # projects onto it, so that slave and master traces are both polynomial on each
        # piece (a BE trace of degree p needs p + 1 Gauss points per piece)
        mpts = np.vstack([A, B])
        mseg, ms, mexc, _ = project_onto_polyline(mpts, xa, xb)
        inner = (mexc == 0) & (ms > 1e-12) & (ms < 1 - 1e-12)
        if not self.split:
            inner[:] = False
        nq = self.nq
        if S.kind == "BE" or M.kind == "BE":
            nq = max(nq, max(S.degree, M.degree) + 1)
        t, w = gauss_legendre(nq)
        t, w = np.asarray(t, dtype=float), np.asarray(w, dtype=float)
        pf, ps, pw = [], [], []
        for i in range(fs.size):
            br = np.unique(np.concatenate([[0.0, 1.0], ms[inner & (mseg == i)]]))
            # drop breakpoints closer than rounding (a master vertex seen from two segments)
            br = br[np.concatenate([[True], np.diff(br) > 1e-12])]
            br[-1] = 1.0
            lo, hi = br[:-1], br[1:]
            sp_ = (lo[:, None] + 0.5 * (1 + t)[None, :] * (hi - lo)[:, None]).ravel()
            pf.append(np.full(sp_.size, i))
            ps.append(sp_)
            pw.append((0.5 * (hi - lo)[:, None] * w[None, :]).ravel())
        pf, ps, pw = np.concatenate(pf), np.concatenate(ps), np.concatenate(pw)
        length = np.linalg.norm(xb - xa, axis=1)
        pts = xa[pf] + ps[:, None] * (xb[pf] - xa[pf])
        wts = pw * length[pf]
        self.point_facets = fs[pf]
        # master segments
        normals = msg["normals"]
        seg, s, excess, _ = project_onto_polyline(pts, A, B)
        seg_len = np.linalg.norm(B - A, axis=1)
        # outside: clipped onto an end vertex of the master polyline (a vertex of one
        # master segment only); clipped onto an inner corner vertex is a valid contact
        verts, inv = np.unique(np.concatenate([ma, mb]), return_inverse=True)
        counts = np.bincount(inv)
        vid = np.where(s < 0.5, inv[seg], inv[ma.size + seg])
        outside = (excess * seg_len[seg] > 1e-10 * seg_len.max()) & (counts[vid] == 1)
        nm = normals[seg]
        tm = np.column_stack([nm[:, 1], -nm[:, 0]])
        xm = A[seg] + s[:, None] * (B[seg] - A[seg])
        self.points = pts
        self.weights = np.where(outside, 0.0, wts)
        self.outside = outside
        self.normals, self.tangents = nm, tm
        self.master_points = xm
        self.g0 = np.sum((pts - xm) * nm, axis=1)
        # sparse maps U -> dg_n, dg_t: rows = points, one entry per trace basis function,
        # component and side (the adapters' traces)
        n = pts.shape[0]
        rows, cols, vn, vt = [], [], [], []
        for ad, ids, par, off, sign in ((S, fs[pf], ps, 0, 1.0),
                                        (M, msg["ids"][seg], s, self.offset, -1.0)):
            tc, tv = ad.trace(ids, par)
            for j in range(tv.shape[1]):
                for c in (0, 1):
                    rows.append(np.arange(n))
                    cols.append(tc[:, c, j] + off)
                    vn.append(sign * tv[:, j] * nm[:, c])
                    vt.append(sign * tv[:, j] * tm[:, c])
        rows, cols = np.concatenate(rows), np.concatenate(cols)
        shape = (n, self.ndofs)
        self.Gn = sp.csr_matrix((np.concatenate(vn), (rows, cols)), shape=shape)
        self.Gt = sp.csr_matrix((np.concatenate(vt), (rows, cols)), shape=shape)

    # ------------------------------------------------------------------ dof helpers
    def global_dofs(self, body: str, dofs: np.ndarray) -> np.ndarray:
        """Global indices of a body's local dofs (``body`` = "slave" or "master")."""
        if body == "slave":
            return np.asarray(dofs, dtype=np.int64)
        if body == "master":
            return np.asarray(dofs, dtype=np.int64) + self.offset
        raise ValueError(f"body must be 'slave' or 'master', got {body!r}")

    def dofs_on(self, body: str, labels, component: Optional[int] = None) -> np.ndarray:
        return self.global_dofs(body, self._adapter(body).dofs_on(labels, component))

    def dofs_at(self, body: str, point, component: Optional[int] = None) -> np.ndarray:
        return self.global_dofs(body, self._adapter(body).dofs_at(point, component))

    def traction_load(self, body: str, label: str, traction) -> np.ndarray:
        """Global load vector of a traction on the boundary part ``label`` of ``body``."""
        ad = self._adapter(body)
        f = np.zeros(self.ndofs)
        f[self.global_dofs(body, np.arange(ad.ndofs))] = ad.traction_load(label, traction)
        return f

    def dof_coordinates(self) -> np.ndarray:
        return np.vstack([self.adapters["slave"].dof_coordinates(),
                          self.adapters["master"].dof_coordinates()])

    def displacement_at(self, body: str, U: np.ndarray, labels, s) -> np.ndarray:
        """(n, 2) displacement of ``body`` (global dof vector U) at the points
        a + s (b - a) of its segments on ``labels`` (n = number of segments x len(s))."""
        ad = self._adapter(body)
        sg = ad.segments(labels)
        s = np.atleast_1d(np.asarray(s, dtype=float))
        ids = np.repeat(sg["ids"], s.size)
        par = np.tile(s, sg["ids"].size)
        tc, tv = ad.trace(ids, par)
        u = np.asarray(U)[self.global_dofs(body, np.arange(ad.ndofs))]
        return np.einsum("nj,ncj->nc", tv, u[tc])

    def _adapter(self, body: str):
        if body in ("slave", "master"):
            return self.adapters[body]
        raise ValueError(f"body must be 'slave' or 'master', got {body!r}")

    def _body(self, body: str):
        return self._adapter(body).body

    # ------------------------------------------------------------------ contact law
    def contact_state(self, U: np.ndarray, slip: np.ndarray):
        """Pointwise gap, pressure, friction traction, state and the tangent weights."""
        g_n = self.g0 + self.Gn @ U
        g_t = self.Gt @ U
        active = (g_n <= 0.0) & ~self.outside
        p_n = np.where(active, -g_n / self.eps_n, 0.0)
        kn = np.where(active, 1.0 / self.eps_n, 0.0)
        if self.mu_f > 0:
            t_try = np.where(active, (g_t - slip) / self.eps_t, 0.0)
            bound = self.mu_f * p_n
            stick = active & (np.abs(t_try) <= bound)
            slipping = active & ~stick
            sgn = np.sign(t_try)
            t_t = np.where(stick, t_try, np.where(slipping, bound * sgn, 0.0))
            kt = np.where(stick, 1.0 / self.eps_t, 0.0)
            ktn = np.where(slipping, -self.mu_f * sgn / self.eps_n, 0.0)
        else:
            t_t = np.zeros_like(g_n)
            kt = np.zeros_like(g_n)
            ktn = np.zeros_like(g_n)
            stick = np.zeros(g_n.shape, bool)
            slipping = active
        state = np.full(g_n.shape, OPEN, dtype=np.int8)
        state[stick] = STICK
        state[slipping] = SLIP
        return dict(g_n=g_n, g_t=g_t, p_n=p_n, t_t=t_t, state=state, kn=kn, kt=kt, ktn=ktn)

    def internal_force(self, U: np.ndarray, slip: np.ndarray):
        """K U + f_c(U) and the contact state at U."""
        cs = self.contact_state(U, slip)
        w = self.weights
        f = self.K @ U + self.Gn.T @ (w * -cs["p_n"]) + self.Gt.T @ (w * cs["t_t"])
        return f, cs

    def tangent(self, cs: dict) -> sp.csr_matrix:
        """Consistent Newton matrix K + C (Section 4.2.5) for the state ``cs``."""
        w = self.weights
        C = self.Gn.T @ sp.diags(w * cs["kn"]) @ self.Gn
        if self.mu_f > 0:
            C = C + self.Gt.T @ (sp.diags(w * cs["kt"]) @ self.Gt + sp.diags(w * cs["ktn"]) @ self.Gn)
        return (self.K + C).tocsr()

    # ------------------------------------------------------------------ Algorithm 4.1
    def solve(
        self,
        f_ext: Union[np.ndarray, Callable[[float], np.ndarray], None] = None,
        fixed_dofs: Optional[np.ndarray] = None,
        fixed_values: Union[np.ndarray, Callable[[float], np.ndarray], float, None] = None,
        load_factors: Sequence[float] = (1.0,),
        rtol: float = 1e-10,
        atol: float = 0.0,
        max_iter: int = 30,
        line_search: bool = False,
        min_step: float = 2.0 ** -12,
    ) -> TwoBodyResult:
        """Incremental loading with Newton's method (Algorithm 4.1).

        ``f_ext`` (global load vector at load factor 1, scaled by lambda, or a callable
        lambda -> vector), ``fixed_dofs`` (global Dirichlet dofs) with ``fixed_values``
        (values at lambda = 1, scaled; a callable lambda -> values; None = 0),
        ``load_factors`` increasing pseudo-times lambda_1 < lambda_2 < ...;
        ``line_search`` Armijo backtracking on ||R_free|| (module docstring) down to
        step length ``min_step``; the step lengths are in ``StepRecord.step_lengths``."""
        N = self.ndofs
        lf = np.asarray(load_factors, dtype=float).ravel()
        if lf.size == 0 or not np.all(np.isfinite(lf)):
            raise ValueError(f"load_factors must be a non-empty finite sequence, got {load_factors!r}")
        rtol = float(rtol)
        if not (np.isfinite(rtol) and rtol >= 0):
            raise ValueError(f"rtol must be non-negative, got {rtol!r}")
        atol = float(atol)
        if not (np.isfinite(atol) and atol >= 0):
            raise ValueError(f"atol must be non-negative, got {atol!r}")
        if rtol == 0 and atol == 0:
            raise ValueError("rtol and atol must not both be zero")
        if int(max_iter) != max_iter or max_iter < 1:
            raise ValueError(f"max_iter must be a positive integer, got {max_iter!r}")
        min_step = float(min_step)
        if not (np.isfinite(min_step) and 0 < min_step <= 1):
            raise ValueError(f"min_step must lie in (0, 1], got {min_step!r}")
        fixed = np.asarray([] if fixed_dofs is None else fixed_dofs, dtype=np.int64).ravel()
        if fixed.size and (fixed.min() < 0 or fixed.max() >= N):
            raise ValueError(f"fixed_dofs must lie in [0, {N}), got range [{fixed.min()}, {fixed.max()}]")
        if np.unique(fixed).size != fixed.size:
            raise ValueError("fixed_dofs must not contain duplicates")
        free = np.setdiff1d(np.arange(N), fixed)

        def load_at(lam):
            if f_ext is None:
                f = np.zeros(N)
            elif callable(f_ext):
                f = np.asarray(f_ext(lam), dtype=float)
            else:
                f = lam * np.asarray(f_ext, dtype=float)
            if f.shape != (N,):
                raise ValueError(f"f_ext must have shape ({N},), got {f.shape}")
            if fixed_values is None:
                g = np.zeros(fixed.size)
            elif callable(fixed_values):
                g = np.asarray(fixed_values(lam), dtype=float) * np.ones(fixed.size)
            else:
                g = lam * np.asarray(fixed_values, dtype=float) * np.ones(fixed.size)
            if g.shape != (fixed.size,):
                raise ValueError(f"fixed_values must have shape ({fixed.size},), got {g.shape}")
            return f, g

        U = np.zeros(N)
        slip = np.zeros(self.points.shape[0])
        steps: list = []
        converged, reason = True, "converged"
        cs = self.contact_state(U, slip)
        for j, lam in enumerate(lf):
            f, g = load_at(lam)
            U[fixed] = g
            ref = None
            res_hist: list = []
            ok, why = False, ""
            lengths: list = []
            fint, cs = self.internal_force(U, slip)
            for k in range(int(max_iter) + 1):
                r = (f - fint)[free]
                rn = float(np.linalg.norm(r))
                res_hist.append(rn)
                if not np.isfinite(rn):
                    why = f"non-finite residual in step {j}"
                    break
                if ref is None:
                    ref = max(float(np.linalg.norm(f[free])), rn)
                if rn <= atol + rtol * ref:
                    ok, why = True, "converged"
                    break
                if k == int(max_iter):
                    why = f"max_iter ({max_iter}) reached in step {j}"
                    break
                A = self.tangent(cs)[free][:, free].tocsc()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", spla.MatrixRankWarning)
                        dU = spla.splu(A).solve(r)
                except RuntimeError:
                    dU = np.full(free.size, np.nan)
                if not np.all(np.isfinite(dU)) or (
                    np.linalg.norm(A @ dU - r) > 1e-6 * rn
                ):
                    why = f"singular Newton matrix in step {j}"
                    break
                alpha = 1.0
                while True:
                    Ut = U.copy()
                    Ut[free] += alpha * dU
                    fint_t, cs_t = self.internal_force(Ut, slip)
                    rt = float(np.linalg.norm((f - fint_t)[free]))
                    # Armijo on the merit ||R_free||_2 (the full step always when
                    # line_search is off); below min_step the last trial is taken
                    if (not line_search or rt <= (1.0 - 1e-4 * alpha) * rn
                            or alpha * 0.5 < min_step):
                        break
                    alpha *= 0.5
                lengths.append(alpha)
                U, fint, cs = Ut, fint_t, cs_t
            st = cs["state"]
            steps.append(StepRecord(float(lam), len(res_hist) - 1, res_hist, ok, why,
                                    int(np.sum(st == STICK)), int(np.sum(st == SLIP)),
                                    int(np.sum(st == OPEN)), lengths))
            if not ok:
                converged, reason = False, why
                break
            # backward Euler update of the slip (tangential "macro-displacement")
            slip = np.where(cs["state"] == OPEN, cs["g_t"], cs["g_t"] - self.eps_t * cs["t_t"])
        return TwoBodyResult(
            U=U.copy(), u_slave=U[: self.offset].copy(), u_master=U[self.offset:].copy(),
            converged=converged, reason=reason, steps=steps, points=self.points,
            weights=self.weights, g_n=cs["g_n"], g_t=cs["g_t"], p_n=cs["p_n"],
            t_t=cs["t_t"], state=cs["state"], slip=slip,
        )
