"""The report's figures: Fig. 3a, 3b and 3c, and the paths of the best individuals coloured by expert."""

from __future__ import annotations

import numpy as np

from imrl_jax.analysis.relive import DRAWN_STEPS
from imrl_jax.analysis.claims import SEEN, TESTED
from imrl_jax.analysis.arena_figures import draw_arena, draw_path, expert_legend
from imrl_jax.analysis.plotting import CONDITION_STYLES, EXPERT_COLOURS, SEEN_COLOURS, new_figure, style_axis


def _draw_curves(ax, series: dict, title: str, xlabel: str, ylabel: str, integer_x: bool = False) -> None:
    """Mean curves with a +-1 sd band, one per condition in the paper's line styles: {condition: (x, mean, sd, label)}."""
    from matplotlib.ticker import MaxNLocator

    banded = set()
    for condition, (x, mean, sd, label) in series.items():
        ax.plot(x, mean, label=label, **CONDITION_STYLES[condition])
        _band(ax, x, mean, sd, CONDITION_STYLES[condition], banded)
    ax.set_ylim(bottom=0)
    if integer_x:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    else:
        ax.set_xlim(left=0)
    style_axis(ax, title, xlabel, ylabel)
    if ax.lines:  # an empty panel (a stage not run yet) has nothing to name
        ax.legend(fontsize=7)


def _fitness_series(evolutions: dict) -> dict:
    return {c: (np.arange(len(best)), best.mean(1), best.std(1), f"{c} ({best.shape[1]} seeds)")
            for c, best in evolutions.items()}


#: Fig. 3a (evolutions' best fitness per generation) and 3b (learning tests' performance per bin): a panel's series
#: from its runs, its axes' labels, whether its x counts generations.
CURVES = dict(a=(_fitness_series, "generation", "best fitness", True),
              b=(lambda tests: {c: (t["steps"], t["mean"], t["sd"], c) for c, t in tests.items()},
                 "cycles of the task", "performance per bin", False))


def _panel(ax, panel: str, runs: dict, title: str) -> None:
    """Fig. 3a or 3b on one axis: a mean curve over seeds or runs per condition, with a +-1 sd band."""
    series, xlabel, ylabel, integer_x = CURVES[panel]
    _draw_curves(ax, series(runs), title, xlabel, ylabel, integer_x)


def fig_curves(panel: str, runs: dict, title: str):
    """Fig. 3a (``panel`` "a": best fitness per generation) or 3b ("b": learning tests, x in cycles) alone."""
    fig = new_figure(5.6, 3.5)
    _panel(fig.add_subplot(), panel, runs, title)
    fig.tight_layout()
    return fig


def _draw_steady(ax, steady: dict, variant: str, title: str, ylabel: str = "steady-state performance") -> None:
    """Fig. 3c's bars for one variant: mean over runs (dark, +-1 sd) and best run (light) per condition."""
    x = np.arange(len(TESTED))
    rows = [steady.get((variant, c)) or dict(steady_mean=np.nan, steady_sd=0.0, steady_best_run=np.nan)
            for c in TESTED]
    ax.bar(x - 0.19, [r["steady_mean"] for r in rows], 0.38, yerr=[r["steady_sd"] for r in rows], color="0.35",
           capsize=3, label="mean over runs")
    ax.bar(x + 0.19, [r["steady_best_run"] for r in rows], 0.38, color="0.75", label="best run")
    ax.set_xticks(x, TESTED, fontsize=7)
    style_axis(ax, title, "", ylabel)
    ax.grid(False, axis="x")
    ax.set_ylim(bottom=0)


def fig_steady(steady: dict, variants: list[str], title: str):
    """Fig. 3c: steady state per condition, mean over runs (dark, +-1 sd) and best run (light); a panel per variant."""
    fig = new_figure(3.0 * len(variants) + 0.6, 3.3)
    axes = fig.subplots(1, len(variants), sharey=True, squeeze=False)[0]
    for ax, variant in zip(axes, variants):
        _draw_steady(ax, steady, variant, variant, "steady-state performance" if ax is axes[0] else "")
    axes[-1].legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig


#: The conditions of the paper's Fig. 3b (EE-ES does not learn: it appears in 3c only).
FIG3B = ("LE-LS", "EE-LS", "SLE")


