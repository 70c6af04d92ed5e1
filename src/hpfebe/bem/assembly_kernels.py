"""The numba kernels of the Galerkin assembly (:mod:`hpfebe.bem.assembly` owns the Python
side: spaces, rules, tables, threads).

The row loop :func:`_assemble_rows_serial` runs over the pairs (test element i, trial
element j) of its rows and, per pair, integrates one local block by the case it falls in,
then scatters it (:func:`_scatter`):

* far pair, tabulated (the lower bound of the distance fixes the Gauss orders): the
  Laplace kernels fused, any other kernel by a kernel batch, both written out in the row
  loop;
* near pair (:func:`_near_block`, inlined): coincident, adjacent (a shared vertex) or
  general, by the matching function of :mod:`hpfebe.bem.integration`.

The row loop is a numba kernel over 100 lines (the exception of issue 24): its two far
fast paths as ``inline="always"`` functions of their own gave the same bits but cost
2.7x the time of the Laplace V + K at N = 1024, p = 1 (0.145 -> 0.40 s CPU, one thread,
measured 2026-12; presumably the reference counting of their ~15 array arguments per
pair), so they stay written out, as a call of integration.far_block per pair did before
(the comment at the fast path).  The mirror of a symmetric matrix, its in-place
symmetrisation, the element geometry and the sandwich W = T^T V T have kernels here too.

Caching: numba's on-disk cache keys a function on the contents of its own file only; the
cached ``_assemble_rows_serial`` keeps the machine code of the :mod:`.integration` and
:mod:`.kernels` functions it was compiled with.  :mod:`hpfebe._numba_cache` therefore
keys the whole cache directory on every kernel source: an edit of those files gets a
fresh cache.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..spaces import n_local
from .integration import ETA, adjacent_block, coincident_block, far_block, nearest_ends
from .kernels import INV_2PI, KP_LAPLACE_LOG_R, LAPLACE_DL, LAPLACE_SL, kernel_batch


@njit(cache=True)
def _shared_vertex(elements, i, j):
    """(q, r) with elements[i, q] == elements[j, r], or (-1, -1).  A function of its own:
    written inline, the constant -1 gave adjacent_block a second, literal-typed
    specialisation (3.8 s of compile time)."""
    for q in range(1, -1, -1):          # the last match in (q, r) order, as always
        for r in range(1, -1, -1):
            if elements[i, q] == elements[j, r]:
                return q, r
    return -1, -1


@njit(cache=True)
def _collinear(nodes, elements, normals, i, j):
    """Whether test element i lies on the line of trial element j (to 1e-15 of the
    distances): there (x - y) . n_y = 0, the Laplace double layer kernel vanishes and
    the block is exactly 0 (a quarter of all pairs on a polygon side, p = 1)."""
    aI, bI, aJ = nodes[elements[i, 0]], nodes[elements[i, 1]], nodes[elements[j, 0]]
    nJ = normals[j]
    d0 = (aI[0] - aJ[0]) * nJ[0] + (aI[1] - aJ[1]) * nJ[1]
    d1 = (bI[0] - aJ[0]) * nJ[0] + (bI[1] - aJ[1]) * nJ[1]
    # |d| > 1e-15 (|x| + |y|) >= 1e-15 hypot(x, y): not collinear, without the libm
    # hypot call (its cost dominated K's far pairs, issue 14)
    x0, y0 = aI[0] - aJ[0], aI[1] - aJ[1]
    if abs(d0) > 1e-15 * (abs(x0) + abs(y0)) or abs(d0) > 1e-15 * math.hypot(x0, y0):
        return False
    x1, y1 = bI[0] - aJ[0], bI[1] - aJ[1]
    return not (abs(d1) > 1e-15 * (abs(x1) + abs(y1))
                or abs(d1) > 1e-15 * math.hypot(x1, y1))


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


_FUSE_DL = True     # see _assemble_rows_serial


@njit(cache=True, inline="always")
def _near_block(kernel, logc, haslog, kp, d, nodes, elements, normals, aI, bI, i, j, kt,
                pt, kr, pr, mt, mr, rules, scratch, blk):
    """The local block of a near pair: coincident (i == j), adjacent (a shared vertex) or
    general, integrated by the matching function of :mod:`.integration`.  ``rules`` =
    (gx, gw, lx, lw, gll_x, gll_b), ``scratch`` the arrays of :func:`_scratch` (tuples:
    a call of more than 30 arguments is compiled with ``*args``, which numba cannot
    inline)."""
    gx, gw, lx, lw, gll_x, gll_b = rules
    phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack = scratch
    for a in range(mt * d):
        for b in range(mr * d):
            blk[a, b] = 0.0
    aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
    vI, vJ = _shared_vertex(elements, i, j)
    if i == j:
        coincident_block(kernel, logc, haslog, kp, d, aI, bI, normals[i],
                         kt, pt, kr, pr, gx, gw, lx, lw, gll_x, gll_b,
                         phi, psi, Kq, rxs, rys, blk)
    elif vI >= 0:
        adjacent_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ,
                       bJ, normals[j], vI, vJ, kt, pt, kr, pr, gx, gw, lx,
                       lw, gll_x, gll_b, phi, psi, Phi, Psi, Kq, tmp, rxs,
                       rys, wx, ww, stack, blk)
    else:
        rI, rJ = nearest_ends(aI, bI, aJ, bJ)
        far_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ,
                  normals[j], 0.0, 1.0, 0.0, 1.0, rI, rJ, kt, pt, kr, pr,
                  gx, gw, gll_x, gll_b, Phi, Psi, Kq, tmp, rxs, rys, wx, ww,
                  stack, blk)


@njit(cache=True, nogil=True)
def _assemble_rows_serial(kernel, logc, haslog, kp, d, nodes, elements, normals, L, mid,
                          kt, degt, dofs_t, kr, degr, dofs_r, symmetric,
                          gx, gw, lx, lw, gll_x, gll_b, tab_t, tab_r, thr, out, rows,
                          starts):
    """Rows of the test elements ``rows`` (pairs j >= i only if ``symmetric``) into out,
    in chunks rows[starts[c]:starts[c+1]], each with its own scratch arrays (allocated
    once per chunk, not per row: the small-N overhead).  Rows belong to test elements,
    so calls on disjoint rows never write the same entry (threads: :func:`assemble`).

    A plain, ``nogil`` compilation (the name of the former single-thread variant,
    beside a parfor ``_assemble_rows`` that issue 14 removed).  The compile-time
    constant ``_FUSE_DL`` selects the fused Laplace double-layer fast path below; it
    was False in the former parfor compilation, whose
    ``noalias`` arguments vectorised the unfused loop instead (issue 14: serial V
    0.97-1.05x and K 0.94-0.97x of the parfor's time on one thread, N = 64 ... 4096,
    p = 1)."""
    ne = elements.shape[0]
    nmax = gx.shape[0] - 1
    ntab = tab_t.shape[1] - 1
    pmax = max(degt.max(), degr.max()) + 1
    for ch in range(starts.shape[0] - 1):
        phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack = _scratch(nmax, pmax, d)
        blk = np.empty((pmax * d, pmax * d))
        for idx in range(starts[ch], starts[ch + 1]):
            i = rows[idx]
            j0 = i if symmetric else 0
            pt = degt[i]
            mt = n_local(kt, pt)
            aI, bI = nodes[elements[i, 0]], nodes[elements[i, 1]]
            for j in range(j0, ne):
                if kernel == LAPLACE_DL and _collinear(nodes, elements, normals, i, j):
                    continue      # block 0: nothing to add to out
                pr = degr[j]
                mr = n_local(kr, pr)
                # fast path for well separated pairs (most of them): the lower bound
                # |mid_i - mid_j| - (L_i + L_j)/2 of the distance fixes the Gauss orders
                # via the thresholds thr[deg, n] of integration._order, basis values are
                # tabulated.  Written out here, not a call of integration.far_block: a
                # call with ~30 array arguments per pair cost more than its quadrature
                # (measured: K for N = 1024, p = 1 went from 0.63 s to 0.19 s)
                dm0 = mid[i, 0] - mid[j, 0]
                dm1 = mid[i, 1] - mid[j, 1]
                dlow = math.sqrt(dm0 * dm0 + dm1 * dm1) - 0.5 * (L[i] + L[j])
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
                if (nx < ntab and ny < ntab and d == 1
                        and (kernel == LAPLACE_SL or (kernel == LAPLACE_DL and _FUSE_DL))):
                    # Laplace: kernel (kernels.laplace_*, the same arithmetic), weights
                    # and the trial-side sum fused per test point: no kernel_batch call
                    # per pair, and scalars that the serial compilation (no noalias)
                    # keeps in registers.  The parfor (noalias) vectorises the division
                    # of the double layer in the loop below instead (_FUSE_DL False, a
                    # compile-time constant of each compilation: K at N = 1024 90 ms
                    # there against 121 ms fused; serial 83 ms fused, 139 ms unfused)
                    Li = L[i]
                    Lj = L[j]
                    aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
                    nJ0, nJ1 = normals[j, 0], normals[j, 1]
                    kp0 = kp[KP_LAPLACE_LOG_R]
                    lc0 = logc[0]
                    for a in range(nx):
                        x0 = aI[0] + gx[nx, a] * (bI[0] - aI[0])
                        x1 = aI[1] + gx[nx, a] * (bI[1] - aI[1])
                        wa = gw[nx, a]
                        for b in range(ny):
                            rx = x0 - (aJ[0] + gx[ny, b] * (bJ[0] - aJ[0]))
                            ry = x1 - (aJ[1] + gx[ny, b] * (bJ[1] - aJ[1]))
                            if kernel == LAPLACE_SL:
                                kv = kp0
                            else:
                                kv = INV_2PI * (rx * nJ0 + ry * nJ1) / (rx * rx + ry * ry)
                            w = wa * gw[ny, b] * Li * Lj
                            if haslog:
                                kv = w * (kv + lc0 * (0.5 * math.log(rx * rx + ry * ry)))
                            else:
                                kv = kv * w
                            rxs[b] = kv
                        for l in range(mr):
                            acc = 0.0
                            for b in range(ny):
                                acc += rxs[b] * tab_r[pr, ny, b, l]
                            tmp[a, l, 0] = acc
                    for k in range(mt):
                        for l in range(mr):
                            acc = 0.0
                            for a in range(nx):
                                acc += tab_t[pt, nx, a, k] * tmp[a, l, 0]
                            blk[k, l] = acc
                elif nx < ntab and ny < ntab:
                    aJ, bJ = nodes[elements[j, 0]], nodes[elements[j, 1]]
                    for a in range(nx):
                        x0 = aI[0] + gx[nx, a] * (bI[0] - aI[0])
                        x1 = aI[1] + gx[nx, a] * (bI[1] - aI[1])
                        for b in range(ny):
                            rxs[a * ny + b] = x0 - (aJ[0] + gx[ny, b] * (bJ[0] - aJ[0]))
                            rys[a * ny + b] = x1 - (aJ[1] + gx[ny, b] * (bJ[1] - aJ[1]))
                    if kernel == LAPLACE_DL:     # kernels.laplace_double_layer
                        nJ0, nJ1 = normals[j, 0], normals[j, 1]
                        for q in range(nx * ny):
                            Kq[q, 0] = INV_2PI * (rxs[q] * nJ0 + rys[q] * nJ1) / (
                                rxs[q] * rxs[q] + rys[q] * rys[q])
                    else:
                        kernel_batch(kernel, rxs, rys, nx * ny, normals[i], normals[j], kp,
                                     Kq)
                    for a in range(nx):       # (q // ny, q % ny per point: two divisions)
                        for b in range(ny):
                            q = a * ny + b
                            w = gw[nx, a] * gw[ny, b] * L[i] * L[j]
                            if haslog:
                                lr = 0.5 * math.log(rxs[q] * rxs[q] + rys[q] * rys[q])
                                for c in range(d * d):
                                    Kq[q, c] = w * (Kq[q, c] + logc[c] * lr)
                            else:
                                for c in range(d * d):
                                    Kq[q, c] *= w
                    # blk = sum_a phi_k(a) sum_b Kq[a, b] psi_l(b): integration.contract_block
                    # written out on the tables (its call here cost 1.3-1.9x at N = 4096)
                    for a in range(nx):
                        for l in range(mr):
                            for c in range(d * d):
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
                    _near_block(kernel, logc, haslog, kp, d, nodes, elements, normals, aI,
                                bI, i, j, kt, pt, kr, pr, mt, mr,
                                (gx, gw, lx, lw, gll_x, gll_b),
                                (phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack), blk)
                _scatter(blk, dofs_t[i], dofs_r[j], mt, mr, d, out)


@njit(cache=True, nogil=True)
def _mirror_rows(A, blocks):
    """A[r, c] = A[c, r] for r > c in the row tiles ``blocks`` (64 rows each), tile by tile:
    a column-wise mirror costs a cache miss per entry once A outgrows the cache."""
    n = A.shape[0]
    bs = 64
    for bi in blocks:
        for bj in range(bi + 1):
            for r in range(bi * bs, min(n, (bi + 1) * bs)):
                for c in range(bj * bs, min(r, (bj + 1) * bs)):
                    A[r, c] = A[c, r]


@njit(cache=True)
def _element_geometry(nodes, elements):
    """(normals, L, mid) of the elements: the same floats as ``mesh.normals``,
    ``np.hypot`` of the edge vectors and ``0.5 * (a + b)`` (checked bitwise), in one call
    instead of ~15 numpy operations (15 us of a 16-element assembly)."""
    ne = elements.shape[0]
    normals = np.empty((ne, 2))
    L = np.empty(ne)
    mid = np.empty((ne, 2))
    for e in range(ne):
        a0, a1 = nodes[elements[e, 0], 0], nodes[elements[e, 0], 1]
        b0, b1 = nodes[elements[e, 1], 0], nodes[elements[e, 1], 1]
        d0 = b0 - a0
        d1 = b1 - a1
        L[e] = math.hypot(d0, d1)
        nrm = math.sqrt(d0 * d0 + d1 * d1)      # np.linalg.norm of BoundaryMesh.lengths
        normals[e, 0] = d1 / nrm
        normals[e, 1] = -(d0 / nrm)
        mid[e, 0] = 0.5 * (a0 + b0)
        mid[e, 1] = 0.5 * (a1 + b1)
    return normals, L, mid


@njit(cache=True, nogil=True)
def _sandwich_rows(indptr, indices, data, V, out, both, rows):
    """out[i, j] = (R V R^T)[i, j] for i in ``rows``, j >= i (R in CSR); if ``both``
    (``rows`` then all rows: one thread) the lower triangle too, by the tiled mirror
    :func:`_mirror_rows` after the upper one.  Threads write the upper triangle only and
    mirror it afterwards: a thread writing out[j, i] too touched every row of out, and
    on a fresh matrix the first chunk took all page faults, 0.3 s of a serial step at
    N = 4096.  One thread writing out[j, i] beside out[i, j] (column by column, a cache
    miss per entry) took 3.9x the time of upper triangle + mirror at N = 4096, p = 1
    (issue 27; the same bits: the mirror copies the entries)."""
    n = out.shape[0]
    if both and rows.shape[0] != n:
        raise ValueError("_sandwich_rows: both=True needs all rows")
    for i in rows:
        for j in range(i, n):
            acc = 0.0
            for a in range(indptr[i], indptr[i + 1]):
                k = indices[a]
                s = 0.0
                for b in range(indptr[j], indptr[j + 1]):
                    s += V[k, indices[b]] * data[b]
                acc += data[a] * s
            out[i, j] = acc
    if both:
        _mirror_rows(out, np.arange((n + 63) // 64))


@njit(cache=True)
def _symmetrise(A):
    """A <- (A + A^T) / 2 in place, tile by tile (64 x 64): the same floats as numpy's
    ``0.5 * (A + A.T)`` (0.5 (a + b) = 0.5 (b + a) in IEEE arithmetic) without its two
    n x n temporaries."""
    n = A.shape[0]
    bs = 64
    for bi in range((n + bs - 1) // bs):
        for bj in range(bi + 1):
            for r in range(bi * bs, min(n, (bi + 1) * bs)):
                for c in range(bj * bs, min(r + 1, (bj + 1) * bs)):
                    v = 0.5 * (A[r, c] + A[c, r])
                    A[r, c] = v
                    A[c, r] = v


@njit(cache=True)
def _transpose_csr(indptr, indices, data, ncols):
    """CSR arrays of the transpose of a CSR matrix with ``ncols`` columns, column indices
    sorted (a counting sort over the rows in order): ``T.T.tocsr()`` + ``sort_indices``
    without scipy's ~25 us of checks."""
    nnz = indptr[-1]
    ptr = np.zeros(ncols + 1, np.int64)
    for a in range(nnz):
        ptr[indices[a] + 1] += 1
    for c in range(ncols):
        ptr[c + 1] += ptr[c]
    fill = ptr[:-1].copy()
    idx = np.empty(nnz, np.int64)
    val = np.empty(nnz)
    for r in range(indptr.shape[0] - 1):
        for a in range(indptr[r], indptr[r + 1]):
            c = indices[a]
            idx[fill[c]] = r
            val[fill[c]] = data[a]
            fill[c] += 1
    return ptr, idx, val
