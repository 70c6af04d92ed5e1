r"""
Every field to ParaView
=======================

The stamping scene of :ref:`sphx_glr_auto_examples_plot_07_j2_contact.py`, loaded step
by step, with every field written to VTU files that ParaView (or meshio) opens, and a
``.pvd`` collection per body that plays them as a time series:

* the FE bodies (:func:`hpfebe.io.write_fe_vtu`): the displacement as point data; the
  plastic strain :math:`\|\varepsilon^p\|`, :math:`\|\operatorname{dev}\sigma\|` and the
  hardening variable :math:`\alpha` of the work piece as cell data (element means);
* the contact boundary (:func:`hpfebe.io.write_contact_vtu`): pressure :math:`p_n`,
  tangential traction :math:`t_t`, gaps, slip and the state (open / stick / slip) at
  every contact point.

Each file is written atomically with the usual mode (0644).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import meshio
import numpy as np

from hpfebe import ElasticBody, ElastoPlasticFE, J2Material, TwoBodyContact
from hpfebe.contact import ContactSettings
from hpfebe.fem import rectangle_mesh
from hpfebe.io import write_contact_vtu, write_fe_vtu, write_pvd
from hpfebe.scenes import E, H, MU_F, NU, SIGMA_Y

out = Path(tempfile.mkdtemp(prefix="hpfebe_vtu_"))     # use your own folder here

stamp = ElasticBody(rectangle_mesh(-0.5, 0.5, 0, 1, 4, 4), E, NU)
work = ElastoPlasticFE(rectangle_mesh(-1, 1, -1, 0, 12, 6), J2Material(E, NU, SIGMA_Y, H))
problem = TwoBodyContact(stamp, work, "bottom", "top", eps_n=1 / (10 * E),
                         eps_t=1 / (5 * E), mu_f=MU_F)
fixed = np.concatenate([problem.dofs_on("slave", "top"), problem.dofs_on("master", "bottom")])
lift = np.where(np.isin(fixed, problem.dofs_on("master", "bottom", 1)), 2e-4, 0.0)

# %%
# Four load steps; after each, one VTU per body and one for the contact points.
# ``initial=`` continues from the last converged state (displacements, slip, the
# committed plastic history stays in the body).
series = {"stamp": [], "work": [], "contact": []}
result = None
for k, lam in enumerate((0.25, 0.5, 0.75, 1.0)):
    result = problem.solve(None, fixed, lam * lift, load_factors=[1.0], initial=result,
                           settings=ContactSettings(max_iter=40, line_search=True))
    assert result.converged, result.reason
    fields = work.fields()
    series["stamp"].append((lam, write_fe_vtu(
        out / f"stamp_{k}.vtu", stamp.mesh,
        {"u": stamp.nodal_displacement(result.u_slave).T})))
    series["work"].append((lam, write_fe_vtu(
        out / f"work_{k}.vtu", work.mesh,
        {"u": work.elastic.nodal_displacement(result.u_master).T},
        cell_data={"eps_p": fields["eps_p_norm_mean"],
                   "dev_sigma": fields["dev_sigma_norm_mean"],
                   "alpha": fields["alpha_mean"]})))
    series["contact"].append((lam, write_contact_vtu(out / f"contact_{k}.vtu", result)))
for name, steps in series.items():
    write_pvd(out / f"{name}.pvd", steps)
print("written:", sorted(p.name for p in out.iterdir()))

# %%
# What ParaView will see: read the last files back with meshio.
back = meshio.read(out / "work_3.vtu")
print("work piece: point data", list(back.point_data), "cell data", list(back.cell_data))
contact = meshio.read(out / "contact_3.vtu")
print("contact points: point data", list(contact.point_data))

fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
x = contact.points[:, 0]
order = np.argsort(x)
a1.plot(x[order], contact.point_data["p_n"][order], "o-", ms=3, label="$p_n$")
a1.plot(x[order], contact.point_data["t_t"][order], "s-", ms=3, label="$t_t$")
a1.set_xlabel("x on $\\Gamma_C$")
a1.legend()
a1.set_title("contact tractions (contact_3.vtu)")
pts, quads = back.points[:, :2], back.cells_dict["quad"]
tri = np.vstack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
eps_p = np.tile(back.cell_data["eps_p"][0], 2)
tc = a2.tripcolor(pts[:, 0], pts[:, 1], tri, facecolors=eps_p)
a2.set_aspect("equal")
a2.set_title(r"$\|\varepsilon^p\|$ (work_3.vtu, cell data)")
fig.colorbar(tc, ax=a2)
plt.show()
