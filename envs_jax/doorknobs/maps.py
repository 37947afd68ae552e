"""Doorknobs worlds (envs.md §3.1-3.3): room maps, walls, doors, clutter, task sampling, and a task's
padded device arrays, including the motion roadmaps its MoveToDoor skill follows.

Slots. An env of capacity M (a map of at most M x M rooms) numbers the room at (row, col) r = row * M + col
and the door a room owns on its bottom (left) side 2r (2r + 1); each shared wall has exactly one door,
owned by the upper (right) room. Room (row, col) of a size x size map has its lower-left corner at
x = col, y = size - 1 - row.
"""
from __future__ import annotations

import functools
import operator
from dataclasses import dataclass
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax import geometry
from envs_jax.doorknobs import roadmap
from envs_jax.precision import float32_window
from planner.search import breadth_first_distances

# ---- §3.1 constants --------------------------------------------------------------------------------
ROOM_SIZE = 1.0
HALLWAY_WIDTH = 0.25  # doorway opening and door length
WALL_DEPTH = 0.01  # wall and door thickness
ROBOT_RADIUS = 0.05
ACTION_MAGNITUDE = 0.05  # max |dx|, |dy| per step
START_RADIUS = 0.1  # clutter anchors and the robot start: room centre +- 0.1
OBSTACLE_SIZE = (0.05, 0.15)  # clutter width and height
DOORWAY_DEPTH = ROBOT_RADIUS + 1e-3  # the doorway is the door thickened by this on both sides
WALL_SEGMENT = (ROOM_SIZE + WALL_DEPTH - HALLWAY_WIDTH) / 2  # 0.38: the wall beside a doorway
DOOR_CENTRE = WALL_SEGMENT + HALLWAY_WIDTH / 2  # 0.505: the door's middle, from the room's corner
IN_DOORWAY = WALL_DEPTH / 2 + DOORWAY_DEPTH  # 0.056: the "position in doorway", off the wall line
KNOB_TARGET = 0.75  # every knob's target_rot (same_levels=True); knobs start at rot 0
OPEN_TOLERANCE = 0.1  # a door opens when |knob rot - target| < 0.1 (the authors' DoorsEnv used 0.01)
MAX_CLUTTER = 3
ROOM_FRACTION = (0.25, 0.75)  # of the map's cells that become rooms
TRAIN_MAP_SIZE, TEST_MAP_SIZE = 2, 5
HORIZON = 200

BOTTOM, LEFT, TOP, RIGHT = range(4)  # sides of a room
SIDE_NORMAL = np.array([(0, 1), (1, 0), (0, -1), (-1, 0)], np.float32)  # pointing into the room
SIDE_CENTRE = np.array([(DOOR_CENTRE, 0), (0, DOOR_CENTRE), (DOOR_CENTRE, 1), (1, DOOR_CENTRE)], np.float32)
WALLS_PER_ROOM = 8  # two per side: the segments beside a doorway, or one full wall and an empty slot

# ---- motion roadmap (our replacement for the authors' BiRRT, envs.md §3.6) ---------------------------
NODE_PAD = ROBOT_RADIUS + 0.01  # clutter corners grown by this much are waypoints
APPROACH = 0.25  # a waypoint this far in front of each doorway
CLEARANCE = ROBOT_RADIUS + 1e-4  # straight moves keep at least this far from every obstacle
CORNER_NODES, APPROACH_NODES, GOAL_NODES = 0, 4 * MAX_CLUTTER, 4 * MAX_CLUTTER + 4
NODES_PER_ROOM = 4 * MAX_CLUTTER + 8  # clutter corners, then one approach and one goal per side


