"""Floor, retina, kinematics and task table against values computed by hand from MODEL.md.

Every expected number here comes from the geometry of MODEL.md ("Arena and floor",
"Robot", "Retina", the task table), worked out on paper, never from the code under test.
Notation: s = 20*sqrt(3) = 34.641 cm, the half-spacing of parallel lines; the hexagon
centred at (160, 200) has vertices (200, 200), (180, 200+s), (140, 200+s), (120, 200),
(140, 200-s), (180, 200-s); (200, 200) joins a red edge to (240, 200), a blue one to
(180, 200+s) and a green one to (180, 200-s). Red edges on the line y = 200 are
[200, 240], [320, 360], [80, 120], [-40, 0]; on y = 200+s they are [140, 180], [260, 300],
[20, 60], [380, 420].
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from imrl_jax.world.arena import BLUE, GREEN, NONE, RED, Pose, advance, floor_colour, move, on_wall, spawn_pose, trial_ends
from imrl_jax.config import Config, ConfigError
from imrl_jax.world.retina import observe, sample_points

S = 20.0 * math.sqrt(3.0)
R3 = math.sqrt(3.0)


@pytest.fixture(scope="module")
def config():
    return Config()


_floor_colour = jax.jit(floor_colour, static_argnums=0)


def colours_at(config, points):
    return np.asarray(_floor_colour(config, jnp.asarray(points, jnp.float32)))


def offset(point, direction_deg, distance):
    """point + distance * (cos, sin)(direction): plain float maths."""
    a = math.radians(direction_deg)
    return (point[0] + distance * math.cos(a), point[1] + distance * math.sin(a))


# ---------------------------------------------------------------------------- floor colour

# (point, expected colour, why)
FLOOR_CASES = [
    # edge midpoints of each colour
    ((220.0, 200.0), RED, "midpoint of red edge (200,200)-(240,200)"),
    ((190.0, 200.0 - S / 2), GREEN, "midpoint of green edge (180,200-s)-(200,200)"),
    ((190.0, 200.0 + S / 2), BLUE, "midpoint of blue edge (200,200)-(180,200+s)"),
    ((160.0, 200.0 + S), RED, "midpoint of red edge (140,200+s)-(180,200+s)"),
    ((130.0, 200.0 + S / 2), GREEN, "midpoint of green edge (120,200)-(140,200+s)"),
    ((130.0, 200.0 - S / 2), BLUE, "midpoint of blue edge (120,200)-(140,200-s)"),
    ((250.0, 200.0 + S / 2), GREEN, "midpoint of green edge (240,200)-(260,200+s)"),
    # vertices: every vertex joins the three colours, an exact tie goes to red
    ((200.0, 200.0), RED, "vertex joining red, green, blue (left end of a red edge)"),
    ((240.0, 200.0), RED, "vertex joining red, green, blue (right end of a red edge)"),
    ((180.0, 200.0 + S), RED, "vertex (180, 200+s)"),
    # 2.9 cm / 3.1 cm off a red line, both sides
    ((220.0, 202.9), RED, "2.9 cm above the red line"),
    ((220.0, 203.1), NONE, "3.1 cm above the red line"),
    ((220.0, 197.1), RED, "2.9 cm below the red line"),
    ((220.0, 196.9), NONE, "3.1 cm below the red line"),
    # beyond the end of a red edge along its line: the vertex (240, 200) has its green and
    # blue edges at +-60 deg from that line, so a point t cm beyond it is t*sin(60) from both
    ((243.1, 200.0), GREEN, "red 3.1 cm, green and blue both 2.685 cm: tie goes to green"),
    ((244.0, 200.0), NONE, "red 4 cm, green and blue both 3.464 cm"),
    # near the vertex (200,200): the nearest edge wins even though others are within 3 cm
    ((199.0, 201.0), BLUE, "blue edge 0.366 cm away, red and green 1.414 cm (vertex)"),
    ((199.0, 199.0), GREEN, "green edge 0.366 cm away, red and blue 1.414 cm (vertex)"),
    ((197.0, 200.5), BLUE, "blue 2.348 cm, green 2.848 cm, red 3.041 cm"),
    ((197.0, 199.5), GREEN, "green 2.348 cm, blue 2.848 cm, red 3.041 cm"),
    # exact ties that are not at a vertex
    ((197.0, 200.0), GREEN, "green and blue both 2.598 cm (red 3.0): tie goes to green"),
    ((201.0, 200.0 - R3), RED, "red and green both 1.732 cm (blue 2.0): tie goes to red"),
    ((201.0, 200.0 + R3), RED, "red and blue both 1.732 cm (green 2.0): tie goes to red"),
    # background: hexagon centres and points well inside hexagons
    ((160.0, 200.0), NONE, "hexagon centre"),
    ((220.0, 200.0 + S), NONE, "hexagon centre (220, 200+s)"),
    ((175.0, 210.0), NONE, "inside hexagon (160,200), 8.6 cm from its nearest edge"),
    # outside the arena, on an edge extended beyond the wall
    ((0.0, 200.0), RED, "on red edge [-40, 0] at the wall x = 0 (inside)"),
    ((-1.0, 200.0), NONE, "on red edge [-40, 0] but outside the arena"),
    ((399.0, 200.0 + S), RED, "on red edge [380, 420] at y = 200+s, inside"),
    ((401.0, 200.0 + S), NONE, "on red edge [380, 420] at y = 200+s, outside"),
    ((200.0 + 112.5, 200.0 - 225 * R3 / 2), BLUE, "blue edge (320,200-6s)-(300,200-5s), inside"),
    ((200.0 + 117.5, 200.0 - 235 * R3 / 2), NONE, "same blue edge, at y = -3.5 (outside)"),
]


def test_floor_colours(config):
    points = [case[0] for case in FLOOR_CASES]
    got = colours_at(config, points)
    expected = np.array([case[1] for case in FLOOR_CASES])
    wrong = [f"{c[2]} {c[0]}: expected {c[1]}, got {g}"
             for c, g in zip(FLOOR_CASES, got) if g != c[1]]
    assert not wrong, "\n".join(wrong)
    assert got.shape == expected.shape


def test_every_vertex_in_the_arena_is_red(config):
    """Vertices c + 40*(cos k60, sin k60) join one edge of each colour: the tie goes to red."""
    vertices = set()
    for i in range(-8, 9):
        for j in range(-8, 9):
            cx, cy = 160.0 + 60.0 * i, 200.0 + S * i + 2 * S * j
            for k in range(6):
                x, y = offset((cx, cy), 60.0 * k, 40.0)
                if 0.0 <= x <= 400.0 and 0.0 <= y <= 400.0:
                    vertices.add((round(x, 9), round(y, 9)))
    assert len(vertices) == 77
    np.testing.assert_array_equal(colours_at(config, sorted(vertices)), RED)


def test_floor_colour_line_width_on_every_colour(config):
    """2.9 cm off the middle of an edge is on it, 3.1 cm is not, on both sides, every colour."""
    edges = {  # (midpoint, direction in degrees) -> colour
        RED: ((220.0, 200.0), 0.0),
        GREEN: ((190.0, 200.0 - S / 2), 60.0),
        BLUE: ((190.0, 200.0 + S / 2), 120.0),
    }
    points, expected = [], []
    for colour, (mid, direction) in edges.items():
        for side in (90.0, -90.0):
            points += [offset(mid, direction + side, 2.9), offset(mid, direction + side, 3.1)]
            expected += [colour, NONE]
        # along the edge, 19 cm from the middle (1 cm before the vertex), still the edge
        points += [offset(mid, direction, 19.0), offset(mid, direction + 180.0, 19.0)]
        expected += [colour, colour]
    np.testing.assert_array_equal(colours_at(config, points), expected)


def test_floor_colour_keeps_leading_shape(config):
    points = jnp.asarray([[[220.0, 200.0], [160.0, 200.0]]] * 3, jnp.float32)  # (3, 2, 2)
    got = floor_colour(config, points)
    assert got.shape == (3, 2)
    np.testing.assert_array_equal(np.asarray(got), [[RED, NONE]] * 3)


# ---------------------------------------------------------------------------- retina


def pose(x, y, heading_deg):
    return Pose(jnp.asarray([x, y], jnp.float32), jnp.asarray(math.radians(heading_deg), jnp.float32))


def index(row, lateral, colour):
    """Position in the 36-vector: [forward row (17, 21)][lateral (-10..10)][R, G, B]."""
    return row * 18 + lateral * 3 + colour


def vector(*on):
    x = np.zeros(36)
    for row, lateral, colour in on:
        x[index(row, lateral, colour)] = 1.0
    return x


RETINA_CASES = [
    # Centred on the red line y = 200 at x = 190, heading 0: the points are at x = 207, 211
    # and y = 190, 194, 198, 202, 206, 210; only y = 198, 202 (lateral -2, +2) are within
    # 3 cm of the red edge [200, 240]; the vertex (200, 200) is more than 7 cm away.
    ((190.0, 200.0, 0.0), vector((0, 2, RED), (0, 3, RED), (1, 2, RED), (1, 3, RED)),
     "on the red line, heading along it"),
    # Heading 90 deg below the red edge: the points are at x = 220 - l (210..230) and
    # y = 195 (row 17: 5 cm off the line) and 199 (row 21: 1 cm off): the red line runs
    # across the far row.
    ((220.0, 178.0, 90.0), vector(*[(1, j, RED) for j in range(6)]),
     "red line across the far row"),
    # Hexagon centre: every point is at least 11 cm inside the hexagon's border.
    ((160.0, 200.0, 0.0), vector(), "inside a hexagon: nothing"),
    # Facing the wall on the line y = 200+s whose red edge [380, 420] crosses it: points at
    # x = 402 and 406 would be red at lateral +-2 but are outside the arena.
    ((385.0, 200.0 + S, 0.0), vector(), "facing the wall, all points outside"),
    # One step back: the near row (x = 398) is inside and sees red at +-2, the far row
    # (x = 402) is outside.
    ((381.0, 200.0 + S, 0.0), vector((0, 2, RED), (0, 3, RED)),
     "near row inside the arena, far row outside"),
    # Approaching the vertex (200, 200) from the left, heading 0, inside hexagon (160, 200):
    # near row x = 197: y = 190, 194, 198 are 2.40, 0.40, 1.60 cm from the green edge going
    # down-left, y = 202, 206, 210 the same from the blue edge going up-left (the red edge
    # starts at x = 200: its vertex is 3.6 cm or more away). Far row x = 201: y = 198 is 1.87
    # cm from green but 2 cm from red, y = 202 1.87 cm from blue; the rest are over 3 cm.
    ((180.0, 200.0, 0.0),
     vector((0, 0, GREEN), (0, 1, GREEN), (0, 2, GREEN), (0, 3, BLUE), (0, 4, BLUE), (0, 5, BLUE),
            (1, 2, GREEN), (1, 3, BLUE)),
     "junction ahead: green on the right, blue on the left"),
]


@pytest.fixture(scope="module")
def observe_many(config):
    """observe() vmapped over a batch of poses, jitted once."""
    return jax.jit(jax.vmap(lambda p: observe(config, p)))


def poses(rows):
    xs = jnp.asarray([[r[0], r[1]] for r in rows], jnp.float32)
    hs = jnp.asarray([math.radians(r[2]) for r in rows], jnp.float32)
    return Pose(xs, hs)


def test_retina_views(observe_many):
    got = np.asarray(observe_many(poses([case[0] for case in RETINA_CASES])))
    assert got.shape == (len(RETINA_CASES), 36)
    for (where, expected, why), x in zip(RETINA_CASES, got):
        np.testing.assert_array_equal(x, expected, err_msg=f"{why} at {where}: on at {np.flatnonzero(x)}")


def test_retina_view_is_binary_one_hot_per_point(observe_many):
    x = np.asarray(observe_many(poses([case[0] for case in RETINA_CASES])))
    assert set(np.unique(x)) <= {0.0, 1.0}
    assert (x.reshape(-1, 12, 3).sum(-1) <= 1).all()


def test_sample_points_heading_90(config):
    # heading 90 deg: forward is +y, the robot's left (positive lateral) is -x
    got = np.asarray(sample_points(config, pose(100.0, 50.0, 90.0)))
    xs = [110.0, 106.0, 102.0, 98.0, 94.0, 90.0]
    expected = np.array([[[x, 67.0] for x in xs], [[x, 71.0] for x in xs]])
    assert got.shape == (2, 6, 2)
    np.testing.assert_allclose(got, expected, atol=1e-4)


def test_sample_points_heading_180(config):
    # heading 180 deg: forward is -x, the robot's left is -y
    got = np.asarray(sample_points(config, pose(100.0, 50.0, 180.0)))
    ys = [60.0, 56.0, 52.0, 48.0, 44.0, 40.0]
    expected = np.array([[[83.0, y] for y in ys], [[79.0, y] for y in ys]])
    np.testing.assert_allclose(got, expected, atol=1e-4)


def test_sample_points_heading_30(config):
    # cos 30 = 0.8660254, sin 30 = 0.5; point = pos + f*(cos, sin) + l*(-sin, cos)
    got = np.asarray(sample_points(config, pose(100.0, 50.0, 30.0)))
    np.testing.assert_allclose(got[0, 0], [100 + 17 * 0.8660254 + 10 * 0.5, 50 + 17 * 0.5 - 10 * 0.8660254],
                               atol=1e-4)  # (119.7224, 49.8397): front row, rightmost
    np.testing.assert_allclose(got[1, 5], [100 + 21 * 0.8660254 - 10 * 0.5, 50 + 21 * 0.5 + 10 * 0.8660254],
                               atol=1e-4)  # (113.1865, 69.1603): far row, leftmost


# ---------------------------------------------------------------------------- kinematics

MOVE_CASES = [
    # (x, y, heading deg), (a0, a1) -> (x, y, heading deg)
    ((100.0, 100.0, 0.0), (0.5, 1.0), (102.0, 100.0, 0.0), "straight at full speed"),
    ((100.0, 100.0, 0.0), (0.5, 0.5), (101.0, 100.0, 0.0), "straight at half speed"),
    ((100.0, 100.0, 0.0), (0.5, 0.0), (100.0, 100.0, 0.0), "standing still"),
    ((100.0, 100.0, 0.0), (1.0, 1.0), (100.0 + R3, 101.0, 30.0), "turn left 30 deg, then move"),
    ((100.0, 100.0, 0.0), (0.0, 0.5), (100.0 + R3 / 2, 99.5, 330.0), "turn right, wrap to 330"),
    ((100.0, 100.0, 90.0), (0.75, 0.0), (100.0, 100.0, 105.0), "turn on the spot by +15 deg"),
    ((100.0, 100.0, 350.0), (1.0, 0.0), (100.0, 100.0, 20.0), "350 + 30 wraps to 20"),
    ((384.0, 200.0, 0.0), (0.5, 1.0), (385.0, 200.0, 0.0), "clamped at the east wall"),
    ((384.0, 200.0, 30.0), (0.5, 1.0), (385.0, 201.0, 30.0), "sliding along the east wall"),
    ((15.0, 15.0, 225.0), (0.5, 1.0), (15.0, 15.0, 225.0), "stuck in the south-west corner"),
    ((100.0, 16.0, 300.0), (0.5, 1.0), (101.0, 15.0, 300.0), "sliding along the south wall"),
    ((20.0, 300.0, 150.0), (0.5, 1.0), (20.0 - R3, 301.0, 150.0), "free move at 150 deg"),
]


def test_move(config):
    moves = jax.jit(jax.vmap(lambda p, a: move(config, p, a)))
    start = poses([c[0] for c in MOVE_CASES])
    actions = jnp.asarray([c[1] for c in MOVE_CASES], jnp.float32)
    got = moves(start, actions)
    pos, heading = np.asarray(got.pos), np.asarray(got.heading)
    for i, (_, _, (x, y, h), why) in enumerate(MOVE_CASES):
        np.testing.assert_allclose(pos[i], [x, y], atol=1e-4, err_msg=why)
        assert 0.0 <= heading[i] < 2 * math.pi, why
        diff = (heading[i] - math.radians(h) + math.pi) % (2 * math.pi) - math.pi
        assert abs(diff) < 1e-5, f"{why}: heading {math.degrees(heading[i])}, expected {h}"


def test_move_heading_stays_wrapped_over_many_turns(config):
    def spin(p, _):
        p = move(config, p, jnp.asarray([1.0, 0.0], jnp.float32))
        return p, p.heading

    _, headings = jax.lax.scan(spin, pose(200.0, 200.0, 0.0), None, length=25)
    headings = np.degrees(np.asarray(headings))
    assert (headings >= 0).all() and (headings < 360).all()
    # 12 turns of 30 deg are a full circle: 25 turns end at 30 deg
    np.testing.assert_allclose(headings[-1], 30.0, atol=1e-3)


def test_walls_targets_and_spawns_by_hand_as_arrays_and_as_pairs(config):
    """The step's arena rules, on a (2,) array (the XLA step) and on a pair of scalars (the GPU kernel)."""
    def both(fn, *xy):  # fn on arrays, then on pairs of scalars
        arrays = fn(*(jnp.asarray(v, jnp.float32) for v in xy))
        pairs = fn(*((jnp.float32(v[0]), jnp.float32(v[1])) for v in xy))
        return arrays, pairs

    # radius 15 cm in a 400 cm arena: the centre touches a wall at 15 or 385
    for pos, touching in (((15.0, 200.0), True), ((200.0, 385.0), True), ((16.0, 384.0), False)):
        arrays, pairs = both(lambda p: on_wall(config, p), pos)
        assert bool(arrays) == bool(pairs) == touching, pos
    # target radius 10 cm: (6, 8) from the target is 10 cm away (reached), (6, 8.01) is not
    for offset, reached in (((6.0, 8.0), True), ((6.0, 8.01), False)):
        pos = (100.0 + offset[0], 300.0 + offset[1])
        for got, late in ((both(lambda p, t: trial_ends(config, p, t, 199), pos, (100.0, 300.0)), False),
                          (both(lambda p, t: trial_ends(config, p, t, 200), pos, (100.0, 300.0)), not reached)):
            for hit, timeout in got:
                assert bool(hit) == reached and bool(timeout) == late, (offset, late)
    # 2 cm a step at full speed along (0.6, 0.8); clamped to [15, 385]
    arrays, pairs = both(lambda p, d: advance(config, p, d, 1.0), (100.0, 384.0), (0.6, 0.8))
    np.testing.assert_allclose(np.asarray(arrays), [101.2, 385.0], rtol=1e-6)
    np.testing.assert_array_equal(np.asarray(arrays), np.asarray(pairs))
    # draws (0, 0.5, 0.25): the west border, the middle, heading 90 deg
    (position, heading), ((x, y), heading_pair) = both(lambda u: spawn_pose(config, u, 0.25), (0.0, 0.5))
    np.testing.assert_allclose(np.asarray(position), [15.0, 200.0])
    assert (float(x), float(y)) == (15.0, 200.0) and float(heading) == float(heading_pair) == pytest.approx(math.pi / 2)


