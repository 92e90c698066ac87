"""Figures in one style: the arena and tasks (the paper's Fig. 1) and trajectories by expert.

matplotlib is imported lazily, inside the functions, so importing the package stays light.
"""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.config import Config

FLOOR_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")  # red, green, blue lines
EXPERT_COLOURS = ("#ff7f0e", "#9467bd", "#111111", "#8c564b", "#e377c2", "#7f7f7f")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def floor_segments(config: Config) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """Every floor edge (start, end, colour index) that touches the arena, each once."""
    a, h = config.edge_length, config.hex_apothem
    ox, oy = config.tiling_origin
    n = int(config.arena_size / a) + 3
    seen, segments = set(), []
    for i in range(-2 * n, 2 * n):
        for j in range(-2 * n, 2 * n):
            cx, cy = ox + 1.5 * a * i, oy + h * i + 2 * h * j
            if not (-2 * a <= cx <= config.arena_size + 2 * a and -2 * a <= cy <= config.arena_size + 2 * a):
                continue
            corners = [np.array([cx + a * math.cos(k * math.pi / 3), cy + a * math.sin(k * math.pi / 3)])
                       for k in range(7)]
            for p, q in zip(corners[:-1], corners[1:]):
                mid = tuple(np.round((p + q) / 2, 3))
                if mid in seen:
                    continue
                seen.add(mid)
                angle = math.degrees(math.atan2(q[1] - p[1], q[0] - p[0])) % 180
                colour = int(round(angle / 60)) % 3
                segments.append((p, q, colour))
    return segments


def draw_arena(ax, config: Config, tasks: bool = False) -> None:
    """The floor lines, the walls and (optionally) the task arrows on a matplotlib axis."""
    from matplotlib.collections import LineCollection

    segments = floor_segments(config)
    lines = LineCollection([(p, q) for p, q, _ in segments],
                           colors=[FLOOR_COLOURS[c] for _, _, c in segments],
                           linewidths=2.0 * config.line_half_width / 3.0, alpha=0.45, zorder=1)
    ax.add_collection(lines)
    size = config.arena_size
    ax.plot([0, size, size, 0, 0], [0, 0, size, size, 0], color="black", lw=1.5, zorder=2)
    ax.set_xlim(-5, size + 5)
    ax.set_ylim(-5, size + 5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if tasks:
        for i, task in enumerate(config.tasks):
            (sx, sy), (tx, ty) = task.start, task.target
            ax.annotate("", xy=(tx, ty), xytext=(sx, sy), zorder=4,
                        arrowprops=dict(arrowstyle="-|>", color="black", lw=1.5))
            ax.text(sx, sy, str(i + 1), fontsize=9, ha="right", va="bottom", zorder=5,
                    bbox=dict(boxstyle="circle,pad=0.15", fc="white", ec="black", lw=0.5))


def draw_path(ax, pos: np.ndarray, k: np.ndarray, breaks: np.ndarray | None = None, lw: float = 1.2):
    """A path (T, 2) whose step t is coloured by the expert k[t] in control; no line across breaks."""
    from matplotlib.collections import LineCollection

    pos, k = np.asarray(pos), np.asarray(k)
    keep = np.ones(len(pos) - 1, bool) if breaks is None else ~np.asarray(breaks)[:-1]
    segs = np.stack([pos[:-1], pos[1:]], 1)[keep]
    colours = [EXPERT_COLOURS[int(e) % len(EXPERT_COLOURS)] for e in k[1:][keep]]
    ax.add_collection(LineCollection(segs, colors=colours, linewidths=lw, zorder=3))


def expert_legend(ax, num_experts: int) -> None:
    """A legend naming the path colour of each expert."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=EXPERT_COLOURS[e], lw=2, label=f"expert {e + 1}") for e in range(num_experts)]
    ax.legend(handles=handles, loc="lower left", fontsize=7, framealpha=0.9)


def plot_life(config: Config, childhood: dict | None, tasks: list[dict], path: str, title: str = "") -> None:
    """One PNG: the arena with the tasks, a childhood path and one path per task.

    ``childhood`` and each entry of ``tasks`` hold ``pos`` (T, 2), ``k`` (T,) and
    ``breaks`` (T,) (True where the robot was put back at the start after that step).
    """
    plt = _pyplot()
    num_panels = 2 + len(tasks)
    cols = 4
    rows = math.ceil(num_panels / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.3 * rows))
    axes = axes.ravel()
    draw_arena(axes[0], config, tasks=True)
    axes[0].set_title("arena and tasks", fontsize=9)
    ax = axes[1]
    draw_arena(ax, config)
    if childhood is not None:
        draw_path(ax, childhood["pos"], childhood["k"], childhood.get("breaks"), lw=0.8)
        ax.set_title(f"childhood, first {len(childhood['pos'])} steps", fontsize=9)
    else:
        ax.set_title("no childhood", fontsize=9)
    num_experts = 1
    for i, record in enumerate(tasks):
        ax = axes[2 + i]
        draw_arena(ax, config)
        draw_path(ax, record["pos"], record["k"], record.get("breaks"))
        task = config.tasks[i]
        ax.plot(*task.start, "o", color="black", ms=4, zorder=5)
        ax.add_patch(plt.Circle(task.target, config.target_radius, fc="none", ec="black", lw=1.2, zorder=5))
        label = record.get("label", "")
        ax.set_title(f"task {i + 1} {label}".strip(), fontsize=9)
        num_experts = max(num_experts, int(np.max(record["k"])) + 1)
    for ax in axes[num_panels:]:
        ax.axis("off")
    expert_legend(axes[1], max(num_experts, config.num_lane_experts))
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


CONDITION_STYLES = {"LE-LS": dict(color="black", lw=2.2), "EE-LS": dict(color="0.55", lw=1.8),
                    "EE-ES": dict(color="black", lw=1.4, ls="--"), "SLE": dict(color="tab:blue", lw=1.4, ls=":")}


def plot_fitness(best_by_condition: dict, path: str, title: str = "") -> None:
    """Fig. 3a: best fitness per generation, mean over seeds with a +-1 std band.

    ``best_by_condition`` maps a condition name to an array (generations, seeds).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for condition, best in best_by_condition.items():
        best = np.asarray(best, float)
        generations = np.arange(len(best))
        mean, std = best.mean(1), best.std(1)
        style = CONDITION_STYLES.get(condition, {})
        ax.plot(generations, mean, label=condition, **style)
        ax.fill_between(generations, mean - std, mean + std, color=style.get("color", "0.5"), alpha=0.15, lw=0)
    ax.set_xlabel("generation")
    ax.set_ylabel("best fitness")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
