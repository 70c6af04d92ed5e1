"""Mirror symmetry of the two-body penalty contact scenes (FE/FE, FE/BE, BE/FE, BE/BE,
single and two passes, Coulomb friction; the scene of tests/invariance/conftest.py).

1. Mirroring the whole scene in the line x = 1/2 (every point, and the prescribed shear
   with it: u_top = M (s, -D) = (-s, -D)) is the same problem in a left-handed frame:
   the FE cells become clockwise (the stiffness uses |det J|), the BE curves are
   reoriented by BoundaryMesh.from_segments (each element reversed, so the BE dofs are
   renumbered), the master normal and tangent are recomputed from the mirrored
   segments (the tangent t = (n_y, -n_x) keeps its rule, so the slip changes sign with
   the shear).  The mirrored solution is M u at the mirrored dof points.
2. The scene without shear is itself symmetric about x = 1/2 (blocks [0, 1], parabola
   centred at 1/2, 4 and 5 cells: symmetric meshes): its solution is its own mirror
   image, friction included (u_x odd, u_y even about x = 1/2).

Bound (conftest.forward_bound): both runs solve the same discrete problem to the backward
error rtol = 1e-12 with data rounded differently, so

    ||M u_ref - u_mirror|| / ||u_ref|| <= cond_2(J_free) (2 rtol + C_ROUND eps_mach)

(case 2: the one run against its own image, whose residual is the mirrored residual:
the same bound); tractions and forces by conftest.traction_bound and force_bound;
with an elastoplastic body times E / H (conftest.plastic_factor).  Measured ~1e-15 ..
1e-14 against bounds of ~1e-10 .. 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest

COMBOS = [("FE", "FE"), ("BE", "FE"), ("FE", "BE"), ("BE", "BE")]
PAIRS = [("slave", "slave"), ("master", "master")]


@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_mirrored_scene(tb, kinds, two_pass):
    M = tb.Isometry.mirror_x(0.5)
    ref, mir = tb.scene(kinds, two_pass=two_pass), tb.scene(kinds, T=M, two_pass=two_pass)
    beta = tb.forward_bound(ref[0], ref[1], ref[3])
    assert tb.mapped_discrepancy(ref, mir, M, PAIRS) <= beta
    a, b = ref[1], mir[1]
    # the total normal force is a scalar of the scene; the friction force changes sign
    fa, fb = a.total_forces(), b.total_forces()
    bound = tb.force_bound(ref[0], a, beta)
    assert abs(fb[0] / fa[0] - 1) <= bound
    tt = tb.traction_bound(ref[0], a, beta)
    assert abs(fb[1] + fa[1]) <= a.weights.sum() * tt
    j = tb.match(tb.point_keys(a, M), tb.point_keys(b))   # mirrored (BE: renumbered)
    assert np.array_equal(a.state, b.state[j])
    assert np.max(np.abs(b.p_n[j] - a.p_n)) <= tt
    assert np.max(np.abs(b.t_t[j] + a.t_t)) <= tt
    assert abs(fa[1]) > 1e-3 * abs(fa[0])                    # friction is active


@pytest.mark.parametrize("kinds", COMBOS, ids="/".join)
def test_symmetric_scene_has_a_symmetric_solution(tb, kinds):
    M = tb.Isometry.mirror_x(0.5)
    ref = tb.scene(kinds, shear=0.0)
    beta = tb.forward_bound(ref[0], ref[1], ref[3])
    assert tb.mapped_discrepancy(ref, ref, M, PAIRS) <= beta
    # in contact where the chords of the two polylines meet (their O(c h^2) mismatch
    # exceeds the penalty penetration elsewhere)
    assert 0 < np.count_nonzero(ref[1].p_n) < ref[1].p_n.size
    # the friction force integrates to zero over the symmetric interface
    fn, ft = ref[1].total_forces()
    assert abs(ft) <= ref[1].weights.sum() * tb.traction_bound(ref[0], ref[1], beta)


@pytest.mark.parametrize("geometry", ["roof", "overhang"])
@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", [("FE", "BE"), ("BE", "BE")], ids="/".join)
def test_mirror_kinked_and_overhanging(tb, kinds, two_pass, geometry):
    """The kinked interface and the overhanging upper block (both symmetric about
    x = 1/2): the mirrored scene, and the unsheared scene against its own image, within
    the same bound (measured 3e-16 .. 3.6e-15)."""
    M = tb.Isometry.mirror_x(0.5)
    kw = dict(tb.GEOMETRIES[geometry], two_pass=two_pass)
    ref, mir = tb.scene(kinds, **kw), tb.scene(kinds, T=M, **kw)
    assert tb.mapped_discrepancy(ref, mir, M, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])
    sym = tb.scene(kinds, shear=0.0, **kw)
    assert tb.mapped_discrepancy(sym, sym, M, PAIRS) <= tb.forward_bound(*sym[:2], sym[3])


@pytest.mark.parametrize("formulation", ["bbar", "full"])
@pytest.mark.parametrize("kinds", [("FE", "FE"), ("BE", "FE")], ids="/".join)
def test_mirror_elastoplastic_master(tb, kinds, formulation):
    """An elastoplastic J2 lower block (conftest.fe_block ``plastic``) sheared by 4 D,
    mirrored; and pressed only, against its own image (the plastic strain even): the
    bound times E / H (conftest.plastic_factor)."""
    M = tb.Isometry.mirror_x(0.5)
    kw = dict(shear=4 * tb.D, fe_kw=dict(plastic=formulation))
    ref, mir = tb.scene(kinds, **kw), tb.scene(kinds, T=M, **kw)
    beta = tb.forward_bound(*ref[:2], ref[3]) * tb.plastic_factor(ref[0])
    assert tb.mapped_discrepancy(ref, mir, M, PAIRS) <= beta
    sym = tb.scene(kinds, **dict(kw, shear=0.0))
    beta = tb.forward_bound(*sym[:2], sym[3]) * tb.plastic_factor(sym[0])
    assert tb.mapped_discrepancy(sym, sym, M, PAIRS) <= beta
    fe = sym[0].bodies["master"].plastic
    eps_p = fe.fields()["eps_p_norm_mean"]
    assert eps_p.max() > 0
    c = fe.mesh.p[:, fe.mesh.t].mean(axis=1).T
    k = tb.match(M(c), c)
    # eps_p: the non-expansive return map of the strain, |d eps| <= 2 ||dU|| / h with
    # h = 1/5 the lower block's cell width
    assert np.abs(eps_p - eps_p[k]).max() <= 2 * beta * np.linalg.norm(sym[1].U) / 0.2


@pytest.mark.parametrize("two_pass", [False, True], ids=["one_pass", "two_pass"])
@pytest.mark.parametrize("kinds", [("FE", "BE"), ("BE", "BE")], ids="/".join)
def test_mirror_tresca(tb, kinds, two_pass):
    """Tresca friction with the even bound conftest.TRESCA: the mirrored scene, the same
    bound."""
    M = tb.Isometry.mirror_x(0.5)
    kw = dict(two_pass=two_pass, tresca=tb.TRESCA)
    ref, mir = tb.scene(kinds, **kw), tb.scene(kinds, T=M, **kw)
    assert tb.mapped_discrepancy(ref, mir, M, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])


def test_mirror_p2_be_two_pass(tb):
    """Degree-2 BE bodies (the GLL interior node order reverses with the elements)."""
    M = tb.Isometry.mirror_x(0.5)
    ref = tb.scene(("BE", "BE"), p=2, two_pass=True)
    mir = tb.scene(("BE", "BE"), T=M, p=2, two_pass=True)
    assert tb.mapped_discrepancy(ref, mir, M, PAIRS) <= tb.forward_bound(*ref[:2], ref[3])


@pytest.mark.parametrize("kind", ["FE", "BE"])
def test_stamping_touch_is_mirror_symmetric(tb, kind):
    """The stamping scene of Section 4.2.7 (hpfebe.scenes.touch): an elastic FE or BE
    stamp [-1/2, 1/2] x [0, 1] (slave) on an elastoplastic Q1 work piece
    [-1, 1] x [-1, 0] (J2, the thesis's E, NU, SIGMA_Y, H), Coulomb mu_f = 0.2, lifted by
    2e-4 in 2 increments and lowered in 1; both meshes (h = 1/4) and the loading are
    symmetric about x = 0, so the work piece's displacement at the peak and at the end,
    and its plastic strain, are mirror symmetric (u_x odd, u_y and eps_p even).

    Bound: the run against its own mirror image, U - M U = J^{-1} (r - M r), with the
    Newton residual ||r|| <= rtol scale (rtol = 1e-12 here, the thesis's STAMP_SOLVER
    otherwise) and the assembly rounding: ||U - M U|| / ||U|| <= cond_2(J) (2 rtol +
    C_ROUND eps_mach).  cond_2(J) of the elastoplastic tangent is at most E / H times
    that of the elastic Newton matrix of the same scene at the peak contact state
    (kappa_el, computed: the J2 algorithmic tangent's least modulus is about H); eps_p is
    the image of the strain under the (non-expansive) return map, so its change is at
    most the strain change, <= 2 ||dU||_2 / h.  Measured 3e-16 .. 8e-16 (u), against
    bounds of ~3e-7."""
    import dataclasses

    from hpfebe import ElasticBody, J2Material, TwoBodyContact
    from hpfebe.scenes import (H, SIGMA_Y, STAMP_SOLVER, StampContact, stamp_body, touch,
                               work_piece)

    E, NU = tb.E, tb.NU
    h = 0.25
    fe = work_piece((-1.0, 1.0, -1.0, 0.0), h, J2Material(E, NU, SIGMA_Y, H, 1.0))
    stamp = stamp_body(kind, (-0.5, 0.5, 0.0, 1.0), h, E, NU)
    sc = StampContact(solver=dataclasses.replace(STAMP_SOLVER, rtol=tb.RTOL))
    tr = touch(stamp, fe, 2e-4, 2, 1, (0.0, -0.25), sc)
    assert tr.converged, tr.reason
    # kappa_el: the elastic Newton matrix of the scene at the peak contact state
    el = TwoBodyContact(stamp, ElasticBody(fe.mesh, E, NU), "bottom", "top",
                        eps_n=1 / (sc.eps_n_factor * E), eps_t=1 / (sc.eps_t_factor * E),
                        mu_f=sc.mu_f)
    U = np.concatenate([tr.peak.u_stamp, tr.peak.u_work])
    J = el.tangent(el.internal_force(U, tr.peak.result.slip)[1])
    J = J if isinstance(J, np.ndarray) else J.toarray()
    free = np.setdiff1d(np.arange(el.ndofs), el.stamp_dofs()[0])
    beta = np.linalg.cond(J[np.ix_(free, free)]) * (E / H) \
        * (2 * tb.RTOL + tb.C_ROUND * tb.MACHEPS)
    x = fe.mesh.p.T
    j = tb.match(x * [-1.0, 1.0], x)
    nd = fe.elastic.nodal_dofs
    for u in (tr.peak.u_work, tr.u_work):
        ux, uy = u[nd[0]], u[nd[1]]
        d = np.sqrt((np.sum((ux + ux[j]) ** 2) + np.sum((uy - uy[j]) ** 2)) / np.sum(u ** 2))
        assert d <= beta
    eps_p = np.asarray(tr.peak.fields["eps_p_norm"])
    assert eps_p.max() > 0                                   # the work piece yields
    c = fe.mesh.p[:, fe.mesh.t].mean(axis=1).T              # cell centroids
    k = tb.match(c * [-1.0, 1.0], c)
    assert np.abs(eps_p - eps_p[k]).max() <= 2 * beta * np.linalg.norm(U) / h
