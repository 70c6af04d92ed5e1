"""Invariance of the mortar contact solutions (Sections 4.3-4.4, issue 25): rigid
rotation, mirror symmetry, swap of the bodies, scaling of lengths / E / the prescribed
displacement, reversed node order, and DtN / global Uzawa / semismooth Newton /
monolithic agreeing on the same discrete problem.

Scenes: the BE model problem of Section 4.3.4 on coarse meshes (hpfebe.scenes.mortar,
Tresca friction) and the FE scene of Section 4.4 on small meshes.  Results are compared
at the contact nodes of body 1, matched by their coordinates (numbering-free): the frame
components (U_n, U_t) of body 1's displacement there.

Bounds.  Two runs of the semismooth Newton method (stop ||F|| <= tol * scale, tol =
1e-10) on the same discrete problem in other coordinates differ by
kappa (2 tol + C eps) in the relative displacement, kappa = cond_2(H) of the linear
response H of Algorithm 4.5 (measured 10-200 here), C = 1e3 for the rounding of the
assembled operators.  A fixed-point method (DtN, Uzawa) stopped at a relative increment
TOL with contraction q is within TOL q / (1 - q) of its fixed point (q measured from its
last increments).
"""

import numpy as np
import pytest

from hpfebe.bem.lame import LameBEM
from hpfebe.constitutive.j2 import J2Material
from hpfebe.contact import MortarContact
from hpfebe.contact.mortar_fe import FEMortarContact
from hpfebe.fem import ElasticBody, ElastoPlasticFE, rectangle_mesh
from hpfebe.geometry import BoundaryMesh
from hpfebe.scenes import dtn_settings, model_gap, model_meshes, section44_scene
from hpfebe.scenes.materials import E, H, NU, PLANE, SIGMA_Y
from hpfebe.scenes.section44 import STAMP, WORK
from hpfebe.solvers import DtNSettings, GlobalUzawaSettings, SemismoothSettings, UzawaSettings

EPS = np.finfo(float).eps
TOL = 1e-10
SEMI = SemismoothSettings(tol=TOL, friction="tresca")
U_TOP = np.array([0.01, -0.09])
F = 2000.0                       # stick and slip zones on the coarse meshes


