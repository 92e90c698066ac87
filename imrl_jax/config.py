"""Every constant of the model (MODEL.md), in one frozen dataclass.

Static settings (shapes, step counts, geometry, the condition) live in :class:`Config`
and are closed over by the ``make_*``/phase functions. The values a researcher may sweep
inside one compiled program (discount, trace decay, learning rates, exploration noise)
are read from it by :meth:`Config.learning_params` into a :class:`LearningParams` pytree,
which is passed as an argument and can be vmapped.

Rows that MODEL.md marks "paper" are the paper's (Schembri, Mirolli & Baldassarre 2007,
section 2); the rest are the values MODEL.md fixes where the paper is silent.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import NamedTuple

from imrl_jax import conditions
from imrl_jax.conditions import Condition

#: Condition names (the rows of :data:`imrl_jax.conditions.CONDITIONS`).
CONDITIONS = conditions.NAMES
#: How walls act in childhood: "clamp" (MODEL.md: the robot slides along them) or
#: "respawn" (also put back at a random pose after ``wall_respawn_steps`` steps on a wall).
CHILDHOOD_WALLS = ("clamp", "respawn")
#: The childhood selector's reward: "surprise" (the paper: the surprise of the expert that
#: kept control) or "progress" (that surprise minus a running mean of the expert's surprise).
CHILDHOOD_SELECTOR_REWARDS = ("surprise", "progress")
EVOLVED_CONDITIONS = conditions.EVOLVED
STEP_KERNELS = ("auto", "xla", "pallas")
KERNEL_RETINAS = ("entries", "points")
#: When the selector's choice ends (docs/TIMESCALE.md): "period" (after ``selector_period`` steps) or "colour"
#: (when a colour comes into view that the retina did not see the step before, as at a junction, or after
#: ``selector_period`` steps at most). A trial's end always ends it. With a period of 1 every choice lasts one step.
SELECTOR_TERMINATIONS = ("period", "colour")

#: Half the distance between parallel lines of the floor: 20*sqrt(3) cm for a = 40 cm.
_S = 20.0 * math.sqrt(3.0)


class UsageError(Exception):
    """Bad input to a command (an option, a sweep, a memory estimate): one line, exit code 2, nothing written."""


class ConfigError(ValueError):
    """A configuration value is impossible; the message names the field (also kept as ``field``)."""

    def __init__(self, message: str, field: str = ""):
        super().__init__(message)
        self.field = field


#: The largest sizes a config may hold: a typo (task_steps=2147483648) is refused before anything is allocated.
MAX_STEPS = 10**9  # per task, per childhood, per trial
MAX_BINS = 100_000
MAX_POPULATION = 100_000
MAX_GENERATIONS = 1_000_000
#: Experts an individual may have: the paper has 3. Compiling a life grows with them (about 3 MB each on a CPU);
#: a thousand took a 24 GB machine down.
MAX_EXPERTS = 64
#: Config's fields of the world (docs/WORLDS.md): set together by ``imrl_jax.world.worlds.configure``; a run in the
#: arena is keyed without them.
WORLD_FIELDS = ("world", "world_settings", "world_inputs", "world_actions")
#: The most inputs and discrete actions another world may give (a perceptron's weights grow with both).
MAX_INPUTS = 10_000
MAX_ACTIONS = 64
#: Any length of the arena, the floor, the robot or its retina, in cm (the paper's arena is 400 cm wide).
MAX_LENGTH = 10_000.0


class Bounds(NamedTuple):
    """The values a number (or each number of a tuple) of a config field may take: lo to hi, either end open."""

    lo: float
    hi: float
    lo_open: bool = False
    hi_open: bool = False

    def holds(self, value) -> bool:
        above = value > self.lo if self.lo_open else value >= self.lo
        below = value < self.hi if self.hi_open else value <= self.hi
        return bool(above and below)

    def __str__(self) -> str:
        text = lambda v: f"{v:_}" if isinstance(v, int) else f"{v:g}"  # noqa: E731
        return f"{'(' if self.lo_open else '['}{text(self.lo)}, {text(self.hi)}{')' if self.hi_open else ']'}"


def _bounded(default, lo, hi, *, lo_open: bool = False, hi_open: bool = False, **metadata):
    """A field with its bounds beside it (``Config.bounds``), checked by validation."""
    return dataclasses.field(default=default, metadata={"bounds": Bounds(lo, hi, lo_open, hi_open), **metadata})


@dataclasses.dataclass(frozen=True)
class Task:
    """One adulthood task: start vertex and heading, target vertex (MODEL.md task table)."""

    start: tuple[float, float]
    heading_deg: float
    target: tuple[float, float]

    @property
    def distance(self) -> float:
        """Straight-line distance from start to target in cm."""
        return math.dist(self.start, self.target)


def paper_tasks() -> tuple[Task, ...]:
    """The six tasks of MODEL.md (pairs 1-2 red, 3-4 green, 5-6 blue first edges)."""
    s = _S
    return (
        Task((140.0, 200.0 - s), 0.0, (240.0, 200.0)),
        Task((360.0, 200.0), 180.0, (240.0, 200.0 + 2 * s)),
        Task((60.0, 200.0 + s), 60.0, (60.0, 200.0 + 3 * s)),
        Task((200.0, 200.0 + 4 * s), 240.0, (120.0, 200.0 + 2 * s)),
        Task((200.0, 200.0 - 4 * s), 120.0, (80.0, 200.0 - 2 * s)),
        Task((300.0, 200.0 - s), 300.0, (300.0, 200.0 - 3 * s)),
    )


class LearningParams(NamedTuple):
    """Dynamic learning values: a pytree of scalars, so sweeps can vmap over them."""

    gamma: float
    trace_lambda: float
    eta_actor: float
    eta_evaluator: float
    eta_selector_actor: float
    eta_selector_critic: float
    noise_std: float
    childhood_trace_lambda: float
    childhood_eta_selector_actor: float
    childhood_eta_selector_critic: float
    progress_rate: float

    def in_childhood(self) -> "LearningParams":
        """The values childhood learns with: its own trace decay and selector rates."""
        return self._replace(trace_lambda=self.childhood_trace_lambda,
                             eta_selector_actor=self.childhood_eta_selector_actor,
                             eta_selector_critic=self.childhood_eta_selector_critic)


@dataclasses.dataclass(frozen=True)
class Config:
    """All constants of the model, with the paper's (and MODEL.md's) values as defaults."""

    # --- condition and life (paper: 150,000 + 600,000 steps; split into 6 tasks fixed here)
    condition: str = "LE-LS"
    num_experts: int = _bounded(3, 1, MAX_EXPERTS)
    childhood_steps: int = _bounded(150_000, 0, MAX_STEPS)
    task_steps: int = _bounded(100_000, 1, MAX_STEPS)
    trial_timeout: int = _bounded(200, 1, MAX_STEPS)  # steps after a trial's start without reaching the target
    num_bins: int = _bounded(100, 1, MAX_BINS)  # bins of the reward/selection curves of each phase
    # steps whose random numbers are drawn in one call (sets the stream: a model value); a block is held per lane
    draw_block: int = _bounded(100, 1, 10_000)
    # --- how it is computed, not what (COMPUTE_FIELDS): a run resumes under other values of these.
    # steps per loop iteration; more than a few dozen only lengthens compilation (100,000 exhausted memory)
    scan_unroll: int = _bounded(1, 1, 64, compute=True)
    # "xla": each step is XLA operations; "pallas": each bin of steps is one GPU kernel
    # (kernel.py; same results up to rounding, interpreted off a GPU); "auto": pallas on a GPU where the kernel
    # implements the model, else xla (kernel_choice.py: a command records the choice in the run's config.json).
    step_kernel: str = dataclasses.field(default="auto", metadata={"compute": True})
    # How the kernel observes (kernel_layout.columns; docs/PERFORMANCE.md "How far from the hardware"): "entries",
    # each of x~'s padded entries computes its own point's colour; "points", each retina point once, x~'s columns
    # colour-major. The same products in another order: results to rounding.
    kernel_retina: str = dataclasses.field(default="entries", metadata={"compute": True})

    # --- the world the agent lives in (docs/WORLDS.md): "arena" is section 2's, with the geometry below. Another
    # world's settings are its own (NAME=VALUE pairs its World reads); its observation size and discrete actions
    # are recorded here, so that a genome is sized without the world (imrl_jax.world.worlds.configure sets them).
    world: str = "arena"
    world_settings: tuple = ()
    world_inputs: int = _bounded(0, 0, MAX_INPUTS)  # 0: the arena's retina
    world_actions: int = _bounded(0, 0, MAX_ACTIONS)  # 0: the arena's (turn, speed); else discrete actions

    # --- arena and floor (fixed here)
    arena_size: float = _bounded(400.0, 0.0, MAX_LENGTH, lo_open=True)
    edge_length: float = _bounded(40.0, 0.0, MAX_LENGTH, lo_open=True)  # and at most arena_size
    tiling_origin: tuple[float, float] = _bounded((160.0, 200.0), 0.0, MAX_LENGTH)  # a hexagon centre, in the arena
    # a point is on an edge when within 3 cm of it; below edge_length / 2 (else lines would cover the hexagons)
    line_half_width: float = _bounded(3.0, 0.0, MAX_LENGTH, lo_open=True)
    colour_tie_tolerance: float = _bounded(1e-3, 0.0, 1.0)  # cm: distances this close count as an exact tie

    # --- robot (paper: 30 cm disc, turn in [-30, 30] deg, move in [0, 2] cm)
    robot_radius: float = _bounded(15.0, 0.0, MAX_LENGTH, lo_open=True)  # and the robot fits in the arena
    max_turn_deg: float = _bounded(30.0, 0.0, 180.0, lo_open=True)
    # At most the target's diameter: reaching is checked once a step, and a longer step could jump over the target.
    max_speed: float = _bounded(2.0, 0.0, MAX_LENGTH, lo_open=True)

    # --- retina (paper: 24 x 8 cm patch, 6 x 2 points, RGB receptors)
    retina_lateral: tuple[float, ...] = _bounded((-10.0, -6.0, -2.0, 2.0, 6.0, 10.0), -MAX_LENGTH, MAX_LENGTH)
    retina_forward: tuple[float, ...] = _bounded((17.0, 21.0), -MAX_LENGTH, MAX_LENGTH)

    # --- tasks (fixed here)
    # Below every task's start-to-target distance: a task already reached at its start would score without moving.
    target_radius: float = _bounded(10.0, 0.0, MAX_LENGTH, lo_open=True)
    tasks: tuple[Task, ...] = dataclasses.field(default_factory=paper_tasks)

    # --- learning (paper: gamma 0.99, eta 0.01, sigma 0.3; traces are an extension, off)
    gamma: float = _bounded(0.99, 0.0, 1.0)
    trace_lambda: float = _bounded(0.0, 0.0, 1.0, hi_open=True)
    eta_actor: float = _bounded(0.01, 0.0, 10.0)  # rates: the sweeps go to 1
    eta_evaluator: float = _bounded(0.01, 0.0, 10.0)
    eta_selector_actor: float = _bounded(0.01, 0.0, 10.0)
    eta_selector_critic: float = _bounded(0.01, 0.0, 10.0)
    noise_std: float = _bounded(0.3, 0.0, 10.0)  # actions are in [0, 1]: more is all noise

    # --- childhood options (docs/CHILDHOOD.md). The defaults are the paper's rules (and
    # MODEL.md's clamp); the childhood_* values apply in childhood in place of the adult ones.
    childhood_walls: str = "clamp"
    wall_respawn_steps: int = _bounded(20, 1, MAX_STEPS)  # with "respawn": steps on a wall before a new random pose
    childhood_selector_reward: str = "surprise"
    # with "progress": rate of each expert's running mean surprise
    progress_rate: float = _bounded(0.001, 0.0, 1.0, lo_open=True)
    childhood_trace_lambda: float = _bounded(0.0, 0.0, 1.0, hi_open=True)
    childhood_eta_selector_actor: float = _bounded(0.01, 0.0, 10.0)
    childhood_eta_selector_critic: float = _bounded(0.01, 0.0, 10.0)
    # Bias of the speed unit of every actor that is learned rather than evolved (LE-LS's
    # experts, SLE's expert). MODEL.md starts every learned weight at 0: half speed.
    initial_speed_bias: float = _bounded(0.0, -100.0, 100.0)  # a sigmoid's: past +-100 it is saturated
    # SLE's action noise anneals linearly to 0 over this many steps of each task, then stays
    # 0 (0: over the whole task, MODEL.md). A learning test's tasks are longer than an adult
    # task: with a fixed horizon SLE's noise schedule does not stretch with the test.
    sle_noise_steps: int = _bounded(0, 0, MAX_STEPS)
    # --- the selector's time-scale (the paper's Discussion; docs/TIMESCALE.md). The paper's selector chooses
    # every step (1). With N > 1 the chosen expert keeps control for N steps (or until the termination event)
    # and the selector learns once per choice, by semi-Markov TD, in childhood and in adulthood.
    selector_period: int = _bounded(1, 1, MAX_STEPS)
    selector_termination: str = "period"

    # --- genetic algorithm (paper: 50 individuals, best 10 x 5 offspring, p = 0.1, U[-1, 1])
    population_size: int = _bounded(50, 1, MAX_POPULATION)
    num_generations: int = _bounded(100, 1, MAX_GENERATIONS)
    num_parents: int = _bounded(10, 1, MAX_POPULATION)
    mutation_prob: float = _bounded(0.1, 0.0, 1.0)
    mutation_scale: float = _bounded(1.0, 0.0, 100.0)  # mutations are U[-scale, scale]
    init_scale: float = _bounded(1.0, 0.0, 100.0)  # generation-0 genes are U[-scale, scale]
    num_elites: int = _bounded(0, 0, MAX_POPULATION)  # no elitism in the paper
    lives_per_fitness: int = _bounded(1, 1, 1000)  # fitness as the mean of this many lives (the paper: 1)

    def __post_init__(self):
        _validate(self)

    # ------------------------------------------------------------------ derived values
    @property
    def num_inputs(self) -> int:
        """The observation's size: the retina's points x 3 receptors (36 in the paper), or another world's."""
        return self.world_inputs or 3 * len(self.retina_lateral) * len(self.retina_forward)

    @property
    def num_actor_units(self) -> int:
        """Each actor's outputs: the arena's (turn, speed), or one per discrete action of another world."""
        return self.world_actions or 2

    @property
    def num_tasks(self) -> int:
        return len(self.tasks)

    @property
    def spec(self) -> Condition:
        """The condition's row of the table (:mod:`imrl_jax.conditions`)."""
        return conditions.CONDITIONS[self.condition]

    @property
    def num_lane_experts(self) -> int:
        """Experts an individual of this condition has (SLE: one)."""
        return self.spec.num_experts(self.num_experts)

    @property
    def num_genes(self) -> int:
        """Genome length of the condition (111, 222, 333; 0 for SLE)."""
        return self.spec.num_genes(self.num_experts, self.num_inputs, self.num_actor_units)

    @property
    def offspring_per_parent(self) -> int:
        return self.population_size // self.num_parents

    @property
    def hex_apothem(self) -> float:
        """Distance between a hexagon's centre and its edges (20*sqrt(3) cm)."""
        return self.edge_length * math.sqrt(3.0) / 2.0

    @property
    def selector_options(self) -> bool:
        """Whether the selector chooses options lasting several steps rather than every step (docs/TIMESCALE.md)."""
        return self.selector_period > 1

    @property
    def adult_noise_steps(self) -> int:
        """Steps over which an adult task's action noise (SLE) anneals to 0."""
        return self.sle_noise_steps or self.task_steps

    def steps_per_trip(self) -> tuple[int, ...]:
        """ceil((distance - target radius) / max speed) for each task (48, 65, 30, ...), at least a step."""
        return tuple(
            max(1, math.ceil((t.distance - self.target_radius) / self.max_speed - 1e-9)) for t in self.tasks
        )

    def theoretical_max(self) -> tuple[float, ...]:
        """Reaches per task of a robot driving the straight line at full speed."""
        return tuple(self.task_steps / n for n in self.steps_per_trip())

    @property
    def lifetime_steps(self) -> int:
        """Steps one individual lives (childhood only in LE-LS) over all tasks."""
        child = self.childhood_steps if self.spec.has_childhood else 0
        return child + self.num_tasks * self.task_steps

    def learning_params(self) -> LearningParams:
        """The dynamic learning values as a pytree (see :class:`LearningParams`)."""
        return LearningParams(*(getattr(self, f) for f in LearningParams._fields))

    def model_differences(self, other: "Config") -> list[str]:
        """The fields that make ``other`` another model than this one: every differing field but the
        compute choices (:data:`COMPUTE_FIELDS`) and the fields this condition never reads."""
        skip = set(COMPUTE_FIELDS) | (self.spec.ignored_fields() if self.condition == other.condition else set())
        return [f.name for f in dataclasses.fields(self)
                if f.name not in skip and getattr(self, f.name) != getattr(other, f.name)]

    def replace(self, **changes) -> "Config":
        """A copy with some fields changed (validated)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise ConfigError(f"unknown config field: {sorted(unknown)[0]}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """A JSON-friendly dict of every field."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "Config":
        """Inverse of :meth:`to_dict`; unknown fields are an error naming the field."""
        data = dict(data)
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = set(data) - names
        if unknown:
            raise ConfigError(f"unknown config field: {sorted(unknown)[0]}")
        # Runs written before childhood had its own values learned with the adult ones.
        for child, adult in (("childhood_trace_lambda", "trace_lambda"),
                             ("childhood_eta_selector_actor", "eta_selector_actor"),
                             ("childhood_eta_selector_critic", "eta_selector_critic")):
            if child not in data and adult in data:
                data[child] = data[adult]
        # Runs recorded before the field existed lived the XLA step: a resume keeps it (never "auto").
        data.setdefault("step_kernel", "xla")
        if "world_settings" in data:  # JSON's lists of [name, value]
            data["world_settings"] = tuple(tuple(pair) for pair in data["world_settings"])
        if "tasks" in data:
            data["tasks"] = tuple(
                t if isinstance(t, Task) else Task(tuple(t["start"]), t["heading_deg"], tuple(t["target"]))
                for t in data["tasks"]
            )
        for name in ("tiling_origin", "retina_lateral", "retina_forward"):
            if name in data:
                data[name] = tuple(data[name])
        return cls(**data)


