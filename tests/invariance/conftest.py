"""Small two-body penalty contact scenes for the invariance suite (helper R4 files:
test_rotation, test_mirror, test_swap, test_orientation).

Scene: an upper block [0, 1] x [0, 1] on a lower block [0, 1] x [-1, 0], FE (Q1,
rectangle_mesh) or BE (Galerkin LameBEM, degree p), 4 cells across the upper, 5 across
the lower (non-matching), the common side y = 0 mapped onto the parabola
y = c (x - 1/2)^2, c = 0.005 (chords of it: the two interface polylines differ by
O(c h^2)), and the whole scene moved by an isometry x -> A x + b (rotation,
reflection).  Loading: the upper block's top prescribed u = A (s, -D) (press by D, shear
by s), the lower block's bottom u = 0 (both components: Dirichlet data that rotate with
the scene), Coulomb friction mu_f = 0.3 (shear 2 D: open and slipping points, sticking
ones in most scenes), 1/eps_n = 1/eps_t = 10 E, two load steps, Newton with the Armijo
line search on ||R|| (without it the semismooth iteration cycles on the unrotated
two-pass BE/FE scene: residuals 0.970, 0.964, 0.970, ... to max_iter, reported as not
converged; the same scene rotated by 1e-3 rad converges in 3 iterations).  The material
is the thesis's (hpfebe.scenes: E, NU).  Variants (keywords of :func:`scene`): a kinked
interface and an overhanging upper block (GEOMETRIES), Tresca friction with a bound
varying along Gamma_C (TRESCA), an elastoplastic J2 lower block
(``fe_kw=dict(plastic=...)``), BE degree 2, two passes, the bodies swapped, the meshes
renumbered / reoriented (be_block, fe_block).

The test files take these helpers through the fixture ``tb`` (this module: a test file
cannot import a conftest unambiguously, tests/conftest.py has the same module name).

Bound of every comparison (:func:`forward_bound`).  Two runs that solve the same discrete
problem in other coordinates / numbering differ only by (i) Newton's stopping residual,
||R|| <= rtol * scale (ContactSettings: l2 norm on the free dofs; scale = the largest
load / body / contact force, <= ||J|| ||U||), in each run, and (ii) the rounding of the
assembled data, O(eps_mach ||J|| ||U||) (C_ROUND = 1e3 for the sums of a few hundred
entries of a quadrature).  With the Newton matrix J of the free dofs at the solution,
U_a - U_b = J^{-1} (r_a - r_b + dJ U) to first order, so

    ||U_a - U_b|| / ||U|| <= cond_2(J) (2 rtol + C_ROUND eps_mach).

J is taken at the converged U with the committed slip (the stick tangent of the law there:
the linearisation of the final equations on the same contact pattern).
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest

from hpfebe import BoundaryMesh, ElasticBody, ElastoPlasticFE, J2Material, LameBEM, \
    TwoBodyContact
from hpfebe.contact import ContactSettings
from hpfebe.fem import rectangle_mesh
from hpfebe.scenes import E, H, NU, SIGMA_Y

SIDES = ("bottom", "right", "top", "left")
D = 1e-4                       # press of the upper block's top
SHEAR = 2 * D                  # shear of the upper block's top (open, stick and slip)
MU = 0.3
EPS = 1.0 / (10.0 * E)         # 1/eps_n = 1/eps_t = 10 E
RTOL = 1e-12                   # Newton's backward-error tolerance of every run here
SETTINGS = ContactSettings(rtol=RTOL, max_iter=40, line_search=True)
C_ROUND = 1e3
MACHEPS = float(np.finfo(float).eps)
STEPS = (0.5, 1.0)


def TRESCA(x: np.ndarray) -> np.ndarray:
    """A Tresca bound F(x) of the reference frame (varying along the interface, even
    about x = 1/2): every point slips under the shear 2 D."""
    return 3.0 + 8.0 * (x[:, 0] - 0.5) ** 2


#: the interface geometries of the suite (keywords of :func:`scene`): the smooth curved
#: interface, a kinked one (the upper polyline's vertex at the kink, y = -0.01 |x - 1/2|)
#: and the upper block overhanging the lower one by 0.1 on both sides (outside points)
GEOMETRIES = {"parabola": dict(c=0.005), "roof": dict(shape="roof", c=-0.01),
              "overhang": dict(upper_x=(-0.1, 1.1))}


@dataclasses.dataclass(frozen=True)
class Isometry:
    """x -> A x + b (A orthogonal)."""

    A: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(2))
    b: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Map points (n, 2)."""
        return np.asarray(x) @ self.A.T + self.b

    def inverse(self, y: np.ndarray) -> np.ndarray:
        """T^{-1} of points (n, 2)."""
        return (np.asarray(y) - self.b) @ self.A

    @staticmethod
    def rotation(theta: float, shift=(0.0, 0.0)) -> "Isometry":
        c, s = np.cos(theta), np.sin(theta)
        return Isometry(np.array([[c, -s], [s, c]]), np.asarray(shift, float))

    @staticmethod
    def mirror_x(x0: float = 0.5) -> "Isometry":
        """x -> 2 x0 - x (the mirror in the line x = x0)."""
        return Isometry(np.diag([-1.0, 1.0]), np.array([2 * x0, 0.0]))


