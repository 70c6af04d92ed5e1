"""The model problem of Section 4.3.4 (thesis lines 19474-19530), the scene of Table 4.1
and Figures 4.17-4.20: body 1 bounded by Gamma^1_D = [-1,1] x {2}, its vertical sides
and the arc Gamma^1_C through (-1, 0.1), (0, 0), (1, 0.1); body 2 = [-1,1] x [-2,0]
with Gamma^2_C = [-1,1] x {0}.  :func:`model_meshes` (the boundary meshes and the normal
of Gamma^1_C), :func:`model_gap` (the arc as an initial gap over a flat Gamma^1_C),
:func:`contact_from_meshes` (the boundary conditions on given, e.g. adaptive, meshes),
:func:`model_problem` (the :class:`hpfebe.contact.MortarContact` of the scene, its data
a :class:`ModelProblem`), :func:`adaptive_model_problem` (Figure 4.20's hp-adaptive
run, Algorithm 4.6) and :func:`mortar_contact_state` (the contact pressure, tangential
traction, gap, slip and stick/slip state of a mortar solution at the nodes of
Gamma^1_C, for :func:`hpfebe.io.contact_vtu`) with :func:`mortar_exports` (the ParaView
meshes of a solution).  The
material data are :mod:`hpfebe.scenes.materials` (E = 266926, nu = 0.29, plane strain);
the friction bound F = 0.1 is the model problem's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..adaptivity.mortar_estimator import hp_adapt
from ..checks import array, choice, integer, real
from ..constitutive.laws import OPEN, SLIP, STICK
from ..bem.lame import LameBEM
from ..contact.mortar import MortarContact
from ..geometry import BoundaryMesh
from ..io import boundary_vtu, contact_vtu
from ..solvers import GlobalUzawaSettings
from .materials import E, NU, PLANE

__all__ = ["ModelProblem", "MortarContactState", "adaptive_model_problem",
           "contact_from_meshes", "model_gap", "model_meshes", "model_problem",
           "mortar_contact_state", "mortar_exports"]


def model_meshes(n1: int = 16, n2: int = 12, p1: int = 2, p2: int = 2,
                 radius: float = 5.05, L: float = 2.0, side_depth: float = 2.0,
                 geometry: str = "arc"):
    """Boundary meshes of the model problem of Section 4.3.4 (see :func:`model_problem`)
    and the normal of Gamma^1_C: (mesh1, mesh2, normal).

    ``geometry``: "arc" - Gamma^1_C is the polygon of the circular arc (nodes on the
    circle), normal = radial direction; "flat" - body 1 is the rectangle [-1,1] x [0,2],
    Gamma^1_C = [-1,1] x {0} (Section 4.3.1: Gamma_C a straight segment, the bodies
    initially in contact) and the arc enters only through the initial gap
    :func:`model_gap` measured along the normal (0, -1) of Gamma^1_C.

    ``side_depth``: Gamma^2_D on the vertical sides of body 2 is {-1,1} x [-side_depth, 0]
    (2 = the whole sides; the thesis prints {-1,1} x [-1,0], i.e. 1, with
    Gamma^2_N = empty); below it the sides are traction free (label "N")."""
    n1, n2, p1, p2 = (integer(name, v, lo=1) for name, v in
                      (("n1", n1), ("n2", n2), ("p1", p1), ("p2", p2)))
    radius = real("radius", radius, lo=1.0, lo_open=True)       # "must exceed 1"
    L = real("L", L, positive=True)
    side_depth = real("side_depth", side_depth, lo=0.0, hi=2.0, lo_open=True)
    geometry = choice("geometry", geometry, ("arc", "flat"))
    yc = radius                                       # centre (0, R): arc through (0, 0)
    half = np.arcsin(1.0 / radius)
    ang = np.linspace(-half, half, int(n1) + 1)
    arc = np.column_stack([radius * np.sin(ang), yc - radius * np.cos(ang)])
    h1, h2 = L / n1, L / n2
    top = float(arc[0, 1])
    nside = int(np.ceil((2.0 - top) / h1 - 1e-9))
    verts = np.vstack([arc, [[1.0, 2.0], [-1.0, 2.0]]])
    n_sides = [1] * int(n1) + [nside, int(np.ceil(2.0 / h1 - 1e-9)), nside]
    labels = ["C"] * int(n1) + ["N", "D", "N"]
    if geometry == "flat":
        ns = int(np.ceil(2.0 / h1 - 1e-9))
        verts = np.array([[-1.0, 0.0], [1.0, 0.0], [1.0, 2.0], [-1.0, 2.0]])
        n_sides, labels = [int(n1), ns, ns, ns], ["C", "N", "D", "N"]
    mesh1 = BoundaryMesh.polygon(verts, n=n_sides, labels=labels, p=int(p1))
    k2 = int(np.ceil(2.0 / h2 - 1e-9))
    if side_depth >= 2.0:
        mesh2 = BoundaryMesh.polygon([(-1, -2), (1, -2), (1, 0), (-1, 0)],
                                     n=[k2, k2, int(n2), k2], labels=["D", "D", "C", "D"],
                                     p=int(p2))
    else:
        kd = int(np.ceil(side_depth / h2 - 1e-9))
        kn = int(np.ceil((2.0 - side_depth) / h2 - 1e-9))
        d = float(side_depth)
        mesh2 = BoundaryMesh.polygon([(-1, -2), (1, -2), (1, -d), (1, 0), (-1, 0), (-1, -d)],
                                     n=[k2, kn, kd, int(n2), kd, kn],
                                     labels=["D", "N", "D", "C", "D", "N"], p=int(p2))

    def normal(x):
        d = np.asarray(x, dtype=float) - np.array([0.0, yc])
        return d / np.linalg.norm(d, axis=1)[:, None]

    def normal_flat(x):
        return np.tile([0.0, -1.0], (len(x), 1))

    return mesh1, mesh2, (normal if geometry == "arc" else normal_flat)


def model_gap(radius: float = 5.05):
    """The initial gap of the "flat" scene: the height of the arc through (-1, 0.1),
    (0, 0), (1, 0.1) above Gamma_C, g(x) = R - (R^2 - x^2)^(1/2)."""
    radius = real("radius", radius, lo=1.0, lo_open=True)

    def gap(x):
        x = np.asarray(x, dtype=float)
        return radius - np.sqrt(radius ** 2 - np.minimum(x[:, 0] ** 2, radius ** 2))

    return gap


@dataclass(frozen=True)
class ModelProblem:
    """The data of the model problem of Section 4.3.4 (thesis lines 19474-19530),
    :func:`model_problem`.

    Parameters
    ----------
    n1, n2 : int
        elements on Gamma^1_C (equal angles, h1 = L / n1) and on Gamma^2_C (h2 = L / n2);
        the other sides get ceil(length / h) elements
    p1, p2 : int
        the polynomial degrees of body 1 and body 2
    E, nu, plane : float, float, str
        the material (:mod:`hpfebe.scenes.materials`), plane strain by default
    F : float
        the given (Tresca) friction bound, >= 0
    u_top : (float, float)
        the displacement U of Gamma^1_D = [-1, 1] x {2}
    radius, L : float
        the radius of the arc Gamma^1_C (> 1) and the length of Gamma_C
    side_depth : float
        the Dirichlet part {-1, 1} x [-side_depth, 0] of body 2's sides (2: all of them)
    test_space : str
        of the mortar projection (:class:`~hpfebe.contact.MortarContact`)
    geometry : str
        "arc" (Gamma^1_C the arc's polygon) or "flat" (Gamma^1_C straight, the arc only
        as initial gap, :func:`model_gap`)
    gap : callable or None
        an initial gap function replacing the scene's (e.g. zero: Algorithm 4.5's step 3
        as printed, without g)
    """

    n1: int = 16
    n2: int = 12
    p1: int = 2
    p2: int = 2
    E: float = E
    nu: float = NU
    F: float = 0.1
    u_top: tuple = (0.0, -0.09)
    radius: float = 5.05
    plane: str = PLANE
    L: float = 2.0
    side_depth: float = 2.0
    test_space: str = "full"
    geometry: str = "arc"
    gap: Callable | None = None

    def __post_init__(self):
        for name in ("n1", "n2", "p1", "p2"):
            object.__setattr__(self, name, integer(name, getattr(self, name), lo=1))
        object.__setattr__(self, "F", real("F", self.F, nonnegative=True))
        object.__setattr__(self, "u_top", tuple(array("u_top", self.u_top, shape=(2,))))

    def meshes(self):
        """(mesh1, mesh2, normal of Gamma^1_C): :func:`model_meshes` of the data."""
        return model_meshes(self.n1, self.n2, self.p1, self.p2, self.radius, self.L,
                            self.side_depth, self.geometry)


def contact_from_meshes(mesh1, mesh2, normal, problem: ModelProblem = ModelProblem()
                        ) -> MortarContact:
    """The model problem's boundary conditions (material, F, u_top, test space and gap
    of ``problem``; its meshes unused) on given meshes (e.g. adaptive ones); the gap
    (``problem.gap`` None): measured along the normal to mesh2."""
    bem1 = LameBEM(mesh1, problem.E, problem.nu, problem.plane)
    bem2 = LameBEM(mesh2, problem.E, problem.nu, problem.plane)
    return _model_contact(bem1, bem2, normal, problem, problem.gap)


def _model_contact(bem1, bem2, normal, problem: ModelProblem, gap) -> MortarContact:
    """The model problem's boundary conditions on the bodies ``bem1``, ``bem2``."""
    return MortarContact(bem1, bem2, ("D", problem.u_top), ("D", (0.0, 0.0)), problem.F,
                         normal=normal, test_space=problem.test_space, gap=gap)