# ---------------------------------------------------------------------------- tasks

# MODEL.md task table: start, heading, target, first colour, edges, first turn, distance
TASK_TABLE = [
    ((140.0, 200.0 - S), 0.0, (240.0, 200.0), RED, 3, "L", 105.830),
    ((360.0, 200.0), 180.0, (240.0, 200.0 + 2 * S), RED, 4, "R", 138.564),
    ((60.0, 200.0 + S), 60.0, (60.0, 200.0 + 3 * S), GREEN, 2, "L", 69.282),
    ((200.0, 200.0 + 4 * S), 240.0, (120.0, 200.0 + 2 * S), GREEN, 3, "R", 105.830),
    ((200.0, 200.0 - 4 * S), 120.0, (80.0, 200.0 - 2 * S), BLUE, 4, "L", 138.564),
    ((300.0, 200.0 - S), 300.0, (300.0, 200.0 - 3 * S), BLUE, 2, "R", 69.282),
]


def test_task_table_matches_model(config):
    assert config.num_tasks == 6
    for task, (start, heading, target, _, _, _, distance) in zip(config.tasks, TASK_TABLE):
        np.testing.assert_allclose(task.start, start, atol=1e-9)
        np.testing.assert_allclose(task.target, target, atol=1e-9)
        assert task.heading_deg == heading
        assert task.distance == pytest.approx(distance, abs=1e-3)


