"""Beyond the thesis: the coercivity threshold of the hp-Nitsche form (Lemma 2.2.3).

For p = 1..10 we compute lambda*(p) = inf{lambda_Nit : a_h positive definite on V_hp} on
the thesis's p-version meshes of Example 1 (FE h = 1/5, BE h = 1/6) and, for p = 1, 2, 3,
on its h-version meshes, as the largest generalised eigenvalue of the interface Schur
complement (hpfebe.coupling.coercivity explains the formulation).  For alpha = 0, 1, 2
the thresholds are lambda*(alpha) = lambda*(0) p^-alpha (the penalty scales with
p^alpha, checked in the tests).  Beside it: the sufficient condition of Lemma 2.2.3 as
printed, lambda_Nit >= 1/2 p^(2-alpha) + C_inv p^(2-alpha) (gamma = 2), with C_inv the
computed constant of the inverse inequality (2.7), and the sharper C_inv p^(2-alpha)
that Young's inequality gives without slack.  Statement: whether lambda_Nit = 1, 5, 10
are below or above lambda* for p = 1, 2, 3 on the thesis's meshes.
"""

from __future__ import annotations

import time

import pandas as pd
from matplotlib.figure import Figure

from hpfebe.scenes import interface, interface_readings as rd
from hpfebe.suite import ArtefactResult, Claim, from_config, new_figure, progress, style_axes

ARTEFACTS = ("figure_coercivity",)

ALPHAS = interface.ALPHAS        # penalty exponents p^alpha
THESIS_LAMBDAS = rd.THESIS_LAMBDAS     # the lambda_Nit of Example 3
#: the scene's parameters (config section ch2_coercivity)
Params = interface.CoercivityScene


def _figure(main: pd.DataFrame, prm: Params) -> Figure:
    fig, ax = new_figure((7.0, 5.0))
    for alpha, c in zip(ALPHAS, ("C0", "C1", "C2")):
        g = main[main.alpha == alpha]
        ax.semilogy(g.p, g.lambda_star, "o-", color=c,
                    label=f"computed lambda*, alpha={alpha:g}")
        ax.semilogy(g.p, g.lemma_bound, "--", color=c, label=f"Lemma 2.2.3, alpha={alpha:g}")
    for value in THESIS_LAMBDAS:
        ax.axhline(value, color="gray", lw=0.6, ls=":")
        ax.annotate(f"lambda={value}", (prm.degrees[-1], value), fontsize=7, color="gray")
    style_axes(ax, "p = p1 = p2", "lambda_Nit", f"Coercivity threshold, Example 1, FE "
               f"h=1/{prm.mesh[0]}, BE h=1/{prm.mesh[1]} (h1 = {prm.h_def} length)",
               title_size=9, legend=dict(fontsize=7))
    return fig


def _claims(table: pd.DataFrame, main: pd.DataFrame) -> list[Claim]:
    return [
        Claim("beyond the thesis: with alpha = 0 the threshold grows with p (like p^2)",
              *rd.threshold_growth(main), kind="beyond"),
        Claim("the computed threshold respects the sufficient condition of Lemma 2.2.3",
              *rd.lemma(main), id="lemma"),
        Claim("thesis (Example 3): the coercivity threshold lies between lambda = 1 and 5 for "
              "p = 1 and between 5 and 10 for p = 3", *rd.example3(table), id="example3")]


def run(config: dict, quick: bool = False) -> list[ArtefactResult]:
    """figure_coercivity (``quick`` is unused: config/quick.yaml sets the sizes)."""
    prm = from_config(Params, config, scene="ch2_coercivity")
    t0 = time.perf_counter()
    table = pd.DataFrame(interface.coercivity_rows(prm, progress))
    main = table[table.mesh == f"{prm.mesh[0]}/{prm.mesh[1]}"]
    statement = rd.thresholds(table[table.alpha == 0.0])
    return [ArtefactResult(
        name="figure_coercivity", table=table, figure=_figure(main, prm),
        claims=_claims(table, main),
        notes="Beyond the thesis. " + statement + ". " + " ".join(interface.COERCIVITY_CHOICES)
              + " lambda* is within 1 % of young_bound: the BE part hardly helps.",
        meta=dict(run_s=round(time.perf_counter() - t0, 2),
                  allow_nan_columns=["C_inv", "young_bound", "lemma_bound"]))]
