"""Adaptive FE/FE two-body frictional contact (Section 4.2.8, Figures 4.13-4.16): the
indicator (3.100) of each body with the contact datum, the adaptive loop on the pair of
meshes, and the artefacts of experiments/ch4_adaptive_fefe.py through the command line."""

import json
import math
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pandas as pd
import pytest

from hpfebe.adaptivity import (adapt, contact_traction_datum, fe_indicators, lame_stress,
                               mark_max, two_body_indicators)
from hpfebe.contact import ContactSettings, TwoBodyContact
from hpfebe.fem import is_conforming
from hpfebe.fem.elasticity import ElasticBody, rectangle_mesh

ROOT = Path(__file__).resolve().parents[2]
E, NU = 266926.0, 0.29
BOX_S, BOX_M = (-0.5, 0.5, 0.0, 2.0), (-2.0, 2.0, -2.0, 0.0)
CONTACT, OPEN = ("bottom", "top"), (("left", "right"), ("left", "right"))


def _meshes():
    return (rectangle_mesh(*BOX_S, 4, 8, kind="tri"), rectangle_mesh(*BOX_M, 16, 8, kind="tri"))


def _solve(meshes):
    """The scene of Section 4.2.8: slave top fixed, master bottom lifted by 5e-4."""
    S, M = (ElasticBody(m, E, NU, "strain") for m in meshes)
    pr = TwoBodyContact(S, M, ["bottom", "left", "right"], ["top", "left", "right"],
                        eps_n=1.0 / (10 * E), eps_t=1.0 / (5 * E), mu_f=0.1)
    fixed, is_y = pr.stamp_dofs()
    res = pr.solve(None, fixed, 5e-4 * is_y, load_factors=np.arange(1, 6) / 5, settings=ContactSettings(rtol=1e-10, max_iter=30))
    assert res.converged, res.reason
    return pr, res


@pytest.fixture(scope="module")
def solved():
    return _solve(_meshes())


# ----------------------------------------------------------------------------- datum
def test_contact_traction_datum_interpolates_on_the_labelled_facets():
    m = rectangle_mesh(0.0, 2.0, 0.0, 1.0, 2, 2, kind="tri")
    pts = np.array([[1.5, 0.0], [0.5, 0.0], [0.0, 0.5]])       # the last one on "left"
    tr = np.array([[3.0, -1.0], [1.0, -2.0], [99.0, 99.0]])
    f = contact_traction_datum(m, "bottom", pts, tr)
    x = np.array([[0.2, 1.0, 1.9, 2.0 + 1e-3]])
    v = f(x, np.zeros_like(x), 0 * x, -1 + 0 * x)
    assert v.shape == (2, 1, 4)
    np.testing.assert_allclose(v[:, 0], [[1.0, 2.0, 3.0, 0.0], [-2.0, -1.5, -1.0, 0.0]])
    with pytest.raises(ValueError, match="label"):
        contact_traction_datum(m, "C", pts, tr)
    with pytest.raises(ValueError, match="shape"):
        contact_traction_datum(m, "bottom", pts, tr[:2])
    with pytest.raises(ValueError, match="no point"):
        contact_traction_datum(m, "top", pts, tr)
    with pytest.raises(ValueError, match="axis"):
        contact_traction_datum(m, "bottom", pts, tr, axis=2)


def test_two_body_indicators_use_the_penalty_traction(solved):
    """Equal to fe_indicators with the datum built by hand: the penalty traction
    p_n n_m - t_t t_m at the slave points on y = 0, linear in x, zero for |x| > 1/2,
    its negative on the master."""
    pr, res = solved
    eta_s, eta_m = two_body_indicators(pr, res, contact=CONTACT, free=OPEN)
    sel = (np.abs(res.points[:, 1]) < 1e-12) & (res.weights > 0)
    order = np.argsort(res.points[sel, 0])
    xs = res.points[sel, 0][order]
    tr = (res.p_n[:, None] * pr.normals - res.t_t[:, None] * pr.tangents)[sel][order]
    assert np.abs(tr).max() > 0          # the bodies are in contact

    def f(x, y, nx, ny):
        inside = np.abs(x) <= 0.5 + 1e-12
        return np.array([np.where(inside, np.interp(x, xs, tr[:, c]), 0.0) for c in (0, 1)])

    def zero(x, y, nx, ny):
        return np.zeros((2,) + np.shape(x))

    stress = lame_stress(E, NU, "strain")
    ref_s = fe_indicators(pr.slave.basis, res.u_slave, stress=stress,
                          tractions={"bottom": f, "left": zero, "right": zero})
    ref_m = fe_indicators(pr.master.basis, res.u_master, stress=stress,
                          tractions={"top": lambda *a: -f(*a), "left": zero, "right": zero})
    np.testing.assert_array_equal(eta_s, ref_s)
    np.testing.assert_array_equal(eta_m, ref_m)
    with pytest.raises(ValueError, match="pairs"):
        two_body_indicators(pr, res, contact=("bottom",))


