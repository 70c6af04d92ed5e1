"""The reproducibility suite around the solver core: the results contract and claims
(:mod:`.results`), typed experiment parameters (:mod:`.params`), the report that sets
every reproduced number beside the published one (:mod:`.report`) and the numba warm-up
(:mod:`.warmup`).  The solver packages never import it; the CLI and the experiments do.

The modules are imported on use (``from hpfebe.suite.results import Claim``): the report
needs pandas and matplotlib, which a job that only writes results does not."""
