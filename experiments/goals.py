"""Why evolving goals is easier than evolving behaviours (docs/GOALS.md): the size-matched controls' first runs.

    python -m experiments run goals          # run (or go on with) every stage, in order
    python -m experiments list goals         # the stages, done or to run

The paper's conditions (LE-LS: 111 reinforcer genes; EE-LS: 222 actor genes) differ in both the size
and the kind of what is evolved. The controls cross the two (MODEL.md "Size-matched controls"):
EE-LS-T evolves behaviours at LE-LS's size, LE-LS-2R goals at EE-LS's size. Each is evolved under
``skills`` and ``faithful`` for 5 seeds x 100 generations of 50 lives at the paper's lengths (150,000 +
6 x 100,000 steps), then its 5 best x 4 tests are learning-tested, as in the future-work study. The
landscape measures (``imrl_jax.landscape``) and the report come with the study's next stages.
"""

import os
import sys

from experiments.claims_study import SCREEN
from experiments.table import Row, Table

TABLE = Table("goals", "docs/GOALS.md", 9, out=os.path.join("experiments", "results", "goals"), scale=SCREEN, rows=(
    Row("EE-LS-T", "EE-LS-T", "skills"),  # behaviours at goals' size
    Row("LE-LS-2R", "LE-LS-2R", "skills"),  # goals at behaviours' size
    Row("EE-LS-T-faithful", "EE-LS-T", "faithful"),
    Row("LE-LS-2R-faithful", "LE-LS-2R", "faithful"),
))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
