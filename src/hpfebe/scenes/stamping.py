"""The stamping examples of Section 4.2.7 (thesis lines 14810-14920): an elastic stamp
(slave; FE :class:`~hpfebe.fem.elasticity.ElasticBody` or BE
:class:`~hpfebe.bem.lame.LameBEM`) pressed onto an elastoplastic work piece (master,
:class:`~hpfebe.fem.plastic_body.ElastoPlasticFE`, J2 flow (4.21)-(4.22)) by lifting the
work piece's bottom; frictional penalty contact by
:class:`hpfebe.contact.two_body.TwoBodyContact` (Algorithm 4.1: incremental loading,
semismooth Newton with the algorithmic tangents (4.36)-(4.43) of the plastic body).

One *touch* (:func:`touch`): stamp top fixed, work piece bottom u_y = g (u_x = 0) with g
raised from 0 to ``u_total`` in ``n_load`` equal increments and lowered back to 0 in
``n_unload`` increments.  The increments are one load path of Algorithm 4.1
(:func:`hpfebe.solvers.load_path` on the load steps of :class:`TouchSteps`): load factor
lambda in (k - 1, k] is increment k, the prescribed values ramped from the last to the
new ones (a cut increment is halved between them, at most ``max_cuts`` times per
increment); Newton starts from the secant extrapolation of the last two converged
increments, at the first unloading increment from the rigidly lowered work piece (the
plastic body's force is a pure function of the displacement and its committed history,
so the start only changes the iteration count: measured 3-6 Newton iterations per
loading increment after the first instead of 15-20 from the last state).  The slip and
the plastic history are committed after each converged step.

A second touch (Example 1) starts from the state left by the first: the work piece keeps
its committed history and carries the residual displacement of the first touch as an
``offset`` (its contact geometry is the deformed one, :class:`PlasticFEBody`).

Recorded per converged increment (:class:`StepRecord`): the prescribed g, the applied
force (the vertical reaction at the work piece's bottom, sum of f_int over its y dofs,
per unit thickness), ||dev sigma|| and ||eps_p|| at the characteristic point X (element
means, averaged over the elements touching X), Newton iterations.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..bem.lame import LameBEM
from ..checks import array, boolean, choice, instance, integer, real
from ..geometry import BoundaryMesh
from ..fem.elasticity import ElasticBody, rectangle_mesh
from ..fem.plastic_body import ElastoPlasticFE
from ..constitutive.j2 import J2Material
from ..bodies import BEBody, PlasticBEBody, PlasticFEBody
from ..bodies.plastic_be import ElastoPlasticBE, rectangle_work_piece
from ..contact.loading import LoadSteps
from ..contact.settings import ContactSettings
from ..contact.two_body import TwoBodyContact
from ..constitutive.laws import OPEN
from ..solvers import Iterate, SolverInfo, load_path

SIDES = ("bottom", "right", "top", "left")
STAMP_KINDS = ("FE", "BE")
MESH_KINDS = ("quad", "tri")


#: the solver of the touches: Newton to rtol = 1e-8 of the force scale, at most 40
#: iterations, Armijo line search on ||R||, at most 4 cuts per increment, and the bonded
#: predictor of :class:`TwoBodyContact` (taken when it lowers the merit; measured: the
#: first increment of the second touch of Example 1 at h = 0.1 needs 33 iterations with
#: it, 98 in 3 attempts without).  ``lu_ordering`` "MMD_AT_PLUS_A" is ~1.7x faster per
#: factorisation than SuperLU's default "COLAMD", with other round-off: measured, the
#: iteration counts of the unloading increments and the load path of a hard increment
#: (a step cut or not) change, and with them the results of those runs by up to
#: 1e-4 .. 3e-2 relative.
STAMP_SOLVER = ContactSettings(rtol=1e-8, max_iter=40, max_cuts=4, line_search=True,
                               predictor=True)


@dataclass(frozen=True)
class StampContact:
    """The penalty contact of a stamping scene: 1/eps_n = eps_n_factor E, 1/eps_t =
    eps_t_factor E, Coulomb mu_f; ``F``: a given (Tresca) friction bound, |t_t| <= F on
    all of Gamma_C (the penalty law (4.20) with the slip bound F in place of mu_f |p_n|);
    None = Coulomb with mu_f, a given F replaces mu_f (:meth:`friction`).  ``two_pass``:
    the symmetric two-pass penalty contact of :class:`TwoBodyContact` (a second pass
    with the stamp and the work piece swapped; contact stiffness about 2/eps_n on a flat
    interface, the single pass at eps/2 there); False = the thesis's single pass.
    ``open_start``: an increment after one that ended with the contact open starts from
    that state moved rigidly (:meth:`TouchSteps.extrapolated`), without the bonded
    predictor while its start has no point in contact; False = the secant extrapolation
    there too.  ``bonded_increments``: the bonded predictor (``solver.predictor``) is
    tried in the first this many increments of a touch only (None: in every
    increment); later ones start from the secant extrapolation of two converged
    increments, which the predictor never beat in Example 1 (measured: taken in
    increments 1-2 only, in all its runs at h = 0.2, 0.1, 0.05, FE and BE stamps), so
    its Newton system there is saved.
    ``solver``: the :class:`ContactSettings` of the touches (:data:`STAMP_SOLVER`; a
    touch sets the floor ``atol`` = rtol x :func:`reference_force`, ``max_cuts`` counts
    per increment)."""

    eps_n_factor: float = 10.0
    eps_t_factor: float = 5.0
    mu_f: float = 0.2
    F: float | None = None
    two_pass: bool = False
    solver: ContactSettings = STAMP_SOLVER
    open_start: bool = True
    bonded_increments: int | None = 2

    def __post_init__(self):
        checked = dict(eps_n_factor=real("eps_n_factor", self.eps_n_factor, positive=True),
                       eps_t_factor=real("eps_t_factor", self.eps_t_factor, positive=True),
                       mu_f=real("mu_f", self.mu_f, nonnegative=True),
                       F=real("F (Tresca bound)", self.F, nonnegative=True,
                              allow_none=True),
                       two_pass=boolean("two_pass", self.two_pass),
                       open_start=boolean("open_start", self.open_start),
                       bonded_increments=None if self.bonded_increments is None else
                       integer("bonded_increments", self.bonded_increments, lo=0))
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        instance("solver", self.solver, ContactSettings)

    def friction(self) -> dict:
        """The friction keywords of :class:`TwoBodyContact`: Coulomb ``mu_f`` (F None)
        or Tresca ``F`` with mu_f = 0."""
        if self.F is None:
            return dict(mu_f=self.mu_f)
        return dict(mu_f=0.0, F=float(self.F))


@dataclass
class StepRecord:
    touch: int
    phase: str              # "load" / "unload"
    g: float                # prescribed lift of the work piece's bottom
    force: float            # vertical reaction at the bottom (per unit thickness)
    dev_sigma_X: float
    eps_p_X: float
    iterations: int
    attempts: int           # Newton runs (1 + cuts)


@dataclass
class Snapshot:
    """State at the peak of a touch: the stamp (body object and its dof vector), the work
    piece's total displacement (dofs), its committed fields (element means) and the
    contact result."""

    touch: int
    stamp: object
    u_stamp: np.ndarray
    u_work: np.ndarray
    fields: dict
    result: object = None


@dataclass
class TouchResult:
    records: list = field(default_factory=list)
    peak: Snapshot | None = None
    u_work: np.ndarray | None = None      # total work piece displacement at the end
    converged: bool = True
    reason: str = "converged"


def stamp_body(kind: str, box, h: float, E: float, nu: float, p: int = 1,
               mesh_kind: str = "quad"):
    """The elastic stamp on ``box`` = (x0, x1, y0, y1) (x0 < x1, y0 < y1) with mesh size
    h: FE (Q1/P1 rectangle mesh) or BE (Galerkin, degree p, the four sides labelled like
    the FE mesh)."""
    choice("kind", kind, STAMP_KINDS)
    choice("mesh_kind", mesh_kind, MESH_KINDS)
    x0, x1, y0, y1 = _box(box)
    nx, ny = _cells(x1 - x0, h), _cells(y1 - y0, h)
    p = integer("p", p, lo=1)
    if kind == "FE":
        return ElasticBody(rectangle_mesh(x0, x1, y0, y1, nx, ny, mesh_kind), E, nu)
    mesh = BoundaryMesh.polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)],
                                n=[nx, ny, nx, ny], labels=list(SIDES), p=p)
    return LameBEM(mesh, E, nu, "strain")


def work_piece(box, h: float, material: J2Material, formulation: str = "bbar",
               mesh_kind: str = "quad") -> ElastoPlasticFE:
    """The elastoplastic Q1/P1 work piece on ``box`` = (x0, x1, y0, y1) with mesh size h."""
    instance("material", material, J2Material)
    choice("mesh_kind", mesh_kind, MESH_KINDS)
    x0, x1, y0, y1 = _box(box)
    m = rectangle_mesh(x0, x1, y0, y1, _cells(x1 - x0, h), _cells(y1 - y0, h), mesh_kind)
    return ElastoPlasticFE(m, material, formulation)


def _box(box) -> tuple:
    """(x0, x1, y0, y1) of a rectangle: four finite reals with x0 < x1 and y0 < y1."""
    x0, x1, y0, y1 = (float(v) for v in array("box (x0, x1, y0, y1)", box, shape=(4,)))
    if not (x0 < x1 and y0 < y1):
        raise ValueError(f"box (x0, x1, y0, y1) must have x0 < x1 and y0 < y1, got "
                         f"{tuple(box)!r}")
    return x0, x1, y0, y1


def _cells(length: float, h: float) -> int:
    h = real("h", h, positive=True)
    return max(1, int(round(length / h)))


def lift_schedule(u_total: float, n_load: int, n_unload: int) -> np.ndarray:
    """g after each increment: n_load equal steps up to u_total, n_unload down to 0."""
    u_total = real("u_total", u_total)
    n_load = integer("n_load", n_load, lo=1)
    n_unload = integer("n_unload", n_unload, lo=0)
    up = u_total * np.arange(1, n_load + 1) / n_load
    down = u_total * (1.0 - np.arange(1, n_unload + 1) / n_unload) if n_unload else []
    return np.concatenate([up, down])


def _stamp_on_work(stamp, body, E: float, settings: StampContact):
    """The penalty contact of the stamp's bottom (slave) on the work piece's top
    (master), 1/eps = factor x E, and the dofs a touch prescribes: the stamp's top and
    the work piece's bottom (``is_y`` marks the lifted y components)."""
    pr = TwoBodyContact(stamp, body, "bottom", "top",
                        eps_n=1.0 / (settings.eps_n_factor * E),
                        eps_t=1.0 / (settings.eps_t_factor * E), **settings.friction(),
                        two_pass=bool(settings.two_pass))
    return (pr, *pr.stamp_dofs())


