"""Files in and out at the edge of the core: gmsh meshes in through meshio
(:mod:`.meshes`); boundary, FE and contact fields to VTU (and PVD series) for ParaView,
written atomically (:mod:`.vtu`); a BE body's interior field on a sampling mesh by the
representation formula (:mod:`.fields`)."""

from .fields import interior_vtu, sampling_mesh, write_interior_vtu
from .meshes import read_boundary_mesh, read_fe_mesh
from .vtu import (CONTACT_FIELDS, boundary_vtu, contact_vtu, fe_vtu, write_boundary_vtu,
                  write_contact_vtu, write_fe_vtu, write_pvd, write_vtu, write_vtu_series)

__all__ = ["read_fe_mesh", "read_boundary_mesh",
           "boundary_vtu", "fe_vtu", "contact_vtu", "CONTACT_FIELDS",
           "write_boundary_vtu", "write_fe_vtu", "write_contact_vtu", "write_pvd", "write_vtu",
           "write_vtu_series", "interior_vtu", "sampling_mesh", "write_interior_vtu"]