def fig3(evolutions: dict, tests: dict, steady: dict, variant: str, title: str):
    """The paper's Fig. 3 for one variant, side by side: (a) fitness, (b) learning (no EE-ES), (c) steady state."""
    fig = new_figure(14.0, 3.8)
    a, b, c = fig.subplots(1, 3, gridspec_kw=dict(width_ratios=[1.0, 1.0, 0.8]))
    _panel(a, "a", evolutions, "(a) best fitness, mean +-1 sd over seeds")
    _panel(b, "b", {k: t for k, t in tests.items() if k in FIG3B}, "(b) learning tests, mean +-1 sd over runs")
    _draw_steady(c, steady, variant, "(c) steady state: last cycles of (b)")
    c.legend(fontsize=7)
    for ax, missing in ((a, not evolutions), (b, not any(k in FIG3B for k in tests)),
                        (c, not any((variant, k) in steady for k in TESTED))):
        if missing:  # an unfinished run: say so rather than leave a blank panel
            not_run(ax)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


#: A childhood path whose extent stays below this (cm) is drawn as a mark and said to stay put.
STILL_CM = 2.0


def fig_paths(life: dict, title: str):
    """Each task's path after learning coloured by the expert in control, the last childhood steps, what experts see."""
    from matplotlib.patches import Circle

    config, childhood = life["config"], life["childhood"]
    fig = new_figure(12.8, 8.0)  # tall enough that the lower row's two-line titles clear the upper row
    axes = fig.subplots(2, 4).ravel()
    for i, (ax, trajectory, task) in enumerate(zip(axes[[1, 2, 3, 5, 6, 7]], life["tasks"], config.tasks)):
        draw_arena(ax, config)
        shown = trajectory.window(len(trajectory.k) - DRAWN_STEPS, len(trajectory.k))
        draw_path(ax, shown.pos, shown.k, shown.breaks)
        ax.plot(*task.start, "o", color="black", ms=4, zorder=5)
        ax.add_patch(Circle(task.target, config.target_radius, fc="none", ec="black", lw=1.2, zorder=5))
        ax.set_title(f"task {i + 1}: performance {life['performance'][i]:.2f} in the life\n"
                     f"after it: {int(trajectory.reached.sum())} reaches / {len(trajectory.k):,} steps", fontsize=7.5)
    ax, panel = axes[0], "arena and tasks (no childhood)"
    draw_arena(ax, config, tasks=childhood is None)
    if childhood is not None:
        pos = np.asarray(childhood.pos)
        draw_path(ax, pos, childhood.k, childhood.breaks, lw=0.8)
        panel = f"last {len(childhood.k):,} childhood steps"
        if np.ptp(pos, axis=0).max() < STILL_CM:  # a path too short to see: mark where the robot sits
            x, y = pos.mean(axis=0)
            ax.plot(x, y, "x", color="black", ms=7, mew=1.5, zorder=6)
            panel += f":\nthe robot stays at ({x:.0f}, {y:.0f}) cm (moves < {STILL_CM:g} cm)"
    ax.set_title(panel, fontsize=8)
    expert_legend(ax, config.num_experts)
    ax, shares = axes[4], np.nan_to_num(np.asarray(life["shares"], float))
    for j, (name, colour) in enumerate(zip(SEEN, SEEN_COLOURS)):
        ax.bar(np.arange(len(shares)) + (j - 1.5) * 0.2, shares[:, j], 0.2, color=colour, edgecolor="black", lw=0.4,
               label=name)
    ax.set_xticks(range(len(shares)), [f"expert {e + 1}\n{int(n):,} steps" for e, n in enumerate(life["steps"])],
                  fontsize=7)
    for e, label in enumerate(ax.get_xticklabels()):
        label.set_color(EXPERT_COLOURS[e % len(EXPERT_COLOURS)])
    ax.set_ylim(0, 1)
    style_axis(ax, "what each expert sees (central receptors)", "", "share of readings")
    ax.legend(fontsize=6, ncol=2)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def _band(ax, x, mean, sd, style: dict, banded: set) -> None:
    """A +-1 sd band; for a second condition drawn in the same colour, thin edge lines in its own line style."""
    colour = style.get("color", "0.5")
    if colour in banded:
        for edge in (mean - sd, mean + sd):
            ax.plot(x, edge, color=colour, lw=0.6, ls=style.get("ls", "-"), alpha=0.6)
    else:
        ax.fill_between(x, mean - sd, mean + sd, color=colour, alpha=0.13, lw=0)
        banded.add(colour)


