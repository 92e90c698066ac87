"""Pictures of the arena (section 2, the paper's Fig. 1; section 3's behaviour): the floor, the walls and the
tasks, paths coloured by the expert in control, the robot and what its retina sees, and an individual's life
animated.

Every ``plot_*`` function returns a matplotlib ``Figure`` in the style of :mod:`imrl_jax.analysis.plotting`
(which saves it); the ``draw_*`` functions draw on a given axis, for the studies' own figures.
"""

from __future__ import annotations

import math

import numpy as np

from imrl_jax.analysis.plotting import (EXPERT_COLOURS, FLOOR_COLOURS, NOTHING_COLOUR, SEEN_COLOURS, animation_writer,
                                       new_figure)
from imrl_jax.config import Config


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
    ax.set_xlim(-2, size + 2)
    ax.set_ylim(-2, size + 2)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for spine in ax.spines.values():  # the wall is the frame (zoom_on_task shows them again)
        spine.set_visible(False)
    if tasks:
        for i, task in enumerate(config.tasks):
            (sx, sy), (tx, ty) = task.start, task.target
            ax.annotate("", xy=(tx, ty), xytext=(sx, sy), zorder=4,
                        arrowprops=dict(arrowstyle="-|>", color="black", lw=1.5))
            ax.text(sx, sy, str(i + 1), fontsize=9, ha="right", va="bottom", zorder=5,
                    bbox=dict(boxstyle="circle,pad=0.15", fc="white", ec="black", lw=0.5))


def draw_path(ax, pos: np.ndarray, k: np.ndarray, breaks: np.ndarray | None = None, lw: float = 1.6):
    """A path (T, 2) of poses after each step, the move into pos[t] coloured by the expert k[t].

    ``breaks[t]`` marks a step after which the robot was put back at the start (so
    pos[t] is the start): the jump pos[t-1] -> pos[t] is not drawn.
    """
    from matplotlib.collections import LineCollection

    pos, k = np.asarray(pos), np.asarray(k)
    keep = np.ones(len(pos) - 1, bool) if breaks is None else ~np.asarray(breaks)[1:]
    segs = np.stack([pos[:-1], pos[1:]], 1)[keep]
    colours = [EXPERT_COLOURS[int(e) % len(EXPERT_COLOURS)] for e in k[1:][keep]]
    ax.add_collection(LineCollection(segs, colors=colours, linewidths=lw, zorder=3, capstyle="round"))


def draw_task_ends(ax, config: Config, index: int) -> None:
    """Task ``index``'s start (a dot) and target (a circle of the target radius)."""
    from matplotlib.patches import Circle

    task = config.tasks[index]
    ax.plot(*task.start, "o", color="black", ms=4, zorder=5)
    ax.add_patch(Circle(task.target, config.target_radius, fc="none", ec="black", lw=1.2, zorder=5))


def expert_handles(names: list[str], ends: bool = False) -> list:
    """Legend handles naming the path colour of each expert, with the start and target if ``ends``."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=EXPERT_COLOURS[e % len(EXPERT_COLOURS)], lw=2, label=name)
               for e, name in enumerate(names)]
    if ends:
        handles += [Line2D([], [], ls="", marker="o", color="black", ms=4, label="start"),
                    Line2D([], [], ls="", marker="o", mfc="none", mec="black", ms=8, label="target")]
    return handles


def expert_legend(ax, num_experts: int, names: list[str] | None = None, ends: bool = False,
                  loc: str = "lower left") -> None:
    """A legend naming the path colour of each expert (``names``: one label each), with the start and target if ``ends``."""
    names = names or [f"expert {e + 1}" for e in range(num_experts)]
    ax.legend(handles=expert_handles(names, ends), loc=loc, fontsize=6.5, framealpha=0.9, handlelength=1.5)


def legend_experts(num_experts: int, expressed=None) -> list[int]:
    """The experts a path legend names: all, or those ``expressed`` (1 / 0 per expert) leaves in (the others never
    drive); the legend keeps their numbers, so a path's colour still tells its expert."""
    if expressed is None:
        return list(range(num_experts))
    return [e for e in range(num_experts) if e >= len(expressed) or expressed[e] > 0]


