"""What the Python module saves, timed (docs/python.md):

1. Views: VIEWS renders of a model at 640x480 on one vkray.Renderer, the camera turning about the
   model, against as many `vkray render` processes of the same views (each writes its EXR, no PNG).
2. Rays: cast_rays of a 1000x1000 camera's pixel rays (one million rays, given as an array) against
   render() of the same camera's 1000x1000 pixels, best of FRAMES each on the same Renderer: the
   rays listed row by row (they keep their places in packets), in a random order (ordered by
   direction into packets first) and each moved along itself to an origin of its own (no packets:
   every ray walks the tree alone).
3. Rays that share nothing: a million from random points on the sphere of twice the model's radius
   about its centre towards random points within that radius, through cast_rays, and a million
   occlusion queries between pairs of random points within it (t_max the pair's distance) through
   occluded, numpy to numpy, best of FRAMES each, beside Open3D's RaycastingScene (Embree 3 on
   every core: cast_rays and test_occlusions) on the same rays in float32, where Open3D is
   installed (Debian: python3-open3d; the install script leaves it out). `vkray bench --suite rays`
   times Embree itself on rays made the same way.

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/python_speed.py [MODEL.obj] [VIEWS]
"""
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import vkray

MODEL = sys.argv[1] if len(sys.argv) > 1 else "../shared/models/stanford-bunny.obj"
VIEWS = int(sys.argv[2]) if len(sys.argv) > 2 else 100
FRAMES = 10  # best of: a run of lavapipe on 2 shared cores varies by 10-20% from call to call
CLI = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "vkray")


def orbit(camera, count):
    """`count` eyes turned about the vertical axis through the target, at the framed distance."""
    target, eye = np.array(camera["to"]), np.array(camera["from"])
    offset = eye - target
    radius, height = math.hypot(offset[0], offset[2]), offset[1]
    for k in range(count):
        angle = 2 * math.pi * k / count
        yield [target[0] + radius * math.sin(angle), target[1] + height, target[2] + radius * math.cos(angle)]


def pixel_rays(camera, width, height):
    """The camera's pixel rays in double, as docs/outputs.md's output contract defines them."""
    eye, target, up = (np.array(camera[k], dtype=np.float64) for k in ("from", "to", "up"))
    forward = (eye - target) / np.linalg.norm(eye - target)
    right = np.cross(up, forward)
    right /= np.linalg.norm(right)
    distance = 1.0 / math.tan(math.radians(camera["fovy"]) / 2)
    shorter = min(width, height)
    uu, vv = np.meshgrid((2 * np.arange(width) + 1 - width) / shorter, (height - 2 * np.arange(height) - 1) / shorter)
    directions = uu[..., None] * right + vv[..., None] * np.cross(forward, right) - distance * forward
    return np.concatenate([np.broadcast_to(eye, directions.shape), directions], axis=-1).reshape(-1, 6)


def views():
    scene = vkray.load(MODEL, 640, 480)
    eyes = list(orbit(scene.camera, VIEWS))
    start = time.perf_counter()
    renderer = vkray.Renderer(scene)
    for eye in eyes:
        renderer.render({"from": eye})
    in_process = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        for k, eye in enumerate(eyes):
            subprocess.run([CLI, "render", MODEL, "--width", "640", "--height", "480", "--no-preview",
                            "--camera", "from=%r,%r,%r" % tuple(eye), "-o", os.path.join(folder, f"view-{k}.exr")],
                           check=True, capture_output=True)
        processes = time.perf_counter() - start
    print(f"{VIEWS} views at 640x480 of {os.path.basename(MODEL)}: one Renderer {in_process:.2f} s "
          f"({1e3 * in_process / VIEWS:.1f} ms a view, device and upload included); {VIEWS} processes "
          f"{processes:.2f} s ({1e3 * processes / VIEWS:.0f} ms a view); ratio {in_process / processes:.3f}")


