"""The model problems of Section 2.2.5 and the runs of Chapter 2 built on them
(``experiments/ch2_convergence``, ``ch2_lambda``, ``ch2_coercivity``).

* Example 1 (smooth, (2.10)-(2.12)): Omega = [-1,1]^2, Omega2 = [-1,0] x [-1/2,1/2] (BEM),
  Omega1 = Omega minus Omega2 (FEM), Gamma_D = {-1} x [-1,1],
  u = (x+1)/((x+1)^2+(y+2)^2) = -2 pi d/dx G((-1,-2), (x,y)), f = 0, t_hat = du/dn.
* Example 2 (singular, (2.13)-(2.15)): the L-shape Omega = [-1,1]^2 minus [0,1] x [-1,0],
  Omega2 = [-1/2,1/2]^2 minus [0,1/2] x [-1/2,0], Gamma_D = {0} x [-1,0] U [0,1] x {0},
  u = r^(2/3) sin(2 theta/3), theta in [0, 3 pi/2] measured from the positive x axis.

Meshes (the thesis gives only the sizes): see :class:`hpfebe.coupling.InterfaceProblem`.
Sides of dOmega2 on Gamma_D get the label "D", the others "I" (interface; neither example
has a BE Neumann part).

:func:`lambda_sweep` builds the system of one mesh pair once, solves it for several
lambda_Nit (only the penalty blocks are rescaled) and measures the errors of
:mod:`hpfebe.coupling.errors`: the rows of the Chapter 2 tables and figures
(:func:`sweep_rows` over a list of cases).  The mesh sequences and parameters of the
thesis's tables and figures are the dataclasses :class:`ConvergenceScene` (Examples 1, 2:
Tables 2.1-2.4, Figures 2.1-2.4), :class:`LambdaScene` (Example 3, Figures 2.5-2.12) and
:class:`CoercivityScene` (the threshold of Lemma 2.2.3).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ..analysis import observed_rates
from ..checks import integer, real
from ..coupling.coercivity import coercivity_threshold, inverse_constant, lemma_2_2_3_bound
from ..coupling.errors import (BEDomainSetup, be_domain_errors_both, be_solution_at,
                               be_trace_energy_error, fe_errors)
from ..coupling.nitsche import DEFAULT_ALPHA, DEFAULT_H_DEF, InterfaceProblem, NitscheFEBE

log = logging.getLogger(__name__)

_TOL = 1e-12


# ----------------------------------------------------------------------- Example 1
def _u_smooth(x, y):
    a, b = x + 1.0, y + 2.0
    return a / (a * a + b * b)


def _grad_smooth(x, y):
    a, b = x + 1.0, y + 2.0
    r4 = (a * a + b * b) ** 2
    return (b * b - a * a) / r4, -2.0 * a * b / r4


def _in_omega2_smooth(x, y):
    return (x < 0.0) & (np.abs(y) < 0.5)


def _in_omega1_smooth(x, y):
    return ~_in_omega2_smooth(x, y)


def _label_smooth(x, y):
    lab = np.full(np.shape(x), "N", dtype="<U1")
    on_d = np.abs(x + 1.0) < _TOL
    on_omega2 = (((np.abs(x) < _TOL) & (np.abs(y) <= 0.5))
                 | ((np.abs(np.abs(y) - 0.5) < _TOL) & (x <= 0.0)))
    lab[on_omega2 & ~on_d] = "I"
    lab[on_d] = "D"
    return lab


SMOOTH = InterfaceProblem(
    name="smooth", u=_u_smooth, grad_u=_grad_smooth, f=None,
    xbreaks=(-1.0, 0.0, 1.0), ybreaks=(-1.0, -0.5, 0.5, 1.0),
    in_omega1=_in_omega1_smooth, in_omega2=_in_omega2_smooth, fe_label=_label_smooth,
    # counter-clockwise; side k joins vertex k and k+1; the side x = -1 is on Gamma_D
    be_vertices=((-1.0, -0.5), (0.0, -0.5), (0.0, 0.5), (-1.0, 0.5)),
    be_labels=("I", "I", "I", "D"),
)


# ----------------------------------------------------------------------- Example 2
def _theta(x, y):
    """Polar angle in [0, 2 pi) (the L-shape uses [0, 3 pi/2])."""
    return np.mod(np.arctan2(y, x), 2.0 * np.pi)


def _u_singular(x, y):
    r = np.hypot(x, y)
    return r ** (2.0 / 3.0) * np.sin(2.0 * _theta(x, y) / 3.0)


def _grad_singular(x, y):
    r = np.hypot(x, y)
    th = _theta(x, y)
    with np.errstate(divide="ignore"):
        c = (2.0 / 3.0) * r ** (-1.0 / 3.0)
    return -c * np.sin(th / 3.0), c * np.cos(th / 3.0)


def _in_omega2_singular(x, y):
    return (np.abs(x) < 0.5) & (np.abs(y) < 0.5) & ~((x > 0.0) & (y < 0.0))


def _in_omega1_singular(x, y):
    return ~((x > 0.0) & (y < 0.0)) & ~_in_omega2_singular(x, y)


def _label_singular(x, y):
    lab = np.full(np.shape(x), "N", dtype="<U1")
    on_d = ((np.abs(x) < _TOL) & (y < 0.0)) | ((np.abs(y) < _TOL) & (x > 0.0))
    on_omega2 = np.abs(np.maximum(np.abs(x), np.abs(y)) - 0.5) < _TOL
    lab[on_omega2 & ~on_d] = "I"
    lab[on_d] = "D"
    return lab


SINGULAR = InterfaceProblem(
    name="singular", u=_u_singular, grad_u=_grad_singular, f=None,
    xbreaks=(-1.0, -0.5, 0.0, 0.5, 1.0), ybreaks=(-1.0, -0.5, 0.0, 0.5, 1.0),
    in_omega1=_in_omega1_singular, in_omega2=_in_omega2_singular, fe_label=_label_singular,
    be_vertices=((0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (-0.5, 0.5), (-0.5, -0.5), (0.0, -0.5)),
    be_labels=("D", "I", "I", "I", "I", "D"),
    singular_points=((0.0, 0.0),),
)

PROBLEMS = {"smooth": SMOOTH, "singular": SINGULAR}


def problem(name: str) -> InterfaceProblem:
    """The model problem ``"smooth"`` (Example 1) or ``"singular"`` (Example 2)."""
    if name not in PROBLEMS:
        raise ValueError(f"problem must be one of {sorted(PROBLEMS)}, got {name!r}")
    return PROBLEMS[name]


_by_name = problem      # lambda_sweep's argument ``problem`` shadows the function


# ----------------------------------------------------------------------- lambda_Nit sweeps
def lambda_sweep(problem: InterfaceProblem | str, fe_h_inv: float, be_h_inv: float, p: int,
                 lambdas, alpha: float = DEFAULT_ALPHA, h_def: str = DEFAULT_H_DEF,
                 companions: bool = False) -> list[dict]:
    """One row per lambda_Nit in ``lambdas`` for the mesh pair (fe_h_inv, be_h_inv) and
    p1 = p2 = p; the system is assembled once.  Row keys: lambda_nit, p, fe_h_inv,
    be_h_inv, n_fe, n_be, dof, fe_l2, fe_h1, be_l2, be_h1 (``fe_errors``,
    ``be_domain_errors``), assembly_s, solve_s, wall_time_s (assembly + solve),
    residual (relative, of the linear solve); ``companions`` adds be_energy
    (``be_trace_energy_error``, which assembles a richer W per solve) and be_h1_interp
    (``be_domain_errors(interpolate_exact=True)``)."""
    pb = _by_name(problem) if isinstance(problem, str) else problem
    lambdas = [float(v) for v in np.atleast_1d(lambdas)]
    if not lambdas:
        raise ValueError("lambdas must name at least one lambda_Nit")
    t0 = time.perf_counter()
    model = NitscheFEBE(pb, fe_h_inv, be_h_inv, int(p), alpha=alpha, h_def=h_def)
    t_asm = time.perf_counter() - t0
    rows = []
    setup = None                    # BE-part error geometry, shared by the lambda_Nit
    for lambda_nit in lambdas:
        t1 = time.perf_counter()
        sol = model.solve(lambda_nit)
        t_solve = time.perf_counter() - t1
        fe = fe_errors(model, sol)
        setup = setup or BEDomainSetup(model)
        if companions:
            be, be_exact = be_domain_errors_both(model, sol, setup=setup)
        else:
            be = setup.errors(model, sol, ("solution",))["solution"]
        row = dict(lambda_nit=lambda_nit, p=int(p), fe_h_inv=fe_h_inv, be_h_inv=be_h_inv,
                   n_fe=model.n1, n_be=model.n2, dof=model.ndof, fe_l2=fe["l2"],
                   fe_h1=fe["h1"], be_l2=be["l2"], be_h1=be["h1"], assembly_s=t_asm,
                   solve_s=t_solve, wall_time_s=t_asm + t_solve,
                   residual=sol.info["residual"])
        if companions:
            row["be_energy"] = be_trace_energy_error(model, sol)
            row["be_h1_interp"] = be_exact["h1"]
        rows.append(row)
        log.info("%s p=%d FE 1/%g BE 1/%g lambda_Nit=%g dof=%d: FE %.3e %.3e BE %.3e %.3e "
                 "(%.2f s + %.2f s)", pb.name, p, fe_h_inv, be_h_inv, lambda_nit,
                 model.ndof, fe["l2"], fe["h1"], be["l2"], be["h1"], t_asm, t_solve)
    return rows


def _each(items, desc=""):
    return items


def sweep_rows(name: str, series: str, cases, lambdas, alpha: float, h_def: str,
               desc: str = "", companions: bool = False, progress=_each) -> list[dict]:
    """One row per (case, lambda_Nit) of problem ``name``: cases are (fe_h_inv,
    be_h_inv, p) triples; keys problem, series, then those of :func:`lambda_sweep`."""
    rows = []
    for fh, bh, p in progress(list(cases), desc=desc or f"{name} {series}"):
        rows += [dict(problem=name, series=series, **r) for r in
                 lambda_sweep(name, fh, bh, p, lambdas, alpha, h_def, companions)]
    return rows


# ----------------------------------------------------------------------- Examples 1, 2
def _check_pairs(where: str, pairs) -> None:
    if any(len(pr) != 2 for pr in pairs):
        raise ValueError(f"{where} must be [fe_h_inv, be_h_inv] pairs, got {pairs}")


@dataclass(frozen=True)
class SmoothParams:
    """Example 1: h-version meshes and degrees, the p-version mesh and degrees."""

    h_pairs: tuple[tuple[int, ...], ...] = ((2, 3), (5, 6), (11, 12), (23, 24), (47, 48))
    degrees: tuple[int, ...] = (1, 2, 3)
    p_mesh: tuple[int, ...] = (5, 6)
    p_degrees: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8)
    max_fe_h_inv: dict = field(default_factory=dict)   # {p: largest FE h^-1 of the h-version}

    def __post_init__(self):
        _check_pairs("ch2_convergence.smooth.h_pairs", self.h_pairs)
        _check_pairs("ch2_convergence.smooth.p_mesh", (self.p_mesh,))


@dataclass(frozen=True)
class SingularParams:
    """Example 2: h-version meshes (p = 1), the p-version mesh and degrees."""

    h_pairs: tuple[tuple[int, ...], ...] = ((4, 8), (8, 12), (16, 20), (32, 36), (64, 68),
                                            (128, 132), (256, 260))
    p_mesh: tuple[int, ...] = (4, 6)
    p_degrees: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7)

    def __post_init__(self):
        _check_pairs("ch2_convergence.singular.h_pairs", self.h_pairs)
        _check_pairs("ch2_convergence.singular.p_mesh", (self.p_mesh,))


@dataclass(frozen=True)
class ConvergenceScene:
    """Examples 1 and 2 (Tables 2.1-2.4, Figures 2.1-2.4, the work-precision runs)."""

    lambda_nit: float = 10.0
    alpha: float = 0.0
    h_def: str = "edge"
    smooth: SmoothParams = SmoothParams()
    singular: SingularParams = SingularParams()
    timing_repeats: int = 3          # work-precision: the minimum of at most this many
    timing_budget_s: float = 1.0     # timings, fewer once a run's timings sum to this

    def __post_init__(self):
        integer("ch2_convergence.timing_repeats", self.timing_repeats, lo=1)
        real("ch2_convergence.timing_budget_s", self.timing_budget_s, positive=True)


EXAMPLES = ("smooth", "singular")


def sweep_cases(prm: ConvergenceScene, example: str) -> dict[str, list[tuple[int, int, int]]]:
    """The (fe_h_inv, be_h_inv, p) cases of the h- and p-sweep of ``example``."""
    if example == "smooth":
        sm = prm.smooth
        cap = {int(k): v for k, v in sm.max_fe_h_inv.items()}
        (pf, pb), degrees_h, pairs, p_degrees = sm.p_mesh, sm.degrees, sm.h_pairs, \
            sm.p_degrees
    elif example == "singular":
        sg, cap = prm.singular, {}
        (pf, pb), degrees_h, pairs, p_degrees = sg.p_mesh, (1,), sg.h_pairs, sg.p_degrees
    else:
        raise ValueError(f"example must be one of {EXAMPLES}, got {example!r}")
    return {"h": [(fh, bh, p) for p in degrees_h for fh, bh in pairs
                  if fh <= cap.get(p, np.inf)],
            "p": [(pf, pb, p) for p in p_degrees]}


def warm_up(prm: ConvergenceScene) -> float:
    """Seconds of one small solve: numba compilation or loading of its cache, kept out
    of the timings."""
    t0 = time.perf_counter()
    NitscheFEBE(problem("smooth"), 2, 3, 1).solve(prm.lambda_nit)
    return time.perf_counter() - t0


def timed_solve(pb, fe_h, be_h, p, prm: ConvergenceScene) -> tuple[float, float]:
    """(assembly, solve) seconds of one run, as :func:`lambda_sweep` times them."""
    t0 = time.perf_counter()
    model = NitscheFEBE(pb, fe_h, be_h, p, alpha=prm.alpha, h_def=prm.h_def)
    t1 = time.perf_counter()
    model.solve(prm.lambda_nit)
    return t1 - t0, time.perf_counter() - t1


# ----------------------------------------------------------------------- Example 3
@dataclass(frozen=True)
class LambdaScene:
    """Example 3: the lambda_Nit sweep on the meshes of Examples 1 and 2."""

    lambdas: tuple[float, ...] = (1.0, 5.0, 10.0, 20.0)   # lambda_Nit values
    alpha: float = 0.0
    h_def: str = "edge"
    smooth_pairs: tuple[tuple[int, ...], ...] = ((2, 3), (5, 6), (11, 12), (23, 24))
    degrees: tuple[int, ...] = (1, 2, 3)
    singular_pairs: tuple[tuple[int, ...], ...] = ((4, 8), (8, 12), (16, 20), (32, 36),
                                                   (64, 68))
    singular_p_mesh: tuple[int, ...] = (4, 6)
    singular_p_degrees: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7)

    def __post_init__(self):
        for name in ("smooth_pairs", "singular_pairs"):
            if any(len(pr) != 2 for pr in getattr(self, name)):
                raise ValueError(f"ch2_lambda.{name} must be [fe_h_inv, be_h_inv] pairs, "
                                 f"got {getattr(self, name)}")
        if len(self.singular_p_mesh) != 2:
            raise ValueError(f"ch2_lambda.singular_p_mesh must be [fe_h_inv, be_h_inv], "
                             f"got {self.singular_p_mesh}")
        if not self.lambdas:
            raise ValueError("ch2_lambda.lambdas must not be empty")


def threshold_rows(prm: LambdaScene, example: str, cases) -> list[dict]:
    """lambda*(p) (coercivity threshold, Lemma 2.2.3) of every (fe_h_inv, be_h_inv, p) of
    ``cases``, with the sweep's alpha and h1."""
    pb = problem(example)
    return [dict(fe_h_inv=fh, be_h_inv=bh, p=p, lambda_star=coercivity_threshold(
        NitscheFEBE(pb, fh, bh, p, alpha=prm.alpha, h_def=prm.h_def)))
        for fh, bh, p in cases]


