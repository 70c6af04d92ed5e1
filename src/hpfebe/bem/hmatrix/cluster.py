"""The cluster tree on the boundary elements and the block tree of an H-matrix.

Cluster tree (Hackbusch, "Hierarchical Matrices", Springer 2015, Sect. 5.3): the elements
are split recursively by the median of their midpoints along the longer side of the
bounding box of the cluster's element supports (the segments themselves, not only the
midpoints), down to clusters of at most ``leaf_size`` elements.  A cluster is a range
of tree positions: its dofs, in any space on the mesh (any degrees, mixed), are the
contiguous range of its elements' local functions (:mod:`.entries`).

Block tree: a pair of clusters (t, s) is admissible if

    min(diam B_t, diam B_s) <= eta * dist(B_t, B_s)                       (standard)

for the bounding boxes B; an admissible pair is a far-field block (low rank, ACA), a
pair of which one is a leaf is a near-field block (dense), any other pair is split into
its children's pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ClusterTree:
    """Clusters as ranges [start, stop) of tree positions; ``order[pos]`` the element at
    tree position pos; ``box[c] = (xmin, ymin, xmax, ymax)``; ``children[c]`` = (left,
    right) or (-1, -1) for a leaf; node 0 the root."""

    order: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    box: np.ndarray
    children: np.ndarray

    @property
    def n_clusters(self) -> int:
        return len(self.start)

    def is_leaf(self, c: int) -> bool:
        return self.children[c, 0] < 0

    @property
    def depth(self) -> int:
        depth = np.zeros(self.n_clusters, int)
        for c in range(self.n_clusters):       # children have larger indices
            for ch in self.children[c]:
                if ch >= 0:
                    depth[ch] = depth[c] + 1
        return int(depth.max()) + 1


def cluster_tree(nodes: np.ndarray, elements: np.ndarray, leaf_size: int) -> ClusterTree:
    """Bisect the elements (median split of the midpoints along the longer side of the
    bounding box of the element supports) until at most ``leaf_size`` per cluster."""
    a, b = nodes[elements[:, 0]], nodes[elements[:, 1]]
    lo_e, hi_e = np.minimum(a, b), np.maximum(a, b)
    mid = 0.5 * (a + b)
    order = np.arange(len(elements))
    start, stop, box, children = [], [], [], []
    stack = [(0, len(elements), -1, 0)]
    while stack:
        s0, s1, parent, side = stack.pop()
        c = len(start)
        if parent >= 0:
            children[parent][side] = c
        els = order[s0:s1]
        lo, hi = lo_e[els].min(axis=0), hi_e[els].max(axis=0)
        start.append(s0)
        stop.append(s1)
        box.append((lo[0], lo[1], hi[0], hi[1]))
        children.append([-1, -1])
        if s1 - s0 <= leaf_size:
            continue
        axis = int(np.argmax(hi - lo))
        half = (s1 - s0) // 2
        part = np.argsort(mid[els, axis], kind="stable")
        order[s0:s1] = els[part]
        stack.append((s0 + half, s1, c, 1))
        stack.append((s0, s0 + half, c, 0))
    return ClusterTree(order=order, start=np.array(start, np.int64),
                       stop=np.array(stop, np.int64), box=np.array(box, float),
                       children=np.array(children, np.int64))


def _diam(box: np.ndarray) -> float:
    return float(np.hypot(box[2] - box[0], box[3] - box[1]))


def _dist(b1: np.ndarray, b2: np.ndarray) -> float:
    dx = max(0.0, b1[0] - b2[2], b2[0] - b1[2])
    dy = max(0.0, b1[1] - b2[3], b2[1] - b1[3])
    return float(np.hypot(dx, dy))


def admissible(tree: ClusterTree, t: int, s: int, eta: float) -> bool:
    """min(diam B_t, diam B_s) <= eta * dist(B_t, B_s) (and dist > 0)."""
    d = _dist(tree.box[t], tree.box[s])
    return d > 0.0 and min(_diam(tree.box[t]), _diam(tree.box[s])) <= eta * d


def block_tree(tree: ClusterTree, eta: float):
    """(near, far): arrays of cluster pairs (t, s), the dense and the low-rank blocks of
    the root pair, partitioning the matrix."""
    near, far = [], []
    stack = [(0, 0)]
    while stack:
        t, s = stack.pop()
        if admissible(tree, t, s, eta):
            far.append((t, s))
        elif tree.is_leaf(t) or tree.is_leaf(s):
            near.append((t, s))
        else:
            for ct in tree.children[t]:
                for cs in tree.children[s]:
                    stack.append((int(ct), int(cs)))
    return (np.array(near, np.int64).reshape(-1, 2), np.array(far, np.int64).reshape(-1, 2))