@dataclass(frozen=True)
class DoorknobsTask:
    """Host-side task spec (hashable)."""

    size: int  # the map has size x size cells
    rooms: tuple[tuple[int, int], ...]  # (row, col), row-major
    doors: tuple[tuple[int, int, int], ...]  # (row, col, BOTTOM or LEFT) of the owning room
    door_mass_friction: tuple[tuple[float, float], ...]  # drawn as the authors did; no effect on dynamics
    clutter: tuple[tuple[tuple[float, ...], ...], ...]  # per room: (x, y, width, height, theta) rectangles
    robot: tuple[float, float]
    goal_room: tuple[int, int]

    horizon: ClassVar[int] = HORIZON

    @property
    def start_room(self) -> tuple[int, int]:
        col, y = int(np.floor(self.robot[0])), int(np.floor(self.robot[1]))
        return (self.size - 1 - y, col)

    @property
    def doors_to_goal(self) -> int:
        """Doors on a shortest room path from the start to the goal room."""
        return door_distances(self.rooms, self.doors, self.start_room)[self.goal_room]

    @property
    def min_steps(self) -> int:
        """No episode reaches the goal in fewer env steps: the robot moves at most ACTION_MAGNITUDE along
        each axis per step, so it needs the larger axis gap to the goal room over that (walls ignored)."""
        row, col = self.goal_room
        x0, y0 = col * ROOM_SIZE, (self.size - 1 - row) * ROOM_SIZE
        dx = max(x0 - self.robot[0], 0.0, self.robot[0] - (x0 + ROOM_SIZE))
        dy = max(y0 - self.robot[1], 0.0, self.robot[1] - (y0 + ROOM_SIZE))
        return int(np.ceil(max(dx, dy) / ACTION_MAGNITUDE - 1e-9))

    def describe(self) -> str:
        return (f"{len(self.rooms)} rooms on {self.size}x{self.size}, {len(self.doors)} doors, "
                f"{self.doors_to_goal} to the goal")


# ---- §3.3 task generation (the authors' numpy draw order) ------------------------------------------
def sample_room_map(rng: np.random.Generator, size: int) -> np.ndarray:
    """A connected set of cells: from a random start, pop random frontier cells and add all their free
    neighbours until there are enough rooms (so 2x2 maps always get 3 rooms: the first pop adds two)."""
    grid = np.zeros((size, size), bool)
    low, high = max(2, int(ROOM_FRACTION[0] * size * size)), int(ROOM_FRACTION[1] * size * size)
    num_rooms = rng.integers(low, high + 1)
    start = tuple(int(v) for v in rng.integers(size, size=2))
    grid[start] = True
    frontier = [start]
    while grid.sum() < num_rooms:
        row, col = frontier.pop(int(rng.integers(len(frontier))))
        for nr, nc in ((row - 1, col), (row + 1, col), (row, col - 1), (row, col + 1)):
            if 0 <= nr < size and 0 <= nc < size and not grid[nr, nc]:
                grid[nr, nc] = True
                frontier.append((nr, nc))
    return grid


def robot_touches(centre: jax.Array, rects: jax.Array, mask: jax.Array) -> jax.Array:
    """The robot circle at `centre` touches one of the masked-in rectangles (float32[N, 5], bool[N]); the
    rows combined one by one: see roadmap.visible."""
    return functools.reduce(operator.or_, mask & geometry.circle_hits_rect(centre, ROBOT_RADIUS, rects))


_overlaps = jax.jit(geometry.rects_overlap)
_hits = jax.jit(robot_touches)


def _robot_collides(grid, robot, row, col, clutter, doors) -> bool:
    """The robot, near the centre of room (row, col), touches its walls, clutter or (closed) doors."""
    walls, used = room_walls(grid, row, col)
    size = grid.shape[0]
    near = [door_geometry(size, *d)[0] for d in doors if (row, col) in door_rooms(d)]
    rects = np.zeros((WALLS_PER_ROOM + MAX_CLUTTER + 4, 5), np.float32)  # one shape: jit compiles once
    mask = np.zeros(len(rects), bool)
    for i, r in enumerate([w for w, u in zip(walls, used) if u] + list(clutter) + near):
        rects[i], mask[i] = r, True
    return bool(_hits(np.float32(robot), rects, mask))


def door_rooms(door: tuple[int, int, int]) -> tuple[tuple[int, int], tuple[int, int]]:
    """The (row, col) of the two rooms a door joins: its owner, then the room below / to the left."""
    row, col, side = door
    return (row, col), ((row + 1, col) if side == BOTTOM else (row, col - 1))


def door_distances(rooms, doors, start: tuple[int, int]) -> dict[tuple[int, int], int]:
    """{room: doors on a shortest room path from `start`} (breadth-first over the doors)."""
    neighbours: dict = {room: [] for room in rooms}
    for door in doors:
        a, b = door_rooms(door)
        neighbours[a].append(b)
        neighbours[b].append(a)
    return breadth_first_distances(neighbours, [start])