#: interface shapes: y = c (x - 1/2)^2 (smooth) or y = c |x - 1/2| (a kink at x = 1/2:
#: a vertex of the upper polyline, inside a segment of the lower one)
SHAPES = {"parabola": lambda x: (x - 0.5) ** 2, "roof": lambda x: np.abs(x - 0.5)}


def _bend(xy: np.ndarray, far: float, c: float, shape: str = "parabola") -> np.ndarray:
    """The blend of curved_block (tests/contact): y += (y - far) / (0 - far) c f(x)
    (the side y = 0 onto y = c f(x), f of SHAPES, the far side fixed, vertical sides
    straight)."""
    out = np.array(xy, dtype=float)
    out[:, 1] += (out[:, 1] - far) / (0.0 - far) * c * SHAPES[shape](out[:, 0])
    return out


def fe_block(upper: bool, c: float, T: Isometry, nx: int, renumber: bool = False,
             shape: str = "parabola", x=(0.0, 1.0), plastic: str | None = None):
    """The Q1 block; ``renumber``: the vertices numbered in reverse and every cell's
    vertices listed clockwise (facets and their directions change), the side labels
    found again from the coordinates; ``plastic``: the lower block an ElastoPlasticFE of
    this formulation ("bbar", "full"), J2 with sigma_Y = SIGMA_Y / 4 (it yields under
    the press), the thesis's H."""
    y0, y1 = (0.0, 1.0) if upper else (-1.0, 0.0)
    m = rectangle_mesh(x[0], x[1], y0, y1, nx, 2)
    if renumber:
        perm = np.arange(m.p.shape[1])[::-1]         # new vertex k = old vertex perm[k]
        inv = np.argsort(perm)
        tol = 1e-10
        m = type(m)(np.ascontiguousarray(m.p[:, perm]),
                    np.ascontiguousarray(inv[m.t][::-1])).with_boundaries({
                        "left": lambda z: np.abs(z[0] - x[0]) < tol,
                        "right": lambda z: np.abs(z[0] - x[1]) < tol,
                        "bottom": lambda z: np.abs(z[1] - y0) < tol,
                        "top": lambda z: np.abs(z[1] - y1) < tol})
    p = T(_bend(m.p.T, y1 if upper else y0, c, shape)).T
    m = dataclasses.replace(m, doflocs=np.ascontiguousarray(p))
    if plastic and not upper:
        return ElastoPlasticFE(m, J2Material(E, NU, SIGMA_Y / 4, H, 1.0), plastic)
    return ElasticBody(m, E, NU)