# ----------------------------------------------------------------------- Lemma 2.2.3
ALPHAS = (0.0, 1.0, 2.0)


@dataclass(frozen=True)
class CoercivityScene:
    """The coercivity threshold on the p-version mesh of Example 1 (and its h-meshes)."""

    degrees: tuple[int, ...] = tuple(range(1, 11))
    mesh: tuple[int, ...] = (5, 6)                    # [FE h^-1, BE h^-1] of the p-sweep
    h_pairs: tuple[tuple[int, ...], ...] = ((2, 3), (5, 6), (11, 12))
    h_def: str = "edge"

    def __post_init__(self):
        if len(self.mesh) != 2 or any(len(pr) != 2 for pr in self.h_pairs):
            raise ValueError(f"ch2_coercivity.mesh and h_pairs must be [fe_h_inv, be_h_inv] "
                             f"pairs, got {self.mesh}, {self.h_pairs}")
        if not self.degrees or min(self.degrees) < 1:
            raise ValueError(f"ch2_coercivity.degrees must be >= 1, got {self.degrees}")


def coercivity_rows(prm: CoercivityScene, progress=_each) -> list[dict]:
    """lambda*, C_inv and both bounds per p and alpha on the p-sweep mesh; lambda* for
    p = 1, 2, 3 (alpha = 0) on the other h-version meshes."""
    pb, (fh, bh) = problem("smooth"), prm.mesh
    rows = []
    for p in progress(prm.degrees, desc="coercivity p"):
        t1 = time.perf_counter()
        model = NitscheFEBE(pb, fh, bh, p, alpha=0.0, h_def=prm.h_def)
        star0, C = coercivity_threshold(model), inverse_constant(model)
        for alpha in ALPHAS:
            rows.append(dict(mesh=f"{fh}/{bh}", fe_h_inv=fh, be_h_inv=bh, p=p, alpha=alpha,
                             lambda_star=star0 / p ** alpha, C_inv=C,
                             young_bound=C * p ** (2 - alpha),
                             lemma_bound=lemma_2_2_3_bound(p, alpha, C),
                             wall_time_s=time.perf_counter() - t1))
        log.info("p=%d: lambda*(alpha=0) = %.4f, C_inv = %.4f", p, star0, C)
    for fh2, bh2 in prm.h_pairs:
        for p in (1, 2, 3):
            if (fh2, bh2) == (fh, bh):
                continue
            t1 = time.perf_counter()
            model = NitscheFEBE(pb, fh2, bh2, p, alpha=0.0, h_def=prm.h_def)
            rows.append(dict(mesh=f"{fh2}/{bh2}", fe_h_inv=fh2, be_h_inv=bh2, p=p,
                             alpha=0.0, lambda_star=coercivity_threshold(model),
                             C_inv=np.nan, young_bound=np.nan, lemma_bound=np.nan,
                             wall_time_s=time.perf_counter() - t1))
    return rows


