"""Task sets (section 2's six tasks, and tasks never met in evolution): named lists of tasks, loaded and checked.

A task set is a tuple of :class:`~imrl_jax.config.Task` (start vertex and heading, target
vertex), the config's ``tasks`` field. :data:`TASK_SETS` names the built-in ones: ``paper``,
the six of MODEL.md (the default everywhere), and ``novel``, six tasks unlike them (other
starts and targets, zigzags of 5 and 6 edges against the six's 2 to 4; in pairs that start on
the same colour and turn the other way at the first junction, as the six do). A set can also
be a JSON file::

    {"name": "mine", "tasks": [{"start": [200, 200], "heading_deg": 0, "target": [360, 269.282]}, ...]}

:func:`load` reads either and :func:`check` validates every task: its start lies on a line and
its heading runs along one, its target is on the floor, and a zigzag route along the lines
(turning alternately left and right by 60 deg, at most ``MAX_ROUTE`` edges, as the
six) leads from the start to the target. A task's theoretical maximum is computed as for the
six: trips along the straight line from start to target at full speed (``Config.steps_per_trip``).
"""

from __future__ import annotations

import json
import math
import os

from imrl_jax import files
from imrl_jax.config import _S, Config, ConfigError, Task, paper_tasks  # _S: vertices lie at y = 200 + k _S


def novel_tasks() -> tuple[Task, ...]:
    """Six tasks never met in evolution: 5- and 6-edge zigzags, pairs by first colour (red, green, blue)."""
    s = _S
    return (
        Task((200.0, 200.0), 0.0, (360.0, 200.0 + 2 * s)),  # red first, left first, 5 edges (red-green)
        Task((140.0, 200.0 + s), 0.0, (320.0, 200.0 - 2 * s)),  # red first, right first, 6 edges (red-blue)
        Task((200.0, 200.0 + 2 * s), 240.0, (200.0, 200.0 - 4 * s)),  # green, left, 6 edges (green-blue)
        Task((60.0, 200.0 - 3 * s), 60.0, (200.0, 200.0)),  # green, right, 5 edges (green-red)
        Task((120.0, 200.0 + 2 * s), 300.0, (260.0, 200.0 - s)),  # blue, left, 5 edges (blue-red)
        Task((200.0, 200.0 - 2 * s), 120.0, (200.0, 200.0 + 4 * s)),  # blue, right, 6 edges (blue-green)
    )


#: The built-in task sets, by the name ``--task-set`` takes.
TASK_SETS = {"paper": paper_tasks, "novel": novel_tasks}


def _fail(source: str, index: int | None, field: str, message: str) -> ConfigError:
    where = f"{source} task {index + 1}" if index is not None else source
    return ConfigError(f"--task-set: {where}: {field}: {message}")


