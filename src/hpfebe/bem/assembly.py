"""Dense Galerkin assembly of boundary integral operators, parallel over element rows.

One routine, :func:`assemble`, serves every operator: it is specialised by the kernel
(an id of :mod:`hpfebe.bem.kernels`: Laplace V and K, Lame) and by the test/trial
spaces.  Each pair of elements is classified (coincident / adjacent / far),
integrated by the matching function of :mod:`hpfebe.bem.integration` into a local block,
and scattered.  Rows belong to test elements, so the loop over test elements runs in
parallel without write conflicts (the test space must be discontinuous: W_hp): chunks
of rows of the one compiled row loop, ``_assemble_rows_serial`` (``nogil``), taken by
numba.get_num_threads() Python threads as they become free; with one thread (every
Snakemake job) or a mesh too small to pay for threads, one direct call.  The mirror of
the upper triangle, the sandwich W = T^T V T and the finiteness check run the same way.
(Issue 14: this replaced a numba parfor over static row chunks - the same 2-thread wall
time at N = 1024 and 4096 on a quiet machine, but compiling the parfor cost a 2-thread
process ~9 s of a cold start; the serial steps the threads now share were 3 % of V + K + W
at N = 4096, the sandwich's page faults 0.3 s in one task.)

Caching: numba's on-disk cache keys a function on the contents of its own file only, so
the cached ``_assemble_rows_serial`` keeps the machine code of the :mod:`.integration` and
:mod:`.kernels` functions it was compiled with.  After changing those files, delete
``src/hpfebe/bem/__pycache__`` (or point NUMBA_CACHE_DIR elsewhere), or the old code runs.
"""

from __future__ import annotations

import gc
import math
import threading
import types
from contextlib import contextmanager
from functools import lru_cache

import numpy as np
from numba import njit

from ..quadrature import rule_tables
from ..spaces import P_MAX, DiscontinuousSpace, eval_basis, gll_tables, n_local
from .integration import (ETA, NMAX, TOL, adjacent_block, coincident_block, far_block,
                          nearest_ends)
from .kernels import INV_2PI, KP_LAPLACE_LOG_R, LAPLACE_DL, LAPLACE_SL, kernel_batch
from .threads import all_finite, interleaved, n_threads, run_chunks, zeros_aligned


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


_FUSE_DL = True     # see _rows


def _rows(kernel, logc, haslog, kp, d, nodes, elements, normals, L, mid,
          kt, degt, dofs_t, kr, degr, dofs_r, symmetric,
          gx, gw, lx, lw, gll_x, gll_b, tab_t, tab_r, thr, out, rows, starts):
    """Rows of the test elements ``rows`` (pairs j >= i only if ``symmetric``) into out,
    in chunks rows[starts[c]:starts[c+1]], each with its own scratch arrays (allocated
    once per chunk, not per row: the small-N overhead).  Rows belong to test elements,
    so calls on disjoint rows never write the same entry (threads: :func:`assemble`).

    Compiled as ``_assemble_rows_serial`` (a plain, ``nogil`` compilation).  The
    compile-time constant ``_FUSE_DL`` selects the fused Laplace double-layer fast path
    below; it was False in the former parfor compilation, whose ``noalias`` arguments
    vectorised the unfused loop instead (issue 14: serial V 0.97-1.05x and K 0.94-0.97x
    of the parfor's time on one thread, N = 64 ... 4096, p = 1)."""
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
                    # near pair: coincident, adjacent or far integration (.integration)
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
                _scatter(blk, dofs_t[i], dofs_r[j], mt, mr, d, out)


def _renamed(fn, name: str, **constants):
    """A copy of the Python function ``fn`` under another name, with module globals
    replaced by ``constants`` (numba compiles globals as constants): numba's on-disk
    cache files are named after the function's qualified name, so that two dispatchers
    compiled from one source need two names."""
    g = types.FunctionType(fn.__code__, {**fn.__globals__, **constants}, name,
                           fn.__defaults__, fn.__closure__)
    g.__qualname__ = name
    g.__module__ = fn.__module__
    g.__doc__ = fn.__doc__
    return g


# the row loop, compiled once (the name of the former single-thread variant, beside a
# parfor ``_assemble_rows`` that issue 14 removed; run on Python threads by assemble)
_assemble_rows_serial = njit(cache=True, nogil=True)(
    _renamed(_rows, "_assemble_rows_serial", _FUSE_DL=True))


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


MIN_PAIRS_PER_THREAD = 4096   # below this many element pairs one thread is faster


def _n_threads(work: float) -> int:
    return n_threads(work, MIN_PAIRS_PER_THREAD)


def _threaded(fn, args, items: np.ndarray, work: float, per_thread: int = 4) -> None:
    """fn(*args, chunk) over chunks of ``items`` on the threads of :mod:`.threads` (the
    nogil kernels write disjoint rows); one direct call when ``work`` (element pairs) is
    too small to pay for threads.  ``per_thread`` chunks per thread, each a run of
    ``items``, taken by the threads as they become free."""
    nt = min(_n_threads(work), len(items))
    if nt <= 1:
        fn(*args, items)
        return
    run_chunks(lambda c: fn(*args, c), np.array_split(items, min(len(items), per_thread * nt)),
               nt)


