"""The host's part of cast_rays (docs/command-line.md, "On a GPU: transfers and long dispatches"): a call's wall
time less its dispatches' GPU time (timings['dispatch_gpu_ms'], which holds ordering the rays by
direction where the device does it, timings['order_gpu_ms']), for a million rays from one origin
given two ways: a sensor's 256 rows of 4096 (elevation -15..15 degrees, azimuth -30..30 about the
view of the bunny) and directions drawn over the whole sphere. Best of CALLS calls each, float64
rays (the C API's own type: no conversion in Python).

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/cast_rays_host_part.py [MODEL.obj] [CALLS]
"""
import sys
import time

import numpy as np

import vkray

MODEL = sys.argv[1] if len(sys.argv) > 1 else "../shared/models/stanford-bunny.obj"
CALLS = int(sys.argv[2]) if len(sys.argv) > 2 else 5

scene = vkray.load(MODEL, 64, 64)
renderer = vkray.Renderer(scene)
eye, target = np.array(scene.camera["from"]), np.array(scene.camera["to"])
forward = (target - eye) / np.linalg.norm(target - eye)
right = np.cross(forward, [0.0, 1.0, 0.0])
right /= np.linalg.norm(right)
up = np.cross(right, forward)
elevation = np.radians(np.linspace(-15, 15, 256))[:, None]
azimuth = np.radians(np.linspace(-30, 30, 4096))[None, :]
sensor = (np.cos(elevation) * np.cos(azimuth))[..., None] * forward + \
         (np.cos(elevation) * np.sin(azimuth))[..., None] * right + np.sin(elevation)[..., None] * up
sphere = np.random.default_rng(1).normal(size=(1 << 20, 3))
for name, directions in (("a sensor's 256 rows of 4096", sensor.reshape(-1, 3)), ("directions over the sphere", sphere)):
    rays = np.ascontiguousarray(np.concatenate([np.broadcast_to(eye, directions.shape), directions], axis=-1))
    best = None
    for _ in range(CALLS):
        start = time.perf_counter()
        renderer.cast_rays(rays)
        wall = 1e3 * (time.perf_counter() - start)
        if best is None or wall < best[0]:
            best = (wall, dict(renderer.timings))
    wall, timings = best
    gpu = timings["dispatch_gpu_ms"]
    where = "the device read the rays and wrote the hits in place" if timings["rays_in_place"] else "through the host"
    ordered = f", of which ordering them {timings['order_gpu_ms']:.1f} ms" if "order_gpu_ms" in timings else ""
    print(f"{name}: {len(rays)} rays, call {wall:.1f} ms, dispatches {gpu:.1f} ms (GPU time{ordered}), host's part "
          f"{100 * (wall - gpu) / wall:.0f}% (ordering and writing the rays {timings['rays_ms']:.1f} ms, reading hits "
          f"back {timings['readback_ms']:.1f} ms; walk: {timings['rays_walk']}, {where})")
