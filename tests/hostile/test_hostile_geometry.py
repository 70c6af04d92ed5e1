"""Issue 25, the geometry of Chapter 4's bodies: BE cells outside the body, overlapping
or degenerate (:class:`hpfebe.bodies.ElastoPlasticBE`), and NaN / inf / negative numbers
in the geometry builders the scenes use (:meth:`BoundaryMesh.polygon`,
:meth:`BoundaryMesh.from_segments`, :func:`rectangle_mesh`, :func:`block_grid`,
:func:`tensor_block_mesh`, :func:`rectangle_work_piece`): each is refused with a
ValueError that names the parameter, where numpy, scipy or a silent NaN mesh met them
before."""

import numpy as np
import pytest

from hpfebe import BoundaryMesh
from hpfebe.bem.lame import LameBEM
from hpfebe.bodies import ElastoPlasticBE
from hpfebe.bodies.cell_operators import check_cells
from hpfebe.bodies.plastic_be import crossed_cells, rectangle_work_piece
from hpfebe.constitutive.j2 import J2Material
from hpfebe.fem import block_grid, rectangle_mesh, tensor_block_mesh
from hpfebe.fem.newton_potential import CellComplex
from hpfebe.geometry.containment import INSIDE, ON, OUTSIDE, classify_points, first_cut

MAT = J2Material(1000.0, 0.3, 1.0, 10.0, 1.0)
BOX = (-2.0, 2.0, -3.0, -1.0)
#: the work piece's boundary, 4 x 2 elements (element length 1)
BODY = BoundaryMesh.polygon([(-2, -3), (2, -3), (2, -1), (-2, -1)], n=[4, 2, 4, 2])
#: an L-shaped body [0, 2]^2 minus (1, 2]^2
L_BODY = BoundaryMesh.polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)],
                              n=[2, 1, 1, 1, 1, 2])


def _grid(box=BOX, nx=4, ny=2):
    m = rectangle_mesh(*box, nx, ny, "quad")
    return m.p.T.copy(), m.t.T.copy()


def test_containment_of_points_and_polygons():
    pts = [(0.5, 0.5), (1.5, 1.5), (1.0, 1.5), (2.5, 0.5), (1.5, 0.5), (0.0, 0.0)]
    np.testing.assert_array_equal(classify_points(L_BODY, pts),
                                  [INSIDE, OUTSIDE, ON, OUTSIDE, INSIDE, ON])
    # Gamma cuts a polygon reaching into the notch (through its reflex corner (1, 1):
    # no proper crossing of edges), not one beside it that touches it along an edge
    nodes = np.array([[0.5, 0.5], [1.9, 0.9], [1.9, 1.9], [0.9, 1.9], [0, 0], [1, 0],
                      [1, 1], [0, 1]], dtype=float)
    assert first_cut(L_BODY, nodes, [[4, 5, 6, 7], [0, 1, 2, 3]]) == (1, 3)   # y = 1
    assert first_cut(L_BODY, nodes, [[4, 5, 6, 7]]) == (-1, -1)
    # a hole: its inside is outside the body
    ring = BoundaryMesh.join(BoundaryMesh.polygon([(0, 0), (4, 0), (4, 4), (0, 4)], n=4),
                             BoundaryMesh.polygon([(1, 1), (3, 1), (3, 3), (1, 3)], n=2))
    np.testing.assert_array_equal(classify_points(ring, [(2, 2), (0.5, 2), (1, 2)]),
                                  [OUTSIDE, INSIDE, ON])


def _bad_cells():
    p, t = _grid()
    cases = {"shifted": (BODY, CellComplex(p + [0.5, 0.0], t),
                         r"cells must lie inside the body: cell node \d+ at \[2.5"),
             "in the notch": (L_BODY, CellComplex(*_grid((0, 2, 0, 2), 2, 2)),
                              r"cell node \d+ at \[2.0, 2.0\] is outside"),
             "duplicate": (BODY, CellComplex(p, np.vstack([t, t[:1]])),
                           r"cells must not overlap: cells 0 .* and 8"),
             "crossing Gamma": (L_BODY, CellComplex([[0.2, 0.2], [1.9, 0.2], [0.2, 1.9]],
                                                    np.array([[0, 1, 2]])),
                                r"the boundary element \d .* cuts cell 0")}
    # two triangles overlapping without a vertex of one inside the other
    q = np.array([[-1.5, -2.9], [-0.5, -2.9], [-1.0, -1.9], [-1.5, -2.2], [-0.5, -2.2],
                  [-1.0, -3.0 + 1e-3]])
    cases["star of David"] = (BODY, CellComplex(q, np.array([[0, 1, 2], [3, 5, 4]])),
                              "cells must not overlap: cells 0 .* and 1")
    # a node moved across its neighbours' edges folds a cell
    q = p.copy()
    inner = np.flatnonzero((np.abs(p[:, 1] + 2) < 1e-12) & (np.abs(p[:, 0]) < 2 - 1e-9))
    q[inner[1]] += [1.3, 0.1]
    cases["folded"] = (BODY, CellComplex(q, t), r"cells must be convex polygons: cell \d+")
    tiny = np.array([[0.0, -2.0], [1e-6, -2.0], [0.0, -2.0 + 1e-6], [-1.0, -2.5],
                     [1.0, -2.5], [0.0, -1.5]])
    cases["degenerate"] = (BODY, CellComplex(tiny, np.array([[0, 1, 2], [3, 4, 5]])),
                           r"cells must not be degenerate: cell 0 .* has area 5e-13")
    q = p.copy()
    q[0] = np.nan                                  # CellComplex itself lets NaN through
    cases["nan"] = (BODY, CellComplex(q, t), r"cells.nodes must be finite, got nan")
    return cases