class TouchSteps:
    """The load steps of one touch (:class:`hpfebe.solvers.LoadStep`) on the load steps
    of the contact problem (:class:`hpfebe.contact.loading.LoadSteps`): load factor
    lambda in (k - 1, k] is increment k of the lift schedule ``lifts`` (g_0 = 0), the
    prescribed lift ramped linearly from g_{k-1} to g_k on the dofs ``is_y``; the start of
    an increment is :meth:`extrapolated`; after each converged increment
    ``on_increment(k, result)`` is called with the :class:`~hpfebe.contact.ContactResult` of its last
    step (its ``info`` the increment's attempts)."""

    def __init__(self, pr: TwoBodyContact, fixed, is_y, lifts, work_y,
                 solver: ContactSettings, on_increment: Callable, open_start: bool = True,
                 bonded_increments: int | None = None):
        self.contact = LoadSteps(pr, None, fixed, self.lift, solver)
        self.is_y, self.lifts, self.work_y = is_y, np.asarray(lifts, dtype=float), work_y
        self.on_increment = on_increment
        self.open_start = bool(open_start)
        self.bonded_increments = bonded_increments
        self.hist = []                 # (g, U) of the converged increments
        self.opened = False            # the last converged increment ended open
        self.rigid = False             # the current increment started rigidly moved
        self.attempts = []             # SolverInfo of the current increment's attempts
        self.lam, self.lam_done = 0.0, 0.0

    @staticmethod
    def increment(lam: float) -> int:
        """The (0-based) increment of load factor lam in (k, k + 1]."""
        return int(np.ceil(lam)) - 1

    def lift(self, lam: float) -> np.ndarray:
        """The prescribed values at load factor lam: g_{k-1} + (lam - k) (g_k - g_{k-1})
        on the lifted dofs, 0 on the others."""
        k = self.increment(lam)
        a, b = (self.lifts[k - 1] if k else 0.0), self.lifts[k]
        return np.where(self.is_y, a + (lam - k) * (b - a), 0.0)

    def extrapolated(self, x: np.ndarray, g: float) -> np.ndarray:
        """The Newton start of an increment to the lift g: the secant extrapolation of
        the last two converged increments (x before the first).  At a reversal of the
        lift (unloading) the extrapolation points the wrong way; there the start is U1
        with the work piece's y dofs ``work_y`` translated by g - g1 and the stamp at
        rest: the plastic work piece springs back by O(sigma_Y / E) x height only, far
        less than the lift, so the contact opens.  After an increment that ended with
        the contact open (every point OPEN; ``open_start``) the start is that state
        moved the same way: the exact solution while the contact stays open (the
        bodies unloaded, the work piece elastic), where the secant extrapolation would
        repeat the last increment's springback (measured, Example 1 h = 0.05: the
        unloading increments 11 and 9 iterations -> 1-2)."""
        self.rigid = False
        if not self.hist:
            return x
        if self.open_start and self.opened:
            (g1, U1) = self.hist[-1]
            self.rigid = True
            U = U1.copy()
            U[self.work_y] += g - g1
            U[:self.contact.pr.offset] = 0.0
            return U
        if len(self.hist) == 1:
            (g1, U1), (g0, U0) = self.hist[-1], (0.0, np.zeros_like(x))
        else:
            (g1, U1), (g0, U0) = self.hist[-1], self.hist[-2]
        if (g - g1) * (g1 - g0) > 0:
            return U1 + (g - g1) / (g1 - g0) * (U1 - U0)
        U = U1.copy()
        U[self.work_y] += g - g1
        U[:self.contact.pr.offset] = 0.0
        return U

    def newton_options(self) -> dict:
        """The Newton keywords of the contact steps, the bonded predictor skipped at a
        rigidly moved start (:meth:`extrapolated`) with no point in contact and after
        the first ``bonded_increments`` increments."""
        opts = self.contact.newton_options()
        bonded = opts.get("predictor")
        if bonded is not None:
            def predictor(it: Iterate):
                if self.rigid and np.all(it.data["state"] == OPEN):
                    return None
                if self.bonded_increments is not None and \
                        self.increment(self.lam) >= self.bonded_increments:
                    return None
                return bonded(it)
            opts["predictor"] = predictor
        return opts

    # LoadStep protocol
    def problem(self, lam: float):
        self.lam = lam
        return self.contact.problem(lam)

    def start(self, x: np.ndarray, lam: float) -> np.ndarray:
        k = self.increment(lam)
        if self.lam_done == k:         # the first step of increment k (or its cut)
            x = self.extrapolated(x, self.lifts[k])
        return self.contact.start(x, lam)

    def record(self, it: Iterate, info: SolverInfo) -> None:
        self.contact.record(it, info)
        self.attempts.append(info)

    def commit(self, it: Iterate) -> None:
        self.contact.commit(it)
        self.lam_done = self.lam
        k = self.increment(self.lam)
        if self.lam == k + 1:          # increment k converged
            self.hist.append((self.lifts[k], it.x.copy()))
            self.opened = bool(np.all(it.data["state"] == OPEN))
            info = SolverInfo(True, "converged", steps=self.attempts,
                              iterations=sum(a.iterations for a in self.attempts))
            self.attempts = []
            # the LU cache of the contact steps holds one increment's factorisations
            self.contact.forget_factorisations()
            self.on_increment(k, self.contact.pr.result(it, info, self.contact))


