"""The two constructor keywords of LaplaceBEM / LameBEM, ``compression`` and ``tol``, and
the dispatch of the operators that :class:`~hpfebe.bem.operators.BoundaryOperators`
defines (B, K', S_hat, Psi) to the compressed ones.  ``compression=None`` (default) is
the dense path: every method below then calls the dense one, nothing else changes.
"""

from __future__ import annotations

import numpy as np

from ...checks import choice, real
from .operators import CompressedOperators, HMatrixSettings

COMPRESSIONS = (None, "hmatrix")


class Compressible:
    """Mixin before BoundaryOperators: ``self.hm`` is None (dense) or the
    :class:`CompressedOperators` of this mesh."""

    hm = None

    def _set_compression(self, compression, tol) -> None:
        self.compression = choice("compression", compression, COMPRESSIONS)
        self.tol = real("tol", tol, lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        if self.compression == "hmatrix":
            self.hm = CompressedOperators(self, HMatrixSettings(tol=self.tol))

    @property
    def B(self):
        return self.hm.B if self.hm is not None else super().B

    @property
    def K_adj(self):
        return self.hm.K_adj if self.hm is not None else super().K_adj

    @property
    def S_hat(self):
        """Dense: the matrix; compressed: a symmetric LinearOperator W + B^T P B whose
        P is applied by CG on the compressed V (never V^-1 densely)."""
        return self.hm.S_hat if self.hm is not None else super().S_hat

    @property
    def V_cho(self):
        if self.hm is not None:
            raise AttributeError("V_cho: no dense factorisation with compression="
                                 f"{self.compression!r} (use Psi or hm.solve_V)")
        return super().V_cho

    def Psi(self, U):
        if self.hm is None:
            return super().Psi(U)
        U = np.asarray(U, dtype=float)
        n = self.d * self.V_space.ndof
        if U.ndim not in (1, 2) or U.shape[0] != n:
            raise ValueError(f"U must have {n} rows (d x V_hp dofs), got shape {U.shape}")
        if not np.all(np.isfinite(U)):
            raise ValueError("U contains NaN or infinite entries")
        return self.hm.Psi(U)

    def hmatrix_info(self, sampled_rows: int = 8) -> dict:
        """Storage, ranks, build times and errors of the compressed operators built so
        far (:meth:`CompressedOperators.info`); ValueError on the dense path."""
        if self.hm is None:
            raise ValueError("hmatrix_info: compression is None (dense operators)")
        return self.hm.info(sampled_rows)
