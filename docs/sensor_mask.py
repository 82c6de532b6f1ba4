"""Ray masks (docs/python.md, "Ray masks"): a robot (the armadillo, standing in for one) carries a spinning
sensor of 64 rings of 1024 rays at its chest, inside its own body's surface; the room holds the dragon and
the bunny. The robot has mask 2, everything else 1:

1. mask=1, the sensor's rays pass through its own robot: its hits against a renderer made from the
   scene without the robot (mesh ids the same, distances within float32's error), and against the
   reference with the same mask;
2. what masks cost: the best of ROUNDS rounds of CALLS calls of cast_rays (the sensor) and of a
   1920x1080 render of the room's camera, in the scene without masks, then with them (mask=255: the
   same hits, the masks tested; mask=1: the robot left out).

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/sensor_mask.py [CALLS] [ROUNDS]
"""
import math
import os
import sys
import time

import numpy as np

import vkray
from obj_arrays import load_obj, room

CALLS = int(sys.argv[1]) if len(sys.argv) > 1 else 20
ROUNDS = int(sys.argv[2]) if len(sys.argv) > 2 else 3
MODELS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "models")
ROBOT, EVERYTHING_ELSE = 2, 1

robot, robot_triangles = load_obj(os.path.join(MODELS, "armadillo-50k.obj"), 1.6)
dragon, dragon_triangles = load_obj(os.path.join(MODELS, "stanford-dragon-100k.obj"), 1.0)
bunny, bunny_triangles = load_obj(os.path.join(MODELS, "stanford-bunny.obj"), 0.5)
walls, wall_triangles = room(5.0, 3.0)
meshes = [{"vertices": robot, "triangles": robot_triangles},
          {"vertices": dragon + [3.0, 0.0, 1.0], "triangles": dragon_triangles},
          {"vertices": bunny + [-2.0, 0.0, 2.5], "triangles": bunny_triangles},
          {"vertices": walls, "triangles": wall_triangles}]
floor = [[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]]
camera = {"from": [-4.0, 2.5, 4.5], "to": [0.5, 0.6, 0.0], "fovy": 60}
masks = {0: ROBOT, 1: EVERYTHING_ELSE, 2: EVERYTHING_ELSE, 3: EVERYTHING_ELSE, 4: EVERYTHING_ELSE}
masked = vkray.Scene(meshes=meshes, planes=floor, camera=camera, width=1920, height=1080, masks=masks)
plain = vkray.Scene(meshes=meshes, planes=floor, camera=camera, width=1920, height=1080)
without_robot = vkray.Scene(meshes=meshes[1:], planes=floor, camera=camera, width=1920, height=1080)

elevation, azimuth = np.meshgrid(np.radians(np.linspace(-15, 15, 64)), np.linspace(0, 2 * math.pi, 1024, endpoint=False),
                                 indexing="ij")
directions = np.stack([np.cos(elevation) * np.cos(azimuth), np.sin(elevation), np.cos(elevation) * np.sin(azimuth)], -1)
sensor = np.array([0.0, 1.1, 0.0])  # inside the armadillo's chest
rays = np.concatenate([np.broadcast_to(sensor, directions.shape), directions], -1).reshape(-1, 6)

renderer = vkray.Renderer(masked)
own = renderer.cast_rays(rays, mask=EVERYTHING_ELSE)
alone = vkray.Renderer(without_robot).cast_rays(rays)
reference = vkray.Reference(masked).cast_rays(rays, mask=EVERYTHING_ELSE)
everything = renderer.cast_rays(rays)
print(f"{len(rays)} rays from inside the robot: {np.mean(everything['mesh_id'] == 0):.1%} hit the robot with every bit, "
      f"{np.sum(own['mesh_id'] == 0)} with mask={EVERYTHING_ELSE}")
# The scene without the robot numbers its objects one lower.
same_ids = np.array_equal(own["mesh_id"], np.where(alone["mesh_id"] == vkray.NO_HIT, vkray.NO_HIT, alone["mesh_id"] + 1))
hit = np.isfinite(reference["t"])
error = np.abs(own["t"][hit] - reference["t"][hit]) / reference["t"][hit]
print(f"against the scene without the robot: mesh ids {'the same' if same_ids else 'DIFFER'}, t relative difference "
      f"max {np.max(np.abs(own['t'][hit] - alone['t'][hit]) / alone['t'][hit]):.2e}; against the reference with "
      f"the mask: {np.sum(np.isfinite(own['t']) != hit)} hit/miss flips, t rel. error p99 {np.quantile(error, 0.99):.2e} "
      f"max {error.max():.2e}")


def best_ms(call):
    """The best round's time of one call, in ms."""
    best = math.inf
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for _ in range(CALLS):
            call()
        best = min(best, (time.perf_counter() - start) * 1000.0 / CALLS)
    return best


plain_renderer = vkray.Renderer(plain)
rows = [("no masks", plain_renderer, 255), ("masks, mask=255", renderer, 255), (f"masks, mask={EVERYTHING_ELSE}", renderer, 1)]
print(f"best of {ROUNDS} rounds of {CALLS} calls, ms a call: cast_rays ({len(rays)} rays) / render 1920x1080 (depth, "
      f"normal)")
for name, caster, mask in rows:
    cast = best_ms(lambda: caster.cast_rays(rays, mask=mask, outputs=("t", "mesh_id")))
    image = best_ms(lambda: caster.render(mask=mask))
    print(f"  {name:18} {cast:7.1f} / {image:7.1f}")