def _touch_path(pr, fixed, is_y, work_y, lifts, settings: StampContact, force: float,
                on_increment, touch_id: int) -> TouchResult:
    """All increments of one touch (lifts ``lifts``) as one load path; ``force`` the
    reference force of the stopping test (:func:`reference_force`: the floor atol =
    rtol x force).  A failed increment (after ``max_cuts`` cuts) ends the touch with its
    reason."""
    solver = dataclasses.replace(settings.solver, atol=settings.solver.rtol * force)
    steps = TouchSteps(pr, fixed, is_y, lifts, work_y, solver, on_increment,
                       settings.open_start, settings.bonded_increments)
    _, info = load_path(steps, np.arange(1.0, len(lifts) + 1), steps.contact.x0,
                        max_cuts=solver.max_cuts, cuts_per_step=True,
                        **steps.newton_options())
    out = TouchResult()
    if not info.converged:
        k = TouchSteps.increment(info.steps[-1].load_factor)
        out.converged = False
        out.reason = (f"touch {touch_id}, increment {k + 1} (g = {lifts[k]:.3e}): "
                      f"{info.reason}")
    return out


def _extent(points: np.ndarray) -> tuple[float, float]:
    """(width, height) of the bounding box of points (2, n)."""
    return float(np.ptp(points[0])), float(np.ptp(points[1]))