def zoom_on_task(ax, config: Config, index: int, margin: float = 70.0) -> None:
    """Limit an arena axis to a square around task ``index``'s start and target (at least ``margin`` cm around)."""
    task = config.tasks[index]
    (x0, y0), (x1, y1) = task.start, task.target
    half = max(abs(x1 - x0), abs(y1 - y0)) / 2 + margin
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    ax.set_xlim(cx - half, cx + half)
    ax.set_ylim(cy - half, cy + half)
    for spine in ax.spines.values():
        spine.set_visible(True)
        spine.set_color("0.6")


def plot_arena(config: Config, title: str = "arena and tasks"):
    """The arena with the six tasks (start dots, arrows to the targets), as in the paper's Fig. 1."""
    fig = new_figure(4.0, 4.1)
    ax = fig.add_subplot()
    draw_arena(ax, config, tasks=True)
    for task in config.tasks:
        ax.plot(*task.start, "o", color="black", ms=3, zorder=5)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_paths(config: Config, rows: list[dict], title: str = ""):
    """Paths coloured by the expert in control: one row per individual, a first panel, then one panel per task.

    Each row holds ``tasks``: one dict per task with ``pos`` (T, 2), ``k`` (T,), ``breaks``
    (T,) (True where the robot was put back at the start after that step) and an optional
    ``label``; optionally ``name`` (the row's heading), ``childhood`` (a dict like a task's,
    drawn in the first panel; without it the first panel shows the arena and the tasks) and
    ``experts`` (legend names of the experts). Task panels are zoomed on the task.
    """
    cols = 1 + config.num_tasks
    fig = new_figure(2.0 * cols + 1.3, 2.45 * len(rows) + (0.5 if title else 0.1))
    fig.set_layout_engine("constrained")
    subfigures = fig.subfigures(len(rows), 1, squeeze=False)[:, 0]
    for row, sub in zip(rows, subfigures):
        panels = sub.subplots(1, cols)
        first = panels[0]
        childhood = row.get("childhood")
        draw_arena(first, config, tasks=childhood is None)
        if childhood is not None:
            draw_path(first, childhood["pos"], childhood["k"], childhood.get("breaks"), lw=0.8)
            first.set_title(f"childhood, first {len(childhood['pos']):,} steps", fontsize=8)
        else:
            first.set_title("the arena and the six tasks", fontsize=8)
        num_experts = max([int(np.max(t["k"])) + 1 for t in row["tasks"]] + [config.num_lane_experts])
        experts = row.get("experts") or [f"expert {e + 1}" for e in range(num_experts)]
        for i, (ax, record) in enumerate(zip(panels[1:], row["tasks"])):
            draw_arena(ax, config)
            draw_path(ax, record["pos"], record["k"], record.get("breaks"))
            draw_task_ends(ax, config, i)
            zoom_on_task(ax, config, i)
            label = record.get("label", "")
            ax.set_title(f"task {i + 1}" + (f": {label}" if label else ""), fontsize=8)
        sub.legend(handles=expert_handles(experts, ends=True), loc="outside right center", fontsize=7,
                   frameon=False, handlelength=1.5)
        if row.get("name"):
            sub.suptitle(row["name"], fontsize=9, x=0.0, ha="left")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_life(config: Config, childhood: dict | None, tasks: list[dict], title: str = ""):
    """One individual: its first childhood steps (if any) and a path on each task (see :func:`plot_paths`)."""
    return plot_paths(config, [dict(childhood=childhood, tasks=tasks)], title)


