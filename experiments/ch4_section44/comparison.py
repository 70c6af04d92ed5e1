"""The comparison of Figure 4.21 (mortar) with Figure 4.22 (penalty), thesis line ~20715:
"5-8 % in displacement, 2-3 % in stress": the claims on the relative differences of the
mortar and the penalty fields on common points and their split into variants
(:func:`hpfebe.scenes.section44_fields.comparison_rows`,
:data:`hpfebe.scenes.section44_fields.VARIANTS`), re-tested on the sensitivity variants
(:func:`hpfebe.scenes.section44_fields.comparison_readings`)."""

from __future__ import annotations

from hpfebe.scenes import section44 as s44
from hpfebe.scenes import section44_fields as f44
from hpfebe.suite import Claim


def _law(prm: s44.Section44Scene) -> str:
    return (f"Tresca F = {prm.F:g}" if prm.penalty_law == "tresca" else
            f"Coulomb mu_f = {prm.mu_f:g}")


def comparison_claims(rows: list, prm: s44.Section44Scene, sens: dict | None = None
                      ) -> list[Claim]:
    """The thesis's "5-8 % in displacement, 2-3 % in stress" twice: on its own setup
    (mortar Tresca F against penalty Coulomb mu_f; id ``bands``) and with the friction
    law matched (the method's difference alone; beyond the thesis), and (explanation of
    ``bands``) whether the friction law is the reason where the thesis's setup leaves
    the bands, on the table's meshes and on every sensitivity variant (``sens``)."""
    r = f44.comparison_readings(prm, rows, sens)
    bands = (f"at most {f44.BANDS['displacement']:.0%} in displacement and "
             f"{f44.BANDS['stress']:.0%} in stress")
    return [Claim(f"the thesis's setup - mortar (Tresca F = {prm.F:g}, Figure 4.21) against "
                  f"penalty ({_law(prm)}, 1/eps_n = {prm.figure_factor:g} E, Figure 4.22) - "
                  f"differs by 5-8 % in displacement and 2-3 % in stress (checked: {bands})",
                  *r["bands"], id="bands"),
            Claim(f"(beyond the thesis) with the friction law matched - penalty with the "
                  f"mortar's Tresca F = {prm.F:g}, 1/eps_n = {f44.matched_factor(prm):g} E "
                  f"(the stiffest of Table 4.3, nearest to the mortar's exact "
                  f"non-penetration) - the methods differ by 5-8 % in displacement and 2-3 % "
                  f"in stress (checked: {bands})", *r["matched"], kind="beyond",
                  id="matched"),
            Claim("(analysis) where the thesis's setup leaves the bands, the friction law is "
                  "the reason: every such field lies within them with the friction law "
                  f"matched at the same penalty ({f44.MATCHED}), on the table's meshes and in "
                  "every sensitivity variant", *r["friction_law"], kind="explanation",
                  id="friction_law", explains=("bands",))]