def _stamp_extent(stamp) -> tuple[float, float]:
    return _extent(stamp.mesh.p if isinstance(stamp, ElasticBody) else stamp.mesh.nodes.T)


def reference_force(stamp, material: J2Material, work_size, u_total: float,
                    settings: StampContact) -> float:
    """The reference force of a touch's stopping test (the floor atol = rtol x this
    force; the backward-error rule of :mod:`hpfebe.solvers.info`): the work piece's
    width W times the smaller of its yield stress (J2Material.stress_floor: sigma_Y, at
    most the stress of a 0.1 % strain, 1e-3 E) and the elastic stress of the prescribed
    lift, |u_total| / (H_s / E_s + H_w / E_w + eps_n) (the stamp, the work piece (heights
    H_s, H_w) and the normal penalty spring in series).  When the stamp is lifted off,
    the forces at equilibrium shrink to residual stresses and the relative test alone
    asks for more digits than round-off leaves; the floor stops there.  Scale-free: it
    scales with the forces when lengths, moduli or the lift are scaled (a yield force
    alone did not: a stamp pressed by 4.2e-12 had its start accepted after 0 iterations
    with a force 14.7 x the linear one).  ``work_size``: (W, H_w)."""
    W, H_w = work_size
    H_s = _stamp_extent(stamp)[1]
    E_w = material.E
    compliance = H_s / stamp.E + H_w / E_w + 1.0 / (settings.eps_n_factor * E_w)
    return W * min(material.stress_floor, abs(u_total) / compliance)


