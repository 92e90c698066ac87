"""imrl-jax: Schembri, Mirolli & Baldassarre (2007) intrinsically motivated RL robot in JAX."""

__version__ = "0.1.0"

from imrl_jax.config import CONDITIONS, Config, ConfigError, LearningParams, Task, make_config

__all__ = ["CONDITIONS", "Config", "ConfigError", "LearningParams", "Task", "make_config", "__version__"]
