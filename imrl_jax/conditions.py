"""The paper's four conditions (section 2, "The four conditions"; MODEL.md "Conditions") as one table.

A condition is one :class:`Condition` in :data:`CONDITIONS`: which networks its genome
encodes (and so its number of genes and the decoding), whether it lives a childhood, its
adult :class:`Phase` (who learns, from which reward), what a task starts from, whether it is
evolved, and how plots draw it. Everything else in the engine (config validation, decoding,
the lifetime, the NumPy reference, evolution, learning tests, plots, the report) reads this
table; a new condition is a new row (plus its learning rule, if it brings one).

This module imports only the genome parts (``imrl_jax.genome``) and no JAX, so the experiment scripts can read it.
"""

from __future__ import annotations

import dataclasses
import re
from typing import NamedTuple

from imrl_jax.genome import EVOLVED_FIELDS, EVOLVED_PARAMETERS, PARTS, get_part  # noqa: F401 (the table's names)


class Phase(NamedTuple):
    """Static description of a phase: who learns, from what, and whether there is a target."""

    experts_learn: bool
    selector_learns: bool
    intrinsic: bool  # rewards: own reinforcer for experts, expert surprise for the selector
    has_target: bool
    noisy: bool  # actions get Gaussian noise annealed linearly to 0 over the phase
    respawn: bool = False  # a robot on a wall for config.wall_respawn_steps steps gets a random pose
    progress: bool = False  # childhood selector: surprise minus the expert's running mean surprise
    # Evolved evaluators (the paper's future work (a)): an expert's reinforcement is the change of its evolved,
    # fixed evaluation, "discounted" gamma V(x_t) - V(x_{t-1}) or "difference" V(x_t) - V(x_{t-1}); "" no.
    evaluation: str = ""


#: Childhood (LE-LS): experts learn from their own reinforcers, the selector from the surprise.
CHILDHOOD = Phase(experts_learn=True, selector_learns=True, intrinsic=True, has_target=False, noisy=True)
#: Adulthood with a learning selector (LE-LS, EE-LS): experts frozen, selector learns from the task's reward.
ADULT_LEARNING_SELECTOR = Phase(False, True, False, True, False)
#: Adulthood of EE-ES: nothing learns.
ADULT_EVOLVED_SELECTOR = Phase(False, False, False, True, False)
#: Adulthood of SLE: its one expert learns from the task's reward, with annealed noise.
ADULT_SINGLE_EXPERT = Phase(True, False, False, True, True)
#: Adulthood of the whole hierarchy on the task's reward (future work (b)): experts and selector learn, with noise.
ADULT_HIERARCHY = Phase(True, True, False, True, True)

#: The networks of an agent (fields of ``networks.Agent``), in the order a genome lists them.
NETWORKS = ("reinforcer", "actor", "evaluator", "selector_actor", "selector_critic")
SELECTOR = ("selector_actor", "selector_critic")

#: Config fields that only childhood reads.
CHILDHOOD_FIELDS = ("childhood_steps", "childhood_walls", "wall_respawn_steps", "childhood_selector_reward",
                    "progress_rate", "childhood_trace_lambda", "childhood_eta_selector_actor",
                    "childhood_eta_selector_critic")
#: Config fields that only the genetic algorithm reads.
GA_FIELDS = ("population_size", "num_generations", "num_parents", "mutation_prob", "mutation_scale", "init_scale",
             "num_elites", "lives_per_fitness")


