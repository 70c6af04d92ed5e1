"""The study of Section 4.2.8 in hpfebe.scenes.adaptive_fefe: the parameters refuse what
the figures cannot use, the steps shown, the observed rates, and the concentration
measures on a uniform refinement (no concentration: new vertices as dense near the
features as anywhere)."""

from types import SimpleNamespace

import numpy as np
import pytest

from hpfebe.fem import refine_labelled
from hpfebe.scenes import adaptive_fefe as scene


@pytest.mark.parametrize("kw,name", [
    (dict(mesh_steps=(0, -1)), "mesh_steps"), (dict(theta=0.0), "theta"),
    (dict(n_refinements=0), "n_refinements"), (dict(linear_solver="cg"), "linear_solver"),
    (dict(concentration_share=1.5), "concentration_share"), (dict(rtol=0.0), "rtol")])
def test_study_refuses_bad_parameters(kw, name):
    with pytest.raises(ValueError, match=name):
        scene.AdaptiveStudy(**kw)


def test_shown_steps_end_with_the_last_step():
    prm = scene.AdaptiveStudy(mesh_steps=(0, 2, 9))
    assert prm.shown_steps(5) == [0, 2, 4]
    assert prm.shown_steps(10) == [0, 2, 9]


def test_observed_rates():
    dof = np.array([10.0, 40.0, 160.0, 640.0])
    ad = [dict(dof_slave=d, eta_slave=d ** -0.5) for d in dof]
    un = [dict(dof_slave=d, eta_slave=2 * d ** -0.25) for d in dof]
    ra, ru = scene.observed_rates(ad, un, "slave")
    assert ra == pytest.approx(-0.5) and ru == pytest.approx(-0.25)
    assert np.isnan(scene.observed_rates(ad[:1], un[:1], "slave")[0])


def test_uniform_refinement_does_not_concentrate():
    prm = scene.AdaptiveStudy()
    m0 = prm.initial_meshes()
    meshes = [m0, tuple(refine_labelled(m) for m in m0)]
    for body, (c, local, h0) in scene.feature_concentration(prm, meshes).items():
        assert c.n_new > 0 and 0.5 < c.enrichment < 1.5, body
        assert all(v < h0 for v in local)         # refined everywhere
    for body, (r_half, c) in scene.wider_radius(prm, meshes).items():
        assert c.share >= prm.concentration_share and r_half > 0
    hist = SimpleNamespace(meshes=meshes, records=[
        dict(ndof=tuple(2 * m.p.shape[1] for m in ms)) for ms in meshes])
    rows = scene.concentration_rows(prm, hist, [0, 1])
    assert rows[0]["new_near_features_slave"] == 0.0 and all(r["conforming"] for r in rows)
    assert rows[1]["elements_slave"] == 4 * rows[0]["elements_slave"]