def _point(source: str, index: int, field: str, value) -> tuple[float, float]:
    if (not isinstance(value, (list, tuple)) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
        raise _fail(source, index, field, f"expected [x, y] in cm, got {value!r}")
    return float(value[0]), float(value[1])


def from_json(text: str, source: str) -> tuple[Task, ...]:
    """The tasks of a task-set file's text (raises ConfigError naming the file, the task and the field)."""
    try:
        data = json.loads(text)
    except RecursionError:
        raise _fail(source, None, "file", "not JSON (nested too deeply)") from None
    except ValueError as error:  # a JSONDecodeError, or a number of more digits than int() takes (no .msg)
        where = f"{error.msg}, line {error.lineno}" if isinstance(error, json.JSONDecodeError) else \
            str(error).split(";")[0]
        raise _fail(source, None, "file", f"not JSON ({where})") from None
    if not isinstance(data, dict) or not isinstance(data.get("tasks"), list) or not data["tasks"]:
        raise _fail(source, None, "tasks", "expected an object with a non-empty list \"tasks\"")
    tasks = []
    for i, entry in enumerate(data["tasks"]):
        if not isinstance(entry, dict):
            raise _fail(source, i, "task", f"expected an object, got {entry!r}")
        unknown = sorted(set(entry) - {"start", "heading_deg", "target"})
        if unknown:
            raise _fail(source, i, unknown[0], "unknown field (a task has start, heading_deg, target)")
        for field in ("start", "heading_deg", "target"):
            if field not in entry:
                raise _fail(source, i, field, "missing")
        heading = entry["heading_deg"]
        if not isinstance(heading, (int, float)) or isinstance(heading, bool) or not math.isfinite(heading):
            raise _fail(source, i, "heading_deg", f"expected a number of degrees, got {heading!r}")
        tasks.append(Task(_point(source, i, "start", entry["start"]), float(heading),
                          _point(source, i, "target", entry["target"])))
    return tuple(tasks)


#: Longest route of any task, in edges (routes are padded to it).
MAX_ROUTE = 8


def edge_colour(heading_deg: float) -> int:
    """Colour of an edge by its direction: 0 deg red, 60 deg green, 120 deg blue (mod 180)."""
    from imrl_jax.world.arena import BLUE, GREEN, RED  # the arena imports JAX; reading a task set does not

    direction = round(heading_deg / 60.0) % 3
    return (RED, GREEN, BLUE)[direction]


def zigzag_route(config: Config, task: Task) -> tuple[tuple[int, ...], str]:
    """The colours of the edges from a task's start to its target, and the first turn.

    Walks the zigzag of MODEL.md from the start vertex along the start heading, turning
    alternately left and right by 60 deg, for every first turn and up to ``MAX_ROUTE``
    edges, and returns the shortest walk that ends on the target.
    """
    a = config.edge_length
    for edges in range(1, MAX_ROUTE + 1):
        for first in ("L", "R"):
            x, y = task.start
            heading = task.heading_deg
            colours = []
            sign = 1.0 if first == "L" else -1.0
            for i in range(edges):
                if i:
                    heading += sign * 60.0
                    sign = -sign
                colours.append(edge_colour(heading))
                x += a * math.cos(math.radians(heading))
                y += a * math.sin(math.radians(heading))
            if math.dist((x, y), task.target) < 1e-6 * a:
                return tuple(colours), first
    raise ValueError(f"task {task} is not a zigzag of at most {MAX_ROUTE} edges")


def check(config: Config, tasks, source: str = "task set") -> tuple[Task, ...]:
    """``tasks`` if every one can be driven along the lines (raises ConfigError naming the task and field)."""
    import jax.numpy as jnp

    from imrl_jax.world.arena import NONE, floor_colour

    tasks = tuple(tasks)
    if not tasks:
        raise _fail(source, None, "tasks", "needs at least one task")
    size, a = config.arena_size, config.edge_length
    for i, task in enumerate(tasks):
        for field, (x, y) in (("start", task.start), ("target", task.target)):
            if not (0.0 <= x <= size and 0.0 <= y <= size):
                raise _fail(source, i, field, f"({x:g}, {y:g}) is off the floor (0 to {size:g} cm)")
        if int(floor_colour(config, jnp.asarray(task.start, jnp.float32))) == NONE:
            raise _fail(source, i, "start", f"({task.start[0]:g}, {task.start[1]:g}) is not on a line")
        ahead = (task.start[0] + a / 2 * math.cos(math.radians(task.heading_deg)),
                 task.start[1] + a / 2 * math.sin(math.radians(task.heading_deg)))
        if int(floor_colour(config, jnp.asarray(ahead, jnp.float32))) != edge_colour(task.heading_deg):
            raise _fail(source, i, "heading_deg", f"{task.heading_deg:g} deg does not run along a line from the start")
        try:
            zigzag_route(config, task)
        except ValueError:
            raise _fail(source, i, "target", f"no zigzag route of at most {MAX_ROUTE} edges along the lines leads "
                                             f"from the start to ({task.target[0]:g}, {task.target[1]:g})") from None
        if math.dist(task.start, task.target) <= config.target_radius:
            raise _fail(source, i, "target", "lies within the target radius of the start")
    return tasks


def load(spec: str, config: Config | None = None) -> tuple[Task, ...]:
    """A task set by name (:data:`TASK_SETS`) or from a JSON file, checked (raises ConfigError naming what is wrong)."""
    config = Config() if config is None else config
    return check(config, read(spec), spec)


#: The largest task-set file read (a task is about 80 bytes: thousands of tasks fit).
MAX_FILE_BYTES = 2**20


def read(spec: str) -> tuple[Task, ...]:
    """The tasks of a set by name or file (UTF-8 JSON, :data:`MAX_FILE_BYTES` at most), not yet checked on a floor."""
    if spec in TASK_SETS:
        return TASK_SETS[spec]()
    if not spec.endswith(".json") and not os.path.exists(spec):
        raise ConfigError(f"--task-set: unknown task set {spec!r} (choose from {', '.join(TASK_SETS)}, or give a "
                          f".json file)")
    return from_json(files.read_text(spec, "--task-set", MAX_FILE_BYTES, ConfigError), spec)


def to_json(tasks, name: str) -> str:
    """A task set as the JSON :func:`load` reads."""
    return json.dumps({"name": name, "tasks": [{"start": list(t.start), "heading_deg": t.heading_deg,
                                                "target": list(t.target)} for t in tasks]}, indent=2)