# ----------------------------------------------------------------------------- the loop
def test_adaptive_loop_on_both_bodies():
    def solve(meshes):
        pr, res = _solve(meshes)
        return (pr, res), (pr.slave.ndofs, pr.master.ndofs)

    def estimate(meshes, state):
        return two_body_indicators(*state, contact=CONTACT, free=OPEN)

    meshes0 = _meshes()
    h = adapt(meshes0, solve, estimate, n_steps=4, theta=0.9)
    eta = h.column("eta")
    assert eta.shape == (4, 2) and np.all(eta[-1] < eta[0])
    assert np.all(np.diff(h.column("ndof"), axis=0) > 0)
    for k in range(3):
        for i in (0, 1):       # each body marked by its own maximum strategy
            np.testing.assert_array_equal(h.marked[k][i], mark_max(h.etas[k][i], 0.9))
    for i, m in enumerate(h.mesh):
        assert is_conforming(m, meshes0[i])
        assert set(m.boundaries) == {"left", "right", "bottom", "top"}
        assert sum(len(v) for v in m.boundaries.values()) == m.boundary_facets().size


# ----------------------------------------------------------------------------- artefacts
@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("results")
    r = subprocess.run([sys.executable, "-m", "hpfebe", "run", "figure_4_13", "--quick",
                        "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    ids = ("figure_4_13", "figure_4_14", "figure_4_15", "figure_4_16")
    return {i: (json.loads((out / f"{i}.json").read_text()), pd.read_csv(out / f"{i}.csv"))
            for i in ids}, out


def test_quick_run_produces_all_artefacts(quick_run):
    res, out = quick_run
    for name, (js, _) in res.items():
        assert (out / f"{name}.png").is_file()
        assert js["claims"] and all(c["holds"] is not None for c in js["claims"]), name
        assert js["meta"]["run_s"] < 60
    vtus = sorted(p.name for p in (out / "vtu").glob("*.vtu"))
    assert len(vtus) == 4 and all(v.startswith("figure_4_16_") for v in vtus), vtus
    assert np.all(np.isfinite(meshio.read(out / "vtu" / vtus[0]).point_data["displacement"]))


def test_claim_kinds_and_links(quick_run):
    """The thesis's statements are thesis claims; the wider reading of 'near' is a
    hypothesis linked to 'most'; Newton convergence and the u_y range are ours."""
    res, _ = quick_run
    kinds = {n: {c["id"]: (c["kind"], c["explains"]) for c in js["claims"]}
             for n, (js, _) in res.items()}
    assert kinds["figure_4_13"] == {"concentrates": ("thesis", []), "most": ("thesis", []),
                                    "wider": ("hypothesis", ["most"])}
    for n in ("figure_4_14", "figure_4_15"):
        assert kinds[n] == {"beats": ("thesis", []), "newton": ("beyond", [])}
    assert kinds["figure_4_16"] == {"uy_range": ("beyond", [])}


def test_adaptive_indicator_below_uniform_at_comparable_dof(quick_run):
    res, _ = quick_run
    for name, body in (("figure_4_14", "slave"), ("figure_4_15", "master")):
        js, t = res[name]
        ad, un = t[t["mode"] == "adaptive"], t[t["mode"] == "uniform"]
        d, e = ad[f"dof_{body}"].iloc[-1], ad[f"eta_{body}"].iloc[-1]
        assert un[f"dof_{body}"].min() <= d <= un[f"dof_{body}"].max()
        e_u = math.exp(np.interp(math.log(d), np.log(un[f"dof_{body}"]),
                                 np.log(un[f"eta_{body}"])))
        assert e < e_u and js["claims"][0]["holds"] is True
        assert ad[f"eta_{body}"].iloc[-1] < ad[f"eta_{body}"].iloc[0]
        assert (un[f"marked_{body}"] == 0).all() and (ad[f"marked_{body}"].iloc[:-1] > 0).all()


def test_newton_converges_and_meshes_conform(quick_run):
    res, _ = quick_run
    js, t = res["figure_4_14"]
    assert t["newton_converged"].all() and js["meta"]["newton_all_converged"]
    for s in t["newton_per_load_step"]:
        its = [int(i) for i in s.split()]
        assert len(its) >= 5 and max(its) <= 10
    t13 = res["figure_4_13"][1]
    assert t13["conforming"].all()
    assert t13["h_min_slave"].iloc[-1] < t13["h_min_slave"].iloc[0]


def test_displacement_between_dirichlet_values(quick_run):
    js, t = quick_run[0]["figure_4_16"]
    assert t["uy_min"].min() >= -1e-12 and t["uy_max"].max() <= 5e-4 * (1 + 1e-9)
    assert js["claims"][0]["holds"] is True


# ----------------------------------------------------------------------------- LU reuse
def test_newton_reuses_factorisations_without_changing_the_result(monkeypatch):
    """LoadSteps keeps the sparse LUs of Newton matrices met before (the semismooth
    iterates revisit contact patterns; here every load step after the first solves in
    one step with the Newton matrix of the converged state before it): fewer
    factorisations than Newton steps, bit-identical iterates with the cache cut to the
    last LU."""
    import scipy.sparse.linalg as spla

    from hpfebe.contact import loading

    calls, splu = [], spla.splu

    def counting_splu(A, *args, **kw):
        calls.append(A.shape[0])
        return splu(A, *args, **kw)

    monkeypatch.setattr(loading.spla, "splu", counting_splu)
    _, cached = _solve(_meshes())
    n_cached = len(calls)
    assert n_cached < sum(cached.iterations)
    calls.clear()
    monkeypatch.setattr(loading.LoadSteps, "LU_CACHE", 0)     # keeps only the last LU
    _, fresh = _solve(_meshes())
    assert n_cached <= len(calls) <= sum(fresh.iterations)
    assert list(cached.iterations) == list(fresh.iterations)
    np.testing.assert_array_equal(cached.U, fresh.U)
