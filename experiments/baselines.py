"""The committed brax baselines (docs/BASELINES.md): PPO and ES on the six tasks at two budgets, then a figure.

    python -m experiments run baselines       # run (or go on with) its four stages
    python -m experiments list baselines      # the stages, done or to run
    python -m experiments report baselines    # comparison.png

Each stage is ``python -m imrl_jax.baselines`` into its folder, done once its summary.json is
written. The report puts the baselines beside the learning tests of the paper scale's results
when they have any, else the cpu scale's, labelled with that scale.
"""

import os
import sys

from experiments.harness.study import RESULTS, SCALES
from experiments.harness.table import Measure, Table
from imrl_jax import conditions

#: The study's folder: each stage's (one per agent and budget) and comparison.png.
OUT = os.path.join(RESULTS, "baselines")
#: The budgets' unit: the paper's learning test, cycles per task (the first budget; the second is 5 times it).
SIZES = dict(test_steps=SCALES["paper"]["test_steps"])
#: Lane-steps a cycle of a baseline costs on 2 cores: the four stages' 244 M cycles took 43.5 min (BASELINES.md).
LANE_STEPS_PER_CYCLE = 31


class BaselinesTable(Table):
    """The baselines' stages; the report draws them beside the paper's architecture (comparison.png)."""

    def tests_dir(self) -> str:
        """The paper scale's reproduction where its learning tests exist, else the cpu scale's."""
        paper = os.path.join(self.results, "paper")
        tested = any(os.path.isfile(os.path.join(paper, preset, "test", condition, "steady.json"))
                     for preset in ("skills", "paper", "extension") for condition in conditions.PAPER)
        return paper if tested else os.path.join(self.results, "cpu")

    def report(self) -> int:
        """comparison.png: the finished baselines beside the learning tests of :meth:`tests_dir`."""
        from experiments.document import scale_label
        from experiments.harness.figures import fig_baselines
        from experiments.harness.loading import read_baselines
        from experiments.reproduction import TABLES
        from imrl_jax.analysis.plotting import save

        if not (found := read_baselines(self.out)):
            print(f"no baseline has finished in {self.out}: nothing to draw")
            return 0
        tests = [t for t in TABLES.values() if os.path.abspath(t.out) == os.path.abspath(self.tests_dir())]
        data = tests[0].data() if tests else dict(tests={}, manifest=None)
        title = (f"brax.training baselines beside the paper's architecture\n(its learning tests at the "
                 f"{scale_label(data['manifest'])})") if data["tests"] else "brax.training baselines"
        print(f"wrote {save(fig_baselines(found, data['tests'], title), os.path.join(self.out, 'comparison.png'))}")
        return 0


#: Each agent at each budget per task (its seeds on each of the six tasks), in ``OUT/AGENT_BUDGET``.
TABLE = BaselinesTable("baselines", os.path.join("docs", "BASELINES.md"), 11, rows=(), scale=SIZES, out=OUT, measures=(
    *(Measure(f"{agent}_{budget}M", "", ("--agent", agent, "--steps", str(budget * SIZES["test_steps"]), "--seeds",
                                         str(num_seeds), "--evals", str(num_evals)), "imrl_jax.baselines",
              float(LANE_STEPS_PER_CYCLE * 6 * num_seeds * budget * SIZES["test_steps"]), f"{agent}_{budget}M",
              kind="baseline") for budget, num_seeds, num_evals in ((1, 5, 11), (5, 3, 21)) for agent in ("ppo", "es")),
))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
