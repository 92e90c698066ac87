"""The best of an evolution lives again (section 3, claims 4 and 7): its evaluated life replayed with the GA's key,
each task then driven from its final weights (paths, stereotypy, speed, colour shares), fresh lives of each seed's
best genome (the mean of lives the GA never drew), and the colour each expert follows (the junction probe)."""

from __future__ import annotations

import numpy as np

from imrl_jax.analysis.claims import mean_speed, turn_consistency

PATH_STEPS = 1000  # steps each task is driven after its learning period (shares, stereotypy)
DRAWN_STEPS = 300  # of which the last ones are drawn
CHILDHOOD_DRAWN_STEPS = 1000
CHILDHOOD_TAIL = 0.25  # childhood shares: its last quarter, when the noise is nearly gone


def relive_best(config_dict: dict, best: dict) -> dict:
    """The fittest genome of ``best`` (each seed's best genomes, their fitness, seeds, indices and generations, as
    an evolution's last generation holds them) relives its evaluated life with the key the GA lived it with; then
    each task is driven from its final weights."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent.lifetime import live
    from imrl_jax.analysis.behaviour import childhood_trajectory, colour_shares, specialisation, task_trajectories
    from imrl_jax.config import Config
    from imrl_jax.evolution.search import life_key

    config = Config.from_dict(config_dict)
    s = int(np.argmax(best["fitness"][:, 0]))
    genome = jnp.asarray(best["genomes"][s, 0], jnp.float32)
    seed, index, generation = int(best["seeds"][s]), int(best["index"][s, 0]), int(best["generations"]) - 1
    params = config.learning_params()
    key = life_key(config, seed, generation, index)
    result = jax.jit(live, static_argnums=1)(key, config, params, genome)
    tasks = task_trajectories(jax.random.fold_in(key, config.num_tasks + 1), config, params, result.adult_agents,
                              PATH_STEPS)
    num_experts = config.num_experts
    pooled = type(tasks[0])(*(np.stack(x) for x in zip(*tasks)))
    shares, steps = colour_shares(config, pooled, num_experts)
    out = dict(config=config, seed=seed, index=index, generation=generation, fitness=float(best["fitness"][s, 0]),
               relived_fitness=float(result.fitness), performance=[float(p) for p in result.performance],
               tasks=tasks, shares=shares, steps=steps, childhood=None,
               stereotypy=turn_consistency(pooled.seen_heading, pooled.heading, pooled.breaks),
               stereotypy_per_task=[turn_consistency(t.seen_heading, t.heading, t.breaks) for t in tasks],
               speed=mean_speed(pooled.seen_pos, pooled.pos, pooled.breaks),
               dominant_expert=float(np.bincount(pooled.k.reshape(-1), minlength=num_experts).max() / pooled.k.size))
    out["probe"] = specialisation(config, result.agent)  # claim 7's definition of "follows", per expert
    if config.spec.has_childhood:
        childhood = childhood_trajectory(key, config, params, genome, config.childhood_steps)
        tail = childhood.window(int(config.childhood_steps * (1 - CHILDHOOD_TAIL)), config.childhood_steps)
        out["childhood"] = childhood.window(max(0, config.childhood_steps - CHILDHOOD_DRAWN_STEPS),
                                            config.childhood_steps)
        out["childhood_shares"], out["childhood_steps"] = colour_shares(config, tail, num_experts)
    return out


#: Fresh lives of each seed's best genome in the report, and the seed of their keys (not any key the GA used).
FRESH_LIVES, FRESH_SEED = 10, 20_071_001


def fresh_fitness(config_dict: dict, best: dict, num_lives: int = FRESH_LIVES, seed: int = FRESH_SEED) -> dict:
    """Each seed's best genome (``best["genomes"][:, 0]``) living ``num_lives`` fresh lives: fitness (S, L), mean, sd.

    The recorded best of a generation is the best of its noisy lives; these lives, with keys the
    GA never used, show what the genome scores on average (it regresses by several hundredths).
    """
    import jax
    import jax.numpy as jnp

    from imrl_jax.config import Config
    from imrl_jax.agent.lifetime import make_evaluate

    config = Config.from_dict(config_dict)
    genomes = jnp.asarray(np.repeat(np.asarray(best["genomes"])[:, 0], num_lives, axis=0), jnp.float32)
    fitness = np.asarray(make_evaluate(config)(jax.random.key(seed), config.learning_params(), genomes).fitness)
    fitness = fitness.reshape(-1, num_lives)
    return dict(fitness=fitness, mean=fitness.mean(1), sd=fitness.std(1, ddof=1), num_lives=num_lives, seed=seed)


def followed_best(config_dict: dict, best: dict, key: int = 0) -> list[list[int]]:
    """The colour each expert follows (``Specialisation.followed``: 0 red, 1 green, 2 blue, -1 none) for each genome
    of ``best`` (seeds x best, in order).

    LE-LS genomes first live a fresh childhood with their run's config (keys from ``key``);
    evolved experts are probed as they are. An expert its genome does not express follows nothing (-1).
    """
    import jax

    from imrl_jax.analysis.behaviour import grown_agents, specialisation
    from imrl_jax.config import Config

    config = Config.from_dict(config_dict)
    genomes = np.asarray(best["genomes"])
    agents, _ = grown_agents(config, genomes.reshape(-1, genomes.shape[-1]), key)
    expressed = None if agents.expressed is None else np.asarray(agents.expressed)
    return [expressed_followed(specialisation(config, jax.tree.map(lambda x: x[i], agents)).followed,
                               None if expressed is None else expressed[i])
            for i in range(genomes.shape[0] * genomes.shape[1])]


def expressed_followed(followed, expressed=None) -> list[int]:
    """The colour each expert follows, -1 for an expert that ``expressed`` (1 / 0 per expert; None: all) leaves out:
    it is never selected, so in a life it follows nothing, whatever its untrained actor would do alone."""
    followed = np.asarray(followed, int)
    if expressed is not None:
        followed = np.where(np.asarray(expressed) > 0, followed, -1)
    return [int(c) for c in followed]


def colours_followed(followed: list[list[int]]) -> list[int]:
    """Distinct colours followed (``Specialisation.num_colours``) by each individual, from the colour each expert follows."""
    return [len(set(f) - {-1}) for f in followed]


def probe_best(config_dict: dict, best: dict, key: int = 0) -> list[int]:
    """Distinct colours followed (``Specialisation.num_colours``) by each genome of ``best`` (seeds x best, in order)."""
    return colours_followed(followed_best(config_dict, best, key))