def model_problem(problem: ModelProblem = ModelProblem(),
                  bem_cache: dict | None = None) -> MortarContact:
    """The model problem of Section 4.3.4 (thesis lines 19474-19530) of the data
    ``problem``: body 1 bounded by Gamma^1_D = [-1,1] x {2} (U = u_top), Gamma^1_N =
    {-1,1} x [0.1, 2] and the arc Gamma^1_C of radius ``radius`` through (-1, 0.1),
    (0, 0), (1, 0.1); body 2 = [-1,1] x [-2,0] with Gamma^2_C = [-1,1] x {0} and
    Gamma^2_D = the rest (U = 0).  Normals of Gamma^1_C: the radial direction of the
    circle; gap along it (the "flat" geometry: :func:`model_gap`).  ``bem_cache``: a
    dict keeping the BE bodies (and their assembled operators) across calls - body 1
    depends only on (n1, p1, radius, L, geometry), body 2 on (n2, p2, L, side_depth), so
    a sweep over degree pairs assembles each body once."""
    q = problem
    mesh1, mesh2, normal = q.meshes()
    gap = model_gap(q.radius) if q.gap is None and q.geometry == "flat" else q.gap
    if bem_cache is None:
        bem1, bem2 = (LameBEM(m, q.E, q.nu, q.plane) for m in (mesh1, mesh2))
        return _model_contact(bem1, bem2, normal, q, gap)
    mat = (float(q.E), float(q.nu), q.plane)
    keys = ((1, q.n1, q.p1, float(q.radius), float(q.L), q.geometry) + mat,
            (2, q.n2, q.p2, float(q.L), float(q.side_depth)) + mat)
    bems = [bem_cache.get(k) or bem_cache.setdefault(k, LameBEM(m, q.E, q.nu, q.plane))
            for k, m in zip(keys, (mesh1, mesh2))]
    return _model_contact(*bems, normal, q, gap)


