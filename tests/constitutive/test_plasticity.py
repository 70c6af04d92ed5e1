"""J2 return map at material points (hpfebe.constitutive.j2): closed-form linear hardening
along uniaxial-strain and simple-shear paths with unloading and reloading (theta = 0, 1),
plastic incompressibility, consistency, the algorithmic tangent against finite
differences, bad input."""

import math

import numpy as np
import pytest

from hpfebe.constitutive.j2 import (J2Material, J2State, consistent_tangent, dev, return_map,
                                  tensor_norm)

MAT = dict(E=266926.0, nu=0.29, sigma_Y=4.0, H=450.0)


def closed_form(mat, qs):
    """Closed-form 1D solution along a fixed deviatoric direction n: dev eps = q n,
    eps_p = p n, beta = b n; |2 mu (q - p) - b| <= sqrt(2/3) (sigma_Y + theta H alpha).
    For each monotone segment q_a -> q_b (direction d): elastic up to
    q* = p + (b + d R) / (2 mu), then dp = d 2 mu (q_b - q*)_+ / (2 mu + 2/3 H).
    Returns (p, b, alpha, s = 2 mu (q - p)) at every q of ``qs`` (path from q = 0)."""
    mu, H, th = mat.mu, mat.H, mat.theta
    p = b = alpha = 0.0
    q_prev, out = 0.0, []
    for q in qs:
        d = math.copysign(1.0, q - q_prev) if q != q_prev else 1.0
        R = math.sqrt(2 / 3) * (mat.sigma_Y + th * H * alpha)
        q_star = p + (b + d * R) / (2 * mu)
        excess = d * (q - q_star)
        if excess > 0:
            dp = d * 2 * mu * excess / (2 * mu + 2 / 3 * H)
            p += dp
            alpha += math.sqrt(2 / 3) * abs(dp)
            b += 2 / 3 * (1 - th) * H * dp
        out.append((p, b, alpha, 2 * mu * (q - p)))
        q_prev = q
    return np.array(out)


def run_path(mat, eps_path):
    """Return map along a sequence of strains (each (N, 3, 3)), committing each step."""
    st = J2State.zeros(eps_path[0].shape[0])
    out = []
    for eps in eps_path:
        rm = return_map(mat, eps, st)
        st = rm.state
        out.append(rm)
    return out


def segments(points, per):
    """Piecewise linear path through ``points`` with ``per`` steps per segment."""
    vals = []
    for a, b in zip(points[:-1], points[1:]):
        vals.extend(np.linspace(a, b, per + 1)[1:])
    return np.array(vals)


@pytest.mark.parametrize("theta", [0.0, 1.0, 0.4])
@pytest.mark.parametrize("path", ["uniaxial", "shear"])
def test_closed_form_load_unload_reload(theta, path):
    mat = J2Material(**MAT, theta=theta)
    ey = 1.5e-5                                   # about the yield strain sigma_Y / E
    if path == "uniaxial":                        # eps = e diag(1, 0, 0)
        N = np.diag([2.0, -1.0, -1.0]) / math.sqrt(6.0)
        factor = math.sqrt(2 / 3)                 # dev eps = sqrt(2/3) e N
        unit = np.diag([1.0, 0.0, 0.0])
    else:                                         # eps_12 = eps_21 = gamma / 2
        N = (np.eye(3)[:, [1]] @ np.eye(3)[[0], :] + np.eye(3)[:, [0]] @ np.eye(3)[[1], :])
        N = N / math.sqrt(2.0)
        factor = 1 / math.sqrt(2.0)
        unit = N * math.sqrt(2.0) / 2.0
    # load to 20 e_y, unload to -15 e_y (reverse yielding), reload to 30 e_y
    amp = segments([0.0, 20 * ey, -15 * ey, 30 * ey], 7)
    rms = run_path(mat, [a * unit[None] for a in amp])
    ref = closed_form(mat, factor * amp)
    p = np.array([np.einsum("ij,ij", r.state.eps_p[0], N) for r in rms])
    b = np.array([np.einsum("ij,ij", r.state.beta[0], N) for r in rms])
    alpha = np.array([r.state.alpha[0] for r in rms])
    s = np.array([np.einsum("ij,ij", dev(r.sigma)[0], N) for r in rms])
    scale = mat.sigma_Y
    np.testing.assert_allclose(p, ref[:, 0], atol=1e-12)
    np.testing.assert_allclose(b, ref[:, 1], atol=1e-10 * scale)
    np.testing.assert_allclose(alpha, ref[:, 2], atol=1e-12)
    np.testing.assert_allclose(s, ref[:, 3], atol=1e-9 * scale)
    # the path reverses plastically (unloading goes through reverse yield) and reloads
    assert np.any([r.plastic[0] for r in rms[7:14]]) and rms[-1].plastic[0]
    # eps_p stays along N; for uniaxial plane strain eps_p_33 != 0
    for r, pk in zip(rms, p):
        np.testing.assert_allclose(r.state.eps_p[0], pk * N, atol=1e-14)
    if path == "uniaxial":
        assert abs(rms[-1].state.eps_p[0, 2, 2]) > 1e-5


def random_state(rng, n, mat):
    """A plastically pre-loaded state at n points (random strain paths)."""
    st = J2State.zeros(n)
    for _ in range(3):
        e = rng.normal(scale=4e-5, size=(n, 3, 3))
        e = 0.5 * (e + e.transpose(0, 2, 1))
        e[:, 2, :] = e[:, :, 2] = 0.0
        st = return_map(mat, e, st).state
    return st