def rays():
    scene = vkray.load(MODEL, 1000, 1000)
    renderer = vkray.Renderer(scene)
    given = np.ascontiguousarray(pixel_rays(scene.camera, 1000, 1000))
    generator = np.random.default_rng(1)
    listings = {
        "row by row": given,
        "in a random order": np.ascontiguousarray(generator.permutation(given)),
        # Each origin moved back along its own ray by up to 1% of the framed distance: the same
        # lines, no shared origin.
        "from origins of their own": np.ascontiguousarray(np.concatenate(
            [given[:, :3] - generator.uniform(0, 0.01, (len(given), 1)) * np.linalg.norm(
                np.array(scene.camera["from"]) - np.array(scene.camera["to"])) * given[:, 3:] /
             np.linalg.norm(given[:, 3:], axis=1, keepdims=True), given[:, 3:]], axis=1)),
    }
    for name, rays in listings.items():
        render_s, cast_s = [], []
        for _ in range(FRAMES):
            start = time.perf_counter()
            renderer.render()
            render_s.append(time.perf_counter() - start)
            start = time.perf_counter()
            renderer.cast_rays(rays)
            cast_s.append(time.perf_counter() - start)
        print(f"1,000,000 rays {name}: render() of 1000x1000 pixels {1e3 * min(render_s):.1f} ms, cast_rays() "
              f"of their rays {1e3 * min(cast_s):.1f} ms (best of {FRAMES}, {renderer.timings['rays_walk']}); "
              f"ratio {min(cast_s) / min(render_s):.2f}")


def obj_vertices(path):
    with open(path) as obj:
        return np.array([line.split()[1:4] for line in obj if line.startswith("v ")], dtype=np.float64)


def incoherent():
    vertices = obj_vertices(MODEL)
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    radius = np.linalg.norm(vertices - centre, axis=1).max()
    generator = np.random.default_rng(2)
    count = 1_000_000

    def on_sphere():
        v = generator.normal(size=(count, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    def in_ball():
        return centre + radius * np.cbrt(generator.uniform(size=(count, 1))) * on_sphere()

    renderer = vkray.Renderer(vkray.load(MODEL))
    origins = centre + 2 * radius * on_sphere()
    rays = np.concatenate([origins, in_ball() - origins], axis=1)
    starts = in_ball()
    segments = np.concatenate([starts, in_ball() - starts], axis=1)
    lengths = np.linalg.norm(segments[:, 3:], axis=1)
    calls = {"cast_rays() of rays from random origins": [lambda: renderer.cast_rays(rays)],
             "occluded() of segments between random points": [lambda: renderer.occluded(segments, t_max=lengths)]}
    try:
        import open3d
        mesh = open3d.t.geometry.TriangleMesh.from_legacy(open3d.io.read_triangle_mesh(MODEL))
        scene = open3d.t.geometry.RaycastingScene()
        scene.add_triangles(mesh)
        unit = np.concatenate([rays[:, :3], rays[:, 3:] / np.linalg.norm(rays[:, 3:], axis=1, keepdims=True)], axis=1)
        o3d_rays = open3d.core.Tensor(unit.astype(np.float32))
        # Open3D's distances are in units of the direction's length: the segment itself up to 1.
        o3d_segments = open3d.core.Tensor(segments.astype(np.float32))
        calls["cast_rays() of rays from random origins"].append(lambda: scene.cast_rays(o3d_rays))
        calls["occluded() of segments between random points"].append(lambda: scene.test_occlusions(o3d_segments, tfar=1.0))
    except ImportError:
        print("Open3D is not installed (Debian: python3-open3d): vkray alone")

    def best(call):
        times = []
        for _ in range(FRAMES):
            start = time.perf_counter()
            call()
            times.append(time.perf_counter() - start)
        return min(times)

    for name, (vkray_call, *open3d_call) in calls.items():
        vkray_s = best(vkray_call)
        line = (f"1,000,000 {name}: {1e3 * vkray_s:.1f} ms (best of {FRAMES}, {renderer.timings['rays_walk']}), "
                f"{count / vkray_s / 1e6:.2f} Mrays/s")
        if open3d_call:
            open3d_s = best(open3d_call[0])
            line += f"; Open3D {1e3 * open3d_s:.1f} ms; Open3D's time over vkray's {open3d_s / vkray_s:.2f}"
        print(line)


if __name__ == "__main__":
    print(f"device: {vkray.Renderer(vkray.load('', 8, 8)).device_name}")
    views()
    rays()
    incoherent()
