"""The worlds by name, the world a config lives in, and a config moved into another world (docs/WORLDS.md)."""

from __future__ import annotations

import dataclasses
import importlib

import jax

from imrl_jax.config import Config, ConfigError
from imrl_jax.world.base import DISCRETE, World
from imrl_jax.world.env import ARENA

#: Every world by its name: the arena, or where another one's ``make_world(settings)`` lives (imported when asked
#: for: an optional library's world costs nothing until then).
WORLDS: dict[str, World | str] = {ARENA.name: ARENA, "xland": "imrl_jax.world.xland"}
#: The genome parts that are the arena's (its actors' turn units; evolved values with the speed unit's bias): not in
#: another world. (Evolved actors, part "actor", have a row per actor unit: per action in another world.)
ARENA_PARTS = ("actor_turn", "parameters")


def register(name: str, world: World | str) -> None:
    """Make ``world`` (a World, or the path of a module with ``make_world(settings)``) world ``name``; a name another
    world holds is refused (ValueError). A world of one's own: docs/WORLDS.md."""
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"register: a world's name is an identifier, got {name!r}")
    if WORLDS.get(name, world) != world:
        raise ValueError(f"register: the name {name!r} is taken by another world ({WORLDS[name]!r})")
    WORLDS[name] = world


def make(name: str, settings: tuple = ()) -> World:
    """World ``name`` with its settings (``(name, value)`` pairs); raises ConfigError naming what is wrong."""
    if name not in WORLDS:
        raise ConfigError(f"world: unknown world {name!r} (known: {', '.join(WORLDS)})", "world")
    found = WORLDS[name]
    if not isinstance(found, str):
        if settings:
            where = ("the config's own fields" if name == ARENA.name else
                     "none: it was registered as an object (register a module's path for settings)")
            raise ConfigError(f"world_settings: the {name} world's settings are {where}", "world_settings")
        return found
    module = importlib.import_module(found)
    kind = getattr(module, "SETTINGS", None)  # the world's settings dataclass: an unknown name refused here
    unknown = sorted({n for n, _ in settings} - {f.name for f in dataclasses.fields(kind)}) if kind else []
    if unknown:
        settable = ", ".join(f.name for f in dataclasses.fields(kind) if isinstance(f.default, (bool, int, float, str)))
        raise ConfigError(f"world_settings: unknown setting {unknown[0]!r} of world {name} (settable: {settable})",
                          "world_settings")
    try:
        return module.make_world(dict(settings))
    except (TypeError, ValueError) as error:  # an impossible setting, named by the world
        raise ConfigError(f"world_settings: {error}", "world_settings") from None


def settings_type(name: str):
    """The dataclass of world ``name``'s own settings (None: the arena's are the config's fields); ImportError if
    the world's optional library is missing."""
    found = WORLDS[name]
    return None if not isinstance(found, str) else getattr(importlib.import_module(found), "SETTINGS", None)


def world_of(config: Config) -> World:
    """The world ``config`` lives in, checked against the sizes the config records (raises ConfigError)."""
    world = make(config.world, config.world_settings)
    if config.world != ARENA.name:
        actions = world.actions(config)
        if (config.world_inputs, config.world_actions) != (world.num_inputs(config), actions.size):
            raise ConfigError(f"world_inputs: {config.world_inputs} inputs and {config.world_actions} actions are not "
                              f"world {config.world}'s (use imrl_jax.world.worlds.configure)", "world_inputs")
        if world.num_tasks(config) != config.num_tasks:
            raise ConfigError(f"world: {config.world}'s {world.num_tasks(config)} tasks are not the config's "
                              f"{config.num_tasks}", "world")
        arena = [p for p in config.spec.genome if p in ARENA_PARTS]
        if arena:
            raise ConfigError(f"condition: {config.condition} evolves the arena's {arena[0]}: not a gene of world "
                              f"{config.world}", "condition")
        assert actions.kind == DISCRETE, "another world's actions are discrete (the arena's are its own)"
    return world


def task_maxima(config: Config):
    """(tasks,) each task's most reaches in ``config.task_steps`` steps, as NumPy floats: performance's denominator
    (the arena's ``config.theoretical_max()``, another world's ``max_reaches``)."""
    import numpy as np

    if config.world == ARENA.name:  # as the arena's reports always divided, to the last bit
        return np.asarray(config.theoretical_max())
    return np.asarray(world_of(config).max_reaches(config), np.float64)


def configure(config: Config, name: str, **settings) -> Config:
    """``config`` living in world ``name`` with ``settings``: its observation size and actions recorded."""
    pairs = tuple(sorted(settings.items()))
    world = make(name, pairs)
    if name == ARENA.name:
        return dataclasses.replace(config, world=name, world_settings=(), world_inputs=0, world_actions=0)
    moved = dataclasses.replace(config, world=name, world_settings=pairs, world_inputs=world.num_inputs(config),
                                world_actions=world.actions(config).size)
    world_of(moved)  # every check, before the config is used
    _check_observation(world, moved)
    return moved


def _check_observation(world: World, config: Config) -> None:
    """Refuse a world whose observation is not ``num_inputs`` numbers (a life would write it, silently, into a row of
    another length); traced, not run."""
    env = world.make_env(config)
    seen = jax.eval_shape(lambda: env.observe(env.reset(jax.random.key(0), world.task(config, 0))))
    if seen.shape != (world.num_inputs(config),):
        raise ConfigError(f"world_inputs: world {config.world} observes an array of shape {seen.shape}, not its "
                          f"num_inputs ({world.num_inputs(config)},)", "world_inputs")
