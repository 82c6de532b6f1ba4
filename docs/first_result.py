"""Time to a first result from Python against a whole `vkray render` process of the same model and
size, one after the other, each in a process of its own (docs/python.md): vkray.load + Renderer() +
the first render() at 640x480, and vkray.load + Renderer() + a first cast_rays of 65,536 rays.

    PYTHONPATH=build/python /usr/bin/python3 docs/first_result.py [MODEL] [ROUNDS]
"""
import os
import subprocess
import sys
import tempfile
import time

model = sys.argv[1] if len(sys.argv) > 1 else "../shared/models/stanford-bunny.obj"
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
vkray_command = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "vkray")

# Each snippet prints its own time from before vkray.load (the import of numpy and vkray excluded,
# as the process's start is excluded from the render's time below: both are what any script pays).
first_render = f"""
import time, vkray
start = time.perf_counter()
renderer = vkray.Renderer(vkray.load({model!r}, 640, 480))
renderer.render()
print(time.perf_counter() - start)
"""
first_cast = f"""
import time, numpy as np, vkray
rays = np.hstack([np.tile([-0.02, 0.1, 0.3], (65536, 1)), np.random.default_rng(1).normal(size=(65536, 3))])
start = time.perf_counter()
renderer = vkray.Renderer(vkray.load({model!r}, 640, 480))
renderer.cast_rays(rays)
print(time.perf_counter() - start)
"""


def python_seconds(snippet):
    return float(subprocess.run([sys.executable, "-c", snippet], check=True, capture_output=True, text=True).stdout)


def render_process_seconds(folder):
    start = time.perf_counter()
    subprocess.run([vkray_command, "render", model, "--width", "640", "--height", "480", "-o", os.path.join(folder, "first.exr")],
                   check=True, capture_output=True)
    return time.perf_counter() - start


with tempfile.TemporaryDirectory() as folder:
    times = {"vkray render process": [], "Python: load, Renderer(), render()": [], "Python: load, Renderer(), cast_rays(65536)": []}
    for _ in range(rounds):  # one after the other, round by round: a busy moment slows all three
        times["vkray render process"].append(render_process_seconds(folder))
        times["Python: load, Renderer(), render()"].append(python_seconds(first_render))
        times["Python: load, Renderer(), cast_rays(65536)"].append(python_seconds(first_cast))
whole = min(times["vkray render process"])
for name, seconds in times.items():
    print(f"{name:44s} best of {rounds}: {min(seconds):.2f} s ({min(seconds) / whole:.2f}x the render process)")