@pytest.mark.parametrize("theta", [0.0, 0.5, 1.0])
def test_incompressible_consistent_and_tangent(theta):
    rng = np.random.default_rng(1)
    mat = J2Material(**MAT, theta=theta)
    n = 200
    st = random_state(rng, n, mat)
    e = rng.normal(scale=5e-5, size=(n, 3, 3))
    e = 0.5 * (e + e.transpose(0, 2, 1))
    e[:, 2, :] = e[:, :, 2] = 0.0
    rm = return_map(mat, e, st)
    assert rm.plastic.sum() > n // 3 and (~rm.plastic).sum() > 0
    # tr eps_p = 0, tr beta = 0
    assert np.abs(np.trace(rm.state.eps_p, axis1=1, axis2=2)).max() < 1e-18
    assert np.abs(np.trace(rm.state.beta, axis1=1, axis2=2)).max() < 1e-12
    # consistency: on the yield surface where plastic, inside where elastic
    f = mat.yield_function(rm.sigma, rm.state.alpha, rm.state.beta)
    assert np.abs(f[rm.plastic]).max() < 1e-12 * mat.E
    assert f[~rm.plastic].max() <= 1e-12 * mat.E
    # algorithmic tangent = central finite difference of the return map
    C = rm.tangent
    h = 1e-9
    for k, l in [(0, 0), (1, 1), (0, 1), (2, 2)]:
        d = np.zeros((3, 3))
        d[k, l] = d[l, k] = 1.0
        sp_ = return_map(mat, e + h * d, st, tangent=None).sigma
        sm_ = return_map(mat, e - h * d, st, tangent=None).sigma
        fd = (sp_ - sm_) / (2 * h)
        an = np.einsum("nijkl,kl->nij", C, d)
        # the kink f_trial = 0 is excluded (no derivative there)
        ok = np.abs(rm.f_trial) > 1e-6 * mat.sigma_Y
        err = np.abs(fd - an)[ok].max() / np.abs(an).max()
        assert err < 1e-6, err
    # symmetries of C_alg
    np.testing.assert_allclose(C, C.transpose(0, 3, 4, 1, 2), atol=1e-9 * mat.E)
    np.testing.assert_allclose(C, C.transpose(0, 2, 1, 3, 4), atol=1e-9 * mat.E)


def test_continuum_tangent_differs_from_algorithmic():
    rng = np.random.default_rng(2)
    mat = J2Material(**MAT, theta=1.0)
    st = random_state(rng, 20, mat)
    e = 3 * rng.normal(scale=5e-5, size=(20, 3, 3))
    e = 0.5 * (e + e.transpose(0, 2, 1))
    a = return_map(mat, e, st, "algorithmic")
    c = return_map(mat, e, st, "continuum")
    np.testing.assert_array_equal(a.sigma, c.sigma)
    pl = a.plastic
    assert pl.any()
    assert np.abs(a.tangent[pl] - c.tangent[pl]).max() > 1e-3 * mat.E
    np.testing.assert_array_equal(a.tangent[~pl], c.tangent[~pl])


def test_elastic_state_gives_hooke():
    mat = J2Material(**MAT)
    e = np.zeros((1, 2, 2))
    e[0, 0, 0] = 1e-6
    rm = return_map(mat, e, J2State.zeros(1))
    assert not rm.plastic[0]
    np.testing.assert_allclose(rm.sigma[0, 0, 0], (mat.lam + 2 * mat.mu) * 1e-6)
    np.testing.assert_allclose(rm.sigma[0, 2, 2], mat.lam * 1e-6)
    assert tensor_norm(rm.state.eps_p).max() == 0.0


@pytest.mark.parametrize("kw,name", [
    (dict(sigma_Y=0.0), "sigma_Y"), (dict(sigma_Y=-1.0), "sigma_Y"),
    (dict(H=-1.0), "H"), (dict(theta=1.5), "theta"), (dict(theta=-0.1), "theta"),
    (dict(E=-1.0), "E"), (dict(nu=0.5), "nu"), (dict(H=float("nan")), "H"),
])
def test_bad_material(kw, name):
    with pytest.raises(ValueError, match=name):
        J2Material(**{**MAT, **kw})


def test_bad_return_map_input():
    mat = J2Material(**MAT)
    with pytest.raises(ValueError, match="eps"):
        return_map(mat, np.zeros((2, 3)), J2State.zeros(2))
    with pytest.raises(ValueError, match="tangent"):
        return_map(mat, np.zeros((2, 3, 3)), J2State.zeros(2), tangent="secant")
    with pytest.raises(ValueError, match="points"):
        return_map(mat, np.zeros((2, 3, 3)), J2State.zeros(3))
    with pytest.raises(ValueError, match="n"):
        J2State.zeros(-1)


def test_consistent_tangent_at_a_subset_is_the_full_tangent_bitwise():
    """consistent_tangent at some points = those rows of return_map's tangent, bit for
    bit; the elastic points carry the elastic tangent exactly."""
    mat = J2Material(266926.0, 0.29, 4.0, 450.0, 0.5)
    rng = np.random.default_rng(7)
    e = rng.normal(scale=3e-5, size=(40, 2, 2))
    rm = return_map(mat, e + np.swapaxes(e, 1, 2), J2State.zeros(40), "algorithmic")
    assert 0 < rm.plastic.sum() < 40
    pts = np.flatnonzero(rm.plastic)[::2]
    np.testing.assert_array_equal(consistent_tangent(mat, rm, "algorithmic", pts),
                                  rm.tangent[pts])
    el = np.flatnonzero(~rm.plastic)
    np.testing.assert_array_equal(rm.tangent[el],
                                  np.broadcast_to(mat.elastic_tangent(), (el.size,) + (3,) * 4))
    with pytest.raises(ValueError, match="tangent"):
        consistent_tangent(mat, rm, "secant")