def be_block(upper: bool, c: float, T: Isometry, nx: int, p: int = 1,
             reverse: bool = False, start: int = 0, shuffle: int | None = None,
             shape: str = "parabola", x=(0.0, 1.0)) -> LameBEM:
    """The block as a BoundaryMesh from explicit segments (n = [nx, 2, nx, 2] per side
    of bottom, right, top, left).  ``reverse``: the segments given clockwise (every
    element reversed: from_segments orients the curve); ``start``: the node numbering
    shifted cyclically by ``start``; ``shuffle``: the elements listed in a random order
    (seed)."""
    y0, y1 = (0.0, 1.0) if upper else (-1.0, 0.0)
    corners = np.array([(x[0], y0), (x[1], y0), (x[1], y1), (x[0], y1)])
    ns = [nx, 2, nx, 2]
    pts, labels = [], []
    for k in range(4):
        t = np.arange(ns[k])[:, None] / ns[k]
        pts.append(corners[k] + t * (corners[(k + 1) % 4] - corners[k]))
        labels += [SIDES[k]] * ns[k]
    nodes = T(_bend(np.vstack(pts), y1 if upper else y0, c, shape))
    ne = len(nodes)
    seg = np.column_stack([np.arange(ne), (np.arange(ne) + 1) % ne])
    labels = np.array(labels)
    if reverse:
        seg = seg[:, ::-1]
    if start:
        perm = np.roll(np.arange(ne), start)          # new node k = old node perm[k]
        inv = np.argsort(perm)
        nodes, seg = nodes[perm], inv[seg]
    if shuffle is not None:
        order = np.random.default_rng(shuffle).permutation(ne)
        seg, labels = seg[order], labels[order]
    mesh = BoundaryMesh.from_segments(nodes, seg, list(labels), p)
    return LameBEM(mesh, E, NU, "strain")


def block(kind: str, upper: bool, c: float = 0.005, T: Isometry = Isometry(), p: int = 1,
          **kw):
    """FE (``kw`` of fe_block) or BE (``kw`` of be_block) block, 4 (upper) or 5 (lower)
    cells across (``x``: its x range, default [0, 1]; ``shape`` of the interface)."""
    nx = 4 if upper else 5
    if kind == "FE":
        return fe_block(upper, c, T, nx, **kw)
    return be_block(upper, c, T, nx, p, **kw)


def scene(kinds=("FE", "FE"), c: float = 0.005, T: Isometry = Isometry(),
          upper_is_slave: bool = True, two_pass: bool = False, shear: float = SHEAR,
          mu_f: float = MU, p: int = 1, be_kw=None, fe_kw=None,
          shape: str = "parabola", upper_x=(0.0, 1.0), tresca=None):
    """(problem, result, names, fixed dofs): the upper block (kinds[0]) pressed and
    sheared onto the lower one (kinds[1]) in the frame T; ``names`` = {"upper":
    "slave"/"master", ...}; ``be_kw`` / ``fe_kw`` the numbering options of every BE / FE
    block (be_block, fe_block); ``shape`` the interface's (SHAPES); ``upper_x`` the upper
    block's x range (wider than [0, 1]: it overhangs the lower block, whose points
    beyond the ends of the lower polyline are ``outside``); ``tresca``: a Tresca bound
    F(x) of the reference frame's points (then no Coulomb friction), given to the
    problem as F(T^{-1} y)."""
    kw = {"BE": be_kw or {}, "FE": fe_kw or {}}
    fric = dict(mu_f=mu_f) if tresca is None else \
        dict(mu_f=0.0, F=lambda y: tresca(T.inverse(y)))
    up = block(kinds[0], True, c, T, p, shape=shape, x=upper_x, **kw[kinds[0]])
    lo = block(kinds[1], False, c, T, p, shape=shape, **kw[kinds[1]])
    if upper_is_slave:
        pr = TwoBodyContact(up, lo, "bottom", "top", eps_n=EPS, eps_t=EPS, **fric,
                            two_pass=two_pass)
        names = {"upper": "slave", "lower": "master"}
    else:
        pr = TwoBodyContact(lo, up, "top", "bottom", eps_n=EPS, eps_t=EPS, **fric,
                            two_pass=two_pass)
        names = {"upper": "master", "lower": "slave"}
    top = [pr.dofs_on(names["upper"], "top", k) for k in (0, 1)]
    bot = pr.dofs_on(names["lower"], "bottom")
    u_top = T.A @ np.array([shear, -D])
    fixed = np.concatenate([top[0], top[1], bot])
    vals = np.concatenate([np.full(top[0].size, u_top[0]), np.full(top[1].size, u_top[1]),
                           np.zeros(bot.size)])
    res = pr.solve(None, fixed, vals, load_factors=list(STEPS), settings=SETTINGS)
    assert res.converged, res.reason
    return pr, res, names, fixed


def field(pr: TwoBodyContact, U: np.ndarray, body: str):
    """(points (m, 2), displacement vectors (m, 2)) of a body's dofs: the points of its
    dof coordinates, each with both components."""
    X = pr.dof_coordinates()
    g = pr.global_dofs(body, np.arange(pr.bodies[body].ndofs))
    xb, ub = X[g], np.asarray(U)[g]
    b = pr.bodies[body]
    if b.kind == "FE":
        nd = b.body.nodal_dofs
        return xb[nd[0]], np.column_stack([ub[nd[0]], ub[nd[1]]])
    return xb[0::2], np.column_stack([ub[0::2], ub[1::2]])   # interleaved components