def test_steps_per_trip_and_theoretical_max(config):
    assert config.steps_per_trip() == (48, 65, 30, 48, 65, 30)
    # ceil((distance - 10) / 2) by hand: 47.9, 64.3, 29.6
    expected = [100_000 / 48, 100_000 / 65, 100_000 / 30] * 2
    np.testing.assert_allclose(config.theoretical_max(), expected)
    np.testing.assert_allclose(config.theoretical_max()[:3], [2083.33, 1538.46, 3333.33], atol=0.01)


def is_vertex(point):
    """Is point = c + 40*(cos k60, sin k60) for a hexagon centre c = (160,200) + i*(60,s) + j*(0,2s)?"""
    for k in range(6):
        cx, cy = offset(point, k * 60.0 + 180.0, 40.0)
        i = (cx - 160.0) / 60.0
        j = (cy - 200.0 - i * S) / (2 * S)
        if abs(i - round(i)) < 1e-9 and abs(j - round(j)) < 1e-9:
            return True
    return False


def test_every_start_and_target_is_a_vertex(config):
    points = [t.start for t in config.tasks] + [t.target for t in config.tasks]
    assert all(is_vertex(p) for p in points)
    assert not is_vertex((160.0, 200.0)) and not is_vertex((220.0, 200.0))  # the check can fail
    # A vertex lies on three edges, 120 deg apart: either at 0 (red), 120 (blue), 240 (green)
    # or at 180 (red), 60 (green), 300 (blue). 1 cm along each, the floor has that colour.
    # Which kind of vertex: is the floor red 1 cm east of it (else the red edge is west)?
    east_red = colours_at(config, [offset(p, 0.0, 1.0) for p in points]) == RED
    probes, expected = [], []
    for p, east in zip(points, east_red):
        first = 0.0 if east else 180.0
        for d in (first, first + 120.0, first + 240.0):
            probes.append(offset(p, d, 1.0))
            expected.append({0: RED, 60: GREEN, 120: BLUE}[round(d) % 180])
        # and between the edges, 5 cm away (4.33 cm from both neighbours), the floor is background: the vertex is a "Y"
        for d in (first + 60.0, first + 180.0, first + 300.0):
            probes.append(offset(p, d, 5.0))
            expected.append(NONE)
    np.testing.assert_array_equal(colours_at(config, probes), expected)