def touch(stamp, fe: ElastoPlasticFE, u_total: float, n_load: int, n_unload: int,
          X, settings: StampContact, offset=None, touch_id: int = 1) -> TouchResult:
    """One touch (module doc): returns the per-increment records, the snapshot at the
    peak and the work piece's total displacement at the end (the offset of a next
    touch).  A failed increment (after ``max_cuts`` cuts) ends the touch with its reason;
    the committed history is that of the last converged increment."""
    instance("fe", fe, ElastoPlasticFE)
    X, touch_id = _touch_args(stamp, X, settings, touch_id)
    lifts = lift_schedule(u_total, n_load, n_unload)
    n_load = integer("n_load", n_load)
    if offset is not None:
        offset = array("offset", offset, shape=(fe.ndofs,))
    body = PlasticFEBody(fe, offset)
    pr, fixed, is_y = _stamp_on_work(stamp, body, fe.material.E, settings)
    bottom_y = fe.elastic.dofs_on("bottom", 1)
    work_y = pr.global_dofs("master", fe.elastic.nodal_dofs[1])
    records, last = [], {}

    def on_increment(k: int, res) -> None:
        last["res"] = res
        records.append(StepRecord(
            touch_id, "load" if k < n_load else "unload", float(lifts[k]),
            float(fe.committed_force()[bottom_y].sum()),
            fe.value_at("dev_sigma_norm", X), fe.value_at("eps_p_norm", X),
            int(res.info.iterations), len(res.info.steps)))
        if k == n_load - 1:
            last["peak"] = Snapshot(touch_id, stamp, res.u_slave.copy(),
                                    body.offset + res.u_master, _mean_fields(fe), res)

    force = reference_force(stamp, fe.material, _extent(fe.mesh.p), float(u_total),
                            settings)
    out = _touch_path(pr, fixed, is_y, work_y, lifts, settings, force, on_increment,
                      touch_id)
    out.records, out.peak = records, last.get("peak")
    if "res" in last:
        out.u_work = body.offset + last["res"].u_master
    return out