@pytest.mark.parametrize("case", sorted(_bad_cells()))
def test_be_cells_outside_overlapping_or_degenerate_are_refused(case):
    mesh, cx, message = _bad_cells()[case]
    with pytest.raises(ValueError, match=message):
        check_cells(mesh, cx)
    if case in ("shifted", "duplicate"):             # through the body's constructor
        with pytest.raises(ValueError, match=message):
            ElastoPlasticBE(LameBEM(mesh, MAT.E, MAT.nu), cx, MAT)


def test_valid_cells_are_accepted():
    """Cells of the whole body, of its top rows only, crossed triangles, and a node on a
    cell edge (a T junction) are valid complexes."""
    p, t = _grid()
    for cx in (CellComplex(p, t), CellComplex(*_grid((-2, 2, -2, -1), 4, 1)),
               crossed_cells(p, t)):
        check_cells(BODY, cx)
    tj = np.array([[-2, -3], [0, -3], [0, -2], [-2, -2], [2, -3], [2, -2.5], [0, -2.5],
                   [2, -2]], dtype=float)
    check_cells(BODY, CellComplex(tj, np.array([[0, 1, 2, 3], [1, 4, 5, 6], [6, 5, 7, 2]])))


def test_cells_along_gamma_must_be_bem_elements():
    """A cell edge on Gamma that is not one BEM element (the BEM mesh coarser than the
    cells on the top side): the Somigliana identity of the interior edges does not hold
    on Gamma."""
    coarse = BoundaryMesh.polygon([(-2, -3), (2, -3), (2, -1), (-2, -1)], n=[4, 2, 2, 2])
    with pytest.raises(ValueError, match=r"cells must meet Gamma in whole BEM elements: "
                                         r"the edge .* lies on Gamma but is no BEM element"):
        ElastoPlasticBE(LameBEM(coarse, MAT.E, MAT.nu), CellComplex(*_grid()), MAT)
    ElastoPlasticBE(LameBEM(BODY, MAT.E, MAT.nu), CellComplex(*_grid()), MAT)


@pytest.mark.parametrize("call, message", [
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (np.nan, 1)]),
     r"vertices must be finite, got nan at index \(2, 0\)"),
    (lambda: BoundaryMesh.polygon([(0, 0), (np.inf, 0), (1, 1)]), "vertices must be finite"),
    (lambda: BoundaryMesh.polygon("square"), "vertices must be an array of real numbers"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1)], h=1e-20),
     r"h gives 3.41e\+20 elements, more than 1e\+07"),
    (lambda: block_grid([0.0, 1.0], 1e20), "h_inv must give at most 1e7 cells"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1)], h=-0.1),
     r"h must be a finite real number > 0, got -0.1"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1)], h=[0.1, np.nan, 0.1]),
     r"h\[1\] must be a finite real number > 0, got nan"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1)], n=[2, 2.5, 2]),
     r"n\[1\] must be an integer >= 1, got 2.5"),
    (lambda: BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1)], n="4"), "n must be an integer"),
    (lambda: BoundaryMesh.from_segments([[0, 0], [1, 0], [np.nan, 1]], [[0, 1], [1, 2], [2, 0]]),
     "nodes must be finite"),
    (lambda: BoundaryMesh.from_segments([[0, 0], [1, 0], [0, 1]], [[0, 1], [1, 2.5], [2, 0]]),
     "segments must hold integers"),
    (lambda: rectangle_mesh(0, np.inf, 0, 1, 2, 2), "x1 must be a finite real number"),
    (lambda: rectangle_mesh(0, 1, np.nan, 1, 2, 2), "y0 must be a finite real number"),
    (lambda: rectangle_mesh("0", 1, 0, 1, 2, 2), "x0 must be a finite real number"),
    (lambda: rectangle_mesh(0, 1, 0, 1, np.nan, 2), "nx must be an integer >= 1, got nan"),
    (lambda: rectangle_mesh(0, 1, 1, 0, 2, 2), "y1 must exceed y0"),
    (lambda: block_grid([0.0, np.nan], 2), "breaks must be finite"),
    (lambda: block_grid([0.0, 1.0], -2), "h_inv must be a finite real number > 0"),
    (lambda: block_grid([0.0, 1.0], 2, "round"), "rounding must be one of"),
    (lambda: tensor_block_mesh([0, np.inf], [0, 1], 2, lambda x, y: x > 0,
                               lambda x, y: np.full(x.shape, "D")), "xbreaks must be finite"),
    (lambda: rectangle_work_piece((0, 1, 0, np.nan), 2, 2, MAT), "box must be finite"),
    (lambda: rectangle_work_piece((0, 1, 0, 1), 2, 2, MAT, cell_rows=3),
     r"cell_rows must be an integer in \[1, 2\]"),
    (lambda: rectangle_work_piece((0, 1, 0, 1), 2, 2.5, MAT), "ny must be an integer"),
    (lambda: rectangle_work_piece((0, 1, 0, 1), 2, 2, MAT, cells="hex"), "cells must be one of"),
])
def test_geometry_builders_refuse_bad_numbers(call, message):
    with pytest.raises(ValueError, match=message):
        call()
