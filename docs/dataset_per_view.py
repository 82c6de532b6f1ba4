"""A dataset of objects placed per view (docs/python.md): five models (the bunny, the dragon, the
armadillo, spot and the cow) stood on the floor of a room at a new random place and turn in every
view, seen by a camera from a random side, each view's depth and mesh_id (the object's label)
written as .npy files, as a synthetic-data generator does. Each view moves every object by
Renderer.set_vertices (its vertices posed with numpy), then renders. Times the whole loop and its
parts, and checks one view against the double-precision reference.

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/dataset_per_view.py [VIEWS] [WIDTH] [HEIGHT]
"""
import math
import os
import sys
import tempfile
import time

import numpy as np

import vkray
from obj_arrays import load_obj, room

VIEWS = int(sys.argv[1]) if len(sys.argv) > 1 else 100
WIDTH = int(sys.argv[2]) if len(sys.argv) > 2 else 640
HEIGHT = int(sys.argv[3]) if len(sys.argv) > 3 else 480
MODELS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "models")
NAMES = ["stanford-bunny.obj", "stanford-dragon-100k.obj", "armadillo-50k.obj", "spot.obj", "cow.obj"]

models = [load_obj(os.path.join(MODELS, name), 0.6) for name in NAMES]
walls, wall_triangles = room(4.0, 3.0)  # the walls bound the scene: see robot_loop.py
floor = [[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]]
rng = np.random.default_rng(7)


def placed(vertices, angle, x, z):
    turn = np.array([[math.cos(angle), 0.0, math.sin(angle)], [0.0, 1.0, 0.0], [-math.sin(angle), 0.0, math.cos(angle)]])
    return vertices @ turn.T + [x, 0.0, z]


def view_layout():
    """Each object's turn and place, on a 3 x 3 grid of 1 m cells over the middle of the floor (one
    object a cell, jittered within it, so that none overlap), and a camera looking at the middle."""
    cells = rng.permutation(9)[:len(models)]
    poses = [(rng.uniform(0, 2 * math.pi), (cell % 3 - 1) + rng.uniform(-0.2, 0.2), (cell // 3 - 1) + rng.uniform(-0.2, 0.2))
             for cell in cells]
    side = rng.uniform(0, 2 * math.pi)
    camera = {"from": [3.2 * math.cos(side), rng.uniform(1.5, 2.5), 3.2 * math.sin(side)], "to": [0.0, 0.3, 0.0],
              "up": [0.0, 1.0, 0.0], "fovy": 50.0}
    return poses, camera


def scene_of(poses, camera):
    meshes = [{"vertices": placed(v, *pose), "triangles": t} for (v, t), pose in zip(models, poses)]
    return vkray.Scene(meshes=meshes + [{"vertices": walls, "triangles": wall_triangles}], planes=floor,
                       camera=camera, width=WIDTH, height=HEIGHT)


layouts = [view_layout() for _ in range(VIEWS)]
start = time.perf_counter()
renderer = vkray.Renderer(scene_of(*layouts[0]))
made_s = time.perf_counter() - start
placing = rendering = writing = 0.0
with tempfile.TemporaryDirectory() as folder:
    start = time.perf_counter()
    for index, (poses, camera) in enumerate(layouts):
        a = time.perf_counter()
        for mesh, ((vertices, _), pose) in enumerate(zip(models, poses)):
            renderer.set_vertices(mesh, placed(vertices, *pose))
        b = time.perf_counter()
        images = renderer.render(camera, aovs=("depth", "mesh_id"))
        c = time.perf_counter()
        for name, image in images.items():
            np.save(os.path.join(folder, f"view-{index:05}-{name}.npy"), image)
        placing, rendering, writing = placing + b - a, rendering + c - b, writing + time.perf_counter() - c
    loop_s = time.perf_counter() - start
triangles = sum(len(t) for _, t in models)
print(f"{VIEWS} views at {WIDTH}x{HEIGHT}, {len(models)} objects ({triangles} triangles) placed anew in each: "
      f"{loop_s:.2f} s ({VIEWS / loop_s:.1f} views/s; a view: placing {1e3 * placing / VIEWS:.1f} ms, rendering "
      f"{1e3 * rendering / VIEWS:.1f} ms, writing {1e3 * writing / VIEWS:.1f} ms); the Renderer made in {made_s:.2f} s")

poses, camera = layouts[-1]
truth = vkray.Reference(scene_of(poses, camera)).render(aovs=("depth", "mesh_id"))
hit = np.isfinite(truth["depth"]) & np.isfinite(images["depth"])
error = np.abs(images["depth"][hit] - truth["depth"][hit]) / truth["depth"][hit]
flips = int(np.sum(np.isfinite(truth["depth"]) != np.isfinite(images["depth"])))
labels = int(np.sum(truth["mesh_id"] != images["mesh_id"]))
print(f"the last view against the reference: depth rel. error p99 {np.percentile(error, 99):.2e}; {flips} hit/miss "
      f"flips, {labels} pixels labelled with another object, of {WIDTH * HEIGHT}")