#: Fields that choose how a life is computed, not what it is: the results are the same (bitwise, or up to
#: rounding for the GPU kernel), so a run may resume under other values of them.
COMPUTE_FIELDS = tuple(f.name for f in dataclasses.fields(Config) if f.metadata.get("compute"))

#: The adult selector's values that made it learn best in experiments/selector_sweep.py
#: (experiments/results/selector_sweep): traces and selector rates, the paper silent on both. The
#: ``extension``, ``skills`` and ``faithful`` presets use them, and the studies name them from here.
ADULT_SELECTOR = dict(trace_lambda=0.98, eta_selector_actor=0.3, eta_selector_critic=0.001)

#: Named presets. ``paper`` is full scale; ``small`` keeps the structure at a length a
#: laptop CPU evolves in minutes (reduced scale: label results made with it as such).
PRESETS: dict[str, dict] = {
    "paper": {},
    # Paper scale with MODEL.md's learning extensions at the values that made an adult
    # selector learn best in experiments/selector_sweep.py (experiments/results/selector_sweep).
    # Its values drive childhood too (as when the preset was chosen and its runs were made).
    "extension": dict(**ADULT_SELECTOR, **{f"childhood_{k}": v for k, v in ADULT_SELECTOR.items()}),
    # The paper's rules in childhood (skills are learned there: docs/CHILDHOOD.md), a robot
    # pinned on a wall in childhood put back at a random pose, learned experts that start
    # fast, the extension's selector in adulthood. The study's choice: experts follow one
    # colour each, and they compose.
    # Learned experts start near full speed (a retina-only reward never pays for speed).
    "skills": dict(**ADULT_SELECTOR, childhood_walls="respawn", initial_speed_bias=4.0),
    # The paper's rules with only the adult selector's unstated values of ``skills`` (traces and
    # rates): the reading under which the most of the paper's claims hold (docs/CLAIMS.md, the
    # claims map's ``paper-selector-sle-test``). SLE's noise anneals over the whole test (the
    # default ``sle_noise_steps`` 0): the paper's "SLE can train its only expert during a very
    # long period of test".
    "faithful": dict(ADULT_SELECTOR),
    "small": dict(
        childhood_steps=15_000,
        task_steps=5_000,
        num_bins=10,
        population_size=20,
        num_parents=4,
        num_generations=10,
    ),
}


