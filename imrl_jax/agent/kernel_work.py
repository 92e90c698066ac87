"""The Pallas kernel's work per lane-step, counted (docs/PERFORMANCE.md "How far from the hardware").

    PYTHONPATH=. python3 -m imrl_jax.agent.kernel_work

Two counts. :func:`network_macs`: the multiply-adds of the networks per step at the config's sizes (n + 1
inputs with the bias, K experts), term by term as :mod:`imrl_jax.agent.kernel`'s ``one_step`` computes them.
:func:`loop_work`: what the kernel's loop body does per step as traced (its jaxpr, with Triton's padded
sizes Kp and N): element operations by kind, reductions, the bytes it reads from global memory (the
draws), and the warp instructions they take with one lane per warp (``num_warps=1``) — each operation
on a vector of N elements is N/32 instructions, a scalar one is one instruction for the whole warp, a
reduction over a warp adds 5 shuffle-and-add rounds. The state (weights, traces, pose) is read and
written once per bin: :func:`state_bytes`.
"""

from __future__ import annotations

import collections
import math
import sys

#: Element-wise primitives counted as floating-point operations (one per element), transcendental ones apart.
ARITHMETIC = {"add", "sub", "mul", "div", "neg", "max", "min", "abs", "sign", "floor", "ceil", "round", "rem",
              "square", "integer_pow", "sqrt", "rsqrt", "pow", "nextafter", "exp2"}
TRANSCENDENTAL = {"exp", "log", "log1p", "expm1", "logistic", "tanh", "sin", "cos", "tan", "atan2", "erf"}
#: Primitives that move or select data (no arithmetic, still an instruction per element).
OTHER = {"select_n", "lt", "le", "gt", "ge", "eq", "ne", "and", "or", "not", "xor", "convert_element_type",
         "broadcast_in_dim", "reshape", "squeeze", "iota", "concatenate", "slice", "dynamic_slice",
         "shift_right_logical", "shift_left", "clamp", "copy", "copy_p", "stop_gradient"}
REDUCTIONS = {"reduce_sum", "reduce_max", "reduce_min", "argmax", "argmin", "reduce_and", "reduce_or"}
WARP = 32


def _size(aval) -> int:
    return int(math.prod(getattr(aval, "shape", ()) or (1,)))


def _subjaxprs(eqn):
    for value in eqn.params.values():
        for v in value if isinstance(value, (list, tuple)) else (value,):
            inner = getattr(v, "jaxpr", v)
            if hasattr(inner, "eqns"):
                yield inner


def count(jaxpr, work=None) -> collections.Counter:
    """Element operations (``flops``, ``transcendental``, ``other``), reduced elements, ``global_read_bytes`` (ref
    reads) and ``warp_instructions`` of ``jaxpr``, its inner jaxprs included (a ``cond``'s branches all counted)."""
    work = collections.Counter() if work is None else work
    for eqn in jaxpr.eqns:
        name = eqn.primitive.name
        inner = list(_subjaxprs(eqn))
        if inner:
            for sub in inner:
                count(sub, work)
            continue
        out = sum(_size(v.aval) for v in eqn.outvars)
        if name in REDUCTIONS:
            elements = _size(eqn.invars[0].aval)
            work["reduced"] += elements
            # per output: the thread-local part (elements / 32 per thread), then 5 shuffle + add rounds over the warp
            work["warp_instructions"] += math.ceil(elements / WARP) + (2 * 5 if elements >= WARP else 0) * out
            continue
        if name == "get":
            work["global_read_bytes"] += out * eqn.outvars[0].aval.dtype.itemsize
        kind = "flops" if name in ARITHMETIC else "transcendental" if name in TRANSCENDENTAL else "other"
        work[kind] += out
        work["warp_instructions"] += math.ceil(out / WARP) * (4 if kind == "transcendental" else 1)
        work[f"ops:{name}"] += 1
    return work


def kernel_jaxpr(config, phase, steps: int = 8):
    """The jaxpr of the kernel of one bin of ``steps`` steps of ``phase`` for ``config`` (traced, not run)."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.agent import kernel as K
    from imrl_jax.agent import lifetime as L
    from imrl_jax.world.env import Pose, at
    from imrl_jax.agent.networks import decode
    from imrl_jax.agent.state import phase_params, spawn_draws

    agent = decode(config, jnp.zeros((config.num_genes,)))
    if not phase.intrinsic:
        agent = L.adult_agent(config, agent)
    task = L.childhood_task(config) if phase.intrinsic else L.task_spec(config, 0)

    def one_bin(key):
        state = L.init_state(config, agent, at(Pose(jnp.array([40.0, 60.0]), jnp.array(math.pi))))
        draws = K.draw_range(key, 0, steps, config.draw_block, phase.noisy, spawn_draws(config, phase))
        return K.run_bin(config, phase, phase_params(phase, config.learning_params()), task, steps, draws,
                         K.pack(state, config), agent.selector_actor.shape[0], interpret=False)

    traced = jax.make_jaxpr(one_bin)(jax.random.key(0))
    return next(e.params["jaxpr"] for e in traced.jaxpr.eqns if e.primitive.name == "pallas_call")


def loop_work(config, phase) -> collections.Counter:
    """What the kernel's loop body does for one step of one lane (see :func:`count`)."""
    kernel = kernel_jaxpr(config, phase)
    loop = next(e for e in kernel.eqns if e.primitive.name == "scan")
    return count(loop.params["jaxpr"].jaxpr)


