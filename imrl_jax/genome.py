"""The parts a genome may encode (MODEL.md "Conditions", "Future-work conditions", "Size-matched controls") as one table.

A part is one :class:`GenomePart` in :data:`PARTS`: the shape of its genes, how they decode into
the JAX ``networks.Agent`` (and back), the config fields it makes ignored, the evolved values it
reports to ``history.csv``, its NumPy-reference twin (how ``reference`` decodes it and what a
reference life does with it). A condition's genome
(``conditions.Condition.genome``) lists parts by name, and every module that reads a genome reads
this table; a new part is :func:`register_part` (a size-matched control is a part plus a row).

This module imports nothing of the package and no JAX when it is imported (``conditions`` reads
it, and the experiment scripts read ``conditions``); its decoders import ``jax.numpy`` when they run.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

#: The learning values LE-LS-P evolves (the paper's future work (c)), one gene each, in this order. A gene g
#: is first mapped onto u = clip((g + 1) / 2, 0, 1) (generation 0's U[-1, 1] onto [0, 1]), then by its map:
#: "log" 10^(lo + u (hi - lo)) (rates), "1-log" 1 - 10^(lo + u (hi - lo)) (discount, trace decays: fine steps
#: near 1), "linear" lo + u (hi - lo). The gene 0 gives u = 0.5: a rate of 0.01, the paper's.
EVOLVED_PARAMETERS = (
    ("gamma", "1-log", -3.0, -0.5),  # 0.684 .. 0.999 (the paper's 0.99 at u = 0.4)
    ("trace_lambda", "1-log", -3.0, 0.0),  # 0 .. 0.999 (the paper's 0 at u = 1; skills' 0.98 at u = 0.43)
    ("eta_actor", "log", -4.0, 0.0),  # 1e-4 .. 1
    ("eta_evaluator", "log", -4.0, 0.0),
    ("eta_selector_actor", "log", -4.0, 0.0),  # skills' adult 0.3 at u = 0.87
    ("eta_selector_critic", "log", -4.0, 0.0),  # skills' adult 0.001 at u = 0.25
    ("childhood_trace_lambda", "1-log", -3.0, 0.0),
    ("childhood_eta_selector_actor", "log", -4.0, 0.0),
    ("childhood_eta_selector_critic", "log", -4.0, 0.0),
    ("noise_std", "linear", 0.0, 1.0),  # the paper's 0.3 at u = 0.3
    ("initial_speed_bias", "linear", -2.0, 6.0),  # MODEL.md's 0 at u = 0.25, skills' 4 at u = 0.75
)
EVOLVED_FIELDS = tuple(name for name, *_ in EVOLVED_PARAMETERS)


@dataclasses.dataclass(frozen=True)
class GenomePart:
    """One part of a genome: its genes' shape, decoding (JAX and the NumPy reference), ignored fields, traits."""

    name: str
    what: str  # in words, for messages
    shape: Callable[[int, int, int], tuple[int, ...]]  # (num_experts, num_weights with the bias, num_actor_units) -> its
    # genes' shape
    # (config, agent, genes of that shape) -> the agent with them in place (the agent so far: zero_agent, then the
    # genome's earlier parts)
    decode: Callable
    # the reference's twin: (config, weights, genes) -> None, writing into the dict of float64 weights (by default
    # the genes under the part's name, for reference_life to take out)
    reference_decode: Callable
    encode: Callable | None = None  # agent -> its genes (any shape); None: not encoded back
    # (config, weights) -> (config, childhood keywords of reference.run_phase): what a reference life does with it
    # before living (it takes its genes out of weights); None: nothing
    reference_life: Callable | None = None
    start: Callable | None = None  # (config, dtype) -> Agent fields it adds to zero_agent (the pytree's structure)
    ignores: tuple[str, ...] = ()  # config fields its genes replace: changing one changes no life
    trait_names: Callable = lambda config: ()  # config -> the names of its values in history.csv
    trait_values: Callable = lambda config, agent: []  # (config, decoded agent) -> one () value per name

    def size(self, num_experts: int, num_weights: int, num_actor_units: int) -> int:
        """Its number of genes."""
        return int(np.prod(self.shape(num_experts, num_weights, num_actor_units), dtype=np.int64))