def make_config(preset: str = "paper", **overrides) -> Config:
    """A config from a named preset with some fields overridden."""
    if preset not in PRESETS:
        raise ConfigError(f"preset: unknown preset {preset!r} (choose from {', '.join(PRESETS)})")
    return Config().replace(**{**PRESETS[preset], **overrides})


def _non_finite_field(c: Config) -> str | None:
    """The first field holding a float that is NaN or infinite (in a tuple or a task too), or None."""

    def numbers(value):
        if isinstance(value, float):
            yield value
        elif isinstance(value, (tuple, list)):
            for item in value:
                yield from numbers(item)
        elif isinstance(value, Task):
            yield from numbers((value.start, value.heading_deg, value.target))

    for field in dataclasses.fields(c):
        if not all(math.isfinite(v) for v in numbers(getattr(c, field.name))):
            return field.name
    return None


def bounds() -> dict[str, Bounds]:
    """Each bounded field's :class:`Bounds` (every number of the model has one; docs/MODEL.md "Bounds")."""
    return {f.name: f.metadata["bounds"] for f in dataclasses.fields(Config) if "bounds" in f.metadata}


#: The checks between fields (each named by the field refused), in the words docs/MODEL.md "Bounds" gives them.
DERIVED_BOUNDS = {
    "childhood_steps": "a multiple of num_bins; positive for a condition with a childhood",
    "task_steps": "a multiple of num_bins",
    "edge_length": "at most arena_size",
    "tiling_origin": "in the arena: each coordinate at most arena_size",
    "line_half_width": "below edge_length / 2",
    "colour_tie_tolerance": "below line_half_width",
    "robot_radius": "below arena_size / 2 (the robot fits in the arena)",
    "max_speed": "at most 2 x target_radius (one step cannot jump over the target)",
    "target_radius": "below every task's start-to-target distance",
    "tasks": "at least one; every start and target on the floor, [0, arena_size] x [0, arena_size]",
    "population_size": "a multiple of num_parents",
    "num_parents": "at most population_size",
    "num_elites": "at most num_parents",
}