def match(a: np.ndarray, b: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """The permutation j with b[j] = a (points equal to 1e-9 of ``scale``)."""
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    j = np.argmin(d, axis=1)
    assert np.all(d[np.arange(len(a)), j] < 1e-9 * scale), "point sets do not match"
    assert np.unique(j).size == len(j)
    return j


def point_keys(res, T: Isometry = Isometry()) -> np.ndarray:
    """(n, 3): the contact points mapped by T and their pass (x 10: points of the two
    passes may coincide), the keys of :func:`match` for the contact points of a result."""
    return np.column_stack([T(res.points), 10.0 * res.passes])


def mapped_discrepancy(ref, other, T: Isometry, body_pairs) -> float:
    """max over the bodies of ||T.A u_ref - u_other|| / ||u_ref|| (l2 over all the dofs of
    the scene; the points of ``other`` matched to T(points of ref)); ``body_pairs``:
    [(name in ref, name in other)]."""
    (pa, ra), (pb, rb) = ref[:2], other[:2]
    num = den = 0.0
    for na, nb in body_pairs:
        xa, ua = field(pa, ra.U, na)
        xb, ub = field(pb, rb.U, nb)
        j = match(T(xa), xb)
        num += np.sum((ua @ T.A.T - ub[j]) ** 2)
        den += np.sum(ua ** 2)
    return float(np.sqrt(num / den))


def forward_bound(pr: TwoBodyContact, res, fixed) -> float:
    """cond_2(J_free) (2 rtol + C_ROUND eps_mach): the bound of the module doc."""
    _, cs = pr.internal_force(res.U, res.slip)
    J = pr.tangent(cs)
    J = J if isinstance(J, np.ndarray) else J.toarray()
    free = np.setdiff1d(np.arange(pr.ndofs), fixed)
    kappa = np.linalg.cond(J[np.ix_(free, free)])
    return float(kappa * (2 * RTOL + C_ROUND * MACHEPS))


def force_bound(pr: TwoBodyContact, res, beta: float) -> float:
    """Bound on the relative change of the total normal contact force int p_n ds when U
    changes by at most beta ||U|| (:func:`forward_bound`) on the same contact pattern:
    F = -w_act . (g0 + Gn U) / eps_n is linear in U there, |dF| <= ||l||_2 beta ||U||_2,
    l = Gn^T (w on the active points) / eps_n."""
    w = res.weights * (res.p_n > 0)
    ell = pr.Gn.T @ w / pr.eps_n
    F = abs(float(res.weights @ res.p_n))
    return float(np.linalg.norm(ell) * beta * np.linalg.norm(res.U) / F)


@pytest.fixture(scope="session")
def tb():
    """This module: the scenes and helpers above."""
    return sys.modules[__name__]


def traction_bound(pr: TwoBodyContact, res, beta: float) -> float:
    """Bound on max |dp_n| and max |dt_t| at the points for ||dU|| <= beta ||U|| on the
    same pattern (and the committed slip of the step before, as far off):
    p_n = -(g0 + Gn U) / eps_n, t_t = (Gt U - slip) / eps_t (stick) or mu_f p_n (slip),
    so |dp_n|, |dt_t| <= (2 ||Gt||_inf / eps_t + (1 + mu_f) ||Gn||_inf / eps_n) beta ||U||_2.
    The friction force int t_t ds changes by at most sum(w) times this."""
    gn = float(abs(pr.Gn).sum(axis=1).max())
    gt = float(abs(pr.Gt).sum(axis=1).max())
    return (2 * gt / pr.eps_t + (1 + pr.mu_f) * gn / pr.eps_n) * beta \
        * float(np.linalg.norm(res.U))


def plastic_factor(pr: TwoBodyContact) -> float:
    """E / H for a scene with an elastoplastic body, else 1: cond_2 of the J2 algorithmic
    tangent is at most E / H times that of the elastic one (its least modulus in the
    plastic directions is about H), so a bound from the tangent at the committed state
    (elastic there) is scaled by this."""
    return E / H if any(not getattr(b, "linear", True) for b in pr.bodies.values()) \
        else 1.0
