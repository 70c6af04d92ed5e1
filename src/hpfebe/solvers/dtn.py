"""The Dirichlet-to-Neumann algorithm (Algorithm 4.3) with damping omega_D, omega_N, for
any two-body mortar contact problem that provides its three steps (:class:`DtNProblem`):

2. the Neumann problem of body 2 under the load of P_k (``problem.neumann_step``),
3. Q_k = (1 - omega_D) Q_{k-1} + omega_D D^-1 B U2 (``problem.mortar.project``),
4. the contact problem of body 1 against the obstacle Q_k (``problem.contact_step``, e.g.
   Uzawa, Algorithm 4.4, warm-started from the previous iteration),
5. R1 = S1 U1 - L1 on the contact dofs (``problem.reaction``),
6. P_{k+1} = (1 - omega_N) P_k + omega_N B^T D^-T R1 (``problem.mortar.adjoint``),
7. stop if ||P_{k+1} - P_k|| <= TOL ||P_{k+1}|| (:func:`hpfebe.solvers.fixed_point`:
   growth by ``divergence``, NaN, a failed inner solve or ``max_iter`` end it with the
   reason).

The problem may be BE bodies (:class:`hpfebe.contact.MortarContact`, Section 4.3) or FE
bodies with an elastoplastic body 2 (:class:`hpfebe.contact.FEMortarContact`, Section 4.4,
Remark 4.3.5); a per-iteration ``hook`` sees every iterate (:class:`DtNState`) and may
record readings, change the friction bound of the next step 4 (Coulomb friction inside
the DtN loop) or name the inner SolverInfo of the iteration.

``transfer``: "functional" - R1 and P are functionals (residual vectors), step 6 as above
(consistent: action = reaction); "function" - the literal reading of steps 5, 6 and (4.88)
with R1 in X^1_hp and P in X^2_hp *functions*: R1 = D^-1 r1 (the L2 Riesz representative
of the residual r1), P_k+1 = (1 - omega_N) P_k + omega_N B^T D^-T R1 (coefficients) and
the load of step 2 <P_k, W^2> = M2 P_k.

``aitken`` (beyond the thesis): step 6 with Aitken's dynamic relaxation of the Neumann
damping, P_k+1 = P_k + w_k r_k with r_k = B^T D^-T R1 - P_k,
w_k = -w_k-1 (r_k-1 . (r_k - r_k-1)) / |r_k - r_k-1|^2 (Irons-Tuck / Kuettler-Wall),
w_1 = omega_N, clipped to [1e-3, 2]; omega_D damping of step 3 as given.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

import numpy as np

from ..checks import boolean, choice, instance, integer, real, tolerance
from .fixed_point import fixed_point
from .info import SolverInfo
from .uzawa import UzawaSettings, _set

TRANSFERS = ("functional", "function")
RELAXATIONS = ("increment", "convex")


@dataclass(frozen=True)
class DtNSettings:
    """Parameters of Algorithm 4.3: the dampings omega_D, omega_N in (0, 1], TOL_DtN,
    the iteration cap, the growth factor of the divergence test, Aitken relaxation of
    omega_N, the ``transfer`` reading (module doc), the step 4 solver's settings
    (``uzawa``) and the floating-point form of step 6: "increment" P + omega_N
    (B^T D^-T R1 - P) (the form Aitken relaxes) or "convex" (1 - omega_N) P + omega_N
    B^T D^-T R1 (as printed) - equal up to rounding; each problem keeps the form its
    published results were computed with."""

    omega_D: float
    omega_N: float
    tol: float = 1e-6
    max_iter: int = 200
    divergence: float = 1e6
    aitken: bool = False
    transfer: str = "functional"
    relaxation: str = "increment"
    uzawa: UzawaSettings = field(default_factory=UzawaSettings)

    def __post_init__(self):
        for name in ("omega_D", "omega_N"):         # "must lie in (0, 1]"
            _set(self, name, real(name, getattr(self, name), lo=0.0, hi=1.0,
                                  lo_open=True))
        _set(self, "tol", tolerance("tol", self.tol))
        _set(self, "divergence", real("divergence", self.divergence, positive=True))
        _set(self, "max_iter", integer("max_iter", self.max_iter, lo=1))
        _set(self, "aitken", boolean("aitken", self.aitken))
        choice("transfer", self.transfer, TRANSFERS)
        choice("relaxation", self.relaxation, RELAXATIONS)
        instance("uzawa", self.uzawa, UzawaSettings)
        if self.aitken and self.relaxation != "increment":
            raise ValueError("aitken relaxes the increment form: relaxation must be "
                             "'increment'")


@dataclass
class DtNState:
    """The iterates of Algorithm 4.3 (what ``problem.contact_step``,
    ``problem.neumann_step`` and the hook see).  After iteration k: ``P`` = P_k (its
    input), ``P_new`` = P_k+1, ``Q`` the obstacle of step 3, ``x`` and ``lam`` the
    contact unknowns and multiplier of step 4 (None / zeros before the first), ``u2``
    the Neumann solution of step 2 as ``problem.neumann_step`` returns it (``u2_old``
    the previous one), ``R1`` the reaction of step 5, ``bound`` the nodal friction bound
    of the next step 4 (None: the problem's own; a hook may set it), ``neumann_info`` /
    ``contact_info`` the inner SolverInfos of the iteration, ``data`` free for the
    problem's and the hook's records."""

    k: int
    P: np.ndarray
    Q: np.ndarray
    lam: np.ndarray
    x: np.ndarray | None = None
    u2: Any = None
    u2_old: Any = None
    R1: np.ndarray | None = None
    P_new: np.ndarray | None = None
    bound: np.ndarray | None = None
    neumann_info: SolverInfo | None = None
    contact_info: SolverInfo | None = None
    data: dict = field(default_factory=dict)


class DtNProblem(Protocol):
    """What :func:`dtn` needs of a problem (``nc`` contact nodes of body 1 with the
    interleaved contact dofs ``c1`` = 2 nc, ``c2`` the contact dofs of body 2):

    mortar                 the mortar projection: ``project`` (X^2 -> X^1, (4.87)),
                           ``adjoint`` (its transpose B^T D^-T), and for
                           ``transfer="function"`` ``riesz`` (D^-1) and ``pair2`` (M2)
    neumann_step(load, state)
                           step 2 under the functional ``load`` on Gamma^2_C (body 2
                           carries -load), warm-started from ``state.u2``: returns (u2,
                           the trace of u2 on the dofs c2, SolverInfo or None); a
                           SolverInfo that did not converge is the iteration's inner
                           info (in ``info.steps``) and ends it with its reason
    contact_step(Q, state, uz)
                           step 4 against the obstacle Q with the Uzawa settings ``uz``,
                           warm-started from ``state.lam``, ``state.x``, with the nodal
                           friction bound ``state.bound`` (None: the problem's): returns
                           (x, lam, SolverInfo)
    reaction(x)            step 5: R1 on the contact dofs of body 1
    """

    nc: int
    c2: np.ndarray
    mortar: Any

    def neumann_step(self, load: np.ndarray, state: DtNState) -> tuple: ...

    def contact_step(self, Q: np.ndarray, state: DtNState,
                     uzawa: UzawaSettings) -> tuple: ...

    def reaction(self, x: np.ndarray) -> np.ndarray: ...


def transfer_maps(mortar, transfer: str):
    """(load of step 2 from P, P from R1 for step 6) of the ``transfer`` reading (module
    doc): identity and B^T D^-T ("functional"), or M2 and B^T D^-T D^-1 ("function")."""
    if transfer not in TRANSFERS:
        raise ValueError(f"transfer must be 'functional' or 'function', got {transfer!r}")
    if transfer == "function":
        return mortar.pair2, (lambda R1: mortar.adjoint(mortar.riesz(R1)))
    return (lambda P: P), mortar.adjoint


def dtn(problem: DtNProblem, settings: DtNSettings,
        hook: Callable[[DtNState], SolverInfo | None] | None = None, bound=None,
        P0=None, data: dict | None = None) -> tuple[np.ndarray, SolverInfo, DtNState]:
    """Algorithm 4.3 on ``problem`` (module doc).  ``hook(state)`` is called once per
    iteration after step 6 (``state.P_new`` set); it may set ``state.bound`` for the next
    step 4, write to ``state.data`` and return the SolverInfo to collect for the
    iteration in ``info.steps`` (None: step 4's; a SolverInfo that did not converge ends
    the iteration with its reason).  ``bound``: the friction bound of the first step 4
    (None: the problem's); ``P0``: the start (default 0 as in Algorithm 4.3, Q_0 = 0);
    ``data``: the initial ``state.data`` (e.g. parameters of the problem's steps).

    Returns (P, SolverInfo of the outer iteration, the last :class:`DtNState`)."""
    nc = int(problem.nc)
    m = problem.mortar
    load2, to_P = transfer_maps(m, settings.transfer)
    wD, wN = float(settings.omega_D), float(settings.omega_N)
    st = DtNState(0, np.zeros(len(problem.c2)), np.zeros(2 * nc), np.zeros(nc),
                  bound=bound, data={} if data is None else data)
    relax = dict(r=None, w=wN)

    def update(P):
        st.k += 1
        st.P = P
        u2, trace, ninfo = problem.neumann_step(load2(P), st)
        st.neumann_info = ninfo
        if ninfo is not None and not ninfo.converged:
            return P, ninfo
        st.u2_old, st.u2 = st.u2, u2
        Q = (1.0 - wD) * st.Q + wD * m.project(trace)                       # step 3
        x, lam, cinfo = problem.contact_step(Q, st, settings.uzawa)          # step 4
        st.Q, st.lam, st.x, st.contact_info = Q, lam, x, cinfo
        st.R1 = problem.reaction(x)                                          # step 5
        st.P_new = _step6(P, to_P(st.R1), wN, settings, relax)               # step 6
        inner = hook(st) if hook is not None else None
        return st.P_new, (cinfo if inner is None else inner)

    P0 = np.zeros(len(problem.c2)) if P0 is None else np.asarray(P0, dtype=float)
    P, info = fixed_point(update, P0, settings.tol, settings.max_iter, norm=2,
                          divergence=settings.divergence)
    return P, info, st


def _step6(P, T, wN: float, settings: DtNSettings, relax: dict) -> np.ndarray:
    """P_k+1 from P_k and T = B^T D^-T R1 (damped, or Aitken-relaxed; ``relax`` holds
    the previous residual and relaxation factor)."""
    if settings.relaxation == "convex":
        return (1.0 - wN) * P + wN * T
    r = T - P
    if settings.aitken and relax["r"] is not None:
        dr = r - relax["r"]
        den = dr @ dr
        if den > 0:
            relax["w"] = float(np.clip(-relax["w"] * (relax["r"] @ dr) / den, 1e-3, 2.0))
    relax["r"] = r
    return P + (relax["w"] if settings.aitken else wN) * r
