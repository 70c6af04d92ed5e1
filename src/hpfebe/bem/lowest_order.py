"""Closed-form Galerkin entries of the lowest-order Laplace operators (p = 1).

At p = 1 the single layer V lives on W_hp = P0 (one constant per element) and the double
layer K has test P0 and trial P1 (the GLL hats of V_hp, dofs at the element ends); the
hypersingular W = T^T V T follows from V.  For straight elements these entries have
closed forms, derived in complex notation (points of R^2 as complex numbers) in
:mod:`.lowest_order_pairs` with the far-pair series and their accuracy ((V1), (K1));
the Lame matrices from the same pass: :mod:`.lowest_order_lame`.

:func:`laplace_p1_vk` assembles V and K of a mesh with all degrees 1 in one pass over the
unordered element pairs, on several threads for large meshes with the same bits
(:class:`~hpfebe.bem.laplace.LaplaceBEM` uses it there; the general quadrature path of
:mod:`hpfebe.bem.assembly` remains the reference), and
:func:`laplace_p1_w` the hypersingular operator W = T^T V T from V without forming T
(T at p = 1: -+1/L_e at the two ends of element e).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .lowest_order_pairs import (INV_2PI, N_SERIES, Q_NEAR, Q_SMOOTH, _k_entries, _on_line,
                                 _pair_far, _pair_near, _smooth_pair)
from .threads import all_finite, interleaved, n_threads, run_chunks, zeros_aligned


@njit(cache=True, nogil=True)
def _element_data(nodes, elements):
    """Start and end points (complex), lengths and unit directions of the elements."""
    ne = elements.shape[0]
    zs = np.empty(ne, np.complex128)
    ze = np.empty(ne, np.complex128)
    L = np.empty(ne)
    dirs = np.empty(ne, np.complex128)
    for e in range(ne):
        zs[e] = complex(nodes[elements[e, 0], 0], nodes[elements[e, 0], 1])
        ze[e] = complex(nodes[elements[e, 1], 0], nodes[elements[e, 1], 1])
        d = ze[e] - zs[e]
        L[e] = math.hypot(d.real, d.imag)
        dirs[e] = d / L[e]
    return zs, ze, L, dirs


@njit(cache=True, nogil=True)
def _vk_rows(zs, ze, L, dirs, nodes, elements, vdofs, wdofs, logR, V, K, Qm, R, direct,
             rows):
    """V (symmetric) and K (W_hp x V_hp) of a mesh with all degrees 1 for the test
    elements i in ``rows``, over the pairs j > i: each gives V_ij = V_ji and the K entries
    of (i, j) (row i) and of (j, i) (row j).  ``direct``: the latter are added to K;
    otherwise stored in R[w_j, 2 i + r] (r = 0, 1 the ends of E_i) for :func:`_gather`, so
    that several threads (disjoint ``rows``) never add to one entry.  If ``Qm`` is not
    empty (W_hp x W_hp, complex), also Q_ij = Q_ji of (Q1), (Q2) (u^2 L_i L_j exactly for
    collinear pairs, the identical pair included)."""
    want_q = Qm.shape[0] > 0
    ne = elements.shape[0]
    ap = np.empty(N_SERIES + 1, np.complex128)
    bp = np.empty(N_SERIES + 1, np.complex128)
    for i in rows:
        ai, bi, Li, u = zs[i], ze[i], L[i], dirs[i]
        wi = wdofs[i]
        # identical pair: I = L^2 (log L - 3/2); K = 0 (collinear)
        V[wi, wi] = -INV_2PI * Li * Li * (math.log(Li) - logR - 1.5)
        if want_q:
            Qm[wi, wi] = (u * u) * (Li * Li)
        for j in range(i + 1, ne):
            aj, bj, Lj, v = zs[j], ze[j], L[j], dirs[j]
            # differences of nearby nodes first (exact, Sterbenz): w_m to relative eps
            wm = 0.5 * ((ai - aj) + (bi - bj))
            h = 0.5 * (Li + Lj)
            r = abs(wm)
            if h >= Q_NEAR * r and (h >= Q_SMOOTH * r or not _smooth_pair(u, v, wm, r)):
                I, J0, J1, J0r, J1r, Q = _pair_near(ai, bi, aj, bj, Li, Lj, u, v, wm, logR)
            else:
                I, J0, J1, J0r, J1r, Q = _pair_far(Li, Lj, u, v, wm, logR, ap, bp)
            wj = wdofs[j]
            V[wi, wj] = -INV_2PI * I
            V[wj, wi] = V[wi, wj]
            if want_q:
                if _on_line(nodes[elements[i, 0]], nodes[elements[i, 1]],
                            nodes[elements[j, 0]], v.imag, -v.real):
                    Q = (u * u) * (Li * Lj)
                Qm[wi, wj] = Q
                Qm[wj, wi] = Q
            # K of (test i, trial j) and of (test j, trial i)
            ka, kb = _k_entries(nodes[elements[i, 0]], nodes[elements[i, 1]],
                                nodes[elements[j, 0]], v, J0, J1)
            if vdofs[j, 0] >= 0:
                K[wi, vdofs[j, 0]] += ka
            if vdofs[j, 1] >= 0:
                K[wi, vdofs[j, 1]] += kb
            ka, kb = _k_entries(nodes[elements[j, 0]], nodes[elements[j, 1]],
                                nodes[elements[i, 0]], u, J0r, J1r)
            if direct:
                if vdofs[i, 0] >= 0:
                    K[wj, vdofs[i, 0]] += ka
                if vdofs[i, 1] >= 0:
                    K[wj, vdofs[i, 1]] += kb
            else:
                R[wj, 2 * i] = ka
                R[wj, 2 * i + 1] = kb


@njit(cache=True, nogil=True)
def _gather(R, vdofs, wdofs, K, rows):
    """K[w_j, dofs of E_i] += R[w_j, 2 i + r] for i < j, j in ``rows`` (the second pass of
    the threaded assembly).  Every K entry of a closed curve has at most two terms (a
    node lies on two elements), so the sum does not depend on their order: the result is
    bitwise that of the direct single-thread pass."""
    for j in rows:
        wj = wdofs[j]
        for i in range(j):
            if vdofs[i, 0] >= 0:
                K[wj, vdofs[i, 0]] += R[wj, 2 * i]
            if vdofs[i, 1] >= 0:
                K[wj, vdofs[i, 1]] += R[wj, 2 * i + 1]


MIN_PAIRS_PER_THREAD = 32768  # below this many element pairs per thread: one thread


def _n_threads(work: float) -> int:
    return n_threads(work, MIN_PAIRS_PER_THREAD)


def _threaded(fn, args, n: int, nt: int) -> None:
    """fn(*args, rows) over chunks of the rows 0..n-1 (interleaved: short and long rows of
    the triangle alternate, 4 chunks per thread) on ``nt`` threads (:mod:`.threads`;
    ``fn`` releases the GIL)."""
    run_chunks(lambda c: fn(*args, c), np.array_split(interleaved(n), 4 * nt), nt)


def applies(mesh) -> bool:
    """Whether the closed forms apply: every element of degree 1."""
    return bool(np.all(mesh.degrees == 1))


def _check_p1(W_space, V_space, scale: float, who: str) -> float:
    mesh = W_space.mesh
    if V_space.mesh is not mesh:
        raise ValueError("W_space and V_space must live on the same mesh")
    if not applies(mesh):
        raise ValueError(f"{who} needs all element degrees 1, got degrees "
                         f"{sorted(set(mesh.degrees.tolist()))}")
    scale = float(scale)
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be positive, got {scale!r}")
    return scale


def _p1_pass(W_space, V_space, scale: float, with_q: bool):
    """(V, K, Q) of the Laplace closed forms in one pass (Q: None unless ``with_q``)."""
    mesh = W_space.mesh
    ne = mesh.n_elements
    V = zeros_aligned((W_space.ndof, W_space.ndof))
    K = zeros_aligned((W_space.ndof, V_space.ndof))
    Q = zeros_aligned((W_space.ndof, W_space.ndof) if with_q else (0, 0), np.complex128)
    vdofs = np.ascontiguousarray(V_space.elem_dofs[:, :2])
    wdofs = np.ascontiguousarray(W_space.elem_dofs[:, 0])
    geo = _element_data(mesh.nodes, mesh.elements)
    args = (*geo, mesh.nodes, mesh.elements, vdofs, wdofs, math.log(scale), V, K, Q)
    nt = _n_threads(0.5 * ne * ne)
    if nt > 1:
        # rows of test elements on nt threads; the K entries of the pairs (j, i), j > i,
        # go through R (rows of several threads would add to one entry), then a second
        # threaded pass over the rows j adds them
        R = np.empty((W_space.ndof, 2 * ne))
        _threaded(_vk_rows, args + (R, False), ne, nt)
        _threaded(_gather, (R, vdofs, wdofs, K), ne, nt)
    else:
        _vk_rows(*args, np.empty((0, 0)), True, np.arange(ne))
    if not (all_finite(V) and all_finite(K) and all_finite(Q)):
        raise FloatingPointError("closed-form assembly produced non-finite entries "
                                 "(intersecting or degenerate elements?)")
    return V, K, (Q if with_q else None)


def laplace_p1_vk(W_space, V_space, scale: float):
    """(V, K) of the Laplace operators (module doc of :mod:`hpfebe.bem.laplace`) on a mesh
    with all degrees 1: V on W_space (P0) x W_space, K on W_space x V_space (P1), kernel
    scale R = ``scale``, by the closed forms (V1), (K1) and the far-pair series.  Serial,
    or on numba.get_num_threads() threads for large meshes (the same bits)."""
    scale = _check_p1(W_space, V_space, scale, "laplace_p1_vk")
    V, K, _ = _p1_pass(W_space, V_space, scale, False)
    return V, K


@njit(cache=True)
def _w_from_v(V, vdofs, L, W):
    """W = T^T V T at p = 1, T[e, dof] = -+1/L_e for the hats at the ends a_e, b_e of
    element e (the arc-length derivatives): the contributions of all element pairs, then
    the upper triangle mirrored (W exactly symmetric, as :func:`assembly.sandwich`)."""
    ne = V.shape[0]
    for e in range(ne):
        ae, be = vdofs[e, 0], vdofs[e, 1]
        for f in range(ne):
            af, bf = vdofs[f, 0], vdofs[f, 1]
            val = V[e, f] / (L[e] * L[f])
            if ae >= 0:
                if af >= 0:
                    W[ae, af] += val
                if bf >= 0:
                    W[ae, bf] -= val
            if be >= 0:
                if af >= 0:
                    W[be, af] -= val
                if bf >= 0:
                    W[be, bf] += val
    n = W.shape[0]
    for k in range(n):
        for l in range(k):
            W[k, l] = W[l, k]


def laplace_p1_w(V: np.ndarray, W_space, V_space) -> np.ndarray:
    """The hypersingular operator W = T^T V T (V_hp x V_hp) of a mesh with all degrees
    1 from its single layer V (W_space x W_space), without forming T (the same matrix as
    ``sandwich(V_space.derivative_matrix(W_space), V)`` to round-off)."""
    mesh = W_space.mesh
    if not applies(mesh):
        raise ValueError("laplace_p1_w needs all element degrees 1, got degrees "
                         f"{sorted(set(mesh.degrees.tolist()))}")
    V = np.ascontiguousarray(V, dtype=float)
    if V.shape != (W_space.ndof, W_space.ndof):
        raise ValueError(f"V must have shape {(W_space.ndof, W_space.ndof)}, got {V.shape}")
    W = zeros_aligned((V_space.ndof, V_space.ndof))
    _w_from_v(V, np.ascontiguousarray(V_space.elem_dofs[:, :2]), mesh.lengths, W)
    return W

