"""Why evolving goals is easier than evolving behaviours (docs/GOALS.md): the size-matched controls' first runs.

    python -m experiments run goals          # run (or go on with) every stage, in order
    python -m experiments list goals         # the stages, done or to run

The paper's conditions (LE-LS: 111 reinforcer genes; EE-LS: 222 actor genes) differ in both the size
and the kind of what is evolved. The controls cross the two (MODEL.md "Size-matched controls"):
EE-LS-T evolves behaviours at LE-LS's size, LE-LS-2R goals at EE-LS's size. Each is evolved under
``skills`` and ``faithful`` for 5 seeds x 100 generations of 50 lives at the paper's lengths (150,000 +
6 x 100,000 steps), then its 5 best x 4 tests are learning-tested, as in the future-work study. Then the landscape
measures (``python -m imrl_jax.landscape_run``) of seed 0 of each condition under ``skills`` at
generations 0, 10 and the last, with learning cut too (H3), and the fitness of random genomes (H4).
"""

import os
import sys

from experiments.claims_study import SCREEN
from experiments.table import Measure, Row, Table

RESULTS = os.path.join("experiments", "results")
#: The paper's runs whose last population was not kept: their best 10 of each seed are (the reproduction's report).
KEPT = ("--best-genomes", os.path.join(RESULTS, "paper", "best_genomes.npz"))
#: A life of each condition, in steps (childhood 150,000 + 6 x 100,000), for the measures' costs.
LIFE = {"LE-LS": 750_000, "EE-LS": 600_000}
#: Lives of a landscape measure: 3 generations x (10 parents x 10 + 5 walks x 10) genomes x 4 lives, 50 random
#: genomes x 4, and 11 generations x 50 replayed; twice the measures with a learning cut.
LIVES, CUT_LIVES = 3 * 150 * 4 + 200 + 550, 3 * 150 * 4 + 200


def landscape(name: str, run: str, life: int, cut: str | None = None, *extra: str) -> Measure:
    """The landscape measures (H3, H4) of a row's or a committed run's seed 0 at generations 0, 10 and the last."""
    args = (("--cut", cut) if cut else ()) + extra
    return Measure(f"landscape-{name}", run, args, cost=float(life * (LIVES + (CUT_LIVES if cut else 0))))


TABLE = Table("goals", "docs/GOALS.md", 9, out=os.path.join(RESULTS, "goals"), scale=SCREEN, rows=(
    Row("EE-LS-T", "EE-LS-T", "skills"),  # behaviours at goals' size
    Row("LE-LS-2R", "LE-LS-2R", "skills"),  # goals at behaviours' size
    Row("EE-LS-T-faithful", "EE-LS-T", "faithful"),
    Row("LE-LS-2R-faithful", "LE-LS-2R", "faithful"),
), measures=(  # under skills (EE-ES learns nothing: its paper run is its only one); H3's cuts: LE-LS-like
    # childhoods to a tenth, EE-LS-like adult selectors to nothing (imrl_jax.landscape.learning_cut)
    landscape("EE-ES", os.path.join(RESULTS, "paper", "paper", "evolve", "EE-ES"), LIFE["EE-LS"], None, *KEPT),
    landscape("EE-LS-T", "EE-LS-T", LIFE["EE-LS"], "0"),
    landscape("EE-LS", os.path.join(RESULTS, "paper", "skills", "evolve", "EE-LS"), LIFE["EE-LS"], "0", *KEPT),
    landscape("LE-LS", os.path.join(RESULTS, "paper", "skills", "evolve", "LE-LS"), LIFE["LE-LS"], "0.1", *KEPT),
    landscape("LE-LS-2R", "LE-LS-2R", LIFE["LE-LS"], "0.1"),
    landscape("EV-LS", os.path.join(RESULTS, "future_work", "EV-LS", "evolve"), LIFE["LE-LS"], "0.1"),
))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
