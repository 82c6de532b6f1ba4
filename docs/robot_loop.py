"""A robot's loop (docs/python.md): a spinning sensor of 64 rings of 1024 rays (65,536 rays from one
origin) in a room (a floor, four walls and a ceiling) with the dragon and the armadillo, and the bunny
carried about. Two loops
of POSES poses each, timed whole as a user's loop runs (numpy's work included):

1. the sensor moves (a new origin each pose) and the scene stays: cast_rays alone;
2. the sensor stays and the bunny moves (turned and carried round the sensor on a circle of twice
   the room's object size): Renderer.set_vertices with the bunny's posed vertices, then cast_rays.

Then the last pose of loop 2 against the double-precision reference made from a scene that holds
the bunny where it was moved: the hits' distances' relative error and the rays that hit in one and
missed in the other. Best of ROUNDS rounds of each loop.

With `open`, the room has no walls and ceiling: the bunny then changes the scene's box, and every
set_vertices refits the whole scene.

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/robot_loop.py [POSES] [ROUNDS] [open]
"""
import math
import os
import sys
import time

import numpy as np

import vkray
from obj_arrays import load_obj, room

POSES = int(sys.argv[1]) if len(sys.argv) > 1 else 100
ROUNDS = int(sys.argv[2]) if len(sys.argv) > 2 else 3
OPEN = len(sys.argv) > 3 and sys.argv[3] == "open"
MODELS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "models")


def sensor_directions(rings=64, columns=1024):
    """Unit directions of a spinning sensor: rings from -15 to +15 degrees, columns all round."""
    elevation = np.radians(np.linspace(-15.0, 15.0, rings))[:, None]
    azimuth = np.linspace(0.0, 2.0 * math.pi, columns, endpoint=False)[None, :]
    return np.stack(np.broadcast_arrays(np.cos(elevation) * np.cos(azimuth), np.sin(elevation),
                                        np.cos(elevation) * np.sin(azimuth)), axis=-1).reshape(-1, 3)


def rays_from(origin, directions):
    return np.concatenate([np.broadcast_to(origin, directions.shape), directions], axis=1)


def posed(vertices, pose):
    """The bunny at pose `pose` of POSES: turned about its vertical axis and carried round the sensor."""
    angle = 2.0 * math.pi * pose / POSES
    turn = np.array([[math.cos(3 * angle), 0.0, math.sin(3 * angle)], [0.0, 1.0, 0.0],
                     [-math.sin(3 * angle), 0.0, math.cos(3 * angle)]])
    return vertices @ turn.T + [2.0 * math.cos(angle), 0.0, 2.0 * math.sin(angle)]


bunny, bunny_triangles = load_obj(os.path.join(MODELS, "stanford-bunny.obj"), 0.5)
dragon, dragon_triangles = load_obj(os.path.join(MODELS, "stanford-dragon-100k.obj"), 1.0)
armadillo, armadillo_triangles = load_obj(os.path.join(MODELS, "armadillo-50k.obj"), 1.0)
# The room's walls and ceiling, 10 x 10 x 3 about the sensor (the floor is a plane): they bound the
# scene, so its box, whose centre every stored position is relative to, stays while the bunny moves
# and set_vertices redoes the bunny's part alone (docs/python.md).
walls, wall_triangles = room(5.0, 3.0)
meshes = [{"vertices": posed(bunny, 0), "triangles": bunny_triangles},
          {"vertices": dragon + [3.0, 0.0, 1.0], "triangles": dragon_triangles},
          {"vertices": armadillo + [-1.0, 0.0, -3.0], "triangles": armadillo_triangles},
          {"vertices": walls, "triangles": wall_triangles}][:3 if OPEN else 4]
floor = [[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]]
scene = vkray.Scene(meshes=meshes, planes=floor)
directions = sensor_directions()
sensor = np.array([0.0, 0.5, 0.0])


def sensor_moves(renderer):
    for pose in range(POSES):
        angle = 2.0 * math.pi * pose / POSES
        renderer.cast_rays(rays_from(sensor + [0.5 * math.cos(angle), 0.0, 0.5 * math.sin(angle)], directions))


updates = []  # each set_vertices: its time, whether the tree kept its shape, and whether the bunny's part alone was redone


def bunny_moves(renderer):
    rays = rays_from(sensor, directions)
    for pose in range(POSES):
        renderer.set_vertices(0, posed(bunny, pose))
        timings = renderer.timings
        updates.append((timings["scene_update_ms"], timings["tree_refitted"], timings["refit_mesh_alone"]))
        hits = renderer.cast_rays(rays)
    return hits


def best_of(loop, renderer):
    times = []
    for _ in range(ROUNDS):
        start = time.perf_counter()
        loop(renderer)
        times.append(time.perf_counter() - start)
    return min(times)


renderer = vkray.Renderer(scene)
renderer.prepare()  # every pipeline made before the loop: no pose pays for one
sensor_s = best_of(sensor_moves, renderer)
bunny_s = best_of(bunny_moves, renderer)
kept = sum(refitted for _, refitted, _ in updates)
alone = sum(mesh_alone for _, _, mesh_alone in updates)
print(f"{len(directions)} rays a pose, {scene.triangle_count} triangles: {POSES} poses of the moving sensor "
      f"{1e3 * sensor_s:.0f} ms ({1e3 * sensor_s / POSES:.1f} ms a pose); {POSES} poses of the moving bunny "
      f"{1e3 * bunny_s:.0f} ms ({1e3 * bunny_s / POSES:.1f} ms a pose, of which set_vertices "
      f"{np.median([ms for ms, _, _ in updates]):.1f} ms, the tree's shape kept in {kept} of {len(updates)}, the bunny's part "
      f"alone redone in {alone}); ratio {bunny_s / sensor_s:.2f} (best of {ROUNDS}); "
      f"the first set_vertices {updates[0][0]:.0f} ms (the scene converted), the second {updates[1][0]:.0f} ms (a whole refit)")

hits = bunny_moves(renderer)
last = dict(meshes[0], vertices=posed(bunny, POSES - 1))
truth = vkray.Reference(vkray.Scene(meshes=[last] + meshes[1:], planes=floor)).cast_rays(rays_from(sensor, directions))
both = np.isfinite(truth["t"]) & np.isfinite(hits["t"])
error = np.abs(hits["t"][both] - truth["t"][both]) / truth["t"][both]
flips = int(np.sum(np.isfinite(truth["t"]) != np.isfinite(hits["t"])))
other_mesh = int(np.sum(truth["mesh_id"][both] != hits["mesh_id"][both]))
print(f"the last pose against the reference: t rel. error p99 {np.percentile(error, 99):.2e} max {error.max():.2e}; "
      f"{flips} hit/miss flips, {other_mesh} hits on another mesh")