@dataclasses.dataclass(frozen=True)
class Condition:
    """One row of the condition table."""

    name: str
    description: str
    genome: tuple[str, ...]  # the genome parts (genome.PARTS) it encodes, in this order (the rest start at 0)
    adult: Phase  # the phase of every adult task
    childhood: Phase | None = None  # the phase of its childhood before the tasks (None: no childhood); the config's
    # childhood options (walls, the selector's reward) are applied to it
    reset: tuple[str, ...] = SELECTOR  # networks set back to their start values at each task
    single_expert: bool = False  # one expert, whatever config.num_experts says
    evolved: bool = True  # evolved by the GA (else it only learns: learning tests from scratch)
    style: dict = dataclasses.field(default_factory=dict, compare=False)  # matplotlib line style

    def num_experts(self, num_experts: int) -> int:
        """Experts an individual has, given the config's ``num_experts``."""
        return 1 if self.single_expert else num_experts

    def num_genes(self, num_experts: int, num_inputs: int, num_actor_units: int = 2) -> int:
        """Genome length: the sizes of the encoded networks (LE-LS 111, EE-LS 222, EE-ES 333, SLE 0 in the arena)."""
        return sum(get_part(name).size(self.num_experts(num_experts), num_inputs + 1, num_actor_units)
                   for name in self.genome)

    @property
    def has_childhood(self) -> bool:
        """Whether it lives a childhood before the tasks."""
        return self.childhood is not None

    @property
    def learns(self) -> bool:
        """Whether anything learns in its life."""
        return self.has_childhood or self.adult.experts_learn or self.adult.selector_learns

    @property
    def learned_actors(self) -> bool:
        """Whether its actors are learned (they start at config.initial_speed_bias) rather than evolved."""
        return "actor" not in self.genome

    def ignored_fields(self) -> frozenset[str]:
        """Config fields its lives never read: changing one changes no life (tested against the reference)."""
        ignored = set()
        if not self.has_childhood:
            ignored.update(CHILDHOOD_FIELDS)
        if not (self.has_childhood or self.adult.experts_learn):
            ignored.update(("eta_actor", "eta_evaluator"))
        if not ((self.has_childhood and not self.childhood.evaluation) or self.adult.experts_learn):
            ignored.add("eta_evaluator")  # evolved evaluators are fixed
        if not self.adult.selector_learns:
            ignored.update(("eta_selector_actor", "eta_selector_critic"))
        if not (self.adult.experts_learn or self.adult.selector_learns):
            ignored.add("trace_lambda")
        if not self.learns:
            ignored.add("gamma")
        if not ((self.has_childhood and self.childhood.noisy) or self.adult.noisy):
            ignored.add("noise_std")
        if not self.adult.noisy:
            ignored.add("sle_noise_steps")
        if not self.evolved:
            ignored.update(GA_FIELDS)
        if self.single_expert:  # one expert: there is nothing to choose
            ignored.update(("num_experts", "selector_period", "selector_termination"))
        for name in self.genome:  # what its genes replace (evolved actors: the speed bias; evolved values: theirs)
            ignored.update(get_part(name).ignores)
        return frozenset(ignored)


