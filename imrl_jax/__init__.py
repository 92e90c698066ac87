"""imrl-jax: Schembri, Mirolli & Baldassarre (2007) intrinsically motivated RL robot in JAX.

The package in layers, each importing only those below it (tests/test_imports.py):

- ``config``, ``conditions``, ``genome``, ``files``: what a run is (settings, the condition table, the genes) and
  how a user's file is read;
- ``world``: the arena, the retina, the task sets and the environment (section 2);
- ``agent``: the networks, their learning and a whole life, as the XLA step, the GPU kernel and the NumPy reference;
- ``evolution``: the search (the paper's GA, evosax), sweeps, landscapes, the devices lanes are laid out on;
- ``analysis``: behaviour, the hand-written controllers, steady states and figures;
- ``runs``: run directories, content keys, checkpoints, events, progress, the command lines' shared checks;
- ``commands``: what a user types, ``python -m imrl_jax.NAME`` (evolve, learning_test, render, ...).
"""

import os as _os

__version__ = "0.1.0"

from imrl_jax.config import CONDITIONS, Config, ConfigError, LearningParams, Task, make_config

# The commands keep their short names: ``python -m imrl_jax.evolve`` runs imrl_jax/commands/evolve.py. The
# package's own modules import them as ``imrl_jax.commands.NAME`` only (tests/test_imports.py).
__path__.append(_os.path.join(_os.path.dirname(__file__), "commands"))

__all__ = ["CONDITIONS", "Config", "ConfigError", "LearningParams", "Task", "make_config", "__version__"]
