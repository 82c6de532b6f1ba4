"""How long a Renderer's constructor takes, and each kind of call's first run against its tenth, for
the bunny at 640x480 (docs/python.md): each call makes its pipeline at its first use, or, with
--prepare, Renderer.prepare() makes them all first.

    PYTHONPATH=build/python /usr/bin/python3 docs/python_first_calls.py [MODEL] [--prepare]
"""
import sys
import time

import numpy as np

import vkray

arguments = [argument for argument in sys.argv[1:] if argument != "--prepare"]
model = arguments[0] if arguments else "../shared/models/stanford-bunny.obj"
scene = vkray.load(model, 640, 480)
start = time.perf_counter()
renderer = vkray.Renderer(scene)
if "--prepare" in sys.argv:
    renderer.prepare()
setup = renderer.timings["setup"]
print(f"constructor {1e3 * (time.perf_counter() - start):.0f} ms (upload {setup['upload_ms']:.0f} ms, "
      f"making and first running the pipelines {setup['pipeline_ms']:.0f} ms) on {renderer.device_name}")
rng = np.random.default_rng(1)
directions = rng.normal(size=(100_000, 3))
sensor = np.hstack([np.broadcast_to(scene.camera["from"], (100_000, 3)), directions])
scattered = np.hstack([rng.uniform(-0.1, 0.1, size=(100_000, 3)), directions])
calls = [("render", lambda: renderer.render()),
         ("cast_rays, one origin", lambda: renderer.cast_rays(sensor)),
         ("cast_rays, many origins", lambda: renderer.cast_rays(scattered)),
         ("occluded, t_max", lambda: renderer.occluded(scattered, t_max=0.05))]
for name, call in calls:
    times = []
    for _ in range(10):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    print(f"{name:24s} first {1e3 * times[0]:6.1f} ms, tenth {1e3 * times[-1]:6.1f} ms: {times[0] / times[-1]:.2f} times")
