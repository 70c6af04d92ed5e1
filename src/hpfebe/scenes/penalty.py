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

import numpy as np

from ..analysis import energy_norm
from ..bem.lame import LameBEM
from ..checks import array, choice, integer, real
from ..constitutive.materials import PLANES
from ..contact.limits import MACHEPS, constrained_limit, solve_penalty_checked
from ..contact.penalty import solve_penalty
from ..geometry import BoundaryMesh
from ..spaces import prolongate
from .materials import E, NU

log = logging.getLogger(__name__)

#: the benchmark square [-1,1]^2 and its side labels (bottom, right, top, left)
SQUARE = ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
SQUARE_LABELS = ("C", "N", "D", "N")
PLANE = "strain"      # the plane of Table 3.1 that reproduces ||u_lim||_S


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
    (S_hat assembled once per mesh), one row per (p, n, C_pen); and the reference info."""
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
    return rows, info



# --------------------------------------------------------------------------- stability
def stability_rows(prm: PenaltyHpScene, progress=_each) -> list[dict]:
    """One row per (p, problem, C_eps): the run's check (limits.PenaltyCheck), its energy
    norm_S, penalty_error (flat) and delta_U against the previous C_eps."""
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
                row["delta_U"] = (energy_norm(S, U - prev) / nrm
                                  if prev is not None and finite else math.nan)
                prev = U
                rows.append(row)
                log.info("%s p=%d C_eps=%.0e cond=%.2e it=%d rel.res=%.1e %s", prob, p, C,
                         chk.condition_number, res.iterations, chk.relative_residual,
                         chk.reason)
    return rows