# ----------------------------------------------------------------------- tables, choices
def part_table(sweep, part: str, h_col: str) -> dict:
    """Columns of the published-format table of one part ("fe" or "be") of the sweep
    ``sweep`` (columns of :func:`sweep_rows`, a mapping column -> values): series, h_inv,
    p, errors and observed rates (w.r.t. h^-1 for series h at fixed p, w.r.t. p for
    series p on its mesh), then dof and timings; the BE part adds the H1 error of the
    same interpolant of the exact u and the trace energy error |u - U2|_W on Gamma2 with
    its rate.  Rows grouped by series and key in the order of the sweep."""
    c = {k: np.asarray(v) for k, v in sweep.items()}
    groups = []
    for series in dict.fromkeys(c["series"]):
        rows = np.flatnonzero(c["series"] == series)
        key, x = (c["p"], c[h_col]) if series == "h" else (c[h_col], c["p"])
        for k in dict.fromkeys(key[rows]):
            g = rows[key[rows] == k]
            groups.append((g[np.argsort(x[g], kind="stable")], x))
    idx = np.concatenate([g for g, _ in groups])

    def rate(col):
        return np.concatenate([observed_rates(1.0 / np.asarray(x[g], float),
                                              np.asarray(c[col][g], float))
                               for g, x in groups])
    out = dict(series=c["series"][idx], h_inv=c[h_col][idx].astype(int), p=c["p"][idx],
               l2_error=c[f"{part}_l2"][idx], l2_rate=rate(f"{part}_l2"),
               h1_error=c[f"{part}_h1"][idx], h1_rate=rate(f"{part}_h1"), dof=c["dof"][idx],
               wall_time_s=c["wall_time_s"][idx], fe_h_inv=c["fe_h_inv"][idx],
               be_h_inv=c["be_h_inv"][idx], lambda_nit=c["lambda_nit"][idx])
    if part == "be" and "be_energy" in c:
        out.update(h1_interp_exact=c["be_h1_interp"][idx],
                   trace_energy_error=c["be_energy"][idx],
                   trace_energy_rate=rate("be_energy"))
    return out


