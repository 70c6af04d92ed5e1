"""Dense Galerkin assembly of boundary integral operators, parallel over element rows.

One routine, :func:`assemble`, serves every operator: it is specialised by the kernel
(an id of :mod:`hpfebe.bem.kernels`: Laplace V and K, Lame) and by the test/trial
spaces.  Each pair of elements is classified (coincident / adjacent / far),
integrated by the matching function of :mod:`hpfebe.bem.integration` into a local block,
and scattered (the numba kernels, one function per case: :mod:`.assembly_kernels`).
Rows belong to test elements, so the loop over test elements runs in
parallel without write conflicts (the test space must be discontinuous: W_hp): chunks
of rows of the one compiled row loop, ``_assemble_rows_serial`` (``nogil``), taken by
numba.get_num_threads() Python threads as they become free; with one thread (every
Snakemake job) or a mesh too small to pay for threads, one direct call.  The mirror of
the upper triangle, the sandwich W = T^T V T and the finiteness check run the same way.
(Issue 14: this replaced a numba parfor over static row chunks - the same 2-thread wall
time at N = 1024 and 4096 on a quiet machine, but compiling the parfor cost a 2-thread
process ~9 s of a cold start; the serial steps the threads now share were 3 % of V + K + W
at N = 4096, the sandwich's page faults 0.3 s in one task.)

Caching: numba's on-disk cache keys a function on the contents of its own file only; the
cached ``_assemble_rows_serial`` keeps the machine code of the :mod:`.integration` and
:mod:`.kernels` functions it was compiled with.  :mod:`hpfebe._numba_cache` therefore
keys the whole cache directory on every kernel source: an edit of those files gets a
fresh cache.
"""

from __future__ import annotations

import gc
import math
import threading
from contextlib import contextmanager
from functools import lru_cache

import numpy as np

from ..quadrature import rule_tables
from ..spaces import P_MAX, DiscontinuousSpace, eval_basis, gll_tables
from .assembly_kernels import (_assemble_rows_serial, _element_geometry, _mirror_rows,
                               _sandwich_rows, _scratch, _transpose_csr)
from .integration import (NMAX, TOL, adjacent_block, coincident_block, far_block,
                          nearest_ends)
from .threads import all_finite, interleaved, n_threads, run_chunks, zeros_aligned


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
