"""Compile the numba kernels once, before the experiments need them (``hpfebe compile``).

numba compiles a kernel at its first call and keeps the machine code in its on-disk cache
(one directory per digest of the kernel sources: :mod:`hpfebe._numba_cache`).  On a fresh machine the
experiments of a ``snakemake -j2`` run would each compile the same kernels at once (two
jobs, the same ~30 s twice); the workflow's ``numba_cache`` rule runs :func:`compile_kernels`
first instead, and only the modules that call numba wait for it.

The scenes are tiny and go through the public API, so they compile exactly the
specialisations (argument types) that the experiments use: the BEM assembly of the
Laplace and Lame operators (the p = 1 closed forms and the general quadrature path), the
potentials at interior points, the gradient of the single layer on Gamma (the residual
estimator), boundary-curve checks, Polyak's projected CG and the Uzawa step of the
mortar solvers, the strain/force kernels of the plastic body and the cell kernels of the
plastic BE work piece.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["compile_kernels"]


def _bem(steps: dict) -> None:
    from ..bem import LameBEM, LaplaceBEM
    from ..geometry import BoundaryMesh

    t = time.perf_counter()
    mesh = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=1)
    steps["geometry"] = time.perf_counter() - t

    t = time.perf_counter()
    lap = LaplaceBEM(mesh)      # p = 1: the closed forms (hpfebe.bem.lowest_order)
    lap.V, lap.K, lap.W
    from ..bem.lowest_order import _gather    # the threaded closed form's second pass

    _gather(np.zeros((1, 2)), np.zeros((1, 2), np.int64), np.zeros(1, np.int64),
            np.zeros((1, 1)), np.arange(1))
    U = np.ones(lap.V_space.ndof)
    pts = np.column_stack([np.linspace(0.2, 0.8, 64), np.full(64, 0.5)])  # tabulated path
    lap.representation(pts, U, lap.Psi(U))
    steps["laplace"] = time.perf_counter() - t

    t = time.perf_counter()
    lame = LameBEM(mesh, 1.0, 0.3)   # p = 1: the closed forms (lowest_order_lame.lame_p1)
    lame.S_hat                       # (its threaded row chunks: the same types)
    steps["lame"] = time.perf_counter() - t

    # the general quadrature path (all kernels, p >= 2): no p = 1 scene reaches it now
    t = time.perf_counter()
    mesh2 = BoundaryMesh.polygon([(0, 0), (1, 0), (1, 1), (0, 1)], n=2, p=2)
    _ = LameBEM(mesh2, 1.0, 0.3).S_hat
    _ = LaplaceBEM(mesh2).S_hat
    steps["quadrature"] = time.perf_counter() - t

    t = time.perf_counter()
    U = np.ones(2 * lame.V_space.ndof)
    psi = lame.Psi(U)
    lame.representation(pts, U, psi)
    lame.stress(pts, U, psi)
    steps["lame_potentials"] = time.perf_counter() - t

    from ..adaptivity._ongamma import grad_single_layer_on_gamma

    t = time.perf_counter()
    grad_single_layer_on_gamma(lap.W_space, np.ones(lap.W_space.ndof), [0], [0.0])
    steps["estimator"] = time.perf_counter() - t


def _contact(steps: dict) -> None:
    from ..scenes.mortar import ModelProblem, model_problem
    from ..solvers import UzawaSettings, projected_cg

    t = time.perf_counter()
    A = np.array([[2.0, -1.0], [-1.0, 2.0]])
    projected_cg(A, np.array([1.0, 1.0]), np.array([0.1, np.inf]))
    steps["projected_cg"] = time.perf_counter() - t

    t = time.perf_counter()
    mc = model_problem(ModelProblem(n1=2, n2=2, p1=1, p2=1))
    mc.uzawa(np.zeros(2 * len(mc.points)), UzawaSettings(max_iter=2, relative=False))
    steps["uzawa"] = time.perf_counter() - t


def _plastic(steps: dict) -> None:
    from ..fem.elasticity import rectangle_mesh
    from ..fem.plastic_body import ElastoPlasticFE
    from ..constitutive.j2 import J2Material

    t = time.perf_counter()
    body = ElastoPlasticFE(rectangle_mesh(0.0, 1.0, 0.0, 1.0, 2, 2),
                           J2Material(1.0, 0.3, 1.0, 0.1))
    body.internal_force(np.zeros(body.ndofs))
    # a plastic state (every point past yield: strains of 10 against sigma_Y / E = 1): the
    # tangent kernels (_tangent_kernel, tangent_factors), compiled inside Example 2's job
    # before, and after a commit the committed force (_force_kernel)
    u = 10.0 * body.dof_coordinates()[:, 0]
    body.internal_force(u)
    body.commit(u)
    body.committed_force()
    steps["plasticity"] = time.perf_counter() - t

    # the BE work piece (Example 2's BE/BE runs): the cell checks, containment, the
    # double layer matrix (bem.potentials.potential_matrix) and the cell-strain Jacobian
    # kernels of hpfebe.bodies (compiled inside ch4_plasticity__ex2 before: jit 4.0 s)
    from ..bodies.plastic_be import rectangle_work_piece

    t = time.perf_counter()
    be = rectangle_work_piece((0.0, 1.0, 0.0, 1.0), 1, 1, J2Material(1.0, 0.3, 1e-3, 0.1),
                              scheme="implicit", cells="crossed")
    mesh, space = be.bem.mesh, be.bem.V_space
    X = np.zeros((space.ndof, 2))                    # the node of each P1 dof
    X[space.elem_dofs[:, 0]] = mesh.nodes[mesh.elements[:, 0]]
    u = np.zeros(be.ndofs)
    u[0::2], u[1::2] = 0.01 * X[:, 0], -0.01 * X[:, 1]   # 10 yield strains: plastic cells
    be.internal_force(u)
    steps["plastic_be"] = time.perf_counter() - t


def _hmatrix(steps: dict) -> None:
    from ..scenes import bem_scaling as bs

    t = time.perf_counter()
    for pde, p in (("laplace", 1), ("laplace", 4), ("lame", 1), ("lame", 2)):
        bs.solve(bs.ScalingRun(pde, 16, p, "hmatrix"))   # figure_bem_scaling's cases
    from ..scenes import bem_hertz as bh

    for kind in ("near_field", "multilevel"):             # figure_bem_hertz ("auto")
        bh.solve(bh.HertzRun(32), preconditioner=kind)
    steps["hmatrix"] = time.perf_counter() - t


def compile_kernels() -> dict[str, float]:
    """Run the tiny scenes; returns the wall time [s] of each (compile time on a cold
    cache, loading time on a warm one)."""
    steps: dict[str, float] = {}
    _bem(steps)
    _contact(steps)
    _plastic(steps)
    _hmatrix(steps)
    return steps