def work_precision_rows(prm: ConvergenceScene, rows: list[dict]) -> list[dict]:
    """The rows of a sweep (:func:`sweep_rows`) with the minimum over the timings of
    assembly, solve and their sum, the slowest sum (wall_time_max_s) and their number
    (timings): the sweep's own timing and more, in rounds over the cases (so that a slow
    phase of the machine does not hit one case only), until a case has
    ``timing_repeats`` timings or its timings sum to ``timing_budget_s`` (as timeit's
    autorange: a run of seconds is timed once or twice, its relative spread is small;
    measured, full configuration: the largest run 2.4 s, its three timings within 13 %;
    the repeats about 11.9 s before (3 timings of every run), 6.2 s now)."""
    asm = np.array([[r["assembly_s"] for r in rows]])
    sol = np.array([[r["solve_s"] for r in rows]])
    for _ in range(prm.timing_repeats - 1):
        spent = np.nansum(asm + sol, axis=0)
        more = np.flatnonzero(spent < prm.timing_budget_s)
        if more.size == 0:
            break
        a, s = np.full(len(rows), np.nan), np.full(len(rows), np.nan)
        for i in more:
            r = rows[i]
            a[i], s[i] = timed_solve(problem(r["problem"]), r["fe_h_inv"], r["be_h_inv"],
                                     r["p"], prm)
        asm, sol = np.vstack([asm, a]), np.vstack([sol, s])
    total = asm + sol
    return [dict(r, assembly_s=a, solve_s=s, wall_time_s=t, wall_time_max_s=tmax,
                 timings=int(n))
            for r, a, s, t, tmax, n in zip(rows, np.nanmin(asm, axis=0),
                                           np.nanmin(sol, axis=0), np.nanmin(total, axis=0),
                                           np.nanmax(total, axis=0),
                                           np.isfinite(total).sum(axis=0))]


