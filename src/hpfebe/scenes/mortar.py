"""The model problem of Section 4.3.4 (thesis lines 19474-19530), the scene of Table 4.1
and Figures 4.17-4.20: body 1 bounded by Gamma^1_D = [-1,1] x {2}, its vertical sides
and the arc Gamma^1_C through (-1, 0.1), (0, 0), (1, 0.1); body 2 = [-1,1] x [-2,0]
with Gamma^2_C = [-1,1] x {0}.  :func:`model_meshes` (the boundary meshes and the normal
of Gamma^1_C), :func:`model_gap` (the arc as an initial gap over a flat Gamma^1_C),
:func:`contact_from_meshes` (the boundary conditions on given, e.g. adaptive, meshes),
:func:`model_problem` (the :class:`hpfebe.contact.MortarContact` of the scene) and
:func:`adaptive_model_problem` (Figure 4.20's hp-adaptive run, Algorithm 4.6).  The
material data are :mod:`hpfebe.scenes.materials` (E = 266926, nu = 0.29, plane strain);
the friction bound F = 0.1 is the model problem's.
"""

from __future__ import annotations

import numpy as np

from ..adaptivity.mortar_estimator import hp_adapt
from ..checks import array, choice, integer, real
from ..bem.lame import LameBEM
from ..contact.mortar import MortarContact
from ..geometry import BoundaryMesh
from ..solvers import GlobalUzawaSettings
from .materials import E, NU, PLANE

__all__ = ["adaptive_model_problem", "contact_from_meshes", "model_gap", "model_meshes",
           "model_problem"]


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


def contact_from_meshes(mesh1, mesh2, normal, E: float = E, nu: float = NU,
                        F: float = 0.1, u_top=(0.0, -0.09),
                        plane: str = PLANE, test_space: str = "full",
                        gap=None) -> MortarContact:
    """The model problem's boundary conditions on given meshes (e.g. adaptive ones);
    ``gap``: the initial gap function (None: measured along the normal to mesh2)."""
    bem1, bem2 = LameBEM(mesh1, E, nu, plane), LameBEM(mesh2, E, nu, plane)
    u_top = tuple(array("u_top", u_top, shape=(2,)))
    return _model_contact(bem1, bem2, normal, F, u_top, test_space, gap)


def _model_contact(bem1, bem2, normal, F, u_top, test_space, gap) -> MortarContact:
    """The model problem's boundary conditions on the bodies ``bem1``, ``bem2``."""
    return MortarContact(bem1, bem2, ("D", u_top), ("D", (0.0, 0.0)), F, normal=normal,
                         test_space=test_space, gap=gap)


def model_problem(n1: int = 16, n2: int = 12, p1: int = 2, p2: int = 2,
                  E: float = E, nu: float = NU, F: float = 0.1,
                  u_top=(0.0, -0.09), radius: float = 5.05, plane: str = PLANE,
                  L: float = 2.0, side_depth: float = 2.0,
                  test_space: str = "full", geometry: str = "arc",
                  bem_cache: dict | None = None, gap=None) -> MortarContact:
    """The model problem of Section 4.3.4 (thesis lines 19474-19530): body 1 bounded by
    Gamma^1_D = [-1,1] x {2} (U = u_top), Gamma^1_N = {-1,1} x [0.1, 2] and the arc
    Gamma^1_C of radius ``radius`` through (-1, 0.1), (0, 0), (1, 0.1); body 2 =
    [-1,1] x [-2,0] with Gamma^2_C = [-1,1] x {0} and Gamma^2_D = the rest (U = 0).
    Meshes: ``n1`` elements on Gamma^1_C (h1 = L / n1, equal angles), ``n2`` on
    Gamma^2_C (h2 = L / n2), the other sides with ceil(length / h) elements; degrees
    p1, p2 everywhere.  Normals of Gamma^1_C: the radial direction of the circle; gap
    along it.  ``geometry="flat"``: Gamma^1_C straight, the arc only as initial gap
    (:func:`model_meshes`); ``side_depth``: Dirichlet part of body 2's sides;
    ``test_space``: of the mortar projection (:class:`MortarContact`).  ``bem_cache``: a
    dict keeping the BE bodies (and their assembled operators) across calls - body 1
    depends only on (n1, p1, radius, L, geometry), body 2 on (n2, p2, L, side_depth), so
    a sweep over degree pairs assembles each body once.  ``gap``: an initial gap function
    replacing the scene's (e.g. zero: Algorithm 4.5's step 3 as printed, without g)."""
    F = real("F", F, nonnegative=True)
    u_top = tuple(array("u_top", u_top, shape=(2,)))
    mesh1, mesh2, normal = model_meshes(n1, n2, p1, p2, radius, L, side_depth, geometry)
    if gap is None and geometry == "flat":
        gap = model_gap(radius)
    if bem_cache is None:
        return contact_from_meshes(mesh1, mesh2, normal, E, nu, F, u_top, plane,
                                   test_space, gap)
    mat = (float(E), float(nu), plane)
    keys = ((1, int(n1), int(p1), float(radius), float(L), geometry) + mat,
            (2, int(n2), int(p2), float(L), float(side_depth)) + mat)
    bems = [bem_cache.get(k) or bem_cache.setdefault(k, LameBEM(m, E, nu, plane))
            for k, m in zip(keys, (mesh1, mesh2))]
    return _model_contact(*bems, normal, F, u_top, test_space, gap)


def adaptive_model_problem(settings: GlobalUzawaSettings, n_steps: int, n=(8, 6),
                           p: int = 1, q=(0.85, 0.9), radius: float = 5.05, **bc):
    """Figure 4.20's run (Section 4.3.5): Algorithm 4.6 on both bodies of the model
    problem (:func:`hpfebe.adaptivity.mortar_estimator.hp_adapt`, marking eta_I >= q[0]
    eta_max, bisection where eta_I >= q[1] eta_max) from the meshes of
    :func:`model_meshes` with n = (n1, n2) elements on Gamma_C, degree p and the arc of
    ``radius`` (the arc stays the initial polygon); on every mesh global Uzawa
    (Algorithm 4.5, ``settings``) with the boundary conditions of
    :func:`contact_from_meshes` (``bc``: E, nu, F, u_top, plane); ``n_steps`` solves.
    A global Uzawa that fails ends the run (RuntimeError).  Returns (AdaptiveHistory,
    the h/p counts of every refinement)."""
    m1, m2, normal = model_meshes(n[0], n[1], p, p, radius)

    def solve(meshes):
        pr = contact_from_meshes(meshes[0], meshes[1], normal, **bc)
        sol = pr.global_uzawa(settings)
        if not sol.info.converged:
            raise RuntimeError(f"figure_4_20: global Uzawa failed: {sol.info.reason}")
        return (pr, sol), (pr.body1.n, pr.body2.n)

    return hp_adapt((m1, m2), solve, n_steps, q[0], q[1])