ROW_CHUNKS_PER_THREAD = 8   # row chunks per thread (taken dynamically) in assemble


def _rows_chunk(args, out, rows):
    """The row loop on the rows ``rows`` (one chunk): a task of :func:`_threaded`."""
    _assemble_rows_serial(*args, out, rows, np.array([0, len(rows)], dtype=np.int64))


def _mirror_upper(A: np.ndarray) -> None:
    nb = (A.shape[0] + 63) // 64
    _threaded(_mirror_rows, (A,), interleaved(nb), 0.5 * A.shape[0] ** 2 / 64)


@lru_cache(maxsize=None)
def rules(n_log: int = 0):
    """(gx, gw, lx, lw) of :func:`hpfebe.quadrature.rule_tables` (NMAX) with the
    log-weighted rules only for n <= ``n_log``: those are what the singular integration
    of degree p <= pmax reads (n_log = pmax + 2), and building all 48 costs ~0.5-1 s of
    Python at the first call of a process, most of a warm start."""
    return rule_tables(NMAX, n_log)


def log_rule_count(pmax: int) -> int:
    """Largest log-weighted Gauss order the integration reads for degrees <= pmax: the
    nl = (deg + 3) // 2 + 1 of :mod:`.integration`, deg <= 2 pmax."""
    return (2 * pmax + 3) // 2 + 1


NTAB = 12  # far pairs needing fewer Gauss points than this use tabulated basis values


@lru_cache(maxsize=None)
def _far_tables(kind: int, pmax: int):
    """Basis values tab[p, n, a, k] at the n-point Gauss nodes (on [0,1]) for degrees
    p <= pmax, and order thresholds thr[deg, n]: the smallest distance/half-length ratio
    for which n points meet integration.TOL (the inverse of integration._order)."""
    gx = rules()[0]
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


COMPILE_GC_THRESHOLD = (10000, 50, 100)   # gc thresholds while numba compiles the kernels


@contextmanager
def _first_call(dispatcher):
    """Around the first call of ``dispatcher`` in a process (numba compiles it, or loads it
    from its cache): Python's cyclic GC with larger thresholds (COMPILE_GC_THRESHOLD),
    restored after.  numba's compiler allocates ~10^6 short-lived cyclic objects, and with
    the default thresholds (700, 10, 10) the repeated full collections were 12 % of a cold
    start (issue 14: first LaplaceBEM.V + LameBEM.S_hat 13.8 -> 12.0 s CPU with the GC
    off, -1.2 s with these thresholds in interleaved runs, +40 MB peak memory).  The
    thresholds are per process: nested or concurrent entries share one save/restore."""
    if dispatcher.signatures:
        yield
        return
    with _GC_LOCK:
        if _GC_STATE["depth"] == 0:
            _GC_STATE["saved"] = gc.get_threshold()
            gc.set_threshold(*COMPILE_GC_THRESHOLD)
        _GC_STATE["depth"] += 1
    try:
        yield
    finally:
        with _GC_LOCK:
            _GC_STATE["depth"] -= 1
            if _GC_STATE["depth"] == 0:
                gc.set_threshold(*_GC_STATE["saved"])


