"""The claims map's rule sets (docs/CLAIMS.md): learning rules as a preset plus overrides, and what each shares.

A leaf of the studies: the reproduction takes a rule set as a variant, the claims map and the time-scale
study measure them; each imports this table, and it imports none of them.
"""

from __future__ import annotations

from typing import NamedTuple

from imrl_jax.config import ADULT_SELECTOR


class RuleSet(NamedTuple):
    """One row of the claims map: learning rules as a preset plus overrides, and what it shares."""

    name: str
    preset: str
    sets: tuple[str, ...]
    about: str
    ee_ls: str  # the rule set whose EE-LS run (and test) this one's is
    sle: str  # the rule set whose SLE test this one's is (itself: its own test)
    le_ls: str = ""  # the rule set whose LE-LS run this one's is ("": its own)
    sle_noise_steps: int | None = None  # SLE's noise horizon: None one task's length (100,000), 0 the whole test


#: The adult selector's values as --set assignments (``config.ADULT_SELECTOR``, the presets' own).
SELECTOR_SETS = tuple(f"{name}={value}" for name, value in ADULT_SELECTOR.items())
RULE_SETS: tuple[RuleSet, ...] = (
    RuleSet("paper", "paper", (), "the learning rules as written (the finished paper-scale run)",
            ee_ls="paper", sle="paper", le_ls="paper"),
    RuleSet("skills", "skills", (), "docs/CHILDHOOD.md's choice (the finished paper-scale run)",
            ee_ls="skills", sle="skills", le_ls="skills"),
    RuleSet("skills-bias0", "skills", ("initial_speed_bias=0.0",),
            "skills whose learned experts start at half speed, as MODEL.md's zero weights (the paper's "
            "\"sub-optimal basic skills\")", ee_ls="skills", sle="skills-bias0"),
    RuleSet("skills-bias1", "skills", ("initial_speed_bias=1.0",), "skills, learned experts start at 73 % speed",
            ee_ls="skills", sle="skills-bias1"),
    RuleSet("skills-bias2", "skills", ("initial_speed_bias=2.0",), "skills, learned experts start at 88 % speed",
            ee_ls="skills", sle="skills-bias2"),
    RuleSet("skills-clamp", "skills", ("childhood_walls=clamp",),
            "skills with MODEL.md's walls in childhood (the robot slides along them, never put back)",
            ee_ls="skills", sle="skills"),
    RuleSet("paper-selector", "paper", SELECTOR_SETS,
            "the paper's rules with only the adult selector's unstated values of skills (traces, selector rates)",
            ee_ls="skills", sle="skills-bias0"),
    RuleSet("paper-selector-sle-test", "paper", SELECTOR_SETS,
            "paper-selector with SLE's noise annealed over the whole 1,000,000-cycle test (every run shared)",
            ee_ls="skills", sle="skills-bias0-sle-test", le_ls="paper-selector", sle_noise_steps=0),
    RuleSet("faithful", "faithful", (), "paper-selector-sle-test at full scale: the `faithful` preset of the "
            "reproduction (`make reproduce`)", ee_ls="skills", sle="faithful", le_ls="faithful", sle_noise_steps=0),
    RuleSet("extension", "extension", (), "MODEL.md's learning extensions, in childhood too", ee_ls="skills",
            sle="skills-bias0"),
    RuleSet("skills-sle-test", "skills", (), "skills, SLE's noise annealed over the whole 1,000,000-cycle test",
            ee_ls="skills", sle="skills-sle-test", le_ls="skills", sle_noise_steps=0),
    RuleSet("skills-bias0-sle-test", "skills", ("initial_speed_bias=0.0",),
            "skills-bias0 with SLE's noise annealed over the whole 1,000,000-cycle test", ee_ls="skills",
            sle="skills-bias0-sle-test", le_ls="skills-bias0", sle_noise_steps=0),
    RuleSet("paper-sle-test", "paper", (), "paper, SLE's noise annealed over the whole 1,000,000-cycle test",
            ee_ls="paper", sle="paper-sle-test", le_ls="paper", sle_noise_steps=0),
    # Every other row under the second SLE reading too: claims 5 and 6 depend on it. Each shares its
    # LE-LS with its row; SLE reads neither the walls nor the childhood, so most share an SLE test too.
    RuleSet("skills-bias1-sle-test", "skills", ("initial_speed_bias=1.0",),
            "skills-bias1 with SLE's noise annealed over the whole test", ee_ls="skills",
            sle="skills-bias1-sle-test", le_ls="skills-bias1", sle_noise_steps=0),
    RuleSet("skills-bias2-sle-test", "skills", ("initial_speed_bias=2.0",),
            "skills-bias2 with SLE's noise annealed over the whole test", ee_ls="skills",
            sle="skills-bias2-sle-test", le_ls="skills-bias2", sle_noise_steps=0),
    RuleSet("skills-clamp-sle-test", "skills", ("childhood_walls=clamp",),
            "skills-clamp with SLE's noise annealed over the whole test (every run shared)", ee_ls="skills",
            sle="skills-sle-test", le_ls="skills-clamp", sle_noise_steps=0),
    RuleSet("extension-sle-test", "extension", (),
            "extension with SLE's noise annealed over the whole test (every run shared)", ee_ls="skills",
            sle="skills-bias0-sle-test", le_ls="extension", sle_noise_steps=0),
)
BY_NAME = {rule.name: rule for rule in RULE_SETS}
