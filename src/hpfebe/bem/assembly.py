"""Dense Galerkin assembly of boundary integral operators, parallel over element pairs.

One routine, :func:`assemble`, serves every operator: it is specialised by the numba
kernel function (Laplace V and K here, Lame in :mod:`hpfebe.bem.lame`) and by the
test/trial spaces.  Each pair of elements is classified (coincident / adjacent / far),
integrated by the matching function of :mod:`hpfebe.bem.integration` into a local block,
and scattered.  Rows belong to test elements, so the loop over test elements runs in
parallel without write conflicts (the test space must be discontinuous: W_hp).
"""

from __future__ import annotations

import warnings

import numpy as np
from numba import njit, prange
from numba.core.errors import NumbaExperimentalFeatureWarning

from ..quadrature import rule_tables
from ..spaces import P_MAX, ContinuousSpace, DiscontinuousSpace, gll_tables, n_local
from .integration import NMAX, adjacent_block, coincident_block, far_block

# kernels are passed to the assemblers as first-class numba functions
warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)


@njit(cache=True)
def _pair_block(kernel, logc, haslog, kp, d, nodes, elements, normals, i, j,
                kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                phi, psi, kv, Phi, Psi, Kq, tmp, wx, ww, blk):
    """Local block of test element i and trial element j into ``blk`` (zeroed here)."""
    mt = n_local(kt, pt) * d
    mr = n_local(kr, pr) * d
    for a in range(mt):
        for b in range(mr):
            blk[a, b] = 0.0
    aI, bI = nodes[elements[i, 0]], nodes[elements[i, 1]]
    aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
    if i == j:
        coincident_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], kt, pt, kr, pr,
                         gx, gw, lx, lw, gll_x, gll_b, phi, psi, kv, blk)
        return
    vI, vJ = -1, -1
    for q in range(2):
        for r in range(2):
            if elements[i, q] == elements[j, r]:
                vI, vJ = q, r
    if vI >= 0:
        adjacent_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                       vI, vJ, kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                       phi, psi, kv, Phi, Psi, Kq, tmp, wx, ww, blk)
    else:
        far_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                  0.0, 1.0, 0.0, 1.0, kt, pt, kr, pr, gx, gw, gll_x, gll_b,
                  Phi, Psi, Kq, tmp, blk)


@njit(cache=True, parallel=True)
def _assemble(kernel, logc, haslog, kp, d, nodes, elements, normals,
              kt, degt, dofs_t, kr, degr, dofs_r, symmetric,
              gx, gw, lx, lw, gll_x, gll_b, out):
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    pmax = max(degt.max(), degr.max()) + 1
    for idx in prange(ne):
        # interleave short and long rows of the triangle (symmetric case) for balance
        i = idx // 2 if idx % 2 == 0 else ne - 1 - idx // 2
        phi = np.empty(pmax)
        psi = np.empty(pmax)
        kv = np.empty(d * d)
        Phi = np.empty((nmax, pmax))
        Psi = np.empty((nmax, pmax))
        Kq = np.empty((nmax, nmax, d * d))
        tmp = np.empty((nmax, pmax, d * d))
        wx = np.empty(4 * nmax * 16)
        ww = np.empty(4 * nmax * 16)
        blk = np.empty((pmax * d, pmax * d))
        j0 = i if symmetric else 0
        pt = degt[i]
        mt = n_local(kt, pt)
        for j in range(j0, ne):
            pr = degr[j]
            mr = n_local(kr, pr)
            _pair_block(kernel, logc, haslog, kp, d, nodes, elements, normals, i, j,
                        kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                        phi, psi, kv, Phi, Psi, Kq, tmp, wx, ww, blk)
            for k in range(mt):
                gk = dofs_t[i, k]
                if gk < 0:
                    continue
                for l in range(mr):
                    gl = dofs_r[j, l]
                    if gl < 0:
                        continue
                    for c1 in range(d):
                        for c2 in range(d):
                            v = blk[k * d + c1, l * d + c2]
                            out[gk * d + c1, gl * d + c2] += v
                            if symmetric and j != i:
                                out[gl * d + c2, gk * d + c1] += v