def test_start_heading_runs_along_an_edge_of_the_first_colour(config):
    probes, expected = [], []
    for task, row in zip(config.tasks, TASK_TABLE):
        first_colour = row[3]
        for t in range(1, 40):  # the whole first edge, vertex to vertex
            probes.append(offset(task.start, task.heading_deg, float(t)))
            expected.append(first_colour)
        probes.append(offset(task.start, task.heading_deg, 40.0 + 4.0))  # past the junction
        expected.append(NONE)
    np.testing.assert_array_equal(colours_at(config, probes), expected)


def test_driving_straight_never_reaches_a_target(config):
    for task in config.tasks:
        x, y = task.start
        for _ in range(400):  # 2 cm steps until the wall
            x, y = offset((x, y), task.heading_deg, 2.0)
            if not (15.0 <= x <= 385.0 and 15.0 <= y <= 385.0):
                break
            assert math.dist((x, y), task.target) > 10.0


def test_paired_tasks_look_the_same_along_their_first_edge(config, observe_many):
    """Tasks 1-2, 3-4, 5-6: identical retina views from the start to the first junction."""
    distances = np.arange(0.0, 42.0, 2.0)  # 0, 2, ..., 40 cm: start vertex to first junction
    rows = []
    for task in config.tasks:
        for d in distances:
            x, y = offset(task.start, task.heading_deg, float(d))
            rows.append((x, y, task.heading_deg))
    views = np.asarray(observe_many(poses(rows))).reshape(6, len(distances), 2, 6, 3)
    for a, b in ((0, 1), (2, 3), (4, 5)):
        np.testing.assert_array_equal(views[a], views[b], err_msg=f"tasks {a + 1} and {b + 1}")
    for i, row in enumerate(TASK_TABLE):
        first = row[3]
        # non-trivial: the first colour is centred (lateral -2 and +2, both rows) while the
        # retina is on the first edge (d <= 16: the far row is then at most 37 cm along; at
        # 39 cm the lateral point +-2 is 1.87 cm from a branch and 2 cm from the edge) ...
        on_edge = distances <= 16
        assert (views[i][on_edge][:, :, 2:4, first] == 1).all(), f"task {i + 1}"
        # ... and the junction ahead comes into view: both other colours are seen
        others = [c for c in (RED, GREEN, BLUE) if c != first]
        for c in others:
            assert views[i][..., c].any(), f"task {i + 1}: colour {c} never seen at the junction"


# ---------------------------------------------------------------------------- config


@pytest.mark.parametrize(
    "field, value",
    [("childhood_steps", -1), ("num_parents", 60), ("condition", "XX")],
)
def test_config_rejects_impossible_values(field, value):
    with pytest.raises(ConfigError) as info:
        Config(**{field: value})
    assert str(info.value).startswith(field), str(info.value)