def solution_fields(name: str, fe_h: float, be_h: float, lambda_nit: float):
    """The computed solution of Figures 2.1 / 2.3 (p = 1): (model, solution, mesh of
    Omega2 of size 1/(2 be_h), the BE part there by the representation formula)."""
    pb = problem(name)
    model = NitscheFEBE(pb, fe_h, be_h, 1)
    sol = model.solve(lambda_nit)
    d2 = pb.omega2_domain(2 * be_h).mesh
    return model, sol, d2, be_solution_at(model, sol.U2, d2.p.T)


#: Examples 1, 2: the choices where the thesis is silent (repeated in the notes)
CONVERGENCE_CHOICES = (
    "alpha = 0 in the penalty lambda_Nit h1^-1 p1^alpha, and h1 = the length of the FE edge "
    "on Gamma_I (not diam K): with them Table 2.2 (h^-1 = 2, p = 1, 2, 3) and Table 2.4 (h- "
    "and p-version) are reproduced to the printed digits.",
    "FE meshes: per-block tensor grids with the cell count of the uniform grid; in Example 1 "
    "the blocks y in [-1,-1/2] / [1/2,1] of odd h^-1 get floor/ceil(h^-1/2) rows (75 "
    "elements for h = 1/5 as in the thesis).  BE meshes: ceil(|side| h^-1) equal elements "
    "per side.",
    "The p-version of Example 2 uses FE h^-1 = 4 and BE h^-1 = 6 (the table headers), not the "
    "h1 = 1/6, h2 = 1/8 of the caption of Figure 2.4: the FE errors of Table 2.4 are then "
    "reproduced exactly for p = 1..7.",
    "BE-part errors: domain L2 / H1-seminorm errors in Omega2 of the Q_p equidistant-node "
    "interpolant, on a mesh of Omega2 of the BE mesh size, of the representation-formula "
    "solution (nodal values U2 on dOmega2): the measure that reproduces Table 2.1 and the "
    "h-version of Table 2.3 (hpfebe.coupling.errors explains why other measures do not). "
    "BE tables add the H1 error of the same interpolant of the exact u and the trace energy "
    "error |u - U2|_W on Gamma2 with its rate (the BE part of the norm of Theorem 2.2.3).",
    "DOF = FE + BE unknowns without Gamma_D.",
)

