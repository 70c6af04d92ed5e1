"""The load steps of Algorithm 4.1 for :class:`hpfebe.contact.two_body.TwoBodyContact`:
at each load factor the Newton problem (residual R = f_int(U) + f_c(U) - F_ext on the free
dofs, its merit, force scale and contact pattern), its start (the last converged state
with the new Dirichlet values), the commit of the slip and of the bodies' history after
convergence (the :class:`hpfebe.solvers.LoadStep` and
:class:`hpfebe.solvers.NewtonProblem` protocols), and the bonded predictor."""

from __future__ import annotations

import contextlib
import hashlib
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..checks import array
from ..solvers import Iterate, SingularStep, SolverInfo
from ..constitutive.laws import STATE_NAMES, updated_slip
from ..fem.plastic_body import ElastoPlasticFE
from .newton_matrix import FixedPatternLU, NewtonMatrix
from .settings import ContactSettings
from .woodbury import WoodburySolver


class LoadSteps:
    """The load steps of :meth:`TwoBodyContact.solve`: the Newton problem at a load
    factor (residual R = K U + f_c(U) - F_ext on the free dofs), its start, and the
    commit of the slip after a converged step (:class:`hpfebe.solvers.LoadStep`)."""

    #: factorisations of the sparse Newton matrix kept for reuse (:meth:`_factor`): at
    #: most this many, and at most LU_CACHE_NNZ nonzeros in their factors together
    #: (about 12 bytes each: 1e8 ~ 1.2 GB, four LUs of 8e4 dofs)
    LU_CACHE = 8
    LU_CACHE_NNZ = 100_000_000

    def __init__(self, pr, f_ext, fixed_dofs, fixed_values, settings: ContactSettings,
                 initial=None):
        merit, linear_solver = settings.merit, settings.linear_solver
        self.settings, self.lu_ordering = settings, settings.lu_ordering
        if linear_solver == "woodbury" and (pr.dense or pr.exact is not None or not all(
                getattr(b, "linear", False) for b in pr.bodies.values())):
            raise ValueError("linear_solver='woodbury' needs linear bodies, an FE body "
                             "(sparse system) and the fixed (gauss) contact points")
        self.linear_solver = linear_solver
        self._woodbury = None
        if merit == "energy" and not all(getattr(b, "linear", False)
                                          for b in pr.bodies.values()):
            raise ValueError("merit='energy' needs linear bodies (a plastic body has no "
                             "potential here): use merit='residual'")
        if merit == "energy" and pr.mu_f > 0:
            raise ValueError("merit='energy' needs a potential law (frictionless or "
                             "Tresca); Coulomb friction has none: use merit='residual'")
        self.pr, self.merit = pr, merit
        N = pr.ndofs
        fixed = array("fixed_dofs", [] if fixed_dofs is None else fixed_dofs,
                      dtype=np.int64).ravel()
        if fixed.size and (fixed.min() < 0 or fixed.max() >= N):
            raise ValueError(f"fixed_dofs must lie in [0, {N}), got range [{fixed.min()}, {fixed.max()}]")
        if np.unique(fixed).size != fixed.size:
            raise ValueError("fixed_dofs must not contain duplicates")
        self.fixed, self.free = fixed, np.setdiff1d(np.arange(N), fixed)
        self.f_ext, self.fixed_values = f_ext, fixed_values
        self.x0, self.slip = np.zeros(N), np.zeros(pr.points.shape[0])
        self.f0, self.w0 = np.zeros(N), np.zeros_like(self.slip)
        if initial is not None:
            _continue_from(self, initial)
        self.f, self.w = self.f0, self.w0
        # cycling of the contact state is detected with and without a line search (a
        # full-step Newton that cycles reports "cycling", not "max_iter")
        self.detect_cycling = True
        self._lu = {}      # factorisations of Newton matrices seen (:meth:`_factor`)
        # a plastic (nonlinear) sparse body: the Newton matrices on one fixed pattern
        # (:meth:`_solve_fixed`; the LU cache never hits for them)
        self.fixed_pattern = linear_solver == "lu" and not pr.dense and \
            pr.exact is None and not all(getattr(b, "linear", False)
                                         for b in pr.bodies.values())
        self._newton = None
        self._predicted = None     # the last bonded predictor (:meth:`step`)

    def newton_options(self) -> dict:
        """The keywords of :func:`hpfebe.solvers.newton` for these steps: the
        settings' stopping test and line search, the bonded predictor if asked for."""
        return dict(self.settings.newton_options(),
                    predictor=self.bonded_predictor if self.settings.predictor else None)

    def _load(self, lam: float):
        N, fixed = self.pr.ndofs, self.fixed
        if self.f_ext is None:
            f = np.zeros(N)
        elif callable(self.f_ext):
            f = array("f_ext", self.f_ext(lam), shape=(N,))
        else:
            f = array("f_ext", self.f_ext, shape=(N,))
            f = self.f0 + lam * (f - self.f0)
        v = self.fixed_values
        if v is None:
            return f, np.zeros(fixed.size)
        g = array("fixed_values", v(lam) if callable(v) else v)
        if g.shape not in ((), (fixed.size,)):     # a scalar, or one value per fixed dof
            raise ValueError(f"fixed_values must be a scalar or have shape ({fixed.size},) "
                             f"(one per fixed dof), got shape {g.shape}")
        g = np.broadcast_to(g, (fixed.size,)).astype(float)
        return f, (g if callable(v) else lam * g)

    # LoadStep protocol
    def problem(self, lam: float):
        self.f, self.g_fixed = self._load(lam)
        self.w = self.w0 + lam * (self.pr.motion - self.w0)
        return self

    def start(self, x: np.ndarray, lam: float) -> np.ndarray:
        x = x.copy()
        x[self.fixed] = self.g_fixed
        return x

    def commit(self, it: Iterate) -> None:
        if self.pr.exact is None:       # (the exact quadrature is frictionless)
            self.slip = updated_slip(it.data["g_t"], it.data["law"], self.pr.eps_t)
        self.pr.commit(it.x)

    def record(self, it: Iterate, info: SolverInfo) -> None:
        st = it.data["state"]
        info.counts = {name: int(np.sum(st == code)) for code, name in STATE_NAMES.items()}

    # NewtonProblem protocol
    def evaluate(self, U: np.ndarray) -> Iterate:
        pr, free = self.pr, self.free
        fint, cs = pr.internal_force(U, self.slip, self.w)
        R = (fint - self.f)[free]
        # force scale of the stopping test: load, body and contact forces of the
        # iterate, the reactions on the fixed dofs included (they keep the scale when
        # the contact opens and the free forces vanish at equilibrium)
        scale = max(np.abs(self.f).max(initial=0.0), np.abs(cs["f_body"]).max(initial=0.0),
                    np.abs(cs["f_c"]).max(initial=0.0), 1e-300)
        merit = pr.energy(U, cs, self.f) if self.merit == "energy" \
            else float(np.linalg.norm(R))
        key = None
        if self.detect_cycling:
            key = cs["law"].key if pr.exact is None else pr.exact.key(U)
        return Iterate(U, R, merit, scale, key, cs)

    def slope(self, it: Iterate, dx: np.ndarray) -> float:
        return float(it.residual @ dx[self.free]) if self.merit == "energy" else -it.merit

    def _solve(self, A, r: np.ndarray) -> np.ndarray:
        """The Newton system on the free dofs: LAPACK for a dense system (symmetric
        solver for the potential laws), a sparse LU with a check of its residual
        otherwise.  Ill-conditioning is not an error here (LAPACK's LinAlgWarning reaches
        the caller): the backward error of the result decides convergence."""
        free, pr = self.free, self.pr
        if pr.dense:
            sym = "sym" if (pr.F is not None or pr.mu_f == 0) else "gen"
            Af = A[np.ix_(free, free)]
            try:
                d = sla.solve(Af, r, assume_a=sym)
            except (np.linalg.LinAlgError, ValueError):
                raise SingularStep("singular Newton matrix (body not fixed?)") from None
            rel = np.linalg.norm(Af @ d - r) / max(np.linalg.norm(r), 1e-300)
            if np.all(np.isfinite(d)) and rel > 1e-6:
                raise SingularStep(f"ill-conditioned Newton matrix: the linear solve has a "
                                   f"relative residual {rel:.1e} (singular or cond * "
                                   f"macheps >~ 1)")
        else:
            Af = A[free][:, free].tocsc()
            try:
                d = self._factor(Af).solve(r)
            except RuntimeError:
                d = np.full(free.size, np.nan)
            if np.all(np.isfinite(d)) and \
                    np.linalg.norm(Af @ d - r) > 1e-6 * np.linalg.norm(r):
                d[:] = np.nan
        if not np.all(np.isfinite(d)):
            raise SingularStep("singular Newton matrix (body not fixed?)")
        dx = np.zeros(pr.ndofs)
        dx[free] = d
        return dx

    def forget_factorisations(self) -> None:
        """Empty the cache of :meth:`_factor` (the factorisations of the steps so far)."""
        self._lu = {}

    def _factor(self, Af: sp.csc_matrix):
        """splu(Af), reused when the same matrix (bit for bit) was factorised before in
        these load steps.  The semismooth Newton iterates of consecutive load steps pass
        through the same contact patterns, and the Newton matrix depends on the pattern
        only (linear bodies: K + C, C piecewise constant in U), so about half of the
        factorisations repeat one made before; a repeat gives the identical LU, hence the
        identical step.  At most ``LU_CACHE`` factorisations with ``LU_CACHE_NNZ``
        nonzeros are kept (least recently used dropped first)."""
        Af.sort_indices()
        digest = hashlib.blake2b(Af.indptr.tobytes(), digest_size=16)
        digest.update(Af.indices.tobytes())
        pattern = (Af.shape, Af.nnz, digest.digest())
        # the values enter the key through a sample only (a repeat has the same sample;
        # the full comparison below decides)
        key = pattern + (Af.data[::max(1, Af.nnz // 256)].tobytes(),)
        hit = self._lu.pop(key, None)
        if hit is not None and np.array_equal(hit[0].indptr, Af.indptr) and \
                np.array_equal(hit[0].indices, Af.indices) and \
                np.array_equal(hit[0].data, Af.data):
            self._lu[key] = hit           # most recently used last
            return hit[1]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", spla.MatrixRankWarning)
            if self.lu_ordering == "COLAMD":
                lu = _ordered_splu(self.pr, Af, pattern)
            else:
                lu = spla.splu(Af, permc_spec=self.lu_ordering, diag_pivot_thresh=0.01,
                               options=dict(SymmetricMode=True))
        self._lu[key] = (Af, lu)
        while len(self._lu) > 1 and (len(self._lu) > self.LU_CACHE or sum(
                v[1].nnz for v in self._lu.values()) > self.LU_CACHE_NNZ):
            self._lu.pop(next(iter(self._lu)))
        return lu

    def step(self, it: Iterate) -> np.ndarray:
        """The Newton step at ``it``; at the bonded predictor (``secant_start``) with the
        secant stiffness of the plastic FE bodies (:func:`_secant_tangents`)."""
        predicted, self._predicted = self._predicted, None
        if predicted is not None and it.x is predicted and "K_body" not in it.data:
            with _secant_tangents(self.pr):
                return self._newton_step(it)
        return self._newton_step(it)

    def _newton_step(self, it: Iterate) -> np.ndarray:
        if self.linear_solver == "woodbury":
            law, w = it.data["law"], it.data["weights"]
            return self._solve_woodbury(it.data, w * law.dp_n, w * law.dt_t,
                                        w * law.dt_n, -it.residual)
        if self.fixed_pattern:
            law, w = it.data["law"], it.data["weights"]
            return self._solve_fixed(it.data, w * law.dp_n, w * law.dt_t, w * law.dt_n,
                                     -it.residual)
        return self._solve(self.pr.tangent(it.data), -it.residual)

    def _solve_fixed(self, cs, wn, wt, wtn, r: np.ndarray) -> np.ndarray:
        """The Newton system K_body + C on the free dofs assembled on the fixed pattern
        of :class:`~hpfebe.contact.newton_matrix.NewtonMatrix` and factorised by
        :class:`~hpfebe.contact.newton_matrix.FixedPatternLU` (PARDISO's symbolic
        analysis once per load steps if pypardiso is installed, else SuperLU with the
        ``lu_ordering``), with the residual check of :meth:`_solve`."""
        K = cs["K_body"]
        for attempt in (0, 1):
            if self._newton is None:
                opts = {} if self.lu_ordering == "COLAMD" else dict(
                    permc_spec=self.lu_ordering, diag_pivot_thresh=0.01,
                    options=dict(SymmetricMode=True))
                self._newton = (NewtonMatrix(K, cs["Gn"], cs["Gt"], self.free),
                                FixedPatternLU(opts))
            nm, flu = self._newton
            try:
                A = nm.assemble(K, wn, wt, wtn)
                break
            except ValueError:           # K left the pattern: a new one
                if attempt:
                    raise
                self._newton = None
        try:
            d = flu.factor(A).solve(r)
        except RuntimeError:
            d = np.full(r.size, np.nan)
        if not np.all(np.isfinite(d)) or \
                np.linalg.norm(A @ d - r) > 1e-6 * np.linalg.norm(r):
            raise SingularStep("singular Newton matrix (body not fixed?)")
        dx = np.zeros(self.pr.ndofs)
        dx[self.free] = d
        return dx

    def _solve_woodbury(self, cs, wn, wt, wtn, r: np.ndarray) -> np.ndarray:
        """The Newton system K + C on the free dofs by :class:`WoodburySolver` (K
        factorised once per load path), with the residual check of :meth:`_solve`."""
        wb = self._woodbury
        if wb is None or wb.K is not cs["K_body"]:
            wb = self._woodbury = WoodburySolver(cs["K_body"], self.free, self.pr.offset,
                                                 self.pr.Gn, self.pr.Gt)
        d = wb.solve(wn, wt, wtn, r)
        if not np.all(np.isfinite(d)) or \
                np.linalg.norm(wb.matvec(wn, wt, wtn, d) - r) > 1e-6 * np.linalg.norm(r):
            raise SingularStep("singular Newton matrix (body not fixed?)")
        dx = np.zeros(self.pr.ndofs)
        dx[self.free] = d
        return dx

    def bonded_predictor(self, it: Iterate):
        """The bonded solution (every point in contact and sticking, relative to the
        current slip): the law replaced by the linear springs 1/eps_n, 1/eps_t; None if
        singular."""
        pr, n = self.pr, len(self.slip)
        cs = it.data
        w, Gn, Gt = cs["weights"], cs["Gn"], cs["Gt"]
        ones = np.ones(n)
        pen = -cs["g_n"]
        rel = cs["g_t"] - self.slip
        Rb = cs["f_body"] - self.f + Gn.T @ (w * -pen / pr.eps_n) \
            + Gt.T @ (w * rel / pr.eps_t)
        if self.linear_solver == "woodbury":
            try:
                return it.x + self._solve_woodbury(cs, w * ones / pr.eps_n,
                                                   w * ones / pr.eps_t, 0.0 * w,
                                                   -Rb[self.free])
            except SingularStep:
                return None
        if self.fixed_pattern:
            try:
                x = it.x + self._solve_fixed(cs, w * ones / pr.eps_n, w * ones / pr.eps_t,
                                             0.0 * w, -Rb[self.free])
            except SingularStep:
                return None
            if self.settings.secant_start:
                self._predicted = x       # the first step from it: secant (:meth:`step`)
            return x
        C = Gn.T @ sp.diags(w * ones / pr.eps_n) @ Gn \
            + Gt.T @ sp.diags(w * ones / pr.eps_t) @ Gt
        K = cs["K_body"]
        A = K + C.toarray() if pr.dense else (K + C).tocsr()
        try:
            return it.x + self._solve(A, -Rb[self.free])
        except SingularStep:
            return None


def _continue_from(self, initial) -> None:
    """LoadSteps ``self`` from the converged result ``initial`` (U, slip, load and
    obstacle motion)."""
    pr = self.pr
    if not hasattr(initial, "slip") or initial.U.shape != (pr.ndofs,) or \
            initial.points.shape != pr.points.shape or \
            not np.allclose(initial.points, pr.points) or initial.friction != pr.law_name:
        raise ValueError("initial must be a result of the same bodies, contact points "
                         "and friction law")
    if not initial.converged:
        raise ValueError(f"initial did not converge ({initial.reason}); not a state "
                         "to continue from")
    self.x0, self.slip = initial.U.copy(), initial.slip.copy()
    self.f0, self.w0 = initial.load_vector.copy(), initial.obstacle_motion.copy()


@contextlib.contextmanager
def _secant_tangents(pr):
    """The elastoplastic FE bodies of the contact problem ``pr`` return their secant
    stiffness (:meth:`hpfebe.fem.plastic_body.ElastoPlasticFE.tangent_matrix`) inside
    the block, their own tangent after.  For the step at the bonded predictor, an
    elastic solution whose plastic points lie far past yield: there the algorithmic
    tangent is about H / (3 mu) soft along the flow direction and its step overshoots
    (a line search of many small steps followed); the secant step is that of the
    deformation-theory material through the trial state.  (The iterate's tangent is
    assembled lazily, on its first access inside the block.)"""
    bodies = [b.plastic for b in pr.bodies.values()
              if isinstance(getattr(b, "plastic", None), ElastoPlasticFE)]
    kept = [b.tangent for b in bodies]
    try:
        for b in bodies:
            b.tangent = "secant"
        yield
    finally:
        for b, t in zip(bodies, kept):
            b.tangent = t


#: column orderings of the sparsity patterns met (:func:`_ordered_splu`), at most
#: ORDER_CACHE of them (least recently used dropped first; ~0.7 MB each at 8e3 dofs)
ORDER_CACHE = 64
_ORDERS: dict = {}


class _PermutedLU:
    """splu of A[:, q] with the natural column order, solving A x = b (x[q] = y)."""

    def __init__(self, lu, q: np.ndarray):
        self.lu, self.q = lu, q

    @property
    def nnz(self) -> int:
        return self.lu.nnz

    def solve(self, b: np.ndarray) -> np.ndarray:
        y = self.lu.solve(b)
        x = np.empty_like(y)
        x[self.q] = y
        return x


def _ordered_splu(pr, Af: sp.csc_matrix, pattern):
    """splu(Af) (SuperLU's default COLAMD column ordering), with the ordering of a
    sparsity pattern met before (in any problem) reused: the factorisation of Af[:, q]
    with the natural order, q the final column order SuperLU chose for that pattern
    (COLAMD and its elimination-tree postorder depend on the pattern only), is the same
    factorisation with the same numbers bit for bit (measured), without recomputing
    the ordering (about a fifth of a factorisation of the stamping systems).  The
    pattern of a frictional contact system changes with every stick/slip flip, so
    only 5-40 % of the stamping factorisations meet a known one (measured).  ``pr``:
    the contact problem (unused; the cache is shared)."""
    orders = _ORDERS
    known = orders.pop(pattern, None)
    if known is not None and np.array_equal(known[0], Af.indptr) and \
            np.array_equal(known[1], Af.indices):
        orders[pattern] = known                      # most recently used last
        q = known[2]
        M = Af[:, q].tocsc()
        M.sort_indices()
        return _PermutedLU(spla.splu(M, permc_spec="NATURAL"), q)
    lu = spla.splu(Af)
    orders[pattern] = (Af.indptr.copy(), Af.indices.copy(), np.argsort(lu.perm_c))
    while len(orders) > ORDER_CACHE:
        orders.pop(next(iter(orders)))
    return lu


