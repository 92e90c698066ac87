"""Charts of numbers (section 3 of the paper, Fig. 3): fitness per generation (Fig. 3a), learning curves and a
learning test's performance per bin (Fig. 3b), a baseline's learning curve, the share of control per expert, what
each expert follows, a sweep's outcomes and the evolved traits per generation.

Every ``plot_*`` function returns a matplotlib ``Figure`` in the style of :mod:`imrl_jax.analysis.plotting`
(which saves it).
"""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.analysis.plotting import CONDITION_STYLES, EXPERT_COLOURS, SEEN_COLOURS, new_figure, style_axis
from imrl_jax.config import CONDITIONS, Config


def plot_fitness(curves: dict, title: str = "", ylabel: str = "best fitness"):
    """Fitness per generation (0 first), one line per label: the mean over seeds with a +-1 std band (Fig. 3a).

    ``curves`` maps a label to an array (seeds, generations) (or (generations,)); a label
    that is a condition gets the paper's line style, others a colour ramp in order.
    """
    from matplotlib.ticker import MaxNLocator

    fig = new_figure(5.5, 3.4)
    ax = fig.add_subplot()
    ramp = iter(_series_colours(sum(label not in CONDITIONS for label in curves)))
    for label, values in curves.items():
        values = np.atleast_2d(np.asarray(values, float))
        generations = np.arange(values.shape[-1])
        mean, std = values.mean(0), values.std(0)
        style = CONDITION_STYLES[label] if label in CONDITIONS else dict(color=next(ramp), lw=1.6)
        ax.plot(generations, mean, label=label, marker="o", ms=2.5, **style)
        if values.shape[0] > 1:
            ax.fill_between(generations, mean - std, mean + std, color=style["color"], alpha=0.15, lw=0)
    ax.set_ylim(bottom=0)
    ax.set_xlim(-0.3, max(1, max(np.shape(v)[-1] for v in curves.values()) - 1) + 0.3)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    style_axis(ax, title, "generation", ylabel)
    if len(curves) > 1:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    return fig