#: Example 3: the choices where the thesis is silent
LAMBDA_CHOICES = (
    "alpha = 0, h1 = edge length, BE-part post-processing and meshes as in "
    "ch2_convergence.",
    "'Does not converge': the last FE energy rate (w.r.t. h^-1) is below 0.3.",
    "'Reduced rate': the last FE energy rate is more than 0.3 below the lambda = 20 rate, "
    "or the BE energy rate is.",
    "'Almost the same convergence rates' (smooth, lambda = 10 and 20): the last rates of "
    "all four error curves of every p within 0.15 (the rate tolerance of the tables) of "
    "lambda = 20.",
    "'The same curves': all errors (FE and BE, L2 and energy) within 5 % of lambda = 20.",
    "Coercivity: lambda*(p) of each mesh of the sweep (same alpha and h1) - a_h is "
    "positive definite iff lambda_Nit > lambda*.",
    "The lambda_Nit sweep is on the meshes up to FE h^-1 = 23 (smooth) and 64 (singular) "
    "in the full configuration.",
)

#: the coercivity threshold: the choices where the thesis is silent
COERCIVITY_CHOICES = (
    "alpha = 0, h1 = edge length: the setting that reproduces the thesis's tables.",
    "alpha = 1, 2 rows are lambda*(0) p^-alpha (exact for uniform p).",
    "Lemma bound as printed with gamma = 2 and the computed C_inv of (2.7); young_bound = "
    "C_inv p^(2-alpha) is the sharp version of the lemma's argument.",
)