def _real(value) -> bool:
    """Whether a setting's value is a real number: a Python or NumPy number, or a 0-d array of one (the NumPy
    reference sets a genome's evolved learning values so)."""
    if isinstance(value, bool):
        return False
    if isinstance(value, numbers.Real):
        return True
    kind = getattr(getattr(value, "dtype", None), "kind", "")
    return getattr(value, "shape", None) == () and bool(kind) and kind in "fiu"


def _validate(c: Config) -> None:
    def fail(field: str, why: str):
        raise ConfigError(f"{field}: {why} (got {getattr(c, field)!r})", field)

    non_finite = _non_finite_field(c)
    if non_finite is not None:
        fail(non_finite, "must be a finite number")
    if c.condition not in conditions.CONDITIONS:  # the table as it is now (rows may be registered)
        fail("condition", f"must be one of {', '.join(conditions.CONDITIONS)}")
    if c.step_kernel not in STEP_KERNELS:
        fail("step_kernel", f"must be one of {', '.join(STEP_KERNELS)}")
    if c.kernel_retina not in KERNEL_RETINAS:
        fail("kernel_retina", f"must be one of {', '.join(KERNEL_RETINAS)}")
    if c.childhood_walls not in CHILDHOOD_WALLS:
        fail("childhood_walls", f"must be one of {', '.join(CHILDHOOD_WALLS)}")
    if c.childhood_selector_reward not in CHILDHOOD_SELECTOR_REWARDS:
        fail("childhood_selector_reward", f"must be one of {', '.join(CHILDHOOD_SELECTOR_REWARDS)}")
    if c.selector_termination not in SELECTOR_TERMINATIONS:
        fail("selector_termination", f"must be one of {', '.join(SELECTOR_TERMINATIONS)}")
    for field in dataclasses.fields(c):  # every number within the bounds declared beside its field
        bound = field.metadata.get("bounds")
        if bound is None:
            continue
        value = getattr(c, field.name)
        integer = isinstance(value, int) and not isinstance(value, bool)
        if isinstance(field.default, int) and (not integer or value < bound.lo):
            fail(field.name, "must be a positive integer" if bound.lo == 1 else "must be a non-negative integer")
        values = value if isinstance(value, (tuple, list)) else (value,)
        if not all(_real(v) and bound.holds(v) for v in values):
            fail(field.name, f"must be in {bound}" + (" (each value)" if isinstance(value, (tuple, list)) else ""))
    # Derived bounds (DERIVED_BOUNDS): between fields.
    if c.task_steps % c.num_bins:
        fail("task_steps", f"must be a multiple of num_bins={c.num_bins}")
    if c.spec.has_childhood and (c.childhood_steps == 0 or c.childhood_steps % c.num_bins):
        fail("childhood_steps", f"must be a positive multiple of num_bins={c.num_bins} for {c.condition}")
    if c.num_parents > c.population_size:
        fail("num_parents", f"cannot exceed population_size={c.population_size}")
    if c.population_size % c.num_parents:
        fail("population_size", f"must be a multiple of num_parents={c.num_parents}")
    if c.num_elites > c.num_parents:
        fail("num_elites", f"must be between 0 and num_parents={c.num_parents}")
    if c.edge_length > c.arena_size:
        fail("edge_length", f"must be at most arena_size={c.arena_size:g}")
    if len(c.tiling_origin) != 2 or max(c.tiling_origin) > c.arena_size:
        fail("tiling_origin", f"must be a point (x, y) in the arena, [0, {c.arena_size:g}] x [0, {c.arena_size:g}]")
    if c.line_half_width >= c.edge_length / 2:
        fail("line_half_width", f"must be below edge_length / 2 = {c.edge_length / 2:g} (else lines cover the floor)")
    if c.colour_tie_tolerance >= c.line_half_width:
        fail("colour_tie_tolerance", f"must be below line_half_width={c.line_half_width:g}")
    if 2 * c.robot_radius >= c.arena_size:
        fail("robot_radius", "the robot must fit in the arena")
    if not c.tasks:
        fail("tasks", "needs at least one task")
    for i, task in enumerate(c.tasks):
        for name, (x, y) in (("start", task.start), ("target", task.target)):
            if not (0.0 <= x <= c.arena_size and 0.0 <= y <= c.arena_size):
                raise ConfigError(f"tasks: task {i + 1}: {name}: ({x:g}, {y:g}) is off the floor (0 to "
                                  f"{c.arena_size:g} cm)", "tasks")
    shortest = min(range(c.num_tasks), key=lambda i: c.tasks[i].distance)
    if c.target_radius >= c.tasks[shortest].distance:
        fail("target_radius", f"must be below every task's start-to-target distance (task {shortest + 1}: "
                              f"{c.tasks[shortest].distance:.1f} cm)")
    if c.max_speed > 2 * c.target_radius:
        fail("max_speed", f"must be at most 2 x target_radius = {2 * c.target_radius:g} cm (a longer step could jump "
                          f"over the target)")
    if not c.retina_lateral or not c.retina_forward:
        fail("retina_lateral", "the retina needs at least one point")
    if not isinstance(c.world, str) or not c.world.isidentifier():
        fail("world", "must be a world's name (imrl_jax.world.worlds.WORLDS)")
    if c.world == "arena" and (c.world_settings or c.world_inputs or c.world_actions):
        fail("world_settings" if c.world_settings else "world_inputs" if c.world_inputs else "world_actions",
             "is another world's: the arena's settings are the geometry fields")
    if c.world != "arena" and (c.world_inputs < 1 or c.world_actions < 2):
        fail("world_inputs" if c.world_inputs < 1 else "world_actions",
             f"must be world {c.world}'s (imrl_jax.world.worlds.configure sets them)")
    if not isinstance(c.world_settings, tuple) or not all(
            isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], str) and isinstance(p[1], (str, int, float))
            for p in c.world_settings):
        fail("world_settings", "must be (name, value) pairs, each value a number or a text")