def sample_task(rng: np.random.Generator, size: int, doors_to_goal: int | None = None,
                max_tries: int | None = None) -> DoorknobsTask:
    """A task on a size x size map (the authors' draw order). With `doors_to_goal`, the goal is drawn
    among the rooms exactly that many doors from the start, and the whole task is redrawn while there is
    none (the generalisation sweep's tasks), at most `max_tries` times (ValueError then)."""
    tries = 0
    while max_tries is None or tries < max_tries:
        task = _sample_task(rng, size, doors_to_goal)
        if task is not None:
            return task
        tries += 1
    raise ValueError(f"no {size}x{size} map with a room {doors_to_goal} doors from the start in {max_tries} draws")


def _sample_task(rng: np.random.Generator, size: int, doors_to_goal: int | None) -> DoorknobsTask | None:
    grid = sample_room_map(rng, size)
    rooms = [(int(r), int(c)) for r, c in np.argwhere(grid)]
    while True:  # the authors resample everything but the map while the robot starts in collision
        doors, mass_friction = [], []
        for row, col in rooms:
            for side, (nr, nc) in ((BOTTOM, (row + 1, col)), (LEFT, (row, col - 1))):
                if 0 <= nr < size and 0 <= nc < size and grid[nr, nc]:
                    mass, friction, _ = rng.uniform(0.0, 1.0, size=3)  # the third is the unused target
                    doors.append((row, col, side))
                    mass_friction.append((float(mass), float(friction)))
        clutter = []
        for row, col in rooms:
            cx, cy = col + 0.5, size - 1 - row + 0.5
            placed: list[tuple[float, ...]] = []
            for _ in range(int(rng.integers(0, MAX_CLUTTER + 1))):
                while True:  # clutter in a room does not overlap
                    r = (rng.uniform(cx - START_RADIUS, cx + START_RADIUS),
                         rng.uniform(cy - START_RADIUS, cy + START_RADIUS),
                         rng.uniform(*OBSTACLE_SIZE), rng.uniform(*OBSTACLE_SIZE), rng.uniform(-np.pi, np.pi))
                    if not any(bool(_overlaps(np.float32(r), np.float32(q))) for q in placed):
                        break
                placed.append(tuple(float(v) for v in r))
            clutter.append(tuple(placed))
        row, col = rooms[int(rng.choice(len(rooms)))]
        cx, cy = col + 0.5, size - 1 - row + 0.5
        robot = (float(rng.uniform(cx - START_RADIUS, cx + START_RADIUS)),
                 float(rng.uniform(cy - START_RADIUS, cy + START_RADIUS)))
        if not _robot_collides(grid, robot, row, col, clutter[rooms.index((row, col))], doors):
            break
    if doors_to_goal is None:
        goals = [r for r in rooms if r != (row, col)]
    else:
        goals = [r for r, d in door_distances(rooms, doors, (row, col)).items() if d == doors_to_goal]
        if not goals:
            return None
    goal = goals[int(rng.choice(len(goals)))]
    return DoorknobsTask(size, tuple(rooms), tuple(doors), tuple(mass_friction), tuple(clutter), robot, goal)


def train_task(seed: int) -> DoorknobsTask:
    """The seed's single training task: a 2x2 map (always 3 rooms in an L, 2 doors)."""
    return sample_task(np.random.default_rng(seed), TRAIN_MAP_SIZE)


def test_tasks(seed: int, num_tasks: int = 10) -> list[DoorknobsTask]:
    """The seed's test tasks: 5x5 maps with 6-20 rooms."""
    rng = np.random.default_rng(seed + 10000)
    return [sample_task(rng, TEST_MAP_SIZE) for _ in range(num_tasks)]


