"""The learning rules of section 2 and MODEL.md "Learning": TD surprise, actor-critic updates, traces.

:func:`learn_experts` and :func:`learn_selector` are the paper's rules, stated once; the
functions above them are their building blocks. Each rule is w += eta * delta * e, where e
is the network's eligibility trace (e <- gamma * lambda * e + phi on the steps at which it
learns; lambda = 0 gives the paper's one-step rules exactly).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from imrl_jax.agent.networks import evaluate_both, internal_rewards


def td_error(reward, value, next_value, gamma, terminal):
    """Surprise r + gamma V(x_t) - V(x_{t-1}); a terminal transition does not bootstrap."""
    return reward + gamma * jnp.where(terminal, 0.0, next_value) - value


def unit_features(action, output, xb):
    """phi of one actor unit: ((a - o) * o * (1 - o)) x~ (moves o towards the action)."""
    return ((action - output) * output * (1.0 - output)) * xb


def actor_features(action, output, xb):
    """phi of an expert actor: :func:`unit_features` of each unit, ((a - o) * o * (1 - o)) outer x~."""
    return unit_features(action[:, None], output[:, None], xb[None, :])


def selector_features(k, selection, xb):
    """phi of the selector actor: ((e_k - s) * s * (1 - s)) outer x~."""
    e = jax.nn.one_hot(k, selection.shape[0], dtype=selection.dtype)
    return ((e - selection) * selection * (1.0 - selection))[:, None] * xb[None, :]


def accumulate(trace, phi, gamma, trace_lambda, learn, ended=False):
    """e <- gamma * lambda * e + phi where the network learns this step; unchanged elsewhere.

    A trace that ``ended`` (at the previous step) is read as 0 first.
    """
    # Factors instead of jnp.where: XLA's CPU backend vectorises a multiply of a whole
    # array by each lane's scalar, but not a select on each lane's flag (about 2x
    # faster on the selector's trace). The same numbers, since traces are finite.
    # (1 - ended rather than a select between two literals, whose type Triton's lowering
    # loses: the GPU kernel uses this function too.)
    keep = jnp.where(learn, gamma * trace_lambda, 1.0) * (1.0 - jnp.asarray(ended, trace.dtype))
    return trace * keep + phi * jnp.asarray(learn, trace.dtype)


def ascend(weights, trace, delta, eta):
    """w += eta * delta * e."""
    return weights + eta * (delta * trace)


def ascend_row(weights, row, trace, delta, eta):
    """w[k] += eta * delta * e for the row k that the one-hot vector ``row`` picks; other rows unchanged."""
    # A product with the one-hot instead of a row write: under vmap a row write is a
    # scatter, a slow loop on XLA's CPU backend, and this is one vectorised pass. The
    # same numbers while the weights are finite (the other rows get + 0).
    return weights + row.reshape(row.shape + (1,) * trace.ndim) * (eta * (delta * trace))


def pick_row(matrix, k):
    """matrix[k], as the sum of its rows times a one-hot vector (see :func:`ascend_row`).

    Under vmap a vectorised pass instead of a gather; the same numbers while the other
    rows are finite.
    """
    onehot = jax.nn.one_hot(k, matrix.shape[0], dtype=matrix.dtype)
    picked = onehot[0] * matrix[0]
    for j in range(1, matrix.shape[0]):
        picked = picked + onehot[j] * matrix[j]
    return picked


def after_choice(flag, k):
    """``flag`` itself, made to depend on this step's expert choice ``k`` (``k >= 0`` always holds).

    A speed device, not a rule: it orders the selector's update after the choice, which reads
    the same selector weights, so that XLA updates them in place rather than in a copy made
    every step (docs/PERFORMANCE.md, changelog).
    """
    return flag & (k >= 0)


# --------------------------------------------------------------------------- the rules

def take_row(matrix, k):
    """Row k of matrix (k may be traced)."""
    return jax.lax.dynamic_index_in_dim(matrix, k, 0, keepdims=False)


def learn_experts(phase, params, agent, traces, prev, xb, prev_xb, same):
    """The expert that held control learns from the transition t-1 -> t (section 2; MODEL.md "Learning").

        delta_k = r + gamma V_k(x_t) - V_k(x_{t-1})       (surprise; a terminal transition: r - V_k(x_{t-1}))
        e_v <- gamma lambda e_v + x~_{t-1};                      v_k += eta_evaluator delta_k e_v
        e_W <- gamma lambda e_W + ((a - o) o (1 - o)) x~_{t-1}^T;  W_k += eta_actor delta_k e_W

    r is the expert's own reinforcer r_k(x_t) in childhood, the extrinsic reward (1 on
    reaching the target) for SLE. It learns only when it kept control (k_t == k_{t-1}: the
    paper's two contiguous steps) over a transition that was not cut; its traces end when it
    loses control or the trial ends. Returns the agent, the traces and the surprise delta_k.

    With evolved evaluators (``phase.evaluation``; the paper's future work (a)) the evaluation
    V_k is innate and fixed, and the actor learns from its change alone:

        delta_k = gamma V_k(x_t) - V_k(x_{t-1})   ("discounted"),  or  V_k(x_t) - V_k(x_{t-1})   ("difference")
    """
    gamma, lam = params.gamma, params.trace_lambda
    learn = prev.valid & same
    ends = prev.terminal | ~prev.valid
    kp = prev.k
    held = jax.nn.one_hot(kp, agent.evaluator.shape[0], dtype=xb.dtype)  # the expert that held control
    # Every reinforcer, and every evaluator, at once: a matrix-vector product is one fast
    # kernel (see networks.evaluate_both), where taking row kp first is a slow gather.
    if phase.evaluation:  # the change of the innate evaluation alone
        reward, discount = 0.0, gamma if phase.evaluation == "discounted" else 1.0
    else:
        reward = internal_rewards(agent, xb)[kp] if phase.intrinsic else prev.terminal.astype(xb.dtype)
        discount = gamma
    value_before, value_now = (agent.evaluator @ prev_xb)[kp], (agent.evaluator @ xb)[kp]
    surprise = td_error(reward, value_before, value_now, discount, prev.terminal)
    delta = jnp.where(learn, surprise, 0.0)
    learns_value = not phase.evaluation  # an evolved evaluation is innate: it does not learn
    updated, kept = {}, {}
    if learns_value:
        kept["evaluator"] = accumulate(traces.evaluator, prev_xb, gamma, lam, learn, traces.experts_ended)
    trace_w = accumulate(traces.actor, actor_features(prev.action, prev.output, prev_xb),
                         gamma, lam, learn, traces.experts_ended)
    if learns_value:
        updated["evaluator"] = ascend_row(agent.evaluator, held, kept["evaluator"], delta, params.eta_evaluator)
    agent = agent._replace(**updated, actor=ascend_row(agent.actor, held, trace_w, delta, params.eta_actor))
    traces = traces._replace(**kept, actor=trace_w, experts_ended=~same | ends)
    return agent, traces, surprise


def childhood_selector_reward(phase, params, k, learned, surprise, baseline):
    """The childhood selector's reward for a transition its expert ``k`` ``learned`` from, and the baselines b.

    The paper's is the expert's surprise delta_k. With the ``progress`` option it is learning progress,
    roughly: the surprise beyond what this expert usually gets, delta_k - b_k, with
    b_k <- b_k + rho (delta_k - b_k) on the steps it learns, so that an expert whose reinforcer merely
    pays more everywhere is not favoured.
    """
    if not phase.progress:
        return surprise, baseline
    held = jax.nn.one_hot(k, baseline.shape[0], dtype=baseline.dtype) * learned
    before = jnp.sum(held * baseline)
    return surprise - before, baseline + params.progress_rate * held * (surprise - baseline)


def learn_selector(phase, params, agent, traces, prev, xbs, now, k, same, surprise, baseline):
    """The selector learns from the transition t-1 -> t (section 2; MODEL.md "Learning"), with e = one-hot(k_{t-1}):

        delta_s = R + gamma U(x_t) - U(x_{t-1})         (a terminal transition: R - U(x_{t-1}))
        e_u <- gamma lambda e_u + x~_{t-1};                      u += eta_selector_critic delta_s e_u
        e_S <- gamma lambda e_S + ((e - s) s (1 - s)) x~_{t-1}^T;  S += eta_selector_actor delta_s e_S

    In childhood R is the surprise of the expert that kept control (the paper: "the surprise
    of the selected expert"), and nothing learns when the expert changed; with the
    ``progress`` option, that surprise minus the expert's running mean surprise b_k. In
    adulthood R is the extrinsic reward, every step. x~_{t-1} and x~_t are the rows of
    ``xbs`` in turn (x~_t in row ``now``). Returns the agent, the traces and the baselines b.
    """
    gamma, lam = params.gamma, params.trace_lambda
    ends = prev.terminal | ~prev.valid
    prev_xb = take_row(xbs, 1 - now)
    if phase.intrinsic:
        learn = prev.valid & same
        reward, baseline = childhood_selector_reward(phase, params, prev.k, learn, surprise, baseline)
    else:
        learn, reward = after_choice(prev.valid, k), prev.terminal.astype(prev_xb.dtype)
    u_weights, s_weights = agent.selector_critic, agent.selector_actor
    values = evaluate_both(u_weights, xbs)
    delta = td_error(reward, take_row(values, 1 - now), take_row(values, now), gamma, prev.terminal)
    delta = jnp.where(learn, delta, 0.0)
    trace_u = accumulate(traces.selector_critic, prev_xb, gamma, lam, learn, traces.selector_ended)
    trace_s = accumulate(traces.selector_actor, selector_features(prev.k, prev.selection, prev_xb),
                         gamma, lam, learn, traces.selector_ended)
    agent = agent._replace(selector_critic=ascend(u_weights, trace_u, delta, params.eta_selector_critic),
                           selector_actor=ascend(s_weights, trace_s, delta, params.eta_selector_actor))
    traces = traces._replace(selector_critic=trace_u, selector_actor=trace_s, selector_ended=ends)
    return agent, traces, baseline


def learn_selector_over_option(phase, params, agent, traces, prev, option, xb, choose, same, surprise, baseline):
    """The selector learns from an option when it ends (semi-Markov TD; docs/TIMESCALE.md), with e = one-hot(k):

        R = sum_{i<tau} gamma^i r_{t0+i+1}                   (the option's reward, summed over its tau steps)
        delta_s = R + gamma^tau U(x_t) - U(x_{t0})           (a terminal transition: R - U(x_{t0}))
        e_u <- gamma^tau' lambda e_u + x~_{t0};                          u += eta_selector_critic delta_s e_u
        e_S <- gamma^tau' lambda e_S + ((e - s_{t0}) s_{t0} (1 - s_{t0})) x~_{t0}^T;  S += eta_selector_actor delta_s e_S

    t0 is the step at which the option was chosen, t the step at which it ends (``choose``), and
    tau' the length of the option learned from before it (the traces decay by the time between the
    two choices). r is :func:`learn_selector`'s per-step reward: in adulthood the extrinsic reward; in
    childhood the surprise of the expert in control on the transitions it learned from (an option in
    which it learned from none teaches nothing). Every step adds this step's reward to the option;
    the option returned is the one that goes on (see :func:`imrl_jax.agent.timescale.next_option`). With
    options of one step this is :func:`learn_selector`'s rule. Returns the agent, traces, baselines
    and the option.
    """
    gamma, lam = params.gamma, params.trace_lambda
    ends = prev.terminal | ~prev.valid
    if phase.intrinsic:
        learned = prev.valid & same
        reward, baseline = childhood_selector_reward(phase, params, prev.k, learned, surprise, baseline)
        reward, worth = jnp.where(learned, reward, 0.0), option.learned | learned
    else:
        reward, worth = prev.terminal.astype(xb.dtype), jnp.bool_(True)
    total, discount = option.reward + option.discount * reward, option.discount * gamma
    learn = choose & prev.valid & worth
    u_weights, s_weights = agent.selector_critic, agent.selector_actor
    delta = total + jnp.where(prev.terminal, 0.0, discount * (u_weights @ xb)) - u_weights @ option.start_xb
    delta = jnp.where(learn, delta, 0.0)
    trace_u = accumulate(traces.selector_critic, option.start_xb, option.trace_discount, lam, learn,
                         traces.selector_ended)
    trace_s = accumulate(traces.selector_actor, selector_features(prev.k, option.selection, option.start_xb),
                         option.trace_discount, lam, learn, traces.selector_ended)
    agent = agent._replace(selector_critic=ascend(u_weights, trace_u, delta, params.eta_selector_critic),
                           selector_actor=ascend(s_weights, trace_s, delta, params.eta_selector_actor))
    # The traces end with the trial; between choices nothing reads them.
    traces = traces._replace(selector_critic=trace_u, selector_actor=trace_s,
                             selector_ended=jnp.where(choose, ends, traces.selector_ended))
    option = option._replace(reward=total, discount=discount, learned=worth,
                             trace_discount=jnp.where(learn, discount, option.trace_discount))
    return agent, traces, baseline, option
