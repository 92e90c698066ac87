"""The paper's questions in a second world (docs/WORLDS.md): its conditions and controls in XLand-MiniGrid.

    python -m experiments run worlds         # run (or go on with) every stage, in order
    python -m experiments list worlds        # the stages, done or to run
    python -m experiments report worlds      # the curves and tables of what has finished

Each row is a condition of the paper (and the length control LE-LS-Z, EE-LS's genome length in this world) evolved
in the XLand world of ``imrl_jax/world/xland.py`` (``--world xland``) under the paper's rules, at :data:`SCALE`:
5 seeds x 50 generations of the paper's GA (50 lives, 10 parents), a childhood of 20,000 steps and tasks of 10,000
(the paper's 150,000 and 100,000 scaled to two CPU cores: a task's shortest solution is 12-14 steps, so 10,000
steps still hold 700-800 of them), then a learning test of each seed's 5 best x 2 tests at 10 x the task length.
SLE learns each task from scratch there. The measures test the evolved rows on the world's novel tasks
(``--world-set task_set=xland-novel``), SLE beside them, and measure the landscapes of goals and behaviours (H1, H2,
H4 of docs/GOALS.md: ``imrl_jax.landscape_run`` on each row's seed 0).
"""

from __future__ import annotations

import os
import sys

from experiments.harness.reproduce import test_command, test_cost
from experiments.harness.study import RESULTS
from experiments.harness.table import Measure, Row, Table

#: The study's manifest, logs and measures (its runs lie wherever their keys find them).
OUT = os.path.join(RESULTS, "worlds")
WORLD = ("--world", "xland")
NOVEL = ("--world-set", "task_set=xland-novel")
#: The sizes of its runs (see the module's docstring).
SCALE = dict(seeds=5, generations=50, childhood_steps=20_000, task_steps=10_000, bins=10, best=5, tests=2,
             test_steps=100_000, test_bins=50, steady_steps=10_000)
#: The evolved conditions: the paper's three and the length control.
EVOLVED = ("LE-LS", "EE-LS", "EE-ES", "LE-LS-Z")


#: A life of each condition in steps (childhood, six tasks), for the measures' costs.
LIFE = {"LE-LS": 20_000 + 6 * 10_000, "EE-LS": 6 * 10_000, "EE-ES": 6 * 10_000}
#: Lives of a landscape measure (imrl_jax.landscape_run's defaults, as the goals study): 3 generations x (10 parents
#: x 10 + 5 walks x 10) genomes x 4 lives, 50 random genomes x 4, and replays; twice with a learning cut.
LIVES, CUT_LIVES = 3 * 150 * 4 + 200 + 550, 3 * 150 * 4 + 200
#: The learning cuts of the landscape measures (H4: how much of a goal's value needs learning), as the goals study's.
CUTS = {"LE-LS": "0.1,0.33", "EE-LS": "0", "EE-ES": None}


def landscape(row: Row) -> Measure:
    """The landscape measures (H1, H2, H4) of a row's seed 0 at generations 0, 10 and the last (docs/GOALS.md)."""
    cut = CUTS[row.condition]
    return Measure(f"landscape-{row.name}", row.name, ("--cut", cut) if cut else (),
                   cost=float(LIFE[row.condition] * (LIVES + (CUT_LIVES if cut else 0))))


def novel_test(row: Row) -> Measure:
    """A learning test of ``row``'s run on the world's novel tasks, at the table's sizes."""
    runner = tuple(test_command(SCALE, "paper", "EE-ES", "RUN", "OUT")[4:-2])  # the runner's options, at SCALE
    return Measure(f"{row.name} on novel", row.name, runner + NOVEL, "imrl_jax.learning_test",
                   test_cost(SCALE, row.condition), os.path.join("novel", row.condition), kind="test")


ROWS = tuple(Row(condition, condition, "paper", options=WORLD) for condition in EVOLVED)
TABLE = Table("worlds", "docs/WORLDS.md", 10, out=OUT, scale=SCALE, rows=(
    *ROWS, Row("SLE", "SLE", "paper", options=WORLD), Row("SLE on novel", "SLE", "paper", options=WORLD + NOVEL),
), measures=(*(novel_test(row) for row in ROWS if row.condition in LIFE),
             *(landscape(row) for row in ROWS if row.condition in LIFE)))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