# ---- §3.2 static geometry ------------------------------------------------------------------------
def room_walls(grid: np.ndarray, row: int, col: int) -> tuple[list[tuple], list[bool]]:
    """The room's 8 wall slots (bottom, left, top, right; two each) and which are used: a full wall,
    or two segments leaving a doorway gap where a neighbouring room exists."""
    size = grid.shape[0]
    x, y = col, size - 1 - row
    lo, gap_end, full = -WALL_DEPTH / 2, -WALL_DEPTH / 2 + WALL_SEGMENT + HALLWAY_WIDTH, ROOM_SIZE + WALL_DEPTH
    rects, used = [], []
    for side, (nr, nc) in enumerate(((row + 1, col), (row, col - 1), (row - 1, col), (row, col + 1))):
        hall = 0 <= nr < size and 0 <= nc < size and bool(grid[nr, nc])
        horizontal = side in (BOTTOM, TOP)
        line = (y, x, y, x)[side] + (0, 0, 1, 1)[side] - WALL_DEPTH / 2  # the wall's lower/left edge
        starts, length = ((lo, gap_end), WALL_SEGMENT) if hall else ((lo,), full)
        for start in starts:
            rects.append((x + start, line, length, WALL_DEPTH, 0.0) if horizontal
                         else (line, y + start, WALL_DEPTH, length, 0.0))
            used.append(True)
        if not hall:
            rects.append((0.0, 0.0, 0.0, 0.0, 0.0))
            used.append(False)
    return rects, used


def door_geometry(size: int, row: int, col: int, side: int):
    """(door rectangle, doorway rectangle, centre on the wall line, normal into the owner) of the door a
    room owns on its BOTTOM or LEFT side. The knob shares the door's rectangle (and so its anchor)."""
    x, y = col, size - 1 - row
    if side == BOTTOM:
        door = (x + WALL_SEGMENT, y - WALL_DEPTH / 2, HALLWAY_WIDTH, WALL_DEPTH, 0.0)
        doorway = (x + WALL_SEGMENT, y - IN_DOORWAY, HALLWAY_WIDTH, 2 * IN_DOORWAY, 0.0)
    else:
        door = (x + WALL_DEPTH / 2, y + WALL_SEGMENT, HALLWAY_WIDTH, WALL_DEPTH, np.pi / 2)
        doorway = (x - IN_DOORWAY, y + WALL_SEGMENT, 2 * IN_DOORWAY, HALLWAY_WIDTH, 0.0)
    return door, doorway, np.array((x, y)) + SIDE_CENTRE[side], SIDE_NORMAL[side]


@functools.lru_cache
def layout(map_size: int) -> tuple[np.ndarray, np.ndarray]:
    """Static slot tables of a capacity: door_rooms int32[D, 2] (owner, neighbour) and room_doors
    int32[R, 4] (the door slot on each side); -1 where the grid ends."""
    m = map_size
    door_rooms = np.full((2 * m * m, 2), -1, np.int32)
    room_doors = np.full((m * m, 4), -1, np.int32)
    for row in range(m):
        for col in range(m):
            r = row * m + col
            door_rooms[2 * r] = (r, r + m) if row + 1 < m else (r, -1)
            door_rooms[2 * r + 1] = (r, r - 1) if col > 0 else (r, -1)
            room_doors[r] = (2 * r if row + 1 < m else -1, 2 * r + 1 if col > 0 else -1,
                             2 * (r - m) if row > 0 else -1, 2 * (r + 1) + 1 if col + 1 < m else -1)
    return door_rooms, room_doors


def capacity(task) -> int:
    """The map size M of a (padded) task's arrays."""
    return round(task.room_mask.shape[-1] ** 0.5)


# ---- a task's device arrays ---------------------------------------------------------------------
@struct.dataclass
class Task:
    """A task padded to a capacity of M x M rooms (R = M * M room slots, D = 2R door slots)."""

    room_xy: jax.Array  # float32[R, 2]: lower-left corners
    room_mask: jax.Array  # bool[R]
    walls: jax.Array  # float32[R, 8, 5] rectangles
    wall_mask: jax.Array  # bool[R, 8]
    clutter: jax.Array  # float32[R, 3, 5] rectangles
    clutter_mask: jax.Array  # bool[R, 3]
    door_mask: jax.Array  # bool[D]
    door_rect: jax.Array  # float32[D, 5]: the door, and its knob
    doorway: jax.Array  # float32[D, 5], upright (theta = 0)
    door_point: jax.Array  # float32[D, 2, 2]: position in doorway on the owner's / the neighbour's side
    door_mass: jax.Array  # float32[D]
    door_friction: jax.Array  # float32[D]
    knob_target: jax.Array  # float32[D]
    knob_window: jax.Array  # float32[D, 2]: (lo, hi) of rotations that open the door (`float32_window`)
    robot_start: jax.Array  # float32[2]
    goal_room: jax.Array  # int32
    nodes: jax.Array  # float32[R, K, 2]: roadmap waypoints (clutter corners, approach and goal per side)
    node_cost: jax.Array  # float32[R, 4, K]: path length to the doorway on each side; inf: no path


