r"""
Mortar contact: DtN, Uzawa and semismooth Newton
================================================

Two boundary element bodies in contact with given (Tresca) friction, coupled through
the mortar projection (4.87) :math:`\Phi^1 = D^{-1} B \Phi^2` (Section 4.3), solved three
ways:

* the **Dirichlet-to-Neumann** iteration (Algorithm 4.3, Section 4.3.3): a Neumann
  problem in body 2 and a contact problem of body 1, relaxed by the dampings
  :math:`\omega_D, \omega_N`;
* the global **Uzawa** algorithm (Algorithm 4.5, Section 4.3.5): a projected gradient
  step on the contact traction;
* a monolithic **semismooth Newton** (primal-dual active set) method on the same
  discrete problem.

The scene is the model problem of Section 4.3.4 at a small size: an arc-shaped body 1
pressed down onto the block body 2 (:func:`hpfebe.scenes.model_problem`).
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe.scenes import ModelProblem, model_problem
from hpfebe.solvers import DtNSettings, GlobalUzawaSettings, SemismoothSettings, UzawaSettings

problem = model_problem(ModelProblem(n1=8, n2=6, p1=2, p2=2, F=0.1))

# %%
# The three solvers; each returns a :class:`~hpfebe.contact.MortarSolution` with the
# boundary displacements U1, U2 of the bodies and a
# :class:`~hpfebe.solvers.SolverInfo`.
solutions = {
    "DtN": problem.dtn(DtNSettings(omega_D=0.5, omega_N=0.5, uzawa=UzawaSettings())),
    "Uzawa": problem.global_uzawa(GlobalUzawaSettings(friction="tresca")),
    "semismooth Newton": problem.semismooth_newton(SemismoothSettings(friction="tresca")),
}
for name, sol in solutions.items():
    print(f"{name:18s} converged {sol.info.converged}, {sol.info.iterations} iterations")

# %%
# All three reach the same discrete solution: the vertical displacement of body 1 along
# its contact boundary, and the iteration histories.
bem1 = problem.bem1
mesh1 = bem1.mesh
contact = np.flatnonzero(mesh1.labels == "C")
t = np.linspace(-1, 1, 9)
elem = np.repeat(contact, len(t))
tt = np.tile(t, len(contact))
x = mesh1.points(elem, tt)[:, 0]
order = np.argsort(x)
fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
for (name, sol), style in zip(solutions.items(), ("-", "--", ":")):
    uy = bem1.V_space.evaluate(sol.U1.reshape(-1, 2)[:, 1], elem, tt)
    a1.plot(x[order], uy[order], style, lw=2, label=name)
    res = np.asarray(sol.info.residuals, dtype=float)
    if res.size:
        a2.semilogy(np.arange(1, res.size + 1), res, style, label=name)
diff = max(np.abs(s.U1 - solutions["semismooth Newton"].U1).max() for s in solutions.values())
print(f"largest difference of U1 to the semismooth Newton solution: {diff:.1e}")
a1.set_xlabel("x on $\\Gamma^1_C$")
a1.set_ylabel("$u_y$ of body 1")
a1.legend()
a2.set_xlabel("iteration")
a2.set_ylabel("residual / increment")
a2.set_xscale("log")
a2.legend()
plt.show()
