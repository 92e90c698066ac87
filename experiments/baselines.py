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

from experiments.study import RESULTS
from experiments.table import Measure, Table
from imrl_jax import conditions

#: The study's folder: each stage's (one per agent and budget) and comparison.png.
OUT = os.path.join(RESULTS, "baselines")
#: Lane-steps a cycle of a baseline costs on 2 cores: the four stages' 244 M cycles took 43.5 min (BASELINES.md).
LANE_STEPS_PER_CYCLE = 31


def baseline(agent: str, steps: int, num_seeds: int, num_evals: int) -> Measure:
    """One agent at one budget per task, ``num_seeds`` seeds on each of the six tasks, in ``OUT/AGENT_BUDGET``."""
    name = f"{agent}_{steps // 1_000_000}M"
    return Measure(name, "", ("--agent", agent, "--steps", str(steps), "--seeds", str(num_seeds), "--evals",
                              str(num_evals)), "imrl_jax.baselines", float(LANE_STEPS_PER_CYCLE * 6 * num_seeds * steps),
                   os.path.join(OUT, name), kind="baseline")


class BaselinesTable(Table):
    """The baselines' stages; the report draws them beside the paper's architecture (comparison.png)."""

    def tests_dir(self) -> str:
        """The paper scale's reproduction where its learning tests exist, else the cpu scale's."""
        paper = os.path.join(self.results, "paper")
        return paper if any(os.path.isfile(os.path.join(paper, v, "test", c, "steady.json"))
                            for v in ("skills", "paper", "extension") for c in conditions.PAPER) else \
            os.path.join(self.results, "cpu")

    def report(self) -> int:
        from experiments.document import scale_label
        from experiments.figures import fig_baselines
        from experiments.loading import read_baselines
        from experiments.reproduction import TABLES
        from imrl_jax.plotting import save

        found = read_baselines(self.out)
        if not found:
            print(f"no baseline has finished in {self.out}: nothing to draw")
            return 0
        tests = next((t for t in TABLES.values() if os.path.abspath(t.out) == os.path.abspath(self.tests_dir())), None)
        data = tests.data() if tests is not None else dict(tests={}, manifest=None)
        title = (f"brax.training baselines beside the paper's architecture\n(its learning tests at the "
                 f"{scale_label(data['manifest'])})") if data["tests"] else "brax.training baselines"
        print(f"wrote {save(fig_baselines(found, data['tests'], title), os.path.join(self.out, 'comparison.png'))}")
        return 0


TABLE = BaselinesTable("baselines", os.path.join("docs", "BASELINES.md"), 11, rows=(), scale={}, out=OUT, measures=(
    baseline("ppo", 1_000_000, 5, 11), baseline("es", 1_000_000, 5, 11),
    baseline("ppo", 5_000_000, 3, 21), baseline("es", 5_000_000, 3, 21)))
all_stages, main = TABLE.all_stages, TABLE.main
#: The studies of this module (python -m experiments finds them).
STUDIES = (TABLE.study(__name__.rsplit(".", 1)[-1]),)

if __name__ == "__main__":
    sys.exit(main())