def room_obstacles(task: Task, room: jax.Array, door_open: jax.Array) -> tuple[jax.Array, jax.Array]:
    """float32[15, 5] rectangles and their bool[15] mask that a robot centred in `room` can hit: the
    room's walls (a neighbour's walls coincide with them), its clutter and its closed doors."""
    _, room_doors = layout(capacity(task))
    doors = jnp.asarray(room_doors)[room]
    slot = jnp.maximum(doors, 0)
    closed = (doors >= 0) & task.door_mask[slot] & ~door_open[slot]
    rects = jnp.concatenate([task.walls[room], task.clutter[room], task.door_rect[slot]])
    return rects, jnp.concatenate([task.wall_mask[room], task.clutter_mask[room], closed])


def route_obstacles(task: Task, room: jax.Array, door_open: jax.Array, p: jax.Array) -> tuple[jax.Array, jax.Array]:
    """float32[6, 5] rectangles and their bool[6] mask that can block a straight move from p, in `room`,
    to one of the room's waypoints: its clutter, and the walls and door of the side p is nearest to.

    Why that is enough: every waypoint lies in the room's interior, the square at least CLEARANCE beyond
    the walls' inner faces, and every wall and door grown by CLEARANCE lies outside it, in the strip along
    its side. So a segment from p meets the grown walls or door of a side only if p is in that side's
    strip, and p (the robot) can be in one strip at most: it leaves the interior only in a doorway."""
    _, room_doors = layout(capacity(task))
    q = p - task.room_xy[room]
    side = jnp.argmin(jnp.stack([q[1], q[0], ROOM_SIZE - q[1], ROOM_SIZE - q[0]]))
    door = jnp.asarray(room_doors)[room, side]
    slot = jnp.maximum(door, 0)
    walls = jax.lax.dynamic_slice_in_dim(task.walls[room], 2 * side, 2)
    wall_mask = jax.lax.dynamic_slice_in_dim(task.wall_mask[room], 2 * side, 2)
    closed = (door >= 0) & task.door_mask[slot] & ~door_open[slot]
    rects = jnp.concatenate([task.clutter[room], walls, task.door_rect[slot][None]])
    return rects, jnp.concatenate([task.clutter_mask[room], wall_mask, closed[None]])


def in_entry_cone(p: jax.Array, goal: jax.Array, normal: jax.Array) -> jax.Array:
    """p lies within 45 degrees of the doorway's axis, in front of its goal point. Heading straight for
    the goal from there, the robot enters the doorway within ~0.05 of the door's centre line, so that
    MoveThroughDoor's straight line then clears the wall beside the door."""
    d = p - goal
    along = d @ normal
    across = jnp.abs(d[0] * normal[1] - d[1] * normal[0])
    return across <= along + 1e-6


_grown_corners = jax.jit(lambda rects: geometry.corners(rects, NODE_PAD))


@jax.jit
def _roadmap_visibility(task: Task):
    """Per room: which waypoints are free, which pairs see each other (all doors closed), and which
    waypoints lie in each side's entry cone."""
    normals = jnp.asarray(SIDE_NORMAL)

    def per_room(room):
        rects, mask = room_obstacles(task, room, jnp.zeros_like(task.door_mask))
        nodes = task.nodes[room]
        seen = jax.vmap(lambda p: roadmap.visible(p, nodes, rects, mask, CLEARANCE))(nodes)
        free = jnp.diagonal(seen)  # a segment from a waypoint to itself is the point test
        cone = jax.vmap(lambda p: jax.vmap(in_entry_cone, (None, 0, 0))(p, nodes[GOAL_NODES:], normals))(nodes)
        return free, seen, cone

    return jax.vmap(per_room)(jnp.arange(task.room_mask.shape[0]))