CONDITIONS: dict[str, Condition] = {c.name: c for c in (
    Condition("LE-LS", "learned experts, learning selector: the genome encodes the experts' reinforcers; experts and "
              "selector learn from them in childhood, the selector from the task's reward in adulthood",
              genome=("reinforcer",), adult=ADULT_LEARNING_SELECTOR, childhood=CHILDHOOD,
              style=dict(color="black", lw=2.2)),
    Condition("EE-LS", "evolved experts, learning selector: the genome encodes the experts' actors; the selector "
              "learns from the task's reward", genome=("actor",), adult=ADULT_LEARNING_SELECTOR,
              style=dict(color="0.55", lw=1.8)),
    Condition("EE-ES", "evolved experts, evolved selector: the genome encodes the actors and the selector; nothing "
              "learns", genome=("actor", "selector_actor"), adult=ADULT_EVOLVED_SELECTOR, reset=(),
              style=dict(color="black", lw=1.4, ls="--")),
    Condition("SLE", "single learning expert: no evolution; one expert learns each task from scratch from its "
              "reward", genome=(), adult=ADULT_SINGLE_EXPERT, reset=NETWORKS, single_expert=True, evolved=False,
              style=dict(color="tab:blue", lw=1.4, ls=":")),
    # The paper's future work (a), after Ackley and Littman's evolutionary reinforcement learning: the
    # genome encodes each expert's evaluator, and in childhood each actor learns from the change of its
    # innate evaluation (MODEL.md "Future-work conditions"); adulthood as LE-LS.
    Condition("EV-LS", "evolved evaluators, learning selector: the genome encodes the experts' evaluators; in "
              "childhood each actor learns from the change of its fixed evaluation, gamma V(x_t) - V(x_{t-1}), and the "
              "selector from that surprise; adulthood as LE-LS", genome=("evaluator",), adult=ADULT_LEARNING_SELECTOR,
              childhood=CHILDHOOD._replace(evaluation="discounted"), style=dict(color="tab:green", lw=2.0)),
    Condition("EV-LS-diff", "EV-LS with the undiscounted change of evaluation, V(x_t) - V(x_{t-1}) (Ackley and "
              "Littman's form)", genome=("evaluator",), adult=ADULT_LEARNING_SELECTOR,
              childhood=CHILDHOOD._replace(evaluation="difference"), style=dict(color="tab:olive", lw=2.0)),
    # The paper's future work (d): LE-LS with up to num_experts experts, each expressed or not by a gene of its own.
    Condition("LE-LS-N", "LE-LS with an evolved number of experts: the genome also carries one expression gene per "
              "expert (up to num_experts); an unexpressed expert is never selected and never learns",
              genome=("reinforcer", "expressed"), adult=ADULT_LEARNING_SELECTOR, childhood=CHILDHOOD,
              style=dict(color="tab:red", lw=2.0)),
    # The paper's future work (c): LE-LS whose genome also carries its learning values.
    Condition("LE-LS-P", "LE-LS with evolved learning parameters: the genome also carries the discount, the "
              "experts' and the selector's rates and trace decays (adult and childhood), the exploration noise and the "
              "learned actors' initial speed bias (conditions.EVOLVED_PARAMETERS)", genome=("reinforcer", "parameters"),
              adult=ADULT_LEARNING_SELECTOR, childhood=CHILDHOOD, style=dict(color="tab:brown", lw=2.0)),
    # (c) with the childhood's length evolved too (up to childhood_steps): learning and noise stop at its end.
    Condition("LE-LS-PC", "LE-LS-P whose genome also carries the childhood's length: the experts and the selector "
              "learn and explore for the first round(u x childhood_steps) steps of childhood only, u = clip((g + 1) / "
              "2, 0, 1) of the last gene", genome=("reinforcer", "parameters", "childhood_length"),
              adult=ADULT_LEARNING_SELECTOR, childhood=CHILDHOOD, style=dict(color="tab:orange", lw=1.6)),
    # A size-matched control (MODEL.md "Size-matched controls"): EE-LS with actors of LE-LS's size, 111 genes.
    Condition("EE-LS-T", "EE-LS evolving only each actor's orientation (turn) unit: 3 x 37 = 111 genes, LE-LS's "
              "size; the speed unit's weights are 0 and its bias config.initial_speed_bias (a learned actor's start)",
              genome=("actor_turn",), adult=ADULT_LEARNING_SELECTOR, style=dict(color="0.55", lw=1.8, ls=":")),
    # Size-matched controls with reinforcers of EE-LS's size, 222 genes: a second reinforcer unit per expert, or
    # 111 neutral genes.
    Condition("LE-LS-2R", "LE-LS with two reinforcer units per expert: 2 x 3 x 37 = 222 genes, EE-LS's size; an "
              "expert's internal reward is the mean of its two units' rewards, (r1 + r2) / 2",
              genome=("reinforcer", "second_reinforcer"), adult=ADULT_LEARNING_SELECTOR, childhood=CHILDHOOD,
              style=dict(color="black", lw=1.8, ls=":")),
    Condition("LE-LS-Z", "LE-LS with 3 x 37 = 111 neutral genes after its reinforcers (222 genes, EE-LS's size; "
              "in another world K x (A - 1) x (n + 1): EE-LS's size there); they decode into nothing", genome=("reinforcer", "neutral"), adult=ADULT_LEARNING_SELECTOR,
              childhood=CHILDHOOD, style=dict(color="black", lw=1.2, ls="-.")),
    # The paper's future work (b): the whole hierarchy trained on the task's reward only; no evolution, no
    # childhood, everything reset at each task as SLE is (MODEL.md "Future-work conditions").
    Condition("EXT-LS", "the hierarchy on extrinsic reward only: no evolution, no childhood; in each task, reset, "
              "the three experts (evaluators and actors, while in control) and the selector learn from the task's "
              "reward, with SLE's annealed noise", genome=(), adult=ADULT_HIERARCHY, reset=NETWORKS, evolved=False,
              style=dict(color="tab:purple", lw=1.4, ls="-.")),
)}
#: Condition names, in the table's order.
NAMES = tuple(CONDITIONS)
EVOLVED = tuple(name for name, c in CONDITIONS.items() if c.evolved)
#: The paper's four conditions (its Fig. 3 and claims), and those of them that are evolved.
PAPER = ("LE-LS", "EE-LS", "EE-ES", "SLE")
PAPER_EVOLVED = tuple(name for name in PAPER if CONDITIONS[name].evolved)


#: What a condition's name may be.
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]{0,63}")


def register(condition: Condition) -> Condition:
    """Add a row to the table (a condition of your own, e.g. in a notebook); a name in use is a ValueError."""
    if not isinstance(condition.name, str) or not NAME.fullmatch(condition.name) or ".." in condition.name:
        # a name is a folder's (runs/NAME) and a key's part: no path tricks, nothing a shell or file system mangles
        raise ValueError(f"condition: {condition.name!r} is not a name (letters, digits, and - _ . + inside, at most "
                         f"64 characters)")
    if condition.name in CONDITIONS:
        raise ValueError(f"condition: {condition.name!r} is already a row of the table")
    if condition.evolved and not condition.genome:  # the GA would evolve nothing, and its run could not be resumed
        raise ValueError(f"condition {condition.name}: evolved, but its genome encodes no network (give genome "
                         f"parts, or evolved=False to test it from scratch)")
    unknown = [n for n in condition.genome if n not in PARTS] + [n for n in condition.reset if n not in NETWORKS]
    if unknown:
        raise ValueError(f"condition {condition.name}: {unknown[0]!r} is not a network (choose from "
                         f"{', '.join(PARTS)})")
    CONDITIONS[condition.name] = condition
    return condition


def get(name: str) -> Condition:
    """The row of condition ``name``; an unknown name is a ValueError naming the choices."""
    try:
        return CONDITIONS[name]
    except KeyError:
        raise ValueError(f"condition: unknown condition {name!r} (choose from {', '.join(NAMES)})") from None
