"""Which step kernel lives a run: ``Config.step_kernel = "auto"`` resolved (docs/PERFORMANCE.md).

"auto" is the Pallas kernel (:mod:`imrl_jax.agent.kernel`) where JAX's backend is a GPU and the kernel implements the
run's model (every condition and option in the arena, not another world), and the XLA step otherwise (off a GPU
the kernel would only be interpreted, several times slower).
A command resolves it where it plans a run, so that the run's ``config.json`` records the choice and a resumed
run keeps it; :func:`imrl_jax.agent.lifetime.run_phase` resolves an unresolved config the same way (library use).
The step kernel is a compute field: the run's content key is the same whichever is chosen.
"""

from __future__ import annotations

from imrl_jax.config import Config, ConfigError


def unsupported(config: Config) -> str | None:
    """Why the kernel cannot live ``config`` (one line), or None when it can."""
    from imrl_jax.agent import kernel  # imports lifetime, which imports this module

    why = kernel.unsupported(config)
    if why is None:
        return None
    # kernel's refusal is worded for an explicit pallas: "step_kernel: the pallas kernel does not implement X; use ..."
    return why.split("does not implement ", 1)[-1].split("; use step_kernel=xla")[0]


def default_backend() -> str:
    """JAX's backend ("cpu", "gpu", "tpu"): asked only when a run is planned or traced, not at import."""
    import jax

    return jax.default_backend()


def resolve(config: Config, backend: str | None = None) -> tuple[Config, str | None]:
    """``config`` with an "auto" step kernel made "pallas" or "xla" on ``backend`` (default JAX's), and the note
    that says why a GPU run falls back to the XLA step (else None); an explicit choice is kept as it is, but an
    explicit pallas for a model the kernel does not implement is refused here (ConfigError), before a command writes."""
    if config.step_kernel == "pallas":
        from imrl_jax.agent import kernel

        why = kernel.unsupported(config)
        if why is not None:
            raise ConfigError(why, "step_kernel")
    if config.step_kernel != "auto":
        return config, None
    backend = default_backend() if backend is None else backend
    if backend != "gpu":
        return config.replace(step_kernel="xla"), None
    why = unsupported(config)
    if why is None:
        return config.replace(step_kernel="pallas"), None
    return config.replace(step_kernel="xla"), (f"note: step_kernel=auto: {config.condition} lives on the XLA step on "
                                               f"this GPU, as the Pallas kernel does not implement {why}")


def chosen(config: Config) -> str:
    """The step kernel that lives ``config``: "xla" or "pallas"."""
    return resolve(config)[0].step_kernel

