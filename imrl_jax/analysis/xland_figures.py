"""Pictures of a life in XLand-MiniGrid's room (docs/WORLDS.md, "Seeing a life"), the arena's
:mod:`imrl_jax.analysis.arena_figures` for the second world: the room as the world's state has it at each step
(the corridors' colours, the door closed or open, the key or the floor it was picked from, the walls), the agent as a
triangle pointing its way and filled with the colour of the expert in control, its path coloured by the expert
that made each move, what it sees (the 3 x 3 view its 55 inputs encode) and the expert in control at every step.

:func:`task_life` records a life with :func:`imrl_jax.agent.lifetime.simulate`; :func:`write_life` draws it as a
still (``.png``: every step's path, the last state) or an animation (``.gif``, ``.mp4``), with the signature of
``arena_figures.write_animation``, so that ``python -m imrl_jax.render`` calls either alike.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from imrl_jax.agent.lifetime import simulate
from imrl_jax.agent.state import init_state
from imrl_jax.analysis.arena_figures import legend_experts
from imrl_jax.analysis.plotting import EXPERT_COLOURS, FLOOR_COLOURS, animation_writer, new_figure
from imrl_jax.world.worlds import world_of

#: The still's format; the others are animations.
STILL = ".png"
#: Pixels a cell of the room is drawn with (a door's frame and a key's shape need a few).
CELL_PX = 12
#: xminigrid's tile and colour ids (xminigrid.core.constants; the numbers, so that drawing needs no import of it).
EMPTY, FLOOR, WALL, KEY, DOOR_LOCKED, DOOR_CLOSED, DOOR_OPEN = 0, 1, 2, 7, 8, 9, 10
RED, GREEN, BLUE, YELLOW = 1, 2, 3, 5
#: xminigrid's directions (0 up, 1 right, 2 down, 3 left) as (x, y) on a picture whose rows run down.
AHEAD = np.array([(0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)])


def _rgb(hex_colour: str, pale: float = 0.0) -> np.ndarray:
    """A colour as three floats, mixed with white by ``pale``."""
    rgb = np.array([int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0
    return rgb + (1.0 - rgb) * pale


#: A coloured floor cell: the arena's line colours, pale so that the paths drawn over them show.
FLOOR_RGB = {colour: _rgb(FLOOR_COLOURS[i], 0.55) for i, colour in enumerate((RED, GREEN, BLUE))}
PLAIN_RGB, WALL_RGB, OUTSIDE_RGB = _rgb("#f7f7f7"), _rgb("#5a5a5a"), _rgb("#2b2b2b")
DOOR_RGB = {colour: _rgb(FLOOR_COLOURS[i]) for i, colour in enumerate((RED, GREEN, BLUE))}
KEY_RGB, FRAME_RGB = _rgb("#e6b800"), _rgb("#202020")


class GridLife(NamedTuple):
    """A recorded life in a grid world: ``T`` steps, ``T + 1`` states (before each step, and after the last)."""

    grid: np.ndarray  # (T + 1, rows, cols, 2): (tile, colour) of every cell
    position: np.ndarray  # (T + 1, 2): (row, column)
    direction: np.ndarray  # (T + 1,): 0 up, 1 right, 2 down, 3 left
    pocket: np.ndarray  # (T + 1, 2): the tile held (EMPTY, EMPTY: nothing)
    view: np.ndarray  # (T + 1, view, view, 2): what the agent sees, facing up, itself at the bottom's middle
    k: np.ndarray  # (T,): the expert in control of each step
    reached: np.ndarray  # (T,)
    timeout: np.ndarray  # (T,)
    respawned: np.ndarray  # (T,)

    @property
    def breaks(self) -> np.ndarray:
        """(T,) True where the agent was put elsewhere after the step (the task's start, or a random cell)."""
        return self.reached | self.timeout | self.respawned

    def moves(self, steps: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The path of the first ``steps`` steps: (moves, 2, 2) segments from one cell's centre to the next as
        (x, y) = (column, row), a restart's jump left out; and the expert that made each."""
        steps = len(self.k) if steps is None else steps
        xy = self.position[:, ::-1].astype(float)
        keep = ~self.breaks[:steps]
        return np.stack([xy[:steps], xy[1:steps + 1]], 1)[keep], self.k[:steps][keep]


@functools.partial(jax.jit, static_argnums=(1, 5))
def _task(key, config, params, agent, index, num_steps):
    world = world_of(config)
    task = world.task(config, index, agent.actor.dtype)
    start = world.make_env(config).reset(None, task, agent.actor.dtype)
    _, record = simulate(key, config, config.spec.adult, params, task, init_state(config, agent, start), num_steps,
                         config.task_steps)
    states = jax.tree.map(lambda first, rest: jnp.concatenate([first[None], rest]), start, record.world)
    return states, record


def _views(settings, states) -> np.ndarray:
    """(T + 1, view, view, 2) what the agent sees in each state (xminigrid's view, the one its inputs encode)."""
    from xminigrid.core.observation import transparent_field_of_view
    from xminigrid.types import AgentState

    def view(grid, position, direction, pocket):
        agent = AgentState(position=position.astype(int), direction=direction.astype(int), pocket=pocket)
        return transparent_field_of_view(grid, agent, settings.view_size, settings.view_size)

    return np.asarray(jax.jit(jax.vmap(view))(states.grid, states.position, states.direction, states.pocket))


def task_life(key: jax.Array, config, params, agent, task: int, num_steps: int) -> GridLife:
    """``num_steps`` steps of task ``task`` (0-based) from ``agent`` (e.g. a task's final weights, its selector as it
    ended the task), from the task's start, as in adulthood (``behaviour.task_trajectory``'s for the arena)."""
    states, record = _task(key, config, params, agent, jnp.int32(task), num_steps)
    return GridLife(*(np.asarray(x) for x in (states.grid, states.position, states.direction, states.pocket)),
                    _views(world_of(config).settings, states),
                    *(np.asarray(x) for x in (record.k, record.reached, record.timeout, record.respawned)))


def room_pixels(grid: np.ndarray, px: int = CELL_PX) -> np.ndarray:
    """(rows * px, cols * px, 3) a picture of a grid of (tile, colour): floors in their colour (pale), walls grey, a
    closed door a framed cell of its colour with a handle, an open one only its frame, a key a yellow ring and bit;
    outside the room (EMPTY) dark."""
    grid = np.asarray(grid)
    rows, cols = grid.shape[:2]
    image = np.empty((rows, cols, px, px, 3))
    tile, colour = grid[..., 0], grid[..., 1]
    image[:] = PLAIN_RGB
    for c, rgb in FLOOR_RGB.items():
        image[(tile == FLOOR) & (colour == c)] = rgb
    image[tile == WALL] = WALL_RGB
    image[tile == EMPTY] = OUTSIDE_RGB
    y, x = np.mgrid[0:px, 0:px] + 0.5
    frame = (np.minimum(np.minimum(x, px - x), np.minimum(y, px - y)) < px / 6)
    for r, c in zip(*np.nonzero((tile == DOOR_CLOSED) | (tile == DOOR_LOCKED) | (tile == DOOR_OPEN))):
        door = DOOR_RGB.get(int(colour[r, c]), WALL_RGB)
        if tile[r, c] == DOOR_OPEN:
            image[r, c] = FLOOR_RGB.get(int(colour[r, c]), PLAIN_RGB)
            image[r, c][frame] = door
        else:
            image[r, c] = door
            image[r, c][frame] = FRAME_RGB
            image[r, c][(np.abs(x - 0.7 * px) < px / 10) & (np.abs(y - px / 2) < px / 10)] = FRAME_RGB
    ring = np.abs(np.hypot(x - 0.33 * px, y - px / 2) - px / 5) < px / 12
    bit = (x > 0.45 * px) & (x < 0.85 * px) & (np.abs(y - px / 2) < px / 12)
    tooth = (x > 0.7 * px) & (x < 0.8 * px) & (y > px / 2) & (y < 0.72 * px)
    for r, c in zip(*np.nonzero(tile == KEY)):
        image[r, c][ring | bit | tooth] = KEY_RGB
    return image.transpose(0, 2, 1, 3, 4).reshape(rows * px, cols * px, 3)


def agent_triangle(position, direction, size: float = 0.38) -> np.ndarray:
    """(3, 2) the corners (x, y) of a triangle on cell ``position`` (row, column) pointing ``direction``."""
    centre, ahead = np.array([position[1], position[0]], float), AHEAD[int(direction)]
    side = np.array([-ahead[1], ahead[0]])
    return np.stack([centre + size * ahead, centre - 0.75 * size * ahead + 0.8 * size * side,
                     centre - 0.75 * size * ahead - 0.8 * size * side])


def _cell_lines(ax, rows: int, cols: int) -> None:
    """Thin lines between the cells."""
    ax.vlines(np.arange(cols + 1) - 0.5, -0.5, rows - 0.5, colors="white", lw=0.4, alpha=0.5, zorder=1)
    ax.hlines(np.arange(rows + 1) - 0.5, -0.5, cols - 0.5, colors="white", lw=0.4, alpha=0.5, zorder=1)


def _crop(ax, grid: np.ndarray) -> None:
    """Limit the axis to the cells that are not wall, and one wall round them."""
    rows, cols = np.nonzero(np.asarray(grid)[..., 0] != WALL)
    if len(rows):
        ax.set_xlim(cols.min() - 1.5, cols.max() + 1.5)
        ax.set_ylim(rows.max() + 1.5, rows.min() - 1.5)


def _expert_colour(k) -> str:
    return EXPERT_COLOURS[int(k) % len(EXPERT_COLOURS)]


def _goal(world, task: int):
    """Task ``task``'s start (row, column) and goal: ``("on", cell)`` or ``("hold", tile)``."""
    from imrl_jax.world.xland import tasks

    spec = tasks(world.settings)[task]
    return spec.start, spec.goal


class _Picture(NamedTuple):
    """A figure's artists that a step changes."""

    fig: object
    room: object
    path: object
    agent: object
    view: object
    view_agent: object
    cursor: object
    room_ax: object
    view_ax: object
    num_experts: int


def _picture(config, life: GridLife, task: int | None, title: str, expressed) -> _Picture:
    """The figure of a life, drawn at its start: the room, the task's ends, the path, the agent, its view and the
    experts' strip."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Polygon

    rows, cols = life.grid.shape[1:3]
    fig = new_figure(8.0, 5.0)
    FigureCanvasAgg(fig)
    # A fixed layout (no layout engine), so each frame is drawn once.
    spec = fig.add_gridspec(3, 2, width_ratios=[1.6, 1.0], height_ratios=[0.62, 0.38, 0.12], left=0.03, right=0.97,
                            bottom=0.08, top=0.87, wspace=0.08, hspace=0.3)
    room_ax, view_ax = fig.add_subplot(spec[:2, 0]), fig.add_subplot(spec[0, 1])
    legend_ax, strip_ax = fig.add_subplot(spec[1, 1]), fig.add_subplot(spec[2, :])
    room = room_ax.imshow(room_pixels(life.grid[0]), extent=(-0.5, cols - 0.5, rows - 0.5, -0.5),
                          interpolation="nearest", zorder=0)
    _cell_lines(room_ax, rows, cols)
    _crop(room_ax, life.grid[0])
    handles = []
    if task is not None:
        start, (kind, what) = _goal(world_of(config), task)
        room_ax.plot(start[1], start[0], "o", mfc="none", mec="black", ms=15, mew=1.5, zorder=4)
        handles.append(Line2D([], [], ls="", marker="o", mfc="none", mec="black", ms=8, label="the task's start"))
        if kind == "on":
            room_ax.plot(what[1], what[0], "*", color="black", ms=14, zorder=4)
            handles.append(Line2D([], [], ls="", marker="*", color="black", ms=9, label="its goal: stand here"))
        else:
            handles.append(Line2D([], [], ls="", marker="s", mfc=KEY_RGB, mec="none", ms=8,
                                  label="its goal: hold the key"))
    path = LineCollection([], linewidths=2.4, alpha=0.8, zorder=2, capstyle="round")
    room_ax.add_collection(path)
    agent = Polygon(agent_triangle(life.position[0], life.direction[0]), closed=True, ec="white", lw=1.2, zorder=5)
    room_ax.add_patch(agent)
    num_experts = max(int(life.k.max()) + 1 if len(life.k) else 1, config.num_experts)
    handles = [Line2D([], [], color=_expert_colour(e), lw=2.4, label=f"expert {e + 1}")
               for e in legend_experts(num_experts, None if expressed is None else np.asarray(expressed))] + handles
    legend_ax.axis("off")
    legend_ax.legend(handles=handles, loc="center", fontsize=7.5, frameon=False,
                     title="path and agent: the expert in control", title_fontsize=7.5)
    size = life.view.shape[1]
    view = view_ax.imshow(room_pixels(life.view[0]), extent=(-0.5, size - 0.5, size - 0.5, -0.5),
                          interpolation="nearest")
    view_agent = Polygon(agent_triangle((size - 1, size // 2), 0), closed=True, ec="white", lw=1.2, zorder=5)
    view_ax.add_patch(view_agent)
    strip = np.array([_rgb(_expert_colour(k)) for k in life.k]).reshape(1, -1, 3)
    strip_ax.imshow(strip, aspect="auto", extent=(0, len(life.k), 1, 0), interpolation="nearest")
    for events, colour, label in ((life.reached, "black", "reach"), (life.timeout | life.respawned, "0.55", "restart")):
        steps = np.nonzero(events)[0] + 0.5
        strip_ax.plot(steps, np.full(len(steps), -0.35), "v", color=colour, ms=4, clip_on=False, label=label)
    strip_ax.set_ylim(1, -0.7)
    strip_ax.set_yticks([])
    strip_ax.tick_params(labelsize=7)
    strip_ax.set_xlabel("step (the colour of the expert in control; triangles above: reaches, timeouts)", fontsize=8)
    cursor = strip_ax.axvline(0, color="black", lw=1.2)
    _cell_lines(view_ax, size, size)
    for ax in (room_ax, view_ax):
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(title, fontsize=9, y=0.985, va="top")
    return _Picture(fig, room, path, agent, view, view_agent, cursor, room_ax, view_ax, num_experts)


def _show(picture: _Picture, life: GridLife, t: int) -> None:
    """The picture before step ``t`` (``t = T``: after the last): the room and agent then, the path of the steps
    before it, the expert that drives step ``t`` (the last step's at the end)."""
    segments, experts = life.moves(t)
    # Every trial walks the same cells: the lower an expert's number, the wider its line and the earlier it is
    # drawn, so that the experts that moved between two cells all show, as nested stripes.
    order = np.argsort(experts, kind="stable")
    picture.path.set_segments(segments[order])
    picture.path.set_colors([_expert_colour(k) for k in experts[order]])
    picture.path.set_linewidths(2.0 + 2.2 * (picture.num_experts - 1 - experts[order]))
    picture.room.set_data(room_pixels(life.grid[t]))
    picture.view.set_data(room_pixels(life.view[t]))
    expert = int(life.k[min(t, len(life.k) - 1)])
    for triangle in (picture.agent, picture.view_agent):
        triangle.set_facecolor(_expert_colour(expert))
    picture.agent.set_xy(agent_triangle(life.position[t], life.direction[t]))
    picture.cursor.set_xdata([t, t])
    held = " (holding the key)" if life.pocket[t][0] == KEY else ""
    when = f"after step {t - 1}" if t == len(life.k) else f"step {t}"
    picture.room_ax.set_title(f"{when}: expert {expert + 1} in control{held}; reaches so far: "
                              f"{int(life.reached[:t].sum())}", fontsize=9, color=_expert_colour(expert))
    picture.view_ax.set_title("what it sees (its inputs)", fontsize=9)


def plot_life(config, life: GridLife, task: int | None = None, t: int | None = None, title: str = "",
              expressed=None):
    """The figure of ``life`` before step ``t`` (None: after the last step, the whole path): the room as the state
    has it then, the agent, the path so far coloured by expert, what the agent sees and the experts' strip."""
    picture = _picture(config, life, task, title, expressed)
    _show(picture, life, len(life.k) if t is None else t)
    return picture.fig


def write_life(config, life: GridLife, path: str, task: int | None = None, every: int = 1, fps: int = 20,
               title: str = "", dpi: int = 80, expressed=None) -> int:
    """Draw a :class:`GridLife` into ``path``: ``.png`` a still of every step's path and the last state; ``.gif``
    (Pillow) or ``.mp4`` (ffmpeg on PATH) an animation, one frame every ``every`` steps. ``task`` (0-based) marks that
    task's start and goal; ``expressed`` (1 / 0 per expert) leaves unexpressed experts out of the legend. Returns
    the number of frames (1 for a still)."""
    if "." + path.rsplit(".", 1)[-1].lower() == STILL:
        plot_life(config, life, task, None, title, expressed).savefig(path, dpi=dpi, format="png")
        return 1
    writer = animation_writer(path, fps, stills=(STILL,))
    picture = _picture(config, life, task, title, expressed)
    frames = list(range(0, len(life.k), every))
    with writer.saving(picture.fig, path, dpi):
        for t in frames:
            _show(picture, life, t)
            writer.grab_frame()
    return len(frames)
