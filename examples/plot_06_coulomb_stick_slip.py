r"""
Coulomb friction: stick and slip
================================

An elastic FE block pressed onto a rigid flat that is then dragged sideways.  The
tangential traction follows the Coulomb law by the return map of Sections 3.3.1 and
4.2.1: a trial traction from the tangential penalty :math:`\varepsilon_t^{-1}`, kept if
:math:`|t_t| \le \mu_f p_n` (**stick**), else scaled back onto the cone
:math:`|t_t| = \mu_f p_n` (**slip**).  As the drag grows, the contact goes from full
stick through partial slip to sliding.
"""

import matplotlib.pyplot as plt
import numpy as np

from hpfebe import ElasticBody, RigidObstacle, TwoBodyContact
from hpfebe.constitutive import SLIP, STICK
from hpfebe.contact import ContactSettings
from hpfebe.fem import rectangle_mesh
from hpfebe.scenes import E, NU

MU_F = 0.3
block = ElasticBody(rectangle_mesh(-1, 1, 0, 1, 32, 16), E, NU)   # Q1, plane strain

# %%
# The flat is the line y = 0 (gap g = y on the block's bottom).  Its motion w along
# the contact tangent is ramped with the load: the top of the block is held and pushed
# down by 1e-3 while the flat moves by w.
fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharey=True)
for ax, w in zip(axes, (5e-4, 1e-3, 2e-3)):
    flat = RigidObstacle(gap=lambda x: x[:, 1], motion=w)
    problem = TwoBodyContact(block, flat, "bottom", eps_n=1 / (10 * E),
                             eps_t=1 / (5 * E), mu_f=MU_F)
    top = problem.dofs_on("slave", "top")
    top_y = problem.dofs_on("slave", "top", 1)
    res = problem.solve(None, top, np.where(np.isin(top, top_y), -1e-3, 0.0),
                        load_factors=np.linspace(0.2, 1.0, 5),
                        settings=ContactSettings(line_search=True))
    n_stick, n_slip = np.sum(res.state == STICK), np.sum(res.state == SLIP)
    print(f"w = {w:g}: converged {res.converged}, {n_stick} stick and {n_slip} slip "
          f"points, Newton per step {res.iterations}")
    x = res.points[:, 0]
    order = np.argsort(x)
    ax.plot(x[order], -res.t_t[order], "-", label="$-t_t$")
    ax.plot(x[order], MU_F * res.p_n[order], "k--", label=r"$\mu_f p_n$")
    slip = res.state[order] == SLIP
    ax.plot(x[order][slip], -res.t_t[order][slip], "r.", label="slip")
    ax.set_title(f"w = {w:g}: {n_slip} of {len(x)} points slip")
    ax.set_xlabel("x")
axes[0].legend()
plt.show()