def draw_floor_patches(ax, config: Config) -> None:
    """The floor lines as 6-cm-wide bands in data units (for zoomed views, where widths must scale)."""
    from matplotlib.collections import PolyCollection

    from matplotlib.colors import to_rgb

    # Opaque tints (not transparency), so the overlaps at the vertices do not show.
    tints = [tuple(0.4 + 0.6 * np.asarray(to_rgb(c))) for c in FLOOR_COLOURS]
    w = config.line_half_width
    polys, colours = [], []
    for p, q, c in floor_segments(config):
        d = (q - p) / np.linalg.norm(q - p)
        n = np.array([-d[1], d[0]]) * w
        polys.append([p + n, q + n, q - n, p - n])
        colours.append(tints[c])
    ax.add_collection(PolyCollection(polys, facecolors=colours, edgecolors="none", zorder=1))


def _robot_artists(ax, config: Config, zorder: int = 6, retina_points: bool = False):
    """Artists of the robot (disc, heading line, retina patch, optionally the 12 points); move with _place_robot."""
    from matplotlib.patches import Circle, Polygon

    body = Circle((0, 0), config.robot_radius, fc="white", ec="black", lw=1.0, alpha=0.85, zorder=zorder)
    ax.add_patch(body)
    (nose,) = ax.plot([], [], color="black", lw=1.0, zorder=zorder + 1)
    patch = Polygon(np.zeros((4, 2)), closed=True, fc="none", ec="black", lw=0.8, zorder=zorder + 1)
    ax.add_patch(patch)
    points = None
    if retina_points:
        points = ax.scatter(np.zeros(len(config.retina_lateral) * len(config.retina_forward)),
                            np.zeros(len(config.retina_lateral) * len(config.retina_forward)),
                            s=22, edgecolors="black", linewidths=0.5, zorder=zorder + 2)
    return body, nose, patch, points


def _retina_corners(config: Config, pos, heading) -> np.ndarray:
    """Corners of the retina patch (24 x 8 cm from the robot's front edge) in world coordinates."""
    lateral = np.asarray(config.retina_lateral)
    forward = np.asarray(config.retina_forward)
    half_gap = (lateral[1] - lateral[0]) / 2 if len(lateral) > 1 else 2.0
    row_gap = (forward[1] - forward[0]) / 2 if len(forward) > 1 else 2.0
    f0, f1 = forward.min() - row_gap, forward.max() + row_gap
    l0, l1 = lateral.min() - half_gap, lateral.max() + half_gap
    c, s = math.cos(heading), math.sin(heading)
    local = np.array([[f0, l0], [f1, l0], [f1, l1], [f0, l1]])
    return np.asarray(pos) + local[:, :1] * np.array([c, s]) + local[:, 1:] * np.array([-s, c])


def _place_robot(config: Config, artists, pos, heading, points_xy=None, colours=None) -> None:
    body, nose, patch, points = artists
    body.center = tuple(pos)
    r = config.robot_radius
    nose.set_data([pos[0], pos[0] + r * math.cos(heading)], [pos[1], pos[1] + r * math.sin(heading)])
    patch.set_xy(_retina_corners(config, pos, heading))
    if points is not None and points_xy is not None:
        points.set_offsets(np.asarray(points_xy).reshape(-1, 2))
        points.set_facecolors([SEEN_COLOURS[c] for c in np.asarray(colours).reshape(-1)])