def _rot(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def scene(A=np.eye(2), b=np.zeros(2), scale=1.0, E_=E, u_top=U_TOP, perm_seed=None,
          n=(4, 3), p=(2, 1)):
    """The model problem with every point x mapped to A (scale x) + b (A orthogonal:
    a rotation or reflection), u_top -> A u_top scale, optionally the nodes and
    elements of body 1 renumbered (``perm_seed``)."""
    m1, m2, normal = model_meshes(n[0], n[1], p[0], p[1])
    meshes = []
    for k, m in enumerate((m1, m2)):
        nodes = (scale * m.nodes) @ A.T + b
        el, lab, deg = m.elements, m.labels, m.degrees
        if perm_seed is not None and k == 0:
            rng = np.random.default_rng(perm_seed)
            pn = rng.permutation(len(nodes))
            inv = np.empty_like(pn)
            inv[pn] = np.arange(len(pn))
            nodes, el = nodes[pn], inv[el]
            pe = rng.permutation(len(el))
            el, lab, deg = el[pe], lab[pe], deg[pe]
        if np.linalg.det(A) < 0:             # a reflection reverses the orientation
            el = el[:, ::-1]
        meshes.append(BoundaryMesh(nodes, el, lab, deg))

    def nrm(x):
        return normal(((np.asarray(x) - b) @ A) / scale) @ A.T

    bem1, bem2 = (LameBEM(m, E_, NU, PLANE) for m in meshes)
    return MortarContact(bem1, bem2, ("D", A @ u_top * scale), ("D", (0.0, 0.0)),
                         F * E_ / E, normal=nrm, axis=A[:, 0])


def nodal(pr, sol, A=np.eye(2), b=np.zeros(2), scale=1.0):
    """(points mapped back to the reference scene, U_n, U_t) sorted by the point."""
    x = ((pr.points - b) @ A) / scale
    order = np.lexsort((x[:, 1], x[:, 0]))
    return x[order], sol.x[:pr.nc][order], sol.x[pr.nc:][order]


def kappa(pr) -> float:
    return float(np.linalg.cond(pr._global_operators()["H"]))


def fixed_point_bound(info, tol) -> float:
    """TOL q / (1 - q) of a fixed-point run (q: the largest of its last 3 ratios)."""
    r = np.asarray(info.residuals, dtype=float)
    q = float(np.max(r[-3:] / r[-4:-1])) if r.size >= 4 else 0.5
    return tol * q / (1.0 - min(q, 0.999))


@pytest.fixture(scope="module")
def ref():
    pr = scene()
    sol = pr.semismooth_newton(SEMI)
    assert sol.info.converged, sol.info.reason
    lam = np.abs(sol.lam)
    assert np.any(lam >= 1 - 1e-9) and np.any(lam < 1 - 1e-6)     # slip and stick
    return pr, sol, nodal(pr, sol)


def _compare(ref, other, flip_t=1.0, factor=1.0, bound=None):
    (x0, n0, t0), (x1, n1, t1) = ref[2], other
    assert np.abs(x0 - x1).max() <= 1e-12 * 4
    scale = max(np.abs(n0).max(), np.abs(t0).max())
    err = max(np.abs(n1 / factor - n0).max(), np.abs(flip_t * t1 / factor - t0).max())
    bound = kappa(ref[0]) * (2 * TOL + 1e3 * EPS) if bound is None else bound
    assert err <= bound * scale, (err / scale, bound)


@pytest.mark.parametrize("theta", [0.3, np.pi / 2, -2.0])
def test_rigid_rotation(ref, theta):
    A, b = _rot(theta), np.array([0.7, -1.3])
    pr = scene(A, b)
    sol = pr.semismooth_newton(SEMI)
    assert sol.info.converged, sol.info.reason
    _compare(ref, nodal(pr, sol, A, b))


def test_mirror(ref):
    """x -> -x with u_top -> (-u_x, u_y): the mirror image (U_t changes sign with the
    frame t = (-n_y, n_x) of the mirrored normal)."""
    A = np.diag([-1.0, 1.0])
    pr = scene(A)
    sol = pr.semismooth_newton(SEMI)
    assert sol.info.converged, sol.info.reason
    _compare(ref, nodal(pr, sol, A), flip_t=-1.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_reversed_node_order(ref, seed):
    pr = scene(perm_seed=seed)
    sol = pr.semismooth_newton(SEMI)
    assert sol.info.converged, sol.info.reason
    _compare(ref, nodal(pr, sol))


@pytest.mark.parametrize("what", ["length", "E"])
def test_unit_scaling(ref, what):
    """Lengths x 1e3 (displacements x 1e3, F unchanged: a traction), or E x 1e6 (the
    same displacements; F x 1e6)."""
    if what == "length":
        pr = scene(scale=1e3)
        sol = pr.semismooth_newton(SEMI)
        assert sol.info.converged, sol.info.reason
        _compare(ref, nodal(pr, sol, scale=1e3), factor=1e3)
    else:
        pr = scene(E_=E * 1e6)
        sol = pr.semismooth_newton(SEMI)
        assert sol.info.converged, sol.info.reason
        _compare(ref, nodal(pr, sol))


def test_solvers_agree(ref):
    """DtN (Algorithm 4.3), global Uzawa (4.5) and semismooth Newton solve the same
    discrete problem (Tresca friction)."""
    pr = ref[0]
    d = pr.dtn(DtNSettings(0.7, 0.5, tol=1e-10, uzawa=UzawaSettings(tol=1e-10,
                                                                    max_iter=20000)))
    g = pr.global_uzawa(GlobalUzawaSettings(rho=1.9, friction="tresca", tol=1e-10,
                                            max_iter=50000))
    for sol in (d, g):
        assert sol.info.converged, sol.info.reason
        tol = fixed_point_bound(sol.info, 1e-10)
        if sol is d:      # the inner Uzawa to 1e-10 of its own contraction too
            tol += max(fixed_point_bound(s, 1e-10) for s in sol.info.steps
                       if s.residuals)
        _compare(ref, nodal(pr, sol), bound=kappa(pr) * (tol + 2 * TOL + 1e3 * EPS))


def test_swap_of_the_bodies():
    """Matching meshes of the flat scene (Gamma^1_C = Gamma^2_C, the arc as the initial
    gap): the mortar projection is the identity and exchanging the bodies (body 2 the
    mortar side, normal (0, 1)) is the same discrete problem."""
    m1, _, _ = model_meshes(4, 4, 1, 1, geometry="flat")        # sides "N", top "D"
    m2 = BoundaryMesh.polygon([(-1, -2), (1, -2), (1, 0), (-1, 0)], n=[4, 4, 4, 4],
                              labels=["D", "N", "C", "N"], p=1)    # bottom "D"
    b1, b2 = LameBEM(m1, E, NU, PLANE), LameBEM(m2, E, NU, PLANE)
    up, down = (lambda x: np.tile([0.0, 1.0], (len(x), 1)),
                lambda x: np.tile([0.0, -1.0], (len(x), 1)))
    a = MortarContact(b1, b2, ("D", U_TOP), ("D", (0.0, 0.0)), F, normal=down,
                      gap=model_gap())
    s = MortarContact(b2, b1, ("D", (0.0, 0.0)), ("D", U_TOP), F, normal=up,
                      gap=model_gap())
    sa, ss = a.semismooth_newton(SEMI), s.semismooth_newton(SEMI)
    assert sa.info.converged and ss.info.converged
    # relative displacement U1 - U2 at the common nodes: d_a = U1 - Q2, d_s = U2 - Q1
    xa, xs = nodal(a, sa), nodal(s, ss)
    assert np.abs(xa[0] - xs[0]).max() <= 1e-12
    rel_a = sa.x.reshape(2, -1) - np.stack(a.frame(sa.Q))
    rel_s = ss.x.reshape(2, -1) - np.stack(s.frame(ss.Q))
    oa, os_ = np.lexsort(a.points.T[::-1]), np.lexsort(s.points.T[::-1])
    # n_s = -n_a, t_s = -t_a: the relative displacement of body 2 to body 1 in its
    # frame equals body 1's to body 2 in the other frame
    err = np.abs(rel_a[:, oa] - rel_s[:, os_]).max()
    bound = max(kappa(a), kappa(s)) * (2 * TOL + 1e3 * EPS)
    assert err <= bound * np.abs(rel_a).max(), err
    # the pressure is the same (P on the mortar side's nodes)
    pa, ps = a.frame(sa.P)[0][oa], s.frame(ss.P)[0][os_]
    assert np.abs(pa - ps).max() <= bound * np.abs(pa).max()


# ------------------------------------------------------------------ FE mortar
@pytest.fixture(scope="module")
def fe():
    sc = section44_scene((4, 8), (16, 8), sigma_Y=4e12, F=0.22, formulation="full")
    mono = sc.monolithic(tol=1e-10)
    assert mono.info.converged, mono.info.reason
    return sc, mono


def test_fe_dtn_equals_monolithic(fe):
    """DtN (Algorithm 4.3) and the monolithic semismooth Newton on the same discrete FE
    problem: within the DtN's fixed-point bound."""
    sc, mono = fe
    sol = sc.dtn(dtn_settings(0.5, 0.7, tol=1e-10, tol_U=1e-10))
    assert sol.info.converged, sol.info.reason
    # DtN to 1e-10, Uzawa to 1e-10, the Neumann Newton to its default 1e-8
    bound = 10 * (fixed_point_bound(sol.info, 1e-10) + 1e-10 + 1e-8)
    for k in ("u1", "u2"):
        a, b = sol.extra[k], mono.extra[k]
        assert np.abs(a - b).max() <= bound * np.abs(b).max(), k


@pytest.mark.parametrize("lift", [1e-8, 1e-12])
def test_fe_displacement_scaling(lift):
    """An elastic frictionless FE scene is linear in the prescribed lift: P(lift) / lift
    equal from 1e-4 down to 1e-12 (monolithic, tol 1e-10)."""
    def run(L):
        sc = section44_scene((4, 8), (16, 8), sigma_Y=4e12, F=0.0, lift=L,
                             formulation="full")
        sol = sc.monolithic(tol=1e-10)
        assert sol.info.converged, sol.info.reason
        return sol.P / L
    a, b = run(1e-4), run(lift)
    assert np.abs(a - b).max() <= 1e2 * 1e-10 * np.abs(a).max()


def _renumbered_rectangle(box, cells, reverse: bool):
    """(rectangle mesh, vertex permutation): with ``reverse`` the vertices numbered
    backwards and every cell's vertices listed clockwise (facets, their directions and
    the trace meshes of Gamma_C change), the side labels found again from the
    coordinates; new vertex k = old vertex perm[k]."""
    m = rectangle_mesh(*box, *cells)
    perm = np.arange(m.p.shape[1])
    if not reverse:
        return m, perm
    perm = perm[::-1]
    inv = np.argsort(perm)
    x0, x1, y0, y1 = box
    tol = 1e-10
    return type(m)(np.ascontiguousarray(m.p[:, perm]),
                   np.ascontiguousarray(inv[m.t][::-1])).with_boundaries({
                       "left": lambda z: np.abs(z[0] - x0) < tol,
                       "right": lambda z: np.abs(z[0] - x1) < tol,
                       "bottom": lambda z: np.abs(z[1] - y0) < tol,
                       "top": lambda z: np.abs(z[1] - y1) < tol}), perm


def _fe_scene(reverse: bool, sigma_Y: float):
    """The Section 4.4 mortar scene on small meshes (stamp 4 x 8, work piece 16 x 8,
    Tresca F = 0.22, lift 1e-4), its meshes renumbered and reoriented (``reverse``)."""
    m1, p1 = _renumbered_rectangle(STAMP, (4, 8), reverse)
    m2, p2 = _renumbered_rectangle(WORK, (16, 8), reverse)
    pr = FEMortarContact(ElasticBody(m1, E, NU),
                         ElastoPlasticFE(m2, J2Material(E, NU, sigma_Y, H, 1.0), "full"),
                         ("top", (0.0, 0.0)), ("bottom", (0.0, 1e-4)), 0.22)
    sol = pr.monolithic(tol=TOL)
    assert sol.info.converged, sol.info.reason
    return pr, sol, p1, p2


@pytest.mark.parametrize("sigma_Y", [4e12, SIGMA_Y], ids=["elastic", "plastic"])
def test_fe_reversed_element_orientation(sigma_Y):
    """FE mortar (Section 4.4): both FE meshes with reversed vertex numbering and
    clockwise cells give the same contact answer as the plain meshes: U1, U2 at every
    vertex, the pressure functional P on Gamma^2_C and lambda at the stamp's contact
    nodes, matched by coordinates.  Bound: the monolithic semismooth Newton stops at
    tol = 1e-10 relative; two runs on the same discrete problem differ by
    kappa (2 tol + C eps) with kappa <= 1e2 (the bound of test_fe_displacement_scaling)
    and C = 1e3.  Measured: 1.9e-15 to 8.2e-15 (elastic and plastic)."""
    a, sa, _, _ = _fe_scene(False, sigma_Y)
    b, sb, p1, p2 = _fe_scene(True, sigma_Y)
    bound = 1e2 * (2 * TOL + 1e3 * EPS)
    for key, perm in (("u1", p1), ("u2", p2)):
        ua, ub = sa.extra[key].reshape(-1, 2)[perm], sb.extra[key].reshape(-1, 2)
        assert np.abs(ua - ub).max() <= bound * np.abs(ua).max(), key

    def by_point(pr, sol):
        x = pr.work.mesh.p[:, pr.c2[0::2] // 2].T                 # Gamma^2_C vertices
        o2, o1 = np.lexsort(x.T[::-1]), np.lexsort(pr.points.T[::-1])
        return sol.P.reshape(-1, 2)[o2], sol.lam[o1]

    (Pa, la), (Pb, lb) = by_point(a, sa), by_point(b, sb)
    assert np.abs(Pa - Pb).max() <= bound * np.abs(Pa).max()
    assert np.abs(la - lb).max() <= bound * max(np.abs(la).max(), 1.0)