def _touch_args(stamp, X, settings, touch_id):
    """The checked arguments every touch shares: the stamp's kind, X (a point) and the
    settings; returns (X, touch_id)."""
    instance("stamp", stamp, (ElasticBody, LameBEM), "an elastic stamp (ElasticBody or "
             "LameBEM, stamp_body)")
    instance("settings", settings, StampContact)
    return array("X", X, shape=(2,)), integer("touch_id", touch_id, lo=1)


def _mean_fields(fe: ElastoPlasticFE) -> dict:
    f = fe.fields()
    return {k[:-5]: v.copy() for k, v in f.items() if k.endswith("_mean")}


def stamp_interior(stamp, u_stamp: np.ndarray, nx: int, ny: int):
    """Displacement of the stamp on the vertices of an nx x ny grid of its box: FE nodal
    values (the mesh's own vertices when nx, ny are its cells), BE through the
    representation formula at interior grid points and the trace on the boundary (as
    the thesis does for Figures 4.3, 4.8).  Returns (grid points (n, 2), displacement
    (n, 2), quad cells (m, 4))."""
    if isinstance(stamp, ElasticBody):
        p = stamp.mesh.p.T
        return p, stamp.nodal_displacement(u_stamp).T, stamp.mesh.t.T
    m = stamp.mesh
    lo, hi = np.min(m.a, axis=0), np.max(m.a, axis=0)
    xs, ys = np.linspace(lo[0], hi[0], nx + 1), np.linspace(lo[1], hi[1], ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    pts = np.column_stack([X.ravel(), Y.ravel()])
    tol = 1e-12 * float(np.max(hi - lo))
    inside = (pts[:, 0] > lo[0] + tol) & (pts[:, 0] < hi[0] - tol) & \
             (pts[:, 1] > lo[1] + tol) & (pts[:, 1] < hi[1] - tol)
    disp = np.zeros_like(pts)
    disp[inside] = stamp.representation(pts[inside], u_stamp, stamp.Psi(u_stamp))
    disp[~inside] = _be_trace(stamp, u_stamp, pts[~inside])
    i = np.arange(nx)[None, :] + (nx + 1) * np.arange(ny)[:, None]
    cells = np.stack([i, i + 1, i + nx + 2, i + nx + 1], axis=-1).reshape(-1, 4)
    return pts, disp, cells


def _be_trace(stamp: LameBEM, u: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """The BE boundary displacement (V_hp^2) at boundary points: located on their
    element, evaluated with the element's Lagrange basis."""
    b = BEBody(stamp)
    m = stamp.mesh
    d = m.b - m.a
    rel = pts[:, None, :] - m.a[None]
    s = np.clip(np.einsum("nec,ec->ne", rel, d) / np.einsum("ec,ec->e", d, d), 0.0, 1.0)
    dist = np.linalg.norm(rel - s[..., None] * d[None], axis=-1)
    e = np.argmin(dist, axis=1)
    sp_ = s[np.arange(len(pts)), e]
    cols, vals = b.trace(e, sp_)
    return np.stack([np.einsum("nk,nk->n", vals, u[cols[:, c]]) for c in (0, 1)], axis=1)


# --------------------------------------------------------------------------- comparisons
def element_areas(fe: ElastoPlasticFE) -> np.ndarray:
    """|K| of every element of the work piece (sum of its quadrature weights)."""
    return fe.dx.sum(axis=1)


def plastic_zone(fe: ElastoPlasticFE, eps_p_mean: np.ndarray, tol: float) -> np.ndarray:
    """Mask of the elements whose mean ||eps_p|| exceeds ``tol``."""
    if not tol >= 0:
        raise ValueError(f"tol must be >= 0, got {tol!r}")
    return np.asarray(eps_p_mean) > tol


def zone_mismatch(fe: ElastoPlasticFE, a: np.ndarray, b: np.ndarray) -> float:
    """|A symmetric-difference B| / |A union B| of two element masks (0 = same zone)."""
    w = element_areas(fe)
    union = float(w[a | b].sum())
    return float(w[a ^ b].sum()) / union if union > 0 else 0.0


def field_difference(fe: ElastoPlasticFE, a: np.ndarray, b: np.ndarray) -> float:
    """||a - b||_L2 / ||a||_L2 of two element-wise constant fields on the work piece."""
    w = element_areas(fe)
    na = float(np.sqrt(w @ np.asarray(a) ** 2))
    return float(np.sqrt(w @ (np.asarray(a) - np.asarray(b)) ** 2)) / na if na > 0 else 0.0


def curve_difference(a, b) -> float:
    """max_k |a_k - b_k| / max_k |a_k|: the largest difference of two curves sampled at
    the same load increments, relative to the first curve's peak."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or a.size == 0:
        raise ValueError(f"curves must be non-empty and of equal length, got {a.shape}, "
                         f"{b.shape}")
    peak = float(np.abs(a).max())
    return float(np.abs(a - b).max()) / peak if peak > 0 else float(np.abs(b).max())


# --------------------------------------------------------------------------- BE/BE
def be_work_piece(box, h: float, material: J2Material, cells: str = "crossed"):
    """The elastoplastic BE work piece (thesis Section 4.2.4) on ``box`` with mesh size h:
    a degree-1 LameBEM and cells of size h carrying the plastic strain
    (:func:`hpfebe.bodies.plastic_be.rectangle_work_piece`, backward Euler ("implicit")
    update)."""
    x0, x1, y0, y1 = box
    return rectangle_work_piece(box, _cells(x1 - x0, h), _cells(y1 - y0, h), material,
                                scheme="implicit", cells=cells)


def touch_be(stamp, be, u_total: float, n_load: int, X, settings: StampContact,
             touch_id: int = 1) -> TouchResult:
    """One loading touch (no unloading) of the stamp on the elastoplastic BE work piece
    ``be`` (:class:`hpfebe.bodies.plastic_be.ElastoPlasticBE`, contact body
    :class:`~hpfebe.bodies.plastic_be.PlasticBEBody`): the schedule, predictor and stopping
    rule of :func:`touch`.  Records: the bottom reaction (S_hat u - G(tau) summed over
    the bottom y dofs), ||dev sigma|| and ||eps_p|| of the cells touching X.  The
    snapshot's ``u_work`` is the BE boundary displacement; its ``fields`` the cell fields
    plus the cell-node displacement ``node_u`` (representation formula)."""
    instance("be", be, ElastoPlasticBE)
    X, touch_id = _touch_args(stamp, X, settings, touch_id)
    lifts = lift_schedule(u_total, n_load, 0)
    body = PlasticBEBody(be)
    pr, fixed, is_y = _stamp_on_work(stamp, body, be.material.E, settings)
    by_local = body.dofs_on("bottom", 1)
    work_y = pr.global_dofs("master", np.arange(1, be.ndofs, 2))
    records, last = [], {}

    def on_increment(k: int, res) -> None:
        last["res"] = res
        force = float((be.S @ res.u_master - be.plastic_force())[by_local].sum())
        records.append(StepRecord(
            touch_id, "load", float(lifts[k]), force, be.value_at("dev_sigma_norm", X),
            be.value_at("eps_p_norm", X), int(res.info.iterations), len(res.info.steps)))

    force = reference_force(stamp, be.material, _extent(be.bem.mesh.nodes.T),
                            float(u_total), settings)
    out = _touch_path(pr, fixed, is_y, work_y, lifts, settings, force, on_increment,
                      touch_id)
    out.records = records
    if "res" in last:
        res = last["res"]
        out.u_work = res.u_master.copy()
        f = {k: v.copy() for k, v in be.fields().items()}
        f["node_u"] = be.node_displacements(out.u_work)
        out.peak = Snapshot(touch_id, stamp, res.u_slave.copy(), out.u_work, f, res)
    return out
