"""The claims map's rule sets (docs/CLAIMS.md): learning rules as a preset plus overrides, and their runs' sizes.

A leaf of the studies: the reproduction takes a rule set as a variant, the claims map and the time-scale
study measure them; each imports this table, and it imports none of them.
"""

from __future__ import annotations

from typing import NamedTuple

from imrl_jax.config import ADULT_SELECTOR


#: The conditions whose runs a rule set takes at the paper's sizes by default: the reproduction's. EE-LS depends
#: only on the adult selector's values and EE-ES on nothing learned, so each is one of the reproduction's runs.
SHARED_FULL = ("EE-LS", "EE-ES")
#: Every condition at the paper's sizes: the reproduction's own rule sets.
ALL_FULL = ("LE-LS", "EE-LS", "EE-ES", "SLE")


class RuleSet(NamedTuple):
    """One row of the claims map: learning rules as a preset plus overrides, and which of its runs are at the
    paper's sizes (the others at the screen's); a run is found by what it computes, so rule sets whose lives are
    the same share it."""

    name: str
    preset: str
    sets: tuple[str, ...]
    about: str
    ee_ls: str  # the reproduction's variant whose EE-LS run is this one's (the reproduction shares it so)
    full: tuple[str, ...] = SHARED_FULL  # the conditions run at the paper's sizes
    sle_noise_steps: int | None = None  # SLE's noise horizon: None one task's length (100,000), 0 the whole test

    def whole_test(self, about: str, **fields) -> RuleSet:
        """This rule set under the second SLE reading, its noise annealed over the whole test (``NAME-sle-test``)."""
        return self._replace(name=f"{self.name}-sle-test", about=about, sle_noise_steps=0, **fields)


#: The adult selector's values as --set assignments (``config.ADULT_SELECTOR``, the presets' own).
SELECTOR_SETS = tuple(f"{name}={value}" for name, value in ADULT_SELECTOR.items())
PAPER = RuleSet("paper", "paper", (), "the learning rules as written (the finished paper-scale run)", ee_ls="paper",
                full=ALL_FULL)
SKILLS = RuleSet("skills", "skills", (), "docs/CHILDHOOD.md's choice (the finished paper-scale run)", ee_ls="skills",
                 full=ALL_FULL)
BIASES = tuple(RuleSet(f"skills-bias{bias}", "skills", (f"initial_speed_bias={bias}.0",), about, ee_ls="skills")
               for bias, about in enumerate(("skills whose learned experts start at half speed, as MODEL.md's zero "
                                             "weights (the paper's \"sub-optimal basic skills\")",
                                             "skills, learned experts start at 73 % speed",
                                             "skills, learned experts start at 88 % speed")))
# SLE reads neither the walls nor the childhood: its test is skills' own, at the paper's sizes.
CLAMP = RuleSet("skills-clamp", "skills", ("childhood_walls=clamp",), "skills with MODEL.md's walls in childhood (the "
                "robot slides along them, never put back)", ee_ls="skills", full=(*SHARED_FULL, "SLE"))
SELECTOR = RuleSet("paper-selector", "paper", SELECTOR_SETS, "the paper's rules with only the adult selector's "
                   "unstated values of skills (traces, selector rates)", ee_ls="skills")
EXTENSION = RuleSet("extension", "extension", (), "MODEL.md's learning extensions, in childhood too", ee_ls="skills")
WHOLE = "SLE's noise annealed over the whole"
RULE_SETS: tuple[RuleSet, ...] = (
    PAPER, SKILLS, *BIASES, CLAMP, SELECTOR,
    SELECTOR.whole_test(f"paper-selector with {WHOLE} 1,000,000-cycle test (every run shared)"),
    RuleSet("faithful", "faithful", (), "paper-selector-sle-test at full scale: the `faithful` preset of the "
            "reproduction (`make reproduce`)", ee_ls="skills", full=ALL_FULL, sle_noise_steps=0),
    EXTENSION,
    SKILLS.whole_test(f"skills, {WHOLE} 1,000,000-cycle test", full=("LE-LS", *SHARED_FULL)),
    BIASES[0].whole_test(f"skills-bias0 with {WHOLE} 1,000,000-cycle test"),
    PAPER.whole_test(f"paper, {WHOLE} 1,000,000-cycle test", full=("LE-LS", *SHARED_FULL)),
    # Every other row under the second SLE reading too: claims 5 and 6 depend on it. Each shares its
    # LE-LS with its row; SLE reads neither the walls nor the childhood, so most share an SLE test too.
    *(rule.whole_test(f"{rule.name} with {WHOLE} test{shared}", full=SHARED_FULL) for rule, shared in
      ((BIASES[1], ""), (BIASES[2], ""), (CLAMP, " (every run shared)"), (EXTENSION, " (every run shared)"))),
)
BY_NAME = {rule.name: rule for rule in RULE_SETS}