def draw_retina_grid(ax, config: Config, colours) -> object:
    """What the retina sees: the forward rows x lateral points, as the robot looks (its left on the left).

    ``colours`` (rows, lateral) holds RED 0, GREEN 1, BLUE 2 or NONE -1. Returns the image artist.
    """
    from matplotlib.colors import ListedColormap

    grid = _grid_image(colours)
    image = ax.imshow(grid, cmap=ListedColormap([NOTHING_COLOUR, *FLOOR_COLOURS]), vmin=-0.5, vmax=3.5,
                      origin="upper", aspect="equal")
    lateral, forward = np.asarray(config.retina_lateral), np.asarray(config.retina_forward)
    ax.set_xticks(range(len(lateral)), [f"{v:+g}" for v in lateral[::-1]], fontsize=7)
    ax.set_yticks(range(len(forward)), [f"{v:g}" for v in forward[::-1]], fontsize=7)
    ax.set_xlabel("lateral offset (cm, + = robot's left)", fontsize=8)
    ax.set_ylabel("ahead (cm)", fontsize=8)
    ax.set_xticks(np.arange(len(lateral) + 1) - 0.5, minor=True)
    ax.set_yticks(np.arange(len(forward) + 1) - 0.5, minor=True)
    ax.grid(which="minor", color="white", lw=2)
    ax.tick_params(which="minor", length=0)
    return image


def _grid_image(colours) -> np.ndarray:
    """(rows, lateral) colours as the image the robot sees: far row on top, its left on the left."""
    return (np.asarray(colours)[::-1, ::-1] + 1).astype(float)