def _space_arrays(space):
    # local functions per element: n_local(kind, p_I) with p_I the element degree
    return space.kind, np.ascontiguousarray(space.mesh.degrees), space.elem_dofs


def assemble(kernel, logc, kp, test, trial, d: int = 1, symmetric: bool = False) -> np.ndarray:
    """Dense Galerkin matrix of the kernel ``k(r) = logc * log|r| + kernel(r)`` with rows
    from ``test`` (a :class:`DiscontinuousSpace`) and columns from ``trial``.

    ``d`` is the number of components (1 Laplace, 2 Lame): global index = d*dof + c.
    ``symmetric`` computes only the upper triangle of element pairs and mirrors it
    (requires test is trial and a symmetric kernel)."""
    if not isinstance(test, DiscontinuousSpace):
        raise ValueError("test space must be a DiscontinuousSpace (W_hp); "
                         f"got {type(test).__name__}")
    if test.mesh is not trial.mesh:
        raise ValueError("test and trial spaces must live on the same mesh")
    if symmetric and test is not trial:
        raise ValueError("symmetric=True requires test is trial")
    mesh = test.mesh
    if mesh.degrees.max() > P_MAX:
        raise ValueError(f"degree p must be <= {P_MAX}, got {mesh.degrees.max()}")
    gx, gw, lx, lw = rule_tables(NMAX)
    gll_x, gll_b = gll_tables(P_MAX)
    logc = np.ascontiguousarray(np.asarray(logc, dtype=float).reshape(d * d))
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    kt, degt, dofs_t = _space_arrays(test)
    kr, degr, dofs_r = _space_arrays(trial)
    out = np.zeros((test.ndof * d, trial.ndof * d))
    _assemble(kernel, logc, bool(np.any(logc != 0.0)), kp, d, mesh.nodes, mesh.elements,
              np.ascontiguousarray(mesh.normals), kt, degt, dofs_t, kr, degr, dofs_r,
              symmetric, gx, gw, lx, lw, gll_x, gll_b, out)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError("assembly produced non-finite entries "
                                 "(degenerate geometry or degree too high?)")
    return out


def local_block(kernel, logc, kp, mesh, i: int, j: int, test_kind: int, trial_kind: int,
                d: int = 1) -> np.ndarray:
    """Local block of the pair (test element i, trial element j) with basis kinds
    0 (Legendre, W_hp) or 1 (GLL Lagrange, V_hp) at the elements' degrees; for tests."""
    gx, gw, lx, lw = rule_tables(NMAX)
    gll_x, gll_b = gll_tables(P_MAX)
    logc = np.ascontiguousarray(np.asarray(logc, dtype=float).reshape(d * d))
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    pt, pr = int(mesh.degrees[i]), int(mesh.degrees[j])
    nmax = gx.shape[0] - 1
    pmax = max(pt, pr) + 1
    blk = np.zeros((pmax * d, pmax * d))
    _pair_block(kernel, logc, bool(np.any(logc != 0.0)), kp, d, mesh.nodes, mesh.elements,
                   np.ascontiguousarray(mesh.normals), i, j, test_kind, pt, trial_kind, pr,
                   gx, gw, lx, lw, gll_x, gll_b, np.empty(pmax), np.empty(pmax),
                   np.empty(d * d), np.empty((nmax, pmax)), np.empty((nmax, pmax)),
                   np.empty((nmax, nmax, d * d)), np.empty((nmax, pmax, d * d)),
                   np.empty(64 * nmax), np.empty(64 * nmax), blk)
    mt = (pt if test_kind == 0 else pt + 1) * d
    mr = (pr if trial_kind == 0 else pr + 1) * d
    return blk[:mt, :mr].copy()

