"""Straight-element (p = 1) test meshes of the closed-form tests
(tests/bem/test_bem_lowest_order.py, tests/bem/test_bem_lowest_order_lame.py): squares, an
L-shape, slits, a wedge, a star, graded and n-gon meshes, two-curve boundaries, a tiny
element beside collinear ones."""

import math

import numpy as np

from hpfebe import BoundaryMesh

SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]


def slit(d):
    return BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1 + d, 1), (1 + d, 0.2),
                                 (1, 0.2), (1, 1), (0, 1)], h=0.25, p=1)


def graded(levels):
    """L-shape refined ``levels`` times at the re-entrant corner."""
    m = BoundaryMesh.polygon([(0, 0), (2, 0), (2, 2), (1, 2), (1, 1), (0, 1)], n=2, p=1)
    for _ in range(levels):
        d = np.hypot(*(0.5 * (m.a + m.b) - np.array([1.0, 1.0])).T)
        m = m.refine(np.flatnonzero(d <= d.min() * 1.0001))
    return m


def wedge(deg):
    t = math.radians(deg)
    return BoundaryMesh.polygon([(0, 0), (1, 0), (math.cos(t), math.sin(t))], n=[8, 1, 8],
                                p=1)


def star(k=5):
    r = np.where(np.arange(2 * k) % 2 == 0, 1.0, 0.4)
    t = np.pi * np.arange(2 * k) / k
    return BoundaryMesh.polygon(np.column_stack([r * np.cos(t), r * np.sin(t)]), n=3, p=1)


def ngon(n):
    th = 2 * np.pi * np.arange(n) / n
    return BoundaryMesh.from_segments(np.column_stack([np.cos(th), np.sin(th)]),
                                      np.column_stack([np.arange(n), (np.arange(n) + 1) % n]))


def curves(nodes, seg, refine):
    m = BoundaryMesh.from_segments(nodes, seg)
    for _ in range(refine):
        m = m.refine()
    return m


def annulus():
    """Square with a square hole (two closed curves)."""
    return curves([(0, 0), (3, 0), (3, 3), (0, 3), (1, 1), (2, 1), (2, 2), (1, 2)],
                  [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)], 3)


def near_touching(gap=1e-7):
    """Two unit squares side by side, ``gap`` apart (two closed curves)."""
    x = 1.0 + gap
    return curves([(0, 0), (1, 0), (1, 1), (0, 1), (x, 0), (x + 1, 0), (x + 1, 1), (x, 1)],
                  [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)], 3)


def tiny_beside_collinear(short=1e-9):
    return BoundaryMesh.polygon([(0, 0), (1, 0), (1, short), (1, 1), (0, 1)],
                                n=[4, 1, 3, 4, 4], p=1)


MESHES = {
    "square16": lambda: BoundaryMesh.polygon(SQUARE, n=4, p=1),
    "square64": lambda: BoundaryMesh.polygon(SQUARE, n=16, p=1),
    "square256": lambda: BoundaryMesh.polygon(SQUARE, n=64, p=1),
    "L-shape": lambda: BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2),
                                             (0, 2)], n=8, p=1),
    "slit-1e-2": lambda: slit(1e-2),
    "slit-1e-5": lambda: slit(1e-5),
    "slit-1e-8": lambda: slit(1e-8),
    "wedge-3deg": lambda: wedge(3.0),
    "star": star,
    "graded-12": lambda: graded(12),
    "256-gon": lambda: ngon(256),
    "annulus": annulus,
    "near-touching": near_touching,
    "tiny-1e-9": tiny_beside_collinear,
}


def rel(A, B):
    """max |A - B| / max |B|."""
    A, B = np.asarray(A), np.asarray(B)
    return np.abs(A - B).max() / np.abs(B).max()