def plot_retina_view(config: Config, pos, heading, title: str = "", zoom: float = 50.0):
    """A pose and what its retina sees: the robot on the floor (zoomed) and the 2 x 6 receptor grid.

    ``pos`` (x, y) in cm, ``heading`` in radians.
    """
    from imrl_jax.analysis.behaviour import retina_colours, retina_points

    colours = retina_colours(config, pos, heading)
    points = retina_points(config, pos, heading)
    fig = new_figure(7.2, 3.3)
    ax = fig.add_subplot(1, 2, 1)
    draw_floor_patches(ax, config)
    size = config.arena_size
    ax.plot([0, size, size, 0, 0], [0, 0, size, size, 0], color="black", lw=1.5, zorder=2)
    artists = _robot_artists(ax, config, retina_points=True)
    _place_robot(config, artists, np.asarray(pos, float), float(heading), points, colours)
    ax.set_xlim(pos[0] - zoom, pos[0] + zoom)
    ax.set_ylim(pos[1] - zoom, pos[1] + zoom)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)
    ax.set_title(f"pose ({pos[0]:.0f}, {pos[1]:.0f}) cm, heading {math.degrees(heading) % 360:.0f} deg",
                 fontsize=9)
    grid_ax = fig.add_subplot(1, 2, 2)
    draw_retina_grid(grid_ax, config, colours)
    counts = [int((colours == c).sum()) for c in (0, 1, 2)]
    grid_ax.set_title(f"what the retina sees (R {counts[0]}, G {counts[1]}, B {counts[2]} of {colours.size})",
                      fontsize=9)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def write_animation(config: Config, trajectory, path: str, task: int | None = None, every: int = 1,
                    fps: int = 20, title: str = "", dpi: int = 80, expressed=None) -> int:
    """Animate a :class:`~imrl_jax.analysis.behaviour.Trajectory`: the arena with the path coloured by the expert
    in control, the robot with its retina patch, a zoom on the robot and the retina's 2 x 6 view.

    ``task`` (0-based) marks that task's start and target. Frame t shows the pose at which
    step t's expert was chosen and the path before it; one frame every ``every`` steps.
    ``expressed`` (an evolved number of experts: 1 / 0 per expert) leaves unexpressed experts out of the legend.
    ``.gif`` is written with Pillow, ``.mp4`` with ffmpeg (which must be on PATH).
    Returns the number of frames.
    """
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    from imrl_jax.analysis.behaviour import retina_colours, retina_points

    writer = animation_writer(path, fps)
    seen_pos = np.asarray(trajectory.seen_pos, float)
    seen_heading = np.asarray(trajectory.seen_heading, float)
    pos, k = np.asarray(trajectory.pos, float), np.asarray(trajectory.k)
    breaks, reached = np.asarray(trajectory.breaks), np.asarray(trajectory.reached)
    num_steps = len(k)
    frames = list(range(0, num_steps, every))
    colours = retina_colours(config, seen_pos, seen_heading)  # (T, rows, lateral)
    all_points = retina_points(config, seen_pos, seen_heading)  # (T, rows, lateral, 2)
    num_experts = max(int(k.max()) + 1, config.num_lane_experts)

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = new_figure(8.0, 4.6)
    FigureCanvasAgg(fig)  # draw every frame with Agg directly (no canvas switch per frame)
    # A fixed layout (no layout engine), so each frame is drawn once.
    spec = fig.add_gridspec(2, 2, width_ratios=[1.15, 1.0], height_ratios=[1.45, 1.0], left=0.02, right=0.97,
                            bottom=0.11, top=0.86, wspace=0.12, hspace=0.32)
    ax = fig.add_subplot(spec[:, 0])
    draw_arena(ax, config)
    if task is not None:
        from matplotlib.patches import Circle

        spec_task = config.tasks[task]
        ax.plot(*spec_task.start, "o", color="black", ms=4, zorder=5)
        ax.add_patch(Circle(spec_task.target, config.target_radius, fc="none", ec="black", lw=1.2, zorder=5))
    path_lines = LineCollection([], linewidths=1.3, zorder=3)
    ax.add_collection(path_lines)
    robot = _robot_artists(ax, config, zorder=6)
    handles = [Line2D([], [], color=EXPERT_COLOURS[e % len(EXPERT_COLOURS)], lw=2, label=f"expert {e + 1}")
               for e in legend_experts(num_experts, None if expressed is None else np.asarray(expressed))]
    ax.legend(handles=handles, loc="lower left", fontsize=7, framealpha=0.9)

    zoom_ax = fig.add_subplot(spec[0, 1])
    draw_floor_patches(zoom_ax, config)
    size = config.arena_size
    zoom_ax.plot([0, size, size, 0, 0], [0, 0, size, size, 0], color="black", lw=1.5, zorder=2)
    zoom_ax.set_aspect("equal")
    zoom_ax.set_xticks([])
    zoom_ax.set_yticks([])
    zoom_path = LineCollection([], linewidths=2.0, zorder=3)
    zoom_ax.add_collection(zoom_path)
    zoom_robot = _robot_artists(zoom_ax, config, zorder=6, retina_points=True)
    grid_ax = fig.add_subplot(spec[1, 1])
    image = draw_retina_grid(grid_ax, config, colours[0])
    fig.suptitle(title, fontsize=9, y=0.985, va="top")

    segments = np.stack([seen_pos, pos], 1)  # step t moves from seen_pos[t] to pos[t]
    segment_colours = np.array([EXPERT_COLOURS[int(e) % len(EXPERT_COLOURS)] for e in k])
    zoom = 45.0
    with writer.saving(fig, path, dpi):
        for t in frames:
            keep = ~breaks[:t]
            segs, cols = segments[:t][keep], segment_colours[:t][keep]
            for lines in (path_lines, zoom_path):
                lines.set_segments(segs)
                lines.set_colors(cols)
            p, h = seen_pos[t], seen_heading[t]
            points = all_points[t]
            _place_robot(config, robot, p, h)
            _place_robot(config, zoom_robot, p, h, points, colours[t])
            zoom_ax.set_xlim(p[0] - zoom, p[0] + zoom)
            zoom_ax.set_ylim(p[1] - zoom, p[1] + zoom)
            expert = int(k[t])
            zoom_ax.set_title(f"step {t}: expert {expert + 1} in control", fontsize=9,
                              color=EXPERT_COLOURS[expert % len(EXPERT_COLOURS)])
            image.set_data(_grid_image(colours[t]))
            grid_ax.set_title(f"retina view; reaches so far: {int(reached[:t].sum())}", fontsize=9)
            writer.grab_frame()
    return len(frames)
