"""Dense Galerkin assembly of boundary integral operators, parallel over element pairs.

One routine, :func:`assemble`, serves every operator: it is specialised by the kernel
(an id of :mod:`hpfebe.bem.kernels`: Laplace V and K, Lame) and by the test/trial
spaces.  Each pair of elements is classified (coincident / adjacent / far),
integrated by the matching function of :mod:`hpfebe.bem.integration` into a local block,
and scattered.  Rows belong to test elements, so the loop over test elements runs in
parallel without write conflicts (the test space must be discontinuous: W_hp).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit, prange

from ..quadrature import rule_tables
from ..spaces import P_MAX, DiscontinuousSpace, eval_basis, gll_tables, n_local
from .integration import ETA, NMAX, TOL, adjacent_block, coincident_block, far_block
from .kernels import kernel_batch


@njit(cache=True)
def _pair_block(kernel, logc, haslog, kp, d, nodes, elements, normals, i, j,
                kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b, scratch, blk):
    """Local block of test element i and trial element j into ``blk`` (zeroed here)."""
    phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack = scratch
    mt = n_local(kt, pt) * d
    mr = n_local(kr, pr) * d
    for a in range(mt):
        for b in range(mr):
            blk[a, b] = 0.0
    aI, bI = nodes[elements[i, 0]], nodes[elements[i, 1]]
    aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
    if i == j:
        coincident_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], kt, pt, kr, pr,
                         gx, gw, lx, lw, gll_x, gll_b, phi, psi, Kq, rxs, rys, blk)
        return
    vI, vJ = -1, -1
    for q in range(2):
        for r in range(2):
            if elements[i, q] == elements[j, r]:
                vI, vJ = q, r
    if vI >= 0:
        adjacent_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                       vI, vJ, kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                       phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack, blk)
    else:
        far_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                  0.0, 1.0, 0.0, 1.0, kt, pt, kr, pr, gx, gw, gll_x, gll_b,
                  Phi, Psi, Kq, tmp, rxs, rys, stack, blk)


@njit(cache=True)
def _scratch(nmax, pmax, d):
    """Work arrays of one thread: basis values, kernel batch, rules, subdivision stack."""
    return (np.empty(pmax), np.empty(pmax), np.empty((nmax, pmax)), np.empty((nmax, pmax)),
            np.empty((nmax * nmax, d * d)), np.empty((nmax, pmax, d * d)),
            np.empty(nmax * nmax), np.empty(nmax * nmax), np.empty(64 * nmax),
            np.empty(64 * nmax), np.empty((128, 4)))


@njit(cache=True, inline="always")
def _scatter(blk, dofs_i, dofs_j, mt, mr, d, out):
    """out[dof_k, dof_l] += blk[k, l] (interleaved components) for the local block of a
    test and a trial element with global dofs dofs_i, dofs_j (-1: none)."""
    for k in range(mt):
        gk = dofs_i[k]
        if gk < 0:
            continue
        for l in range(mr):
            gl = dofs_j[l]
            if gl < 0:
                continue
            for c1 in range(d):
                for c2 in range(d):
                    out[gk * d + c1, gl * d + c2] += blk[k * d + c1, l * d + c2]


@njit(cache=True, parallel=True)
def _assemble(kernel, logc, haslog, kp, d, nodes, elements, normals,
              kt, degt, dofs_t, kr, degr, dofs_r, symmetric,
              gx, gw, lx, lw, gll_x, gll_b, tab_t, tab_r, thr, out):
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    ntab = tab_t.shape[1] - 1
    pmax = max(degt.max(), degr.max()) + 1
    dd = d * d
    L = np.empty(ne)
    mid = np.empty((ne, 2))
    for e in range(ne):
        a, b = nodes[elements[e, 0]], nodes[elements[e, 1]]
        L[e] = math.hypot(b[0] - a[0], b[1] - a[1])
        mid[e, 0] = 0.5 * (a[0] + b[0])
        mid[e, 1] = 0.5 * (a[1] + b[1])
    for idx in prange(ne):
        # interleave short and long rows of the triangle (symmetric case) for balance
        i = idx // 2 if idx % 2 == 0 else ne - 1 - idx // 2
        scratch = _scratch(nmax, pmax, d)
        Kq = scratch[4]
        rxs, rys = scratch[6], scratch[7]
        blk = np.empty((pmax * d, pmax * d))
        j0 = i if symmetric else 0
        pt = degt[i]
        mt = n_local(kt, pt)
        aI, bI = nodes[elements[i, 0]], nodes[elements[i, 1]]
        for j in range(j0, ne):
            pr = degr[j]
            mr = n_local(kr, pr)
            # fast path for well separated pairs (most of them): the lower bound
            # |mid_i - mid_j| - (L_i + L_j)/2 of the distance fixes the Gauss orders via
            # the thresholds thr[deg, n] of integration._order, basis values are tabulated.
            # It is written out here instead of calling integration._tensor_rect: a call
            # with ~30 array arguments per pair cost more than its quadrature (measured:
            # K for N = 1024, p = 1 went from 0.63 s to 0.19 s)
            dlow = (math.hypot(mid[i, 0] - mid[j, 0], mid[i, 1] - mid[j, 1])
                    - 0.5 * (L[i] + L[j]))
            nx = ntab
            ny = ntab
            if dlow >= 2.0 * ETA * max(L[i], L[j]):
                rx_ = 2.0 * dlow / L[i]
                ry_ = 2.0 * dlow / L[j]
                dt_ = pt - 1 if kt == 0 else pt
                dr_ = pr - 1 if kr == 0 else pr
                nx = 1
                while nx < ntab and rx_ < thr[dt_, nx]:
                    nx += 1
                ny = 1
                while ny < ntab and ry_ < thr[dr_, ny]:
                    ny += 1
            if nx < ntab and ny < ntab:
                aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
                for a in range(nx):
                    x0 = aI[0] + gx[nx, a] * (bI[0] - aI[0])
                    x1 = aI[1] + gx[nx, a] * (bI[1] - aI[1])
                    for b in range(ny):
                        rxs[a * ny + b] = x0 - (aJ[0] + gx[ny, b] * (bJ[0] - aJ[0]))
                        rys[a * ny + b] = x1 - (aJ[1] + gx[ny, b] * (bJ[1] - aJ[1]))
                kernel_batch(kernel, rxs, rys, nx * ny, normals[i], normals[j], kp, Kq)
                for q in range(nx * ny):
                    w = gw[nx, q // ny] * gw[ny, q % ny] * L[i] * L[j]
                    if haslog:
                        lr = 0.5 * math.log(rxs[q] * rxs[q] + rys[q] * rys[q])
                        for c in range(dd):
                            Kq[q, c] = w * (Kq[q, c] + logc[c] * lr)
                    else:
                        for c in range(dd):
                            Kq[q, c] *= w
                # blk[k, l] = sum_a phi_k(a) sum_b Kq[a, b] psi_l(b), in two stages
                tmp = scratch[5]
                for a in range(nx):
                    for l in range(mr):
                        for c in range(dd):
                            acc = 0.0
                            for b in range(ny):
                                acc += Kq[a * ny + b, c] * tab_r[pr, ny, b, l]
                            tmp[a, l, c] = acc
                for k in range(mt):
                    for l in range(mr):
                        for c1 in range(d):
                            for c2 in range(d):
                                acc = 0.0
                                for a in range(nx):
                                    acc += tab_t[pt, nx, a, k] * tmp[a, l, c1 * d + c2]
                                blk[k * d + c1, l * d + c2] = acc
            else:
                _pair_block(kernel, logc, haslog, kp, d, nodes, elements, normals, i, j,
                            kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b, scratch, blk)
            _scatter(blk, dofs_t[i], dofs_r[j], mt, mr, d, out)
    if symmetric:
        # dofs of W_hp grow with the element index, so the pairs j >= i filled the upper
        # triangle; mirror it in cache-sized tiles (a column-wise mirror inside the pair
        # loop costs a cache miss per entry once the matrix outgrows the cache)
        _mirror_upper(out)


@njit(cache=True, parallel=True)
def _mirror_upper(A):
    """A[r, c] = A[c, r] for r > c, tile by tile."""
    n = A.shape[0]
    bs = 64
    nb = (n + bs - 1) // bs
    for bi in prange(nb):
        for bj in range(bi + 1):
            for r in range(bi * bs, min(n, (bi + 1) * bs)):
                for c in range(bj * bs, min(r, (bj + 1) * bs)):
                    A[r, c] = A[c, r]


NTAB = 12  # far pairs needing fewer Gauss points than this use tabulated basis values


@lru_cache(maxsize=None)
def _far_tables(kind: int, pmax: int):
    """Basis values tab[p, n, a, k] at the n-point Gauss nodes (on [0,1]) for degrees
    p <= pmax, and order thresholds thr[deg, n]: the smallest distance/half-length ratio
    for which n points meet integration.TOL (the inverse of integration._order)."""
    gx, _, _, _ = rule_tables(NMAX)
    gll_x, gll_b = gll_tables(P_MAX)
    tab = np.zeros((pmax + 1, NTAB + 1, NTAB, pmax + 1))
    for p in range(1, pmax + 1):
        for n in range(1, NTAB + 1):
            for a in range(n):
                eval_basis(kind, p, 2.0 * gx[n, a] - 1.0, gll_x, gll_b, tab[p, n, a])
    tab.setflags(write=False)
    return tab


@lru_cache(maxsize=None)
def _order_thresholds(degmax: int):
    thr = np.full((degmax + 1, NTAB + 1), np.inf)
    for deg in range(degmax + 1):
        for n in range(1, NTAB + 1):
            if 2 * n > deg:
                rho = math.exp(math.log(1.0 / TOL) / (2 * n - deg))
                thr[deg, n] = 0.5 * (rho - 1.0 / rho)
    thr.setflags(write=False)
    return thr


def _space_arrays(space):
    # local functions per element: n_local(kind, p_I) with p_I the element degree
    return space.kind, np.ascontiguousarray(space.mesh.degrees), space.elem_dofs


def assemble(kernel: int, logc, kp, test, trial, d: int = 1,
             symmetric: bool = False) -> np.ndarray:
    """Dense Galerkin matrix of the kernel ``k(r) = logc * log|r| + k_reg(r)`` (``kernel``
    the id of k_reg in :mod:`hpfebe.bem.kernels`) with rows
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
    pmax = int(mesh.degrees.max())
    _assemble(kernel, logc, bool(np.any(logc != 0.0)), kp, d, mesh.nodes, mesh.elements,
              np.ascontiguousarray(mesh.normals), kt, degt, dofs_t, kr, degr, dofs_r,
              symmetric, gx, gw, lx, lw, gll_x, gll_b, _far_tables(kt, pmax),
              _far_tables(kr, pmax), _order_thresholds(pmax), out)
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
                gx, gw, lx, lw, gll_x, gll_b, _scratch(nmax, pmax, d), blk)
    mt = (pt if test_kind == 0 else pt + 1) * d
    mr = (pr if trial_kind == 0 else pr + 1) * d
    return blk[:mt, :mr].copy()



@njit(cache=True, parallel=True)
def _sandwich(indptr, indices, data, V, out):
    """out = R V R^T for R in CSR (rows of R = rows of out); only j >= i, mirrored."""
    n = out.shape[0]
    for idx in prange(n):
        i = idx // 2 if idx % 2 == 0 else n - 1 - idx // 2   # balance the triangle
        for j in range(i, n):
            acc = 0.0
            for a in range(indptr[i], indptr[i + 1]):
                k = indices[a]
                s = 0.0
                for b in range(indptr[j], indptr[j + 1]):
                    s += V[k, indices[b]] * data[b]
                acc += data[a] * s
            out[i, j] = acc
            out[j, i] = acc


def sandwich(T, V: np.ndarray) -> np.ndarray:
    """T^T V T for sparse T (n_W x n_V) and dense symmetric V (n_W x n_W), exactly
    symmetric: the hypersingular operator W = T^T V T from the single layer V of the
    arc-length derivatives (T: :meth:`ContinuousSpace.derivative_matrix`)."""
    R = T.T.tocsr()
    R.sort_indices()
    out = np.empty((R.shape[0], R.shape[0]))
    _sandwich(R.indptr, R.indices, R.data, np.ascontiguousarray(V), out)
    return out