def observe_work(config, points: bool = False) -> collections.Counter:
    """The work of the kernel's ``observe`` (x~ from the pose): as it is, each of the N padded entries computing its
    point's position and colour; ``points``: the variant PERFORMANCE.md plans, once per retina point (padded to a
    power of two) and the colours broadcast colour-major to the N entries."""
    import jax
    import jax.numpy as jnp

    from imrl_jax.world.arena import floor_colour_xy
    from imrl_jax.agent.kernel import round_even

    big_n = 1 << config.num_inputs.bit_length()  # n + 1 entries to a power of two, as kernel_layout.pow2
    width = 1 << (config.num_inputs // 3 - 1).bit_length() if points else big_n

    def observe(x, y, c, s, forward, lateral, colours, bias):
        colour = floor_colour_xy(config, x + forward * c - lateral * s, y + forward * s + lateral * c, round_even)
        colour = colour.astype(jnp.float32)
        if points:
            colour = jnp.broadcast_to(colour[None, :], (big_n // width, width)).reshape(big_n)
        return (colour == colours).astype(jnp.float32) + bias

    scalar, vector, wide = jnp.zeros(()), jnp.zeros((width,)), jnp.zeros((big_n,))
    return count(jax.make_jaxpr(observe)(scalar, scalar, scalar, scalar, vector, vector, wide, wide).jaxpr)


def state_bytes(config, phase) -> int:
    """Bytes the kernel reads and writes from global memory once a bin (the lane's state in and out, its counts)."""
    kernel = kernel_jaxpr(config, phase)
    outside = [e for e in kernel.eqns if e.primitive.name in ("get", "swap")]
    # a get's bytes are its output's; a swap writes its value (the new one) in
    return sum(_size(e.outvars[0].aval) * e.outvars[0].aval.dtype.itemsize for e in outside)


def network_macs(config, phase, padded: bool = False, num_experts: int | None = None) -> dict:
    """Multiply-adds of the networks per step at the config's sizes, by term (kernel.py's ``one_step``: a matrix
    K x (n+1) times x~ is K(n+1); a trace or a weight update of a vector n+1, of a matrix K(n+1)); ``padded``: at
    Triton's sizes (K to a power of two Kp, n + 1 to one N), what runs; ``num_experts``: the agent's K where it is
    not the config's (SLE's adult agent has one expert)."""
    k, n1 = num_experts or config.num_experts, config.num_inputs + 1
    if padded:
        k, n1 = 1 << (k - 1).bit_length(), 1 << (n1 - 1).bit_length()
    terms = {"selector forward (K sigmoid units)": k * n1, "actor forward (2 units of each expert)": 2 * k * n1}
    if phase.experts_learn:
        terms.update({"reinforcer forward": k * n1 if phase.intrinsic else 0, "evaluator V(x_t-1), V(x_t)": 2 * k * n1,
                      "expert traces (evaluator, 2 actor units)": 3 * n1,
                      "expert updates (evaluator, 2 actor rows)": 3 * k * n1})
    if phase.selector_learns:
        terms.update({"selector critic V(x_t-1), V(x_t)": 2 * n1, "selector traces (critic, actor)": n1 + k * n1,
                      "selector updates (critic, actor)": n1 + k * n1})
    return {name: macs for name, macs in terms.items() if macs}


def report(config=None) -> list[str]:
    """The counts of LE-LS's childhood and adulthood, as PERFORMANCE.md quotes them."""
    from imrl_jax import conditions as C
    from imrl_jax.config import make_config
    from imrl_jax.agent.state import childhood_phase

    config = make_config("paper", condition="LE-LS") if config is None else config
    lines = []
    for name, phase in (("childhood", childhood_phase(config)), ("adulthood", C.ADULT_LEARNING_SELECTOR),
                        ("EE-ES adulthood", C.ADULT_EVOLVED_SELECTOR)):
        macs, work = network_macs(config, phase), loop_work(config, phase)
        points = loop_work(config.replace(kernel_retina="points"), phase)["warp_instructions"]
        lines.append(f"{name}: networks {sum(macs.values())} multiply-adds at K={config.num_experts}, n+1="
                     f"{config.num_inputs + 1} ({sum(network_macs(config, phase, padded=True).values())} padded); loop body: {work['flops']} "
                     f"flops, {work['transcendental']} transcendental, {work['other']} other element ops, "
                     f"{work['reduced']} reduced; {work['global_read_bytes']} B read a step; ~{work['warp_instructions']}"
                     f" warp instructions a step; state {state_bytes(config, phase)} B a bin")
        lines.append(f"{name}, observing by points (kernel_retina=points): ~{points} warp instructions a step")
    return lines


if __name__ == "__main__":
    sys.stdout.write("\n".join(report()) + "\n")