def _roadmap_costs(task: Task, room_doors: np.ndarray) -> np.ndarray:
    """float32[R, 4, K]: every waypoint's path length to the goal point of each side's doorway. The
    graph for side k: clutter corners and approach points, plus side k's goal, which may only be entered
    from its entry cone."""
    free, seen, cone = (np.asarray(x) for x in _roadmap_visibility(task))
    k = NODES_PER_ROOM
    goal = GOAL_NODES + np.arange(4)
    exists = (room_doors >= 0) & task.door_mask[np.maximum(room_doors, 0)]  # [R, 4]
    node_valid = np.concatenate([np.repeat(task.clutter_mask, 4, axis=1), exists, exists], axis=1)
    member = (np.arange(k) < GOAL_NODES) | (np.arange(k) == goal[:, None])  # [4, K]
    usable = (node_valid & free)[:, None, :] & member[None]  # [R, 4, K]
    edges = usable[..., :, None] & usable[..., None, :] & seen[:, None]
    into_goal = np.arange(k) == goal[:, None]  # [4, K]
    edges &= ~into_goal[None, :, None, :] | np.swapaxes(cone, 1, 2)[:, :, :, None]
    nodes = np.broadcast_to(task.nodes[:, None], usable.shape + (2,))
    cost = roadmap.costs_to_goal(edges, nodes, np.broadcast_to(goal, exists.shape))
    return np.where(usable & exists[..., None], cost, np.inf).astype(np.float32)


@functools.lru_cache(maxsize=4096)
def task_arrays(spec: DoorknobsTask, map_size: int) -> Task:
    """The spec's padded arrays (numpy leaves), roadmaps included."""
    if spec.size > map_size:
        raise ValueError(f"a {spec.size}x{spec.size} map exceeds capacity {map_size}")
    m = map_size
    rooms, doors = m * m, 2 * m * m
    grid = np.zeros((spec.size, spec.size), bool)
    grid[tuple(np.array(spec.rooms).T)] = True
    f32 = lambda *shape: np.zeros(shape, np.float32)
    room_xy, walls, clutter = f32(rooms, 2), f32(rooms, WALLS_PER_ROOM, 5), f32(rooms, MAX_CLUTTER, 5)
    room_mask, wall_mask = np.zeros(rooms, bool), np.zeros((rooms, WALLS_PER_ROOM), bool)
    clutter_mask = np.zeros((rooms, MAX_CLUTTER), bool)
    for (row, col), room_clutter in zip(spec.rooms, spec.clutter):
        r = row * m + col
        room_xy[r], room_mask[r] = (col, spec.size - 1 - row), True
        walls[r], wall_mask[r] = room_walls(grid, row, col)
        for j, rect in enumerate(room_clutter):
            clutter[r, j], clutter_mask[r, j] = rect, True
    door_mask, door_rect, doorway, door_point = np.zeros(doors, bool), f32(doors, 5), f32(doors, 5), f32(doors, 2, 2)
    door_mass, door_friction = f32(doors), f32(doors)
    knob_target = np.full(doors, KNOB_TARGET, np.float32)
    for (row, col, side), (mass, friction) in zip(spec.doors, spec.door_mass_friction):
        d = 2 * (row * m + col) + side
        door_rect[d], doorway[d], centre, normal = door_geometry(spec.size, row, col, side)
        door_point[d] = (centre + IN_DOORWAY * normal, centre - IN_DOORWAY * normal)
        door_mask[d], door_mass[d], door_friction[d] = True, mass, friction
    corners = np.asarray(_grown_corners(clutter)).reshape(rooms, 4 * MAX_CLUTTER, 2)
    side_points = room_xy[:, None] + SIDE_CENTRE[None]
    nodes = np.concatenate([corners, side_points + APPROACH * SIDE_NORMAL, side_points + IN_DOORWAY * SIDE_NORMAL],
                           axis=1)
    goal_row, goal_col = spec.goal_room
    task = Task(room_xy=room_xy, room_mask=room_mask, walls=walls, wall_mask=wall_mask, clutter=clutter,
                clutter_mask=clutter_mask, door_mask=door_mask, door_rect=door_rect, doorway=doorway,
                door_point=door_point, door_mass=door_mass, door_friction=door_friction,
                knob_target=knob_target,
                knob_window=np.stack(float32_window(knob_target, OPEN_TOLERANCE, inclusive=False), -1),
                robot_start=np.array(spec.robot, np.float32), goal_room=np.int32(goal_row * m + goal_col),
                nodes=nodes.astype(np.float32), node_cost=f32(rooms, 4, NODES_PER_ROOM))
    return task.replace(node_cost=_roadmap_costs(task, layout(m)[1]))
