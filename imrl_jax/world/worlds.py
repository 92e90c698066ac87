"""The worlds by name, and the world a config lives in (the paper's arena is one world; docs/WORLDS.md)."""

from __future__ import annotations

from imrl_jax.world.base import World
from imrl_jax.world.env import ARENA

#: Every world by its name.
WORLDS: dict[str, World] = {ARENA.name: ARENA}


def world_of(config) -> World:
    """The world ``config`` lives in: every config lives in the arena until ``Config`` names its world."""
    return WORLDS["arena"]
