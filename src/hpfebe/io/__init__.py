"""Files in and out at the edge of the core: boundary and FE fields to VTU (ParaView),
written atomically (:mod:`.vtu`)."""

from .vtu import boundary_vtu, fe_vtu, write_boundary_vtu, write_fe_vtu, write_vtu

__all__ = ["boundary_vtu", "fe_vtu", "write_boundary_vtu", "write_fe_vtu", "write_vtu"]