#: The parts by name, in the order they were registered.
PARTS: dict[str, GenomePart] = {}


def register_part(part: GenomePart) -> GenomePart:
    """Add a part to the table; a name in use is a ValueError."""
    if part.name in PARTS:
        raise ValueError(f"genome part: {part.name!r} is already registered")
    PARTS[part.name] = part
    return part


def get_part(name: str) -> GenomePart:
    """The part ``name``; an unknown name is a ValueError naming the choices."""
    try:
        return PARTS[name]
    except KeyError:
        raise ValueError(f"genome part: unknown part {name!r} (choose from {', '.join(PARTS)})") from None


def _jnp():
    import jax.numpy as jnp

    return jnp


def unit(gene):
    """Where a gene in [-1, 1] puts its value in the value's range: u = clip((g + 1) / 2, 0, 1)."""
    return _jnp().clip((gene + 1.0) / 2.0, 0.0, 1.0)


def parameter_values(genes) -> dict:
    """The learning values that parameter genes encode (:data:`EVOLVED_PARAMETERS`' maps), as JAX values."""
    values = {}
    for gene, (name, kind, lo, hi) in zip(genes, EVOLVED_PARAMETERS):
        exponent = lo + unit(gene) * (hi - lo)
        values[name] = {"log": 10.0 ** exponent, "1-log": 1.0 - 10.0 ** exponent, "linear": exponent}[kind]
    return values


def reference_parameter_values(genes) -> dict:
    """:func:`parameter_values` in plain Python floats (the NumPy reference's)."""
    values = {}
    for gene, (name, kind, lo, hi) in zip(genes, EVOLVED_PARAMETERS):
        exponent = lo + min(max((gene + 1.0) / 2.0, 0.0), 1.0) * (hi - lo)
        values[name] = {"log": 10.0 ** exponent, "1-log": 1.0 - 10.0 ** exponent, "linear": exponent}[kind]
    return values


def express(genes):
    """Which experts the expression genes express: those with a positive gene, and always the largest one's."""
    return ((genes > 0) | (genes == genes.max())).astype(genes.dtype)


# --------------------------------------------------------------------------- the parts


def _network(name: str, shape: Callable, what: str, ignores: tuple[str, ...] = ()) -> GenomePart:
    """A part whose genes are one network's weights as they are (the paper's conditions)."""

    def reference_decode(config, weights, genes):
        weights[name] = genes.copy()

    return GenomePart(name, what, shape, decode=lambda config, agent, genes: agent._replace(**{name: genes}),
                      reference_decode=reference_decode, encode=lambda agent: getattr(agent, name), ignores=ignores)


def _decode_parameters(config, agent, genes):
    # The individual's own learning values; the speed bias is no learning value but the actors' start.
    jnp = _jnp()
    values = parameter_values(genes)
    bias = values.pop("initial_speed_bias")
    base = config.learning_params()
    params = base._replace(**{f: jnp.asarray(values.get(f, getattr(base, f)), genes.dtype) for f in base._fields})
    return agent._replace(params=params, actor=agent.actor.at[:, 1, -1].set(bias))


def _parameters_life(config, weights):
    values = reference_parameter_values(weights.pop("parameters"))
    config = config.replace(**values)
    weights["actor"][:, 1, -1] = values["initial_speed_bias"]
    return config, {}


def _parameter_traits(config, agent) -> list:
    # The speed bias is no learning value: decode puts it into the actors' weights.
    return [agent.actor[0, 1, -1] if name == "initial_speed_bias" else getattr(agent.params, name)
            for name in EVOLVED_FIELDS]


def _childhood_length_life(config, weights):
    genes = weights.pop("childhood_length")
    return config, {"learning_steps": round(min(max((float(genes[0]) + 1.0) / 2.0, 0.0), 1.0)
                                            * config.childhood_steps)}


def _reference_express(config, weights, genes):
    weights["expressed"] = ((genes > 0) | (genes == genes.max())).astype(np.float64)


def _expression_names(config) -> tuple[str, ...]:
    return ("expressed_experts",) + tuple(f"share_{k}_experts" for k in range(1, config.num_experts + 1))


def _expression_traits(config, agent) -> list:
    count = agent.expressed.sum()
    return [count] + [(count == k).astype(count.dtype) for k in range(1, config.num_experts + 1)]


