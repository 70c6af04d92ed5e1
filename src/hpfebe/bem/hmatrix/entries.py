"""Entries of the Galerkin matrices on element index sets: the sub-block entry point of the
compressed operators (the dense :func:`hpfebe.bem.assembly.assemble` fills whole
matrices only).

Index space ("broken" space, the H-matrix's own numbering): the elements in the order of
the cluster tree, each with its local functions (``n_local(kind, p_e)``, times d
interleaved components, row = k d + c as in the local blocks of
:mod:`hpfebe.bem.integration`).  For W_hp this is W_hp itself permuted; for V_hp it is
the broken (element-wise) GLL space, which the operators map to V_hp by the sparse
assembly matrix S (:mod:`.operators`).

One local block (test element i, trial element j) is integrated exactly as the dense
row loop does (:mod:`hpfebe.bem.assembly_kernels`): well separated pairs by tensor Gauss
with orders from the thresholds of ``integration._order`` on tabulated basis values,
every other pair by ``_near_block`` (coincident, adjacent, general: the singular and
near-singular quadrature).  ``deriv`` (the hypersingular operator in its
integration-by-parts form, DESIGN.md) turns the Legendre x Legendre block A of the
single-layer-type kernel into the GLL x GLL block D_i^T A D_j, with D_e the Legendre
coefficients of the arc-length derivatives of the GLL functions of element e (the local
block of ``ContinuousSpace.derivative_matrix``): <W u, v> = <Vt du/ds, dv/ds>.

The ``op`` tuples (numba cannot inline a call of more than 30 arguments, DESIGN.md on
kernel ids):

    kern  = (kernel, logc, haslog, kp, d, kt, kr, deriv)
    geom  = (nodes, elements, normals, L, mid, degs, order)     order: tree position -> e
    rules = (gx, gw, lx, lw, gll_x, gll_b, tab_t, tab_r, thr, dtab)
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit

from ...quadrature import gauss_legendre
from ...spaces import P_MAX, gll_tables, lagrange_values, legendre_values, n_local
from ..assembly import NTAB, _far_tables, _order_thresholds, log_rule_count, rules
from ..assembly_kernels import _near_block
from ..integration import ETA
from ..kernels import INV_2PI, KP_LAPLACE_LOG_R, LAPLACE_DL, LAPLACE_SL, kernel_batch


def derivative_table(pmax: int) -> np.ndarray:
    """dtab[p, :p, :p + 1]: Legendre coefficients of dl_j/dt of the GLL Lagrange
    functions l_j of degree p on [-1, 1] (times 2 / L_e the local block of
    ``ContinuousSpace.derivative_matrix`` on element e)."""
    tab = np.zeros((pmax + 1, pmax, pmax + 1))
    for p in range(1, pmax + 1):
        xq, wq = gauss_legendre(p + 1)
        Pk = legendre_values(p, xq)
        dl = lagrange_values(p, xq, True)
        tab[p, :p, :p + 1] = (Pk * wq[:, None]).T @ dl * ((2 * np.arange(p) + 1) / 2.0)[:, None]
    return tab


@lru_cache(maxsize=None)
def order_thresholds(degmax: int, qtol: float) -> np.ndarray:
    """thr[deg, n]: the smallest distance / half-length ratio rho_- for which n Gauss
    points integrate a far pair to the relative accuracy ``qtol`` (the estimate
    rho^-(2n - deg) of ``integration._order``, rho = r + sqrt(r^2 + 1)); at qtol =
    integration.TOL these are the thresholds of the dense assembly."""
    ntab = NTAB
    thr = np.full((degmax + 1, ntab + 1), np.inf)
    for deg in range(degmax + 1):
        for n in range(1, ntab + 1):
            if 2 * n > deg:
                rho = math.exp(math.log(1.0 / qtol) / (2 * n - deg))
                thr[deg, n] = 0.5 * (rho - 1.0 / rho)
    thr.setflags(write=False)
    return thr


def rule_tuple(kt: int, kr: int, pmax: int, qtol: float | None = None):
    """The ``rules`` tuple of the module doc for raw basis kinds kt (test), kr (trial);
    ``qtol``: the relative quadrature accuracy of the tabulated far pairs (None: that of
    the dense assembly, integration.TOL)."""
    gx, gw, lx, lw = rules(log_rule_count(pmax))
    gll_x, gll_b = gll_tables(P_MAX)
    thr = _order_thresholds(pmax) if qtol is None else order_thresholds(pmax, float(qtol))
    return (gx, gw, lx, lw, gll_x, gll_b, _far_tables(kt, pmax), _far_tables(kr, pmax),
            thr, derivative_table(pmax))


@njit(cache=True)
def local_size(kind, deriv, p, d):
    """Rows (or columns) of the output local block of an element of degree p."""
    if deriv:
        return (p + 1) * d
    return n_local(kind, p) * d


def work_arrays(rules, pmax: int, d: int):
    """Scratch of :func:`fill` for degrees <= pmax: (scratch, raw, blk), the scratch
    tuple of ``assembly_kernels._scratch`` (built here in numpy: a cached numba function
    returning this nested tuple to Python failed in numba 0.68, "descr is NULL")."""
    nmax = rules[0].shape[0] - 1
    m = pmax + 1
    e = np.empty
    scratch = (e(m), e(m), e((nmax, m)), e((nmax, m)), e((nmax * nmax, d * d)),
               e((nmax, m, d * d)), e(nmax * nmax), e(nmax * nmax), e(64 * nmax),
               e(64 * nmax), e((128, 4)))
    return scratch, e((m * d, m * d)), e((m * d, m * d))


@njit(cache=True, nogil=True)
def _differentiate(raw, blk, dtab, pt, pr, d, si, sj):
    """blk = D_i^T raw D_j with D_e = dtab[p_e] * s_e per component (interleaved)."""
    for k in range(pt + 1):
        for l in range(pr + 1):
            for c1 in range(d):
                for c2 in range(d):
                    acc = 0.0
                    for a in range(pt):
                        da = dtab[pt, a, k]
                        if da == 0.0:
                            continue
                        s = 0.0
                        for b in range(pr):
                            s += raw[a * d + c1, b * d + c2] * dtab[pr, b, l]
                        acc += da * s
                    blk[k * d + c1, l * d + c2] = acc * si * sj


@njit(cache=True, nogil=True)
def fill(kern, geom, rules, toff, roff, r0, r1, c0, c1, krow, lcol, out, work):
    """Entries of the test elements at tree positions r0..r1-1 against the trial
    elements at c0..c1-1 into the 2D array out (offsets ``toff``, ``roff`` of the tree
    positions in the test and trial numbering, relative to r0, c0): the whole block
    (krow = lcol = -1), or only the local row ``krow`` (out of shape (1, n)) or the local
    column ``lcol`` (out (m, 1)).

    Per pair (i, j) the local block as the dense row loop computes it (module doc): the
    tuples are unpacked once, before the loop (an unpacking per pair, i.e. a reference
    count per array, cost ~500 ns a pair, more than the quadrature of a far pair)."""
    kernel, logc, haslog, kp, d, kt, kr, deriv = kern
    nodes, elements, normals, L, mid, degs, order = geom
    gx, gw, lx, lw, gll_x, gll_b, tab_t, tab_r, thr, dtab = rules
    scratch, raw, blk = work
    phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack = scratch
    ntab = tab_t.shape[1] - 1
    bt = toff[r0]
    br = roff[c0]
    for p in range(r0, r1):
        i = order[p]
        pt = degs[i]
        mt = n_local(kt, pt)
        aI0, aI1 = nodes[elements[i, 0], 0], nodes[elements[i, 0], 1]
        bI0, bI1 = nodes[elements[i, 1], 0], nodes[elements[i, 1], 1]
        for q in range(c0, c1):
            j = order[q]
            pr = degs[j]
            mr = n_local(kr, pr)
            dm0 = mid[i, 0] - mid[j, 0]
            dm1 = mid[i, 1] - mid[j, 1]
            dlow = math.sqrt(dm0 * dm0 + dm1 * dm1) - 0.5 * (L[i] + L[j])
            nx = ntab
            ny = ntab
            if dlow >= 2.0 * ETA * max(L[i], L[j]):       # as the dense row loop
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
                aJ0, aJ1 = nodes[elements[j, 0], 0], nodes[elements[j, 0], 1]
                bJ0, bJ1 = nodes[elements[j, 1], 0], nodes[elements[j, 1], 1]
                for a in range(nx):
                    x0 = aI0 + gx[nx, a] * (bI0 - aI0)
                    x1 = aI1 + gx[nx, a] * (bI1 - aI1)
                    for b in range(ny):
                        rxs[a * ny + b] = x0 - (aJ0 + gx[ny, b] * (bJ0 - aJ0))
                        rys[a * ny + b] = x1 - (aJ1 + gx[ny, b] * (bJ1 - aJ1))
                if kernel == LAPLACE_DL:                    # kernels.laplace_double_layer
                    nJ0, nJ1 = normals[j, 0], normals[j, 1]
                    for t in range(nx * ny):
                        Kq[t, 0] = INV_2PI * (rxs[t] * nJ0 + rys[t] * nJ1) / (
                            rxs[t] * rxs[t] + rys[t] * rys[t])
                elif kernel == LAPLACE_SL:                  # kernels.laplace_single_layer
                    for t in range(nx * ny):
                        Kq[t, 0] = kp[KP_LAPLACE_LOG_R]
                else:
                    kernel_batch(kernel, rxs, rys, nx * ny, normals[i], normals[j], kp, Kq)
                for a in range(nx):
                    for b in range(ny):
                        t = a * ny + b
                        w = gw[nx, a] * gw[ny, b] * L[i] * L[j]
                        if haslog:
                            lr = 0.5 * math.log(rxs[t] * rxs[t] + rys[t] * rys[t])
                            for c in range(d * d):
                                Kq[t, c] = w * (Kq[t, c] + logc[c] * lr)
                        else:
                            for c in range(d * d):
                                Kq[t, c] *= w
                for a in range(nx):
                    for l in range(mr):
                        for c in range(d * d):
                            acc = 0.0
                            for b in range(ny):
                                acc += Kq[a * ny + b, c] * tab_r[pr, ny, b, l]
                            tmp[a, l, c] = acc
                for k in range(mt):
                    for l in range(mr):
                        for cc1 in range(d):
                            for cc2 in range(d):
                                acc = 0.0
                                for a in range(nx):
                                    acc += tab_t[pt, nx, a, k] * tmp[a, l, cc1 * d + cc2]
                                raw[k * d + cc1, l * d + cc2] = acc
            else:
                _near_block(kernel, logc, haslog, kp, d, nodes, elements, normals,
                            nodes[elements[i, 0]], nodes[elements[i, 1]], i, j, kt, pt, kr,
                            pr, mt, mr, (gx, gw, lx, lw, gll_x, gll_b),
                            (phi, psi, Phi, Psi, Kq, tmp, rxs, rys, wx, ww, stack), raw)
            if deriv:
                _differentiate(raw, blk, dtab, pt, pr, d, 2.0 / L[i], 2.0 / L[j])
                src = blk
                mo, no = (pt + 1) * d, (pr + 1) * d
            else:
                src = raw
                mo, no = mt * d, mr * d
            if krow >= 0:
                o = roff[q] - br
                for l in range(no):
                    out[0, o + l] = src[krow, l]
            elif lcol >= 0:
                o = toff[p] - bt
                for k in range(mo):
                    out[o + k, 0] = src[k, lcol]
            else:
                ot = toff[p] - bt
                orr = roff[q] - br
                for k in range(mo):
                    for l in range(no):
                        out[ot + k, orr + l] = src[k, l]


@njit(cache=True)
def fill_row(kern, geom, rules, toff, roff, tpos, k, c0, c1, out, work):
    """Row k (local) of the test element at tree position ``tpos`` against the trial
    elements at tree positions c0..c1-1, into out[0 : roff[c1] - roff[c0]]."""
    fill(kern, geom, rules, toff, roff, tpos, tpos + 1, c0, c1, k, -1,
         out.reshape(1, out.shape[0]), work)


@njit(cache=True)
def fill_col(kern, geom, rules, toff, roff, r0, r1, spos, l, out, work):
    """Column l (local) of the trial element at tree position ``spos`` against the test
    elements at tree positions r0..r1-1, into out[0 : toff[r1] - toff[r0]]."""
    fill(kern, geom, rules, toff, roff, r0, r1, spos, spos + 1, -1, l,
         out.reshape(out.shape[0], 1), work)


@njit(cache=True)
def fill_dense(kern, geom, rules, toff, roff, r0, r1, c0, c1, out, work):
    """The dense block of the tree positions r0..r1-1 (test) x c0..c1-1 (trial) into
    out (row-major, (toff[r1] - toff[r0]) x (roff[c1] - roff[c0]))."""
    fill(kern, geom, rules, toff, roff, r0, r1, c0, c1, -1, -1, out, work)