_GC_LOCK = threading.Lock()
_GC_STATE = {"depth": 0, "saved": None}


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
    pmax = int(mesh.degrees.max())
    if pmax > P_MAX:
        raise ValueError(f"degree p must be <= {P_MAX}, got {pmax}")
    gx, gw, lx, lw = rules(log_rule_count(pmax))
    gll_x, gll_b = gll_tables(P_MAX)
    logc = np.ascontiguousarray(np.asarray(logc, dtype=float).reshape(d * d))
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    kt, degt, dofs_t = _space_arrays(test)
    kr, degr, dofs_r = _space_arrays(trial)
    out = zeros_aligned((test.ndof * d, trial.ndof * d))
    nodes, elements = mesh.nodes, mesh.elements
    with _first_call(_element_geometry):
        normals, L, mid = _element_geometry(nodes, elements)
    ne = elements.shape[0]
    args = (kernel, logc, bool(logc.any()), kp, d, nodes, elements, normals, L, mid,
            kt, degt, dofs_t, kr, degr, dofs_r, symmetric, gx, gw, lx, lw, gll_x, gll_b,
            _far_tables(kt, pmax), _far_tables(kr, pmax), _order_thresholds(pmax))
    # rows in chunks (ROW_CHUNKS_PER_THREAD per thread, the interleaved order balancing
    # the triangle of a symmetric matrix) on Python threads, each chunk one call of the
    # nogil row loop, taken by the threads as they become free.  One thread: one direct
    # call (numba compiling it from inside _threaded's frames took 1.6 s more CPU time
    # of a cold start, measured repeatedly, cause unknown).  The order of the rows does
    # not change a bit of the result: each row is one test element's, summed over j.
    work = ne * ne * (0.5 if symmetric else 1.0)
    if _n_threads(work) <= 1:
        with _first_call(_assemble_rows_serial):
            _assemble_rows_serial(*args, out, np.arange(ne),
                                  np.array([0, ne], dtype=np.int64))
        if symmetric:
            _mirror_rows(out, np.arange((out.shape[0] + 63) // 64))
    else:
        with _first_call(_assemble_rows_serial):      # (gc thresholds: per process)
            _threaded(_rows_chunk, (args, out),
                      interleaved(ne) if symmetric else np.arange(ne), work,
                      per_thread=ROW_CHUNKS_PER_THREAD)
        if symmetric:
            # dofs of W_hp grow with the element index, so the pairs j >= i filled the
            # upper triangle
            _mirror_upper(out)
    if not all_finite(out):
        raise FloatingPointError("assembly produced non-finite entries "
                                 "(degenerate geometry or degree too high?)")
    return out


def local_block(kernel, logc, kp, mesh, i: int, j: int, test_kind: int, trial_kind: int,
                d: int = 1) -> np.ndarray:
    """Local block of the pair (test element i, trial element j) with basis kinds
    0 (Legendre, W_hp) or 1 (GLL Lagrange, V_hp) at the elements' degrees, by the same
    integration functions as :func:`assemble` uses for near pairs; for tests."""
    gx, gw, lx, lw = rules(log_rule_count(int(mesh.degrees.max())))
    gll_x, gll_b = gll_tables(P_MAX)
    logc = np.ascontiguousarray(np.asarray(logc, dtype=float).reshape(d * d))
    kp = np.ascontiguousarray(np.asarray(kp, dtype=float).reshape(-1))
    haslog = bool(np.any(logc != 0.0))
    pt, pr = int(mesh.degrees[i]), int(mesh.degrees[j])
    nmax = gx.shape[0] - 1
    pmax = max(pt, pr) + 1
    blk = np.zeros((pmax * d, pmax * d))
    phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack = _scratch(nmax, pmax, d)
    normals = np.ascontiguousarray(mesh.normals)
    elements = mesh.elements
    aI, bI = mesh.nodes[elements[i, 0]], mesh.nodes[elements[i, 1]]
    aJ, bJ = mesh.nodes[elements[j, 0]], mesh.nodes[elements[j, 1]]
    shared = [(q, r) for q in range(2) for r in range(2) if elements[i, q] == elements[j, r]]
    if i == j:
        coincident_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], test_kind, pt,
                         trial_kind, pr, gx, gw, lx, lw, gll_x, gll_b, phi, psi, Kq, rxs, rys,
                         blk)
    elif shared:
        vI, vJ = shared[-1]
        adjacent_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                       vI, vJ, test_kind, pt, trial_kind, pr, gx, gw, lx, lw, gll_x, gll_b,
                       phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack, blk)
    else:
        rI, rJ = nearest_ends(aI, bI, aJ, bJ)
        far_block(kernel, logc, haslog, kp, d, aI, bI, normals[i], aJ, bJ, normals[j],
                  0.0, 1.0, 0.0, 1.0, rI, rJ, test_kind, pt, trial_kind, pr, gx, gw, gll_x,
                  gll_b, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack, blk)
    mt = (pt if test_kind == 0 else pt + 1) * d
    mr = (pr if trial_kind == 0 else pr + 1) * d
    return blk[:mt, :mr].copy()


@njit(cache=True, nogil=True)
def _sandwich_rows(indptr, indices, data, V, out, both, rows):
    """out[i, j] = (R V R^T)[i, j] for i in ``rows``, j >= i (R in CSR), and out[j, i] if
    ``both``.  Threads write the upper triangle only and mirror it afterwards: a thread
    writing out[j, i] too touched every row of out, and on a fresh matrix the first
    chunk took all page faults, 0.3 s of a serial step at N = 4096; one thread writes
    both (the mirror pass costs it ~15 % of W)."""
    n = out.shape[0]
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
                out[j, i] = acc


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


def sandwich(T, V: np.ndarray) -> np.ndarray:
    """T^T V T for sparse T (n_W x n_V) and dense symmetric V (n_W x n_W), exactly
    symmetric: the hypersingular operator W = T^T V T from the single layer V of the
    arc-length derivatives (T: :meth:`ContinuousSpace.derivative_matrix`)."""
    T = T.tocsr()
    if T.has_canonical_format:
        indptr, indices, data = _transpose_csr(T.indptr, T.indices, T.data, T.shape[1])
    else:     # duplicates summed as scipy does
        R = T.T.tocsr()
        R.sort_indices()
        indptr, indices, data = R.indptr, R.indices, R.data
    n = T.shape[1]
    out = zeros_aligned((n, n))
    V = np.ascontiguousarray(V)
    if _n_threads(0.5 * n * n) <= 1:
        _sandwich_rows(indptr, indices, data, V, out, True, np.arange(n))
    else:
        _threaded(_sandwich_rows, (indptr, indices, data, V, out, False), interleaved(n),
                  0.5 * n * n)
        _mirror_upper(out)
    return out
