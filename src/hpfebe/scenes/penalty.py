"""The benchmark of Section 3.2.5 (thesis lines 8540-8640) and the runs built on it
(``experiments/ch3_penalty``: Table 3.1, Figure 3.1; ``experiments/ch3_penalty_hp``: the
rate of Theorem 3.2.6 and a stability stress test).

Omega = [-1,1]^2, Gamma_D = [-1,1] x {1} (u = 0), Gamma_C = [-1,1] x {-1}, Gamma_N = the
vertical sides (traction free) (:func:`square_body`), rigid straight obstacle y = -1 + d
(gap g = -d) or the tilted one g(x) = -d + s (x + 1) (:func:`tilted_gap`), E = 266926,
nu = 0.29 (:mod:`hpfebe.scenes.materials`), uniform meshes with n elements per side of
degree p.  Penalty formulation (3.45)-(3.46), (3.57)

    <S_hat U, v> + (1/eps) int_{Gamma_C} (U_n - g)_+ v_n ds = 0,

solved by :func:`hpfebe.contact.solve_penalty` (semismooth Newton, exact integration of
the positive part), checked by :func:`hpfebe.contact.solve_penalty_checked`.  The sweeps
return one row (dict) per run; the experiments make the tables, claims and figures.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ..analysis import aitken, energy_norm, observed_rates
from ..bem.lame import LameBEM
from ..bodies.body import RigidObstacle, against_obstacle
from ..checks import array, choice, integer, real
from ..constitutive.laws import SLIP
from ..constitutive.materials import PLANES
from ..contact.limits import (MACHEPS, constrained_limit, saturation_index,
                              solve_penalty_checked)
from ..contact.penalty import solve_penalty
from ..contact.two_body import TwoBodyContact
from ..geometry import BoundaryMesh
from ..io import boundary_vtu, contact_vtu
from ..spaces import prolongate
from .materials import E, NU

log = logging.getLogger(__name__)

#: the benchmark square [-1,1]^2 and its side labels (bottom, right, top, left)
SQUARE = ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
SQUARE_LABELS = ("C", "N", "D", "N")
PLANE = "strain"      # the plane of Table 3.1 that reproduces ||u_lim||_S
#: ||u_lim||_S of Table 3.1 (the thesis's Aitken extrapolation, its norm scale)
PUBLISHED_ULIM = 0.154398


def square_body(n: int, E: float, nu: float, plane: str = "strain", p: int = 1) -> LameBEM:
    """The Section 3.2.5 body: [-1,1]^2, n elements of degree p per side, Gamma_C bottom,
    Gamma_N the vertical sides, Gamma_D top."""
    mesh = BoundaryMesh.polygon(SQUARE, n=n, p=p, labels=list(SQUARE_LABELS))
    return LameBEM(mesh, E, nu, plane=plane)


def warm_up(prm) -> float:
    """Seconds of one small S_hat (n = 2, plane strain, the material of ``prm``): numba
    compilation or loading of its cache, kept out of the timings."""
    t0 = time.perf_counter()
    square_body(2, prm.E, prm.nu, PLANE).S_hat
    return time.perf_counter() - t0


def tilted_gap(d: float, slope: float):
    """The tilted obstacle g(x) = -d + slope (x + 1)."""
    return lambda x: -d + slope * (x[:, 0] + 1.0)


def _each(items, desc=""):
    return items


def contact_exports(bem: LameBEM, res, gap, S=None) -> dict:
    """ParaView fields of one penalty solution ``res`` on ``bem`` (issue 26):
    ``"boundary"``, the displacement U on the boundary mesh (:func:`hpfebe.io.boundary_vtu`);
    ``"contact"``, the state at the p_I + 1 Gauss points of every element of Gamma_C
    (:func:`hpfebe.io.contact_vtu`): pressure p_n = (1/eps)(U_n - g)_+, tangential
    traction t_t = 0 (frictionless), gap g_n, tangential displacement g_t, slip (= g_t
    where in contact: a frictionless point slides freely), state (0 open, 2 slip)."""
    body, _, _ = against_obstacle(bem, S, "C", "D", None)
    pr = TwoBodyContact(body, RigidObstacle(gap), "C", eps_n=res.eps, nq=None)
    cs = pr.contact_state(np.asarray(res.U, dtype=float), 0.0)
    state = SimpleNamespace(points=cs["points"], weights=cs["weights"], p_n=cs["p_n"],
                            t_t=cs["t_t"], g_n=cs["g_n"], g_t=cs["g_t"], state=cs["state"],
                            slip=np.where(cs["state"] == SLIP, cs["g_t"], 0.0))
    U = np.asarray(res.U, dtype=float)
    return {"boundary": boundary_vtu(bem.mesh, bem.V_space, {"displacement": U}, d=2),
            "contact": contact_vtu(state)}


def representative_exports(prm, n: int, p: int, eps: float, gap,
                           plane: str = PLANE) -> dict:
    """:func:`contact_exports` of the penalty solution on the square with n elements of
    degree p per side, penalty ``eps`` and gap ``gap`` (the material of ``prm``)."""
    bem = square_body(n, prm.E, prm.nu, plane, p=p)
    S = bem.S_hat
    res = solve_penalty(bem, eps, gap, S=S, max_iter=prm.max_newton_iterations)
    if not res.converged:
        raise RuntimeError(f"penalty Newton failed (n={n}, p={p}, eps={eps}): {res.reason}")
    return contact_exports(bem, res, gap, S)


# --------------------------------------------------------------------------- Table 3.1
@dataclass(frozen=True)
class PenaltyScene:
    """Table 3.1: material, obstacle distance d, meshes, eps = C_eps h (and fixed eps), the
    planes run, the norm scale of the thesis (see experiments/ch3_penalty)."""

    E: float = E
    nu: float = NU
    d: float = 2e-4                  # obstacle y = -1 + d, gap g = -d
    n_per_side: tuple[int, ...] = (4, 8, 16, 32, 64, 128)
    C_eps: tuple[float, ...] = (1e-4, 1e-5, 1e-6, 1e-7)     # eps = C_eps h
    planes: tuple[str, ...] = ("strain", "stress")
    norm_scale: float = math.sqrt(2.0)
    fixed_eps: tuple[float, ...] = (2.5e-5,)
    max_newton_iterations: int = 30

    def __post_init__(self):
        _counts("n_per_side", self.n_per_side, 3, "meshes (Aitken) of n >= 1")
        _positives("C_eps", self.C_eps, 1)
        _positives("fixed_eps", self.fixed_eps, 0)
        if isinstance(self.planes, str) or not self.planes:
            raise ValueError(f"planes must be a non-empty subset of {PLANES}, got "
                             f"{self.planes!r}")
        for pl in self.planes:
            choice("planes entry", pl, PLANES)
        real("E", self.E, positive=True)
        real("nu", self.nu, lo=-1.0, hi=0.5, lo_open=True, hi_open=True)
        real("d", self.d, positive=True)
        real("norm_scale", self.norm_scale, positive=True)
        integer("max_newton_iterations", self.max_newton_iterations, lo=1)


def _counts(name: str, values, least: int, what: str = "entries >= 1") -> np.ndarray:
    """A sequence of at least ``least`` integers >= 1 (a parameter check)."""
    v = array(name, values, ndim=1, dtype=int)
    if v.size < least or (v.size and v.min() < 1):
        raise ValueError(f"{name} needs >= {least} {what}, got {values!r}")
    return v


def _positives(name: str, values, least: int) -> np.ndarray:
    """A sequence of at least ``least`` positive finite reals (a parameter check)."""
    v = array(name, values, ndim=1)
    if v.size < least or np.any(v <= 0):
        raise ValueError(f"{name} must be a list of {'>= %d ' % least if least else ''}"
                         f"positive numbers, got {values!r}")
    return v



def penalty_sweep(prm: PenaltyScene, plane: str, progress=_each) -> list[dict]:
    """<S_hat U, U>^(1/2) for every (n, C_eps) (S_hat assembled once per mesh), plus the
    runs with a fixed eps."""
    rows = []
    for n in progress(prm.n_per_side, desc=f"plane {plane}"):
        t0 = time.perf_counter()
        bem = square_body(n, prm.E, prm.nu, plane)
        S = bem.S_hat
        t_asm = time.perf_counter() - t0
        dof = len(bem.V_space.free_dofs("D", components=2))
        runs = [(C, C / n, "C_eps h") for C in prm.C_eps] + \
               [(math.nan, e, "fixed") for e in prm.fixed_eps]
        for C, eps, kind in runs:
            t1 = time.perf_counter()
            res = solve_penalty(bem, eps, -prm.d, S=S, max_iter=prm.max_newton_iterations)
            wall = time.perf_counter() - t1
            if not res.converged:
                raise RuntimeError(f"penalty Newton failed (n={n}, eps={eps}): {res.reason}")
            rows.append(dict(plane=plane, kind=kind, C_eps=C, n=n, dof=dof, eps=eps,
                             norm=energy_norm(S, res.U),
                             newton_iterations=res.iterations,
                             final_residual=res.residuals[-1],
                             max_pressure=float(res.pressure_nodes[1].max()),
                             min_pressure=float(res.pressure_nodes[1].min()),
                             wall_time_s=wall + (t_asm if C == prm.C_eps[0] else 0.0),
                             assembly_s=t_asm))
            log.info("%s n=%d eps=%.3g norm=%.8f it=%d", plane, n, eps, rows[-1]["norm"],
                     res.iterations)
    return rows



def aitken_limits(rows: list[dict], prm: PenaltyScene):
    """||u_lim||_S per plane, the Aitken extrapolation of <S_hat U,U>^(1/2) over the three
    finest meshes of the smallest C_eps (rows of :func:`penalty_sweep`), and the plane
    whose limit times ``norm_scale`` is closest to :data:`PUBLISHED_ULIM`."""
    Cmin = min(prm.C_eps)
    ulim = {pl: aitken(*[r["norm"] for r in sorted(
        (r for r in rows if r["plane"] == pl and r["C_eps"] == Cmin),
        key=lambda r: r["n"])][-3:]) for pl in prm.planes}
    best = min(prm.planes, key=lambda pl: abs(prm.norm_scale * ulim[pl] - PUBLISHED_ULIM))
    return ulim, best


def error_rows(rows: list[dict], prm: PenaltyScene, ulim: dict, best: str) -> list[dict]:
    """Table 3.1: err = |scale (||u_lim|| - <S_hat U,U>^(1/2))| of the eps = C_eps h runs
    of plane ``best`` (by decreasing C_eps, then n), beside it err_published_ulim (against
    the thesis's 0.154398), err_unscaled (without the norm scale) and the other plane's
    err."""
    scale, other = prm.norm_scale, [pl for pl in prm.planes if pl != best]
    main = [r for r in rows if r["kind"] == "C_eps h"]
    norm_other = {(r["C_eps"], r["n"]): r["norm"] for r in main
                  if other and r["plane"] == other[0]}
    out = []
    for r in sorted((r for r in main if r["plane"] == best),
                    key=lambda r: (-r["C_eps"], r["n"])):
        row = dict(C_eps=r["C_eps"], dof=r["dof"], eps=r["eps"],
                   err=abs(scale * (ulim[best] - r["norm"])),
                   err_published_ulim=abs(PUBLISHED_ULIM - scale * r["norm"]),
                   err_unscaled=abs(ulim[best] - r["norm"]), norm_S=r["norm"],
                   ulim_S=ulim[best])
        if other:
            row["err_" + other[0]] = abs(scale * (ulim[other[0]]
                                                  - norm_other[(r["C_eps"], r["n"])]))
        out.append(dict(row, **{k: r[k] for k in (
            "n", "newton_iterations", "final_residual", "min_pressure", "max_pressure",
            "wall_time_s", "assembly_s")}))
    return out


#: Table 3.1: the choices where the thesis is silent (repeated in the notes)
PENALTY_CHOICES = (
    "h = 1/n (n elements per side) - this reproduces the tabulated eps (DOF 22 <-> n = 4).",
    "DOF = the free displacement unknowns, 2 (3n - 1) (22, 46, ..., 766 as in the table).",
    "Plane strain and plane stress are both run; the one whose Aitken limit matches "
    "0.154398 is reported in the err column, the other beside it.",
    "Norm scale: the thesis's energy norms are sqrt(2) times ours for the same E, nu "
    "(S_hat of this package passes an exact patch test: S_hat U = int sigma(u) n . v for "
    "every linear and quadratic elastic field). All 24 tabulated errors are reproduced "
    "only with that factor; norm_scale (default sqrt(2)) is applied and the unscaled "
    "values are kept in err_unscaled. Since the problem is linear in d once Gamma_C is in "
    "full contact, the factor is exactly what an obstacle shift d sqrt(2) = 2.83e-4 or a "
    "norm convention (2 <S_hat U, U>)^(1/2) gives (checked: n = 4, C_eps = 1e-4: "
    "0.0326598 with d sqrt(2) against the published 0.154398 - 0.121739 = 0.0326594); "
    "doubling E at the same eps does not (0.01826). The thesis's code is not available to "
    "decide which.",
    "||u_lim||_S is our own Aitken extrapolation of <S_hat U,U>^(1/2) over the three "
    "finest meshes of the smallest C_eps (shown beside 0.154398); err uses it.",
)


# --------------------------------------------------------------------------- hp rate
@dataclass(frozen=True)
class HpRateParams:
    """Theorem 3.2.6: eps = C_pen (h/p)^(1 - epsilon) on n_per_side x p; the reference."""

    p: tuple[int, ...] = (1, 2, 3, 4)
    n_per_side: tuple[int, ...] = (2, 4, 8, 16)     # h = 1/n
    C_pen: tuple[float, ...] = (1e-6, 1e-10)        # eps = C_pen (h/p)^(1 - epsilon)
    epsilon: float = 0.25
    n_ref: int = 128
    p_ref: int = 4
    C_ref: float = 1e-10                            # eps_ref = C_ref h_ref / p_ref

    def __post_init__(self):
        _counts("hp_rate.n_per_side", self.n_per_side, 2, "meshes")
        real("hp_rate.epsilon (Theorem 3.2.6)", self.epsilon, lo=0.0, hi=0.5,
             lo_open=True, hi_open=True)
        _counts("hp_rate.p", self.p, 1, "degrees >= 1")
        _positives("hp_rate.C_pen", self.C_pen, 1)
        real("hp_rate.C_ref", self.C_ref, positive=True)
        integer("hp_rate.n_ref", self.n_ref, lo=1)
        integer("hp_rate.p_ref", self.p_ref, lo=1)
        if any(self.n_ref % n for n in self.n_per_side) or self.p_ref < max(self.p):
            raise ValueError(f"hp_rate.n_ref = {self.n_ref} must be a multiple of every n in "
                             f"{self.n_per_side} and p_ref = {self.p_ref} >= max p")


@dataclass(frozen=True)
class StabilityParams:
    """The stress test: fixed mesh, eps = C_eps h, flat and tilted obstacle, acceptance."""

    n_per_side: int = 16
    p: tuple[int, ...] = (1, 2)
    C_eps: tuple[float, ...] = tuple(10.0 ** -k for k in range(4, 21))   # eps = C_eps h
    problems: tuple[str, ...] = ("flat", "tilted")
    tilt_slope: float = 4e-4             # tilted: g = -d + slope (x + 1)
    accept_relative_residual: float = 1e-6
    accept_backward_error_macheps: float = 20.0

    def __post_init__(self):
        if isinstance(self.problems, str):
            raise ValueError(f"stability.problems must be a list of 'flat' / 'tilted', got "
                             f"{self.problems!r}")
        for pr in self.problems:
            choice("stability.problems entry", pr, ("flat", "tilted"))
        c = _positives("stability.C_eps", self.C_eps, 0)
        if np.any(np.diff(c) > 0):
            raise ValueError(f"stability.C_eps must be positive and decreasing, got "
                             f"{self.C_eps}")
        integer("stability.n_per_side", self.n_per_side, lo=1)
        _counts("stability.p", self.p, 1, "degrees >= 1")
        real("stability.tilt_slope", self.tilt_slope)
        real("stability.accept_relative_residual", self.accept_relative_residual,
             positive=True)
        real("stability.accept_backward_error_macheps",
             self.accept_backward_error_macheps, positive=True)


@dataclass(frozen=True)
class PenaltyHpScene:
    """The hp-rate sweep and the stress test of experiments/ch3_penalty_hp."""

    E: float = E
    nu: float = NU
    d: float = 2e-4
    norm_scale: float = math.sqrt(2.0)     # as ch3_penalty (err vs the published limit)
    max_newton_iterations: int = 50
    hp_rate: HpRateParams = HpRateParams()
    stability: StabilityParams = StabilityParams()



def reference_solution(prm: PenaltyHpScene):
    """U_ref on the (n_ref, p_ref) mesh with eps_ref = C_ref h_ref / p_ref."""
    hp = prm.hp_rate
    t0 = time.perf_counter()
    ref = square_body(hp.n_ref, prm.E, prm.nu, PLANE, p=hp.p_ref)
    S_ref = ref.S_hat
    eps_ref = hp.C_ref * (1.0 / hp.n_ref) / hp.p_ref
    rref = solve_penalty(ref, eps_ref, -prm.d, S=S_ref, max_iter=prm.max_newton_iterations)
    if not rref.converged:
        raise RuntimeError(f"reference penalty solve failed: {rref.reason}")
    norm_ref = energy_norm(S_ref, rref.U)
    dof_ref = len(ref.V_space.free_dofs("D", components=2))
    info = dict(n_ref=hp.n_ref, p_ref=hp.p_ref, eps_ref=eps_ref, dof_ref=dof_ref,
                norm_ref=norm_ref, ref_s=time.perf_counter() - t0,
                ref_newton_iterations=rref.iterations)
    log.info("reference n=%d p=%d eps=%.3g dof=%d norm=%.10f (%.1f s)", hp.n_ref, hp.p_ref,
             eps_ref, dof_ref, norm_ref, info["ref_s"])
    return ref, S_ref, rref.U, info


def hp_rate_rows(prm: PenaltyHpScene, progress=_each):
    """Energy errors ||I U - U_ref||_{S_ref} of the eps = C_pen (h/p)^{1-epsilon} solutions
    (S_hat assembled once per mesh), one row per (C_pen decreasing, p, n) with the
    observed rates in h (``rate``) and in DOF^-1 (``rate_dof``) at fixed (C_pen, p),
    NaN on the first mesh; and the reference info."""
    hp = prm.hp_rate
    ref, S_ref, U_ref, info = reference_solution(prm)
    rows = []
    for p in progress(hp.p, desc="p"):
        for n in hp.n_per_side:
            t1 = time.perf_counter()
            bem = square_body(n, prm.E, prm.nu, PLANE, p=p)
            S = bem.S_hat
            asm_s = time.perf_counter() - t1
            h = 1.0 / n
            for k, C_pen in enumerate(hp.C_pen):
                t2 = time.perf_counter()
                eps = C_pen * (h / p) ** (1.0 - hp.epsilon)
                res = solve_penalty(bem, eps, -prm.d, S=S, max_iter=prm.max_newton_iterations)
                newton_s = time.perf_counter() - t2
                if not res.converged:
                    raise RuntimeError(f"penalty Newton failed (p={p}, n={n}, eps={eps}): "
                                       f"{res.reason}")
                e = prolongate(bem.V_space, res.U, ref.V_space, components=2) - U_ref
                err = energy_norm(S_ref, e)
                rows.append(dict(C_pen=C_pen, p=p, n_per_side=n, h=h,
                                 dof=len(bem.V_space.free_dofs("D", components=2)), eps=eps,
                                 energy_error=err, energy_error_rel=err / info["norm_ref"],
                                 err_norm_diff=abs(energy_norm(S, res.U) - info["norm_ref"]),
                                 newton_iterations=res.iterations,
                                 final_residual=res.residuals[-1],
                                 wall_time_s=time.perf_counter() - t2 + (asm_s if k == 0
                                                                         else 0.0),
                                 newton_s=newton_s))
                log.info("C_pen=%g p=%d n=%d eps=%.3g energy error %.4e", C_pen, p, n, eps,
                         err)
    rows.sort(key=lambda r: (-r["C_pen"], r["p"], r["n_per_side"]))
    for C_pen, p in dict.fromkeys((r["C_pen"], r["p"]) for r in rows):
        g = [r for r in rows if (r["C_pen"], r["p"]) == (C_pen, p)]
        e = np.array([r["energy_error"] for r in g], dtype=float)
        h = np.array([r["h"] for r in g], dtype=float)
        inv_dof = np.array([1.0 / r["dof"] for r in g], dtype=float)
        for r, rate, rate_dof in zip(g, observed_rates(h, e), observed_rates(inv_dof, e)):
            r.update(rate=rate, rate_dof=rate_dof)
    return rows, info



# --------------------------------------------------------------------------- stability
def stability_rows(prm: PenaltyHpScene, progress=_each) -> list[dict]:
    """One row per (p, problem, C_eps): the run's check (limits.PenaltyCheck), its energy
    norm_S, penalty_error (flat), delta_U against the previous C_eps and (flat)
    err = |0.154398 - sqrt(2) <S_hat U,U>^(1/2)|."""
    st = prm.stability
    n = st.n_per_side
    rows = []
    for p in st.p:
        bem = square_body(n, prm.E, prm.nu, PLANE, p=p)
        S = bem.S_hat
        U0 = constrained_limit(bem, -prm.d, S)
        n0 = energy_norm(S, U0)
        for prob in st.problems:
            gap = -prm.d if prob == "flat" else tilted_gap(prm.d, st.tilt_slope)
            prev = None
            for C in progress(st.C_eps, desc=f"p={p} {prob}"):
                eps = C / n
                res, chk = solve_penalty_checked(
                    bem, eps, gap, S=S, max_iter=prm.max_newton_iterations,
                    accept_rel=st.accept_relative_residual,
                    accept_eta=st.accept_backward_error_macheps)
                U = res.U
                finite = bool(np.all(np.isfinite(U)))
                nrm = energy_norm(S, U) if finite else math.nan
                row = dict(problem=prob, p=p, n=n, C_eps=C, eps=eps,
                           condition_number=chk.condition_number,
                           cond_x_macheps=chk.condition_number * MACHEPS,
                           newton_iterations=res.iterations, residual=chk.residual,
                           relative_residual=chk.relative_residual,
                           backward_error=chk.backward_error,
                           converged=bool(res.converged), accepted=chk.accepted,
                           reason=chk.reason, lapack_warning=chk.lapack_warning,
                           norm_S=nrm, wall_time_s=chk.solve_s)
                flat = prob == "flat"
                row["penalty_error"] = (energy_norm(S, U - U0) / n0 if flat and finite
                                        else math.nan)
                # against the published limit with the norm scale of Table 3.1
                row["err"] = abs(PUBLISHED_ULIM - prm.norm_scale * nrm) if flat else math.nan
                row["delta_U"] = (energy_norm(S, U - prev) / nrm
                                  if prev is not None and finite else math.nan)
                prev = U
                rows.append(row)
                log.info("%s p=%d C_eps=%.0e cond=%.2e it=%d rel.res=%.1e %s", prob, p, C,
                         chk.condition_number, res.iterations, chk.relative_residual,
                         chk.reason)
    return rows


def breakdown_summary(rows: list[dict]) -> dict:
    """Per (problem, p) of the stress test (rows of :func:`stability_rows`): where the
    runs are not accepted, fail or converge falsely, the largest C_eps at which LAPACK
    warns, the largest condition number and iteration count; for the flat obstacle the
    C_eps at which the penalty error stops decreasing ~ eps and its minimum."""
    out = {}
    for prob, p in dict.fromkeys((r["problem"], r["p"]) for r in rows):
        g = sorted((r for r in rows if (r["problem"], r["p"]) == (prob, p)),
                   key=lambda r: -r["C_eps"])
        C = [float(r["C_eps"]) for r in g]
        bad = [c for c, r in zip(C, g) if not r["accepted"]]
        warn = [c for c, r in zip(C, g) if r["lapack_warning"]]
        info = dict(first_not_accepted=bad[0] if bad else None, not_accepted=bad,
                    failed=[c for c, r in zip(C, g) if not r["converged"]],
                    false_convergence=[c for c, r in zip(C, g)
                                       if r["converged"] and not r["accepted"]],
                    first_lapack_warning=warn[0] if warn else None,
                    max_cond=float(np.nanmax([r["condition_number"] for r in g])),
                    max_iterations=int(max(r["newton_iterations"] for r in g)))
        if prob == "flat":
            pe = np.array([r["penalty_error"] for r in g], dtype=float)
            k = saturation_index(C, pe)
            info["penalty_error_saturates_at"] = C[k] if k is not None else None
            info["min_penalty_error"] = float(np.nanmin(pe))
        out[(prob, int(p))] = info
    return out


#: the hp-rate sweep: the choices where the thesis is silent (repeated in the notes)
HP_RATE_CHOICES = (
    "eps = C_pen (h/p)^{1-epsilon} with C_pen = 1e-6 (the C_eps of Table 3.1 whose rate is "
    "cleanest) and epsilon = 1/4 (the middle of (0, 1/2)); a second sweep with C_pen = "
    "1e-10 (penalty error negligible) separates the discretisation error from the penalty "
    "error.",
    "energy error = ||I U - U_ref||_{S_ref} = ((I U - U_ref)^T S_ref (I U - U_ref))^{1/2}, "
    "the S_hat energy norm (equivalent to the H~^{1/2}(Sigma) norm of Theorem 3.2.6) on "
    "the reference mesh, where I U is the exact embedding of the coarse solution into the "
    "(nested) reference space V_ref (nodal interpolation at the GLL points of the "
    "reference elements; n_ref is a multiple of every n and p_ref >= p, so I is exact) and "
    "U_ref the penalty solution on the reference mesh (n_ref, p_ref = 4) with a tiny "
    "eps_ref = C_ref h_ref / p_ref (C_ref = 1e-10: its own penalty error is ~1e-8 "
    "relative, the stress test shows this eps is numerically harmless). The error of "
    "U_ref itself is not included, so the errors of the finest meshes are slightly "
    "underestimated; the sweep stops at n_ref / 8 to keep this effect small (measured: "
    "n_ref = 64 instead of 128 changes the finest errors by <= 2% and the rates by "
    "<= 0.02). The Table 3.1-style error |<S_hat U, U>^{1/2} - <S_ref U_ref, "
    "U_ref>^{1/2}| (which behaves like the *square* of the energy error, Galerkin "
    "orthogonality) is given beside it (err_norm_diff).",
    "rate = log(e_{k-1}/e_k) / log(h_{k-1}/h_k) at fixed p (= rate in h/p), and rate_dof = "
    "the same against DOF^{-1}.",
    "DOF = free displacement unknowns 2 (number of V_hp nodes off Gamma_D).",
    "With epsilon = 1/4, 1 - epsilon = 0.75 and the corner exponent lambda = 0.718 "
    "(Williams' equation, nu = 0.29) are close, so the C_pen = 1e-10 sweep is what tells "
    "the penalty and the corner singularity apart (verdicts from the run).",
)

#: the stress test: the choices (repeated in the notes)
STABILITY_CHOICES = (
    "Fixed mesh n = 16 per side, eps = C_eps h with C_eps = 1e-4 ... 1e-20 (beyond the "
    "1e-12 asked for, to reach the breakdown), p = 1 and p = 2.",
    "flat: the Table 3.1 obstacle (the whole of Gamma_C in contact, so one Newton step "
    "solves the piecewise linear system); err = |0.154398 - sqrt(2) <S_hat U,U>^{1/2}| "
    "(the published limit and the norm scale of experiments.ch3_penalty), and "
    "penalty_error = ||U - U_0||_S / ||U_0||_S against the eps -> 0 limit on the same "
    "mesh, U_0 = the solution with U_n = -d imposed at the contact nodes (computed by "
    "elimination, no penalty, no ill-conditioning).",
    "tilted: g(x) = -d + 4e-4 (x + 1): contact on part of Gamma_C only, contact elements "
    "cut by the free boundary (the semismooth Newton really iterates). There is no "
    "reference limit: err and penalty_error are NaN (allowed) and delta_U = ||U(C_eps) - "
    "U(10 C_eps)||_S / ||U(C_eps)||_S shows whether the solutions still converge as "
    "eps -> 0.",
    "condition_number = numpy.linalg.cond (2-norm) of the Newton matrix S_hat + (1/eps) "
    "J_c(U) at the returned iterate on the free dofs; residual = the solver's final "
    "max-norm residual; relative_residual = residual / max|(S_hat U)_free| (the physical "
    "force scale, independent of eps); backward_error = max_i |G_i(U)| / (|A| |U|)_i "
    "(componentwise backward error, Oettli-Prager, of G(U) = 0 on the free dofs, A the "
    "Newton matrix: for tiny eps the residual cannot drop below ~ macheps (|A| |U|)_i in "
    "the contact rows - the rounding of U_n - g amplified by 1/eps - however exact U is; a "
    "residual in a row without penalty entries is not excused); accepted = the solver "
    "converged and (relative_residual <= 1e-6 or backward_error <= 20 macheps); LAPACK's "
    "ill-conditioning warnings (rcond < machine eps) are caught and appended to reason.",
)