def adaptive_model_problem(settings: GlobalUzawaSettings, n_steps: int,
                           problem: ModelProblem = ModelProblem(n1=8, n2=6, p1=1, p2=1),
                           q=(0.85, 0.9)):
    """Figure 4.20's run (Section 4.3.5): Algorithm 4.6 on both bodies of the model
    problem (:func:`hpfebe.adaptivity.mortar_estimator.hp_adapt`, marking eta_I >= q[0]
    eta_max, bisection where eta_I >= q[1] eta_max) from the meshes of ``problem``
    (:meth:`ModelProblem.meshes`: n1, n2 elements on Gamma_C, degrees p1, p2; the arc
    stays the initial polygon); on every mesh global Uzawa (Algorithm 4.5, ``settings``) with the
    boundary conditions of :func:`contact_from_meshes`; ``n_steps`` solves.  A global
    Uzawa that fails ends the run (RuntimeError).  Returns (AdaptiveHistory, the h/p
    counts of every refinement)."""
    m1, m2, normal = problem.meshes()

    def solve(meshes):
        pr = contact_from_meshes(meshes[0], meshes[1], normal, problem)
        sol = pr.global_uzawa(settings)
        if not sol.info.converged:
            raise RuntimeError(f"figure_4_20: global Uzawa failed: {sol.info.reason}")
        return (pr, sol), (pr.body1.n, pr.body2.n)

    return hp_adapt((m1, m2), solve, n_steps, q[0], q[1])