def _reference_turn(config, weights, genes):
    weights["actor"][:, 0, :] = genes


def _reference_second_reinforcer(config, weights, genes):
    weights["second_reinforcer"] = genes.copy()


def _raw(name: str) -> Callable:
    """The reference's default decoding: the genes under the part's name (its reference_life takes them out)."""

    def reference_decode(config, weights, genes):
        weights[name] = genes.copy()

    return reference_decode


for _part in (
    _network("reinforcer", lambda k, n, a: (k, n), "evolved reinforcers"),
    # Evolved actors replace the learned actors' start: the speed bias is never read. One row per actor unit: the
    # arena's turn and speed, or another world's discrete actions.
    _network("actor", lambda k, n, a: (k, a, n), "evolved actors", ignores=("initial_speed_bias",)),
    _network("evaluator", lambda k, n, a: (k, n), "evolved evaluators"),
    _network("selector_actor", lambda k, n, a: (k, n), "an evolved selector"),
    _network("selector_critic", lambda k, n, a: (n,), "an evolved selector critic"),
    # One expression gene per expert (an evolved number of experts): expert k is expressed when its gene is
    # positive; the largest gene's expert always is.
    GenomePart("expressed", "an evolved number of experts", lambda k, n, a: (k,),
               decode=lambda config, agent, genes: agent._replace(expressed=express(genes)),
               reference_decode=_reference_express, encode=lambda agent: agent.expressed,
               start=lambda config, dtype: {"expressed": _jnp().ones((config.num_lane_experts,), dtype)},
               trait_names=_expression_names, trait_values=_expression_traits),
    # The learning values (evolved learning parameters): the genome's values replace the config's.
    GenomePart("parameters", "evolved learning parameters", lambda k, n, a: (len(EVOLVED_PARAMETERS),),
               decode=_decode_parameters, reference_decode=_raw("parameters"), reference_life=_parameters_life,
               ignores=EVOLVED_FIELDS, trait_names=lambda config: EVOLVED_FIELDS, trait_values=_parameter_traits,
               ),
    # The childhood's length (one gene): learning and noise stop after round(u x childhood_steps) steps of it,
    # u = clip((g + 1) / 2, 0, 1); childhood_steps is the maximum.
    GenomePart("childhood_length", "an evolved childhood length", lambda k, n, a: (1,),
               decode=lambda config, agent, genes: agent._replace(
                   childhood_length=_jnp().round(unit(genes[0]) * config.childhood_steps)),
               reference_decode=_raw("childhood_length"), reference_life=_childhood_length_life,
               trait_names=lambda config: ("childhood_length",),
               trait_values=lambda config, agent: [agent.childhood_length]),
    # Each actor's orientation (turn) unit only (EE-LS-T): the speed unit keeps zero_agent's start, weights 0 and
    # bias config.initial_speed_bias.
    GenomePart("actor_turn", "evolved turn units", lambda k, n, a: (k, n),
               decode=lambda config, agent, genes: agent._replace(actor=agent.actor.at[:, 0].set(genes)),
               reference_decode=_reference_turn, encode=lambda agent: agent.actor[:, 0]),
    # A second reinforcer unit per expert (LE-LS-2R): the expert's internal reward is the mean of its two units',
    # r_k = (r1 + r2) / 2 (networks.internal_rewards).
    GenomePart("second_reinforcer", "second reinforcer units", lambda k, n, a: (k, n),
               decode=lambda config, agent, genes: agent._replace(second_reinforcer=genes),
               reference_decode=_reference_second_reinforcer, encode=lambda agent: agent.second_reinforcer,
               start=lambda config, dtype: {"second_reinforcer": _jnp().zeros(
                   (config.num_lane_experts, config.num_inputs + 1), dtype)}),
    # Neutral genes (LE-LS-Z): as many as the actors' rows but one (K x (A - 1) x n: the arena's K x 37, so that
    # with the reinforcers the genome is EE-LS's length in any world), decoded into nothing; they lengthen the
    # genome only.
    GenomePart("neutral", "neutral genes", lambda k, n, a: (k, a - 1, n), decode=lambda config, agent, genes: agent,
               reference_decode=lambda config, weights, genes: None),
):
    register_part(_part)