#: Colours of the brax baselines (by agent); the larger budget is drawn dashed.
BASELINE_COLOURS = {"ppo": "tab:red", "es": "tab:green"}


def baseline_label(entry: dict) -> str:
    """'PPO, 1M cycles (5 seeds)'."""
    summary = entry["summary"]
    budget = f"{summary['steps'] / 1e6:g}M" if summary["steps"] >= 1e6 else f"{summary['steps'] / 1e3:g}k"
    return f"{summary['agent'].upper()}, {budget} cycles ({len(summary['seeds'])} seeds)"


def fig_baselines(baselines: dict, tests: dict, title: str):
    """The brax baselines (:func:`experiments.harness.loading.read_baselines`) beside ``tests``: curves and per task."""
    # tests: {(variant, condition): test} of the report's learning tests, drawn thin; a run several variants share
    # comes once, ``variant`` then the label ("every variant")
    fig = new_figure(11.0, 5.0)
    curves, bars = fig.subplots(1, 2, gridspec_kw=dict(width_ratios=[1.0, 1.25]))
    budgets = sorted({b["summary"]["steps"] for b in baselines.values()})
    colour = lambda b: BASELINE_COLOURS.get(b["summary"]["agent"], "0.3")  # noqa: E731
    for b in baselines.values():
        dashed = len(budgets) > 1 and b["summary"]["steps"] == budgets[-1]
        curves.plot(np.maximum(b["steps"], 1)[1:], b["mean"][1:], color=colour(b), lw=2.0, ls="--" if dashed else "-",
                    marker="o", ms=2.5, label=baseline_label(b))
    # variants apart by shade (and hatch below), conditions by colour and line as everywhere
    order = list(dict.fromkeys(variant for variant, _ in tests))
    alpha = {v: (0.95, 0.55, 0.3)[min(i, 2)] for i, v in enumerate(order)}
    hatch = {v: (None, "//", "..")[min(i, 2)] for i, v in enumerate(order)}
    for (variant, condition), t in tests.items():
        curves.plot(t["steps"], t["mean"], label=f"{condition} ({variant})",
                    **dict(CONDITION_STYLES[condition], lw=1.0, alpha=alpha[variant]))
    curves.set_xscale("log")
    curves.set_ylim(0, 1)
    style_axis(curves, "learning curves: mean over the six tasks", "control cycles of experience per task (log)",
               "performance (1: straight line)")
    curves.legend(fontsize=6, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.14))

    learners = [(baseline_label(b), b["per_task"],
                 dict(color=colour(b), alpha=1.0 if b["summary"]["steps"] == budgets[0] else 0.55))
                for b in baselines.values()]
    learners += [(f"{condition} ({variant}), steady state", t["steady"]["steady_per_task"],
                  dict(color=CONDITION_STYLES[condition]["color"], alpha=min(1.0, alpha[variant] + 0.1),
                       hatch=hatch[variant]))
                 for (variant, condition), t in tests.items()]
    width, tasks = 0.85 / max(len(learners), 1), np.arange(1, 7)
    for i, (label, values, style) in enumerate(learners):
        bars.bar(tasks - 0.425 + (i + 0.5) * width, values, width, label=label, edgecolor="white", lw=0.3, **style)
    bars.set_xticks(tasks, [f"task {t}" for t in tasks], fontsize=7)
    bars.set_ylim(0, 1)
    style_axis(bars, "final performance per task (mean over seeds or runs)", "", "performance")
    bars.grid(False, axis="x")
    bars.legend(fontsize=6, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.08))
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig


def not_run(ax) -> None:
    """Say "not run yet" on a panel whose stage has not finished, rather than leave it blank."""
    ax.text(0.5, 0.5, "not run yet", transform=ax.transAxes, ha="center", va="center", color="0.4")


def finish(fig, path: str) -> str:
    """Mark each empty panel as not run yet (:func:`not_run`), lay the figure out and save it."""
    from imrl_jax.analysis.plotting import save

    for ax in (ax for ax in fig.axes if not ax.lines and not ax.patches):
        not_run(ax)
    fig.tight_layout()
    return save(fig, path)
