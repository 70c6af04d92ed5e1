r"""
A J2 elastoplastic body in contact
==================================

An elastic stamp pressed into an elastoplastic work piece (J2 flow theory with linear
hardening, (4.21)-(4.22), the thesis's material data), both finite elements, with
Coulomb friction between them (Section 4.2.7 in miniature).  Each load step is solved
by Newton's method with the consistent tangents of the contact terms (Section 4.2.5)
and of the radial return map (Section 4.2.6); the plastic history is committed after
every converged step.
"""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PolyCollection

from hpfebe import ElasticBody, ElastoPlasticFE, J2Material, TwoBodyContact
from hpfebe.contact import ContactSettings
from hpfebe.fem import rectangle_mesh
from hpfebe.scenes import E, H, MU_F, NU, SIGMA_Y

# %%
# The stamp [-0.5, 0.5] x [0, 1] (slave) on the work piece [-1, 1] x [-1, 0] (master),
# Q1 elements; the work piece yields at sigma_Y with hardening modulus H.
stamp = ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 1, 6, 6), E, NU)
work = ElastoPlasticFE(rectangle_mesh(-1, 1, -1, 0, 16, 8), J2Material(E, NU, SIGMA_Y, H))
problem = TwoBodyContact(stamp, work, "bottom", "top", eps_n=1 / (10 * E),
                         eps_t=1 / (5 * E), mu_f=MU_F)

# %%
# The stamp's top is held, the work piece's bottom pushed up by 2e-4 in four steps.
fixed = np.concatenate([problem.dofs_on("slave", "top"), problem.dofs_on("master", "bottom")])
lift = np.where(np.isin(fixed, problem.dofs_on("master", "bottom", 1)), 2e-4, 0.0)
res = problem.solve(None, fixed, lift, load_factors=np.linspace(0.25, 1, 4),
                    settings=ContactSettings(max_iter=40, line_search=True))
print(res.converged, res.reason, "Newton per step:", res.iterations)
print("contact force:", np.round(res.total_forces(), 2))

# %%
# The committed fields of the work piece, per element: the plastic strain and
# :math:`\|\operatorname{dev}\sigma\|`, which cannot exceed
# :math:`\sqrt{2/3}\,K(\alpha)` (the yield condition (4.21)).
fields = work.fields()
print("fields:", sorted(fields))
eps_p = fields["eps_p_norm_mean"]
dev = fields["dev_sigma_norm_mean"]
bound = np.sqrt(2 / 3) * (SIGMA_Y + H * fields["alpha"].max())
print(f"plastic elements: {np.sum(eps_p > 0)} of {len(eps_p)}; max ||dev sigma|| = "
      f"{fields['dev_sigma_norm'].max():.3f} <= sqrt(2/3) K(alpha_max) = {bound:.3f}")

# %%
# The plastic zone under the stamp's edges, and the deviatoric stress.
mesh = work.mesh
cells = mesh.p.T[mesh.t.T]                      # (nel, 4, 2) corners of each element
fig, axes = plt.subplots(1, 2, figsize=(11, 3.4))
for ax, value, title in ((axes[0], eps_p, r"$\|\varepsilon^p\|$ (element mean)"),
                         (axes[1], dev, r"$\|\operatorname{dev}\sigma\|$ (element mean)")):
    pc = PolyCollection(cells, array=value, cmap="viridis", edgecolors="face")
    ax.add_collection(pc)
    ax.plot([-0.5, -0.5, 0.5, 0.5], [0.25, 0, 0, 0.25], "w-", lw=2)   # the stamp
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 0.25)
    ax.set_aspect("equal")
    ax.set_title(title)
    fig.colorbar(pc, ax=ax)
plt.show()