@dataclass(frozen=True)
class MortarContactState:
    """The contact state of a mortar solution at the nodes of Gamma^1_C (the fields of
    :data:`hpfebe.io.CONTACT_FIELDS`): pressure p_n >= 0 and tangential traction t_t
    (the nodal traction of body 1, -R1 / w in the node frame), the gap g_n = g + Q_n -
    U_n (< 0: penetration), the relative tangential displacement g_t = U_t - Q_t, slip
    = |g_t| where the node slips, state (0 open, 1 stick, 2 slip: |lambda| = 1) and the
    Gauss-Lobatto weights."""

    points: np.ndarray
    p_n: np.ndarray
    t_t: np.ndarray
    g_n: np.ndarray
    g_t: np.ndarray
    slip: np.ndarray
    state: np.ndarray
    weights: np.ndarray


def mortar_contact_state(pr, sol) -> MortarContactState:
    """:class:`MortarContactState` of the solution ``sol`` of the mortar problem ``pr``
    (a :class:`~hpfebe.contact.MortarContact` or FEMortarContact) at the constrained
    nodes of Gamma^1_C (those whose initial gap is finite); the tractions from
    ``sol.extra`` ("pn", "pt") where the solver gave them, else from body 1's reaction
    at the frame unknowns ``sol.x``; a node is open where p_n <= 1e-8 max p_n."""
    nc = pr.nc
    if "pn" in sol.extra:
        p_n, t_t = np.asarray(sol.extra["pn"]), np.asarray(sol.extra["pt"])
    else:
        r_n, r_t = pr.frame(pr.reaction(sol.x))
        p_n, t_t = np.maximum(0.0, -r_n / pr.w), -r_t / pr.w
    Qn, Qt = pr.frame(sol.Q)
    g_t = sol.x[nc:] - Qt
    sliding = np.abs(sol.lam) >= 1.0 - 1e-9
    state = np.where(p_n <= 1e-8 * max(p_n.max(), 0.0), OPEN,
                     np.where(sliding, SLIP, STICK))
    k = np.isfinite(pr.gap)
    return MortarContactState(pr.points[k], p_n[k], t_t[k], (pr.gap + Qn - sol.x[:nc])[k],
                              g_t[k], np.where(state == SLIP, np.abs(g_t), 0.0)[k],
                              state[k], pr.w[k])


def mortar_exports(pr: MortarContact, sol) -> dict:
    """ParaView meshes of a solution of the model problem: both bodies' boundaries with
    their displacement U (sampled at the Gauss-Lobatto points of every element) and the
    contact state along Gamma^1_C (:func:`mortar_contact_state`)."""
    return {"body1": boundary_vtu(pr.bem1.mesh, pr.bem1.V_space, {"u": sol.U1}, d=2),
            "body2": boundary_vtu(pr.bem2.mesh, pr.bem2.V_space, {"u": sol.U2}, d=2),
            "contact": contact_vtu(mortar_contact_state(pr, sol))}
