"""Threaded BEM assembly (issue 14): row chunks of the nogil row loop on Python threads, the
threaded sandwich W = T^T V T and finiteness check give bitwise the matrices of one thread."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem import LameBEM, LaplaceBEM, assembly
from hpfebe.bem.kernels import LAPLACE_DL, LAPLACE_SL
from hpfebe.bem.laplace import NO_LOG, SINGLE_LAYER_LOGC
from hpfebe.bem import threads
from hpfebe.bem.threads import interleaved

pytestmark = pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2,
                                reason="needs NUMBA_NUM_THREADS >= 2")


def _meshes():
    sq = [(0, 0), (1, 0), (1, 1), (0, 1)]
    m = BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (0, 1)], h=0.25, p=1)
    yield "square", BoundaryMesh.polygon(sq, n=6, p=1)
    yield "mixed", m.with_degrees(np.arange(m.n_elements) % 4 + 1)
    yield "slit", BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1.0001, 1), (1.0001, 0.2),
                                        (1, 0.2), (1, 1), (0, 1)], h=0.3, p=2)


def _laplace(mesh):
    op = LaplaceBEM(mesh)
    V = assembly.assemble(LAPLACE_SL, SINGLE_LAYER_LOGC, op.kp, op.W_space, op.W_space,
                          symmetric=True)
    K = assembly.assemble(LAPLACE_DL, NO_LOG, [0.0], op.W_space, op.V_space)
    return V, K, assembly.sandwich(op.T, V)


def _with_threads(nt, f, *args):
    old = numba.get_num_threads()
    numba.set_num_threads(nt)
    try:
        return f(*args)
    finally:
        numba.set_num_threads(old)


@pytest.mark.parametrize("name", ["square", "mixed", "slit"])
def test_threads_bitwise_laplace(name, monkeypatch):
    mesh = dict(_meshes())[name]
    one = _with_threads(1, _laplace, mesh)
    monkeypatch.setattr(assembly, "MIN_PAIRS_PER_THREAD", 1)    # threads on small meshes
    two = _with_threads(2, _laplace, mesh)
    for a, b in zip(one, two):
        assert a.dtype == b.dtype and np.array_equal(a, b)
        assert np.array_equal(np.signbit(a), np.signbit(b))


def test_threads_bitwise_lame(monkeypatch):
    mesh = dict(_meshes())["mixed"]

    def mats():
        op = LameBEM(mesh, 1.0, 0.3)
        return op.V, op.K, op.W

    one = _with_threads(1, mats)
    monkeypatch.setattr(assembly, "MIN_PAIRS_PER_THREAD", 1)
    two = _with_threads(2, mats)
    for a, b in zip(one, two):
        assert np.array_equal(a, b)


def test_threaded_finiteness_check(monkeypatch):
    monkeypatch.setattr(threads, "MIN_ENTRIES_PER_THREAD", 1)
    for A in (np.zeros((300, 200)), np.zeros((300, 200), complex)):
        for nt in (1, 2):
            assert _with_threads(nt, threads.all_finite, A)
            for bad in (np.nan, np.inf, -np.inf, complex(0, np.nan), complex(np.inf, 0)):
                if not np.iscomplexobj(A) and isinstance(bad, complex):
                    continue
                for r, c in ((299, 199), (0, 0)):
                    B = A.copy()
                    B[r, c] = bad
                    assert not _with_threads(nt, threads.all_finite, B)


def test_threaded_chunks_cover_rows_once(monkeypatch):
    """Every row goes to exactly one chunk, ROW_CHUNKS_PER_THREAD per thread."""
    seen = []
    monkeypatch.setattr(assembly, "MIN_PAIRS_PER_THREAD", 1)
    _with_threads(2, assembly._threaded, lambda c: seen.append(np.array(c)), (),
                  interleaved(101), 1e9, assembly.ROW_CHUNKS_PER_THREAD)
    assert len(seen) == 2 * assembly.ROW_CHUNKS_PER_THREAD
    assert np.array_equal(np.sort(np.concatenate(seen)), np.arange(101))


def test_first_call_restores_gc_thresholds():
    """The larger gc thresholds of a first (compiling) call are undone, also when nested."""
    import gc

    class Fresh:
        signatures: tuple = ()

    before = gc.get_threshold()
    with assembly._first_call(Fresh()):
        assert gc.get_threshold() == assembly.COMPILE_GC_THRESHOLD
        with assembly._first_call(Fresh()):
            assert gc.get_threshold() == assembly.COMPILE_GC_THRESHOLD
        assert gc.get_threshold() == assembly.COMPILE_GC_THRESHOLD
    assert gc.get_threshold() == before