def plot_learning_curves(config: Config, curves: dict, title: str = "", bin_steps: int | None = None):
    """Task performance per bin of a phase, one panel per task and one for their mean.

    ``curves`` maps a label to a (tasks, bins) array of reaches per bin divided by the bin's
    theoretical maximum (:func:`imrl_jax.evolution.sweeps.normalised_curve`); 1 is the straight line
    at full speed. ``bin_steps`` labels the x axis in steps (default: task_steps / num_bins).
    """
    bin_steps = config.task_steps // config.num_bins if bin_steps is None else bin_steps
    num_tasks = config.num_tasks
    cols = 4
    rows = math.ceil((num_tasks + 1) / cols)
    fig = new_figure(2.4 * cols, 2.0 * rows + 0.4)
    axes = fig.subplots(rows, cols, sharey=True, squeeze=False).ravel()
    colours = _series_colours(len(curves))
    for (label, curve), colour in zip(curves.items(), colours):
        curve = np.asarray(curve, float)
        x = (np.arange(curve.shape[-1]) + 0.5) * bin_steps
        for t in range(num_tasks):
            axes[t].plot(x, curve[t], color=colour, lw=1.3, label=label)
        axes[num_tasks].plot(x, curve.mean(0), color=colour, lw=1.6, label=label)
    axes[0].set_ylim(bottom=0)  # after every line is drawn: the axes share y
    for t, ax in enumerate(axes[:num_tasks + 1]):
        style_axis(ax, f"task {t + 1}" if t < num_tasks else "mean over tasks")
        if t % cols == 0:
            ax.set_ylabel("performance", fontsize=8)
        if t >= num_tasks + 1 - cols:
            ax.set_xlabel("step of the task", fontsize=8)
    for ax in axes[num_tasks + 1:]:
        ax.axis("off")
    if len(curves) > 1 or next(iter(curves), ""):
        handles, labels = axes[num_tasks].get_legend_handles_labels()
        target = axes[num_tasks + 1] if len(axes) > num_tasks + 1 else axes[num_tasks]
        target.legend(handles, labels, fontsize=7, loc="center" if target is not axes[num_tasks] else "best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


#: The paper's learning tests: tasks of 1,000,000 cycles, 10 runs x 10 best x 10 tests.
PAPER_TEST = dict(task_steps=1_000_000, shape=(10, 10, 10))


def scale_label(config: Config, shape: tuple[int, ...]) -> str:
    """", reduced scale (...)" when a test is shorter or smaller than the paper's, else ""."""
    short = bool(config.task_steps < PAPER_TEST["task_steps"])
    small = bool(np.prod(shape) < np.prod(PAPER_TEST["shape"]))
    parts = [f"{config.task_steps:,} cycles"] * short + [f"{int(np.prod(shape)):,} tests"] * small
    return f", reduced scale ({', '.join(parts)})" if parts else ""


def plot_learning_test(config: Config, curve: np.ndarray):
    """A learning test's mean performance per bin and the range of its runs' means (learning_curve.png).

    ``curve`` (runs, best, tests, tasks, bins): every test's performance per bin
    (:func:`imrl_jax.analysis.steady_state.performance_curve`).
    """
    bin_steps = config.task_steps // config.num_bins
    x = (np.arange(config.num_bins) + 0.5) * bin_steps
    fig = new_figure(6.0, 3.6)
    fig.set_layout_engine("constrained")
    ax = fig.subplots()
    per_run = curve.mean((1, 2, 3))
    ax.fill_between(x, per_run.min(0), per_run.max(0), color="0.85", label="range of the runs' means")
    ax.plot(x, curve.mean((0, 1, 2, 3)), color="k", lw=2, label="mean of all tests")
    ax.set_ylim(0, 1)
    ax.set_xlim(0, config.task_steps)
    runs, best, tests = curve.shape[:3]
    style_axis(ax, f"{config.condition} learning test: {runs} run(s) x {best} best x {tests} test(s), "
                   f"{config.num_tasks} tasks each{scale_label(config, curve.shape[:3])}",
               "cycles of the task (bin centres)",
               "performance per bin (1: straight line)")
    ax.legend(fontsize=7)
    return fig


def plot_baseline(curves: list[dict], tasks, steps: int, title: str):
    """A baseline's performance against cycles of experience per task, the mean over seeds (learning_curve.png).

    ``curves``: a row per evaluation (task, seed, step, performance); ``steps``: the x axis' end.
    """
    fig = new_figure(6.0, 3.6)
    fig.set_layout_engine("constrained")
    ax = fig.subplots()
    colours = ["tab:red", "tab:orange", "tab:green", "tab:olive", "tab:blue", "tab:purple"]
    for task in tasks:
        points = [c for c in curves if c["task"] == task]
        steps_done = sorted({c["step"] for c in points})
        mean = [np.mean([c["performance"] for c in points if c["step"] == s]) for s in steps_done]
        ax.plot(steps_done, mean, color=colours[(task - 1) % len(colours)], lw=1.5, label=f"task {task}")
    ax.set_ylim(0, 1)
    ax.set_xlim(0, steps)
    style_axis(ax, title, "control cycles of experience on the task", "performance (1: straight line)")
    ax.legend(fontsize=7)
    return fig


def plot_selections(selections, title: str = "share of control per expert", bin_steps: int | None = None,
                    xlabel: str = "step"):
    """Stacked shares of steps each expert was in control per bin (``selections`` (bins, K))."""
    selections = np.asarray(selections, float)
    share = selections / np.maximum(selections.sum(-1, keepdims=True), 1)
    bins, num_experts = share.shape
    bin_steps = 1 if bin_steps is None else bin_steps
    x = (np.arange(bins) + 0.5) * bin_steps
    fig = new_figure(5.0, 2.8)
    ax = fig.add_subplot()
    bottom = np.zeros(bins)
    for e in range(num_experts):  # stacked bars, one per bin: the shares are per bin
        ax.bar(x, share[:, e], bin_steps, bottom=bottom, color=EXPERT_COLOURS[e % len(EXPERT_COLOURS)],
               label=f"expert {e + 1}", alpha=0.85, lw=0)
        bottom = bottom + share[:, e]
    ax.set_ylim(0, 1)
    ax.set_xlim(x[0] - bin_steps / 2, x[-1] + bin_steps / 2)
    style_axis(ax, title, xlabel, "share of steps", grid=False)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    return fig


def plot_expert_shares(shares, steps, title: str = "what each expert follows"):
    """Grouped bars: per expert, the share of its control steps' central readings that are R, G, B, nothing.

    ``shares`` (K, 4) and ``steps`` (K,) as returned by :func:`imrl_jax.analysis.behaviour.colour_shares`.
    """
    shares = np.nan_to_num(np.asarray(shares, float))
    num_experts = shares.shape[0]
    fig = new_figure(1.2 + 1.3 * num_experts, 2.8)
    ax = fig.add_subplot()
    width = 0.2
    names = ("red", "green", "blue", "nothing")
    for j, (name, colour) in enumerate(zip(names, SEEN_COLOURS)):
        ax.bar(np.arange(num_experts) + (j - 1.5) * width, shares[:, j], width, color=colour,
               edgecolor="black", lw=0.4, label=name)
    ax.set_xticks(range(num_experts), [f"expert {e + 1}\n({int(n)} steps)" for e, n in enumerate(steps)],
                  fontsize=7)
    for e in range(num_experts):
        ax.get_xticklabels()[e].set_color(EXPERT_COLOURS[e % len(EXPERT_COLOURS)])
    ax.set_ylim(0, 1)
    style_axis(ax, title, "", "share of central readings")
    ax.grid(alpha=0.3, axis="y")
    ax.grid(False, axis="x")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    return fig


def plot_sweep_summary(values_by_field: dict, title: str = "", ylabel: str = "final best fitness",
                       baselines: dict | None = None):
    """One panel per swept field: the outcome (mean +-1 std over seeds) against the field's value.

    ``values_by_field`` maps a field to ``(values (V,), outcomes (V, seeds))``; ``baselines``
    optionally maps a field to the config's value (a dashed vertical line). Fields whose
    positive values span more than a factor 20 get a log x axis.
    """
    fields = list(values_by_field)
    cols = min(len(fields), 3)
    rows = math.ceil(len(fields) / cols)
    fig = new_figure(2.6 * cols + 0.3, 2.3 * rows + 0.3)
    axes = fig.subplots(rows, cols, sharey=True, squeeze=False).ravel()
    for ax, field in zip(axes, fields):
        xs, ys = values_by_field[field]
        xs = np.asarray(xs, float)
        ys = np.atleast_2d(np.asarray(ys, float).T).T if np.ndim(ys) == 1 else np.asarray(ys, float)
        mean, std = ys.mean(-1), ys.std(-1)
        ax.errorbar(xs, mean, yerr=std, color="black", marker="o", ms=4, lw=1.4, capsize=3)
        if ys.shape[-1] > 1:
            for s in range(ys.shape[-1]):
                ax.plot(xs, ys[:, s], color="0.6", lw=0.6, alpha=0.7, zorder=1)
        if np.all(xs > 0) and xs.max() / xs.min() > 20:
            ax.set_xscale("log")
        if baselines and field in baselines:
            ax.axvline(baselines[field], color="0.4", ls="--", lw=0.8)
        style_axis(ax, field, field)
    axes[0].set_ylim(bottom=0)  # after every panel is drawn: the axes share y
    for i, ax in enumerate(axes):
        if i % cols == 0 and i < len(fields):
            ax.set_ylabel(ylabel, fontsize=8)
    for ax in axes[len(fields):]:
        ax.axis("off")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def plot_traits(config: Config, names, traits: np.ndarray, title: str = ""):
    """The evolved values per generation (``traits`` (G, S, T, 2): population mean and the best's, per seed).

    One panel per learning value (log scale for rates and for 1 - discount), the run's config value
    (what its preset fixes by hand) and the paper's dashed; the evolved childhood length in steps, its
    longest (``childhood_steps``) dashed; the expressed experts as their mean count and the population's
    shares of each count, stacked.
    """
    from matplotlib.ticker import MaxNLocator

    from imrl_jax.conditions import EVOLVED_PARAMETERS
    from imrl_jax.config import make_config

    kinds = {name: kind for name, kind, *_ in EVOLVED_PARAMETERS}
    paper = make_config("paper")
    values = [n for n in names if n in kinds or n == "childhood_length"]
    panels = values + (["expressed_experts", "shares"] if "expressed_experts" in names else [])
    columns = min(4, len(panels))
    rows = -(-len(panels) // columns)
    fig = new_figure(2.6 * columns, 2.1 * rows + 0.5)
    generations = np.arange(traits.shape[0])
    for i, panel in enumerate(panels):
        ax = fig.add_subplot(rows, columns, i + 1)
        if panel == "shares":
            shares = [traits[:, :, names.index(f"share_{k}_experts"), 0].mean(1) for k in range(1, config.num_experts + 1)]
            ax.stackplot(generations, shares, labels=[f"{k}" for k in range(1, config.num_experts + 1)],
                         colors=_series_colours(config.num_experts))
            ax.set_ylim(0, 1)
            ax.legend(title="experts", fontsize=6, title_fontsize=6, loc="upper left", bbox_to_anchor=(1.0, 1.0))
            style_axis(ax, "share of the population", "generation", "", grid=False)
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            continue
        t = names.index(panel)
        mean, best = traits[:, :, t, 0].mean(1), traits[:, :, t, 1].mean(1)
        kind = kinds.get(panel, "linear")
        shown = (lambda v: 1.0 - v) if kind == "1-log" else (lambda v: v)
        ax.plot(generations, shown(mean), color="k", lw=1.4, label="population mean")
        ax.plot(generations, shown(best), color="tab:red", lw=1.0, label="the best's")
        if panel in kinds:
            ax.axhline(shown(getattr(config, panel)), color="tab:blue", lw=1, ls="--", label="the preset's value")
            if getattr(paper, panel) != getattr(config, panel):
                ax.axhline(shown(getattr(paper, panel)), color="0.5", lw=1, ls=":", label="the paper's value")
        elif panel == "childhood_length":  # the gene chooses a length up to the whole childhood
            ax.axhline(config.childhood_steps, color="tab:blue", lw=1, ls="--", label="the longest (childhood_steps)")
        if kind in ("log", "1-log"):
            ax.set_yscale("log")
        label = f"1 - {panel}" if kind == "1-log" else f"{panel} (steps)" if panel == "childhood_length" else panel
        style_axis(ax, label, "generation" if i >= len(panels) - columns else "")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    # One legend for the figure: the paper's value is drawn only in panels where the preset differs from it.
    legend = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            if ax.get_legend() is None:  # the shares' legend stays its own
                legend.setdefault(label, handle)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.06 if legend else 0, 1, 1))
    if legend:
        fig.legend(legend.values(), legend.keys(), loc="lower center", fontsize=7, ncol=len(legend), frameon=False)
    return fig


def _series_colours(n: int) -> list:
    """n distinguishable line colours in order (viridis-like ramp for ordered values)."""
    from matplotlib import colormaps

    if n <= 1:
        return ["black"]
    cmap = colormaps["viridis"]
    return [cmap(0.9 * i / (n - 1)) for i in range(n)]
