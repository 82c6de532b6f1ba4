"""What a Renderer's setup costs for many instances of a large model, against as many instances of one
triangle beside one copy of the model: an instance costs its placement, not its mesh's vertices, so
the two should take about the same time. Run from the repository root:

    PYTHONPATH=build/python /usr/bin/python3 docs/instances_setup.py ../shared/models/stanford-bunny.obj 100000

Prints each scene's Renderer() time and its upload (scene conversion, trees, upload), best of three
alternating runs, and set_vertices of the model under 10,000 instances.
"""
import sys
import time

import numpy as np

import vkray


def read_obj(path):
    """An OBJ's positions and its faces fanned into triangles (v lines, f lines' vertex indices)."""
    positions, triangles = [], []
    with open(path) as lines:
        for line in lines:
            fields = line.split()
            if fields and fields[0] == "v":
                positions.append([float(x) for x in fields[1:4]])
            elif fields and fields[0] == "f":
                corners = [int(field.split("/")[0]) for field in fields[1:]]
                corners = [c - 1 if c > 0 else len(positions) + c for c in corners]
                triangles += [[corners[0], corners[k], corners[k + 1]] for k in range(1, len(corners) - 1)]
    return np.array(positions), np.array(triangles)


def grid_transforms(count, spacing):
    """count placements on a square grid, each turned about y."""
    side = int(np.ceil(np.sqrt(count)))
    transforms = np.tile(np.eye(4), (count, 1, 1))
    angles = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    transforms[:, 0, 0] = transforms[:, 2, 2] = np.cos(angles)
    transforms[:, 0, 2], transforms[:, 2, 0] = np.sin(angles), -np.sin(angles)
    transforms[:, 0, 3] = spacing * (np.arange(count) % side)
    transforms[:, 2, 3] = spacing * (np.arange(count) // side)
    return transforms


def setup_time(scene):
    """Seconds of Renderer(scene), and its upload in milliseconds (timings['setup'])."""
    start = time.perf_counter()
    renderer = vkray.Renderer(scene)
    seconds = time.perf_counter() - start
    return seconds, renderer.timings["setup"]["upload_ms"], renderer


def main():
    vertices, triangles = read_obj(sys.argv[1])
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 100000
    size = np.ptp(vertices, axis=0).max()
    transforms = grid_transforms(count, 1.5 * size)
    model_instances = vkray.Scene(meshes=[{"vertices": vertices, "triangles": triangles}],
                                  instances=[{"mesh": 0, "transform": m} for m in transforms])
    triangle = np.array([[0.0, 0.0, 0.0], [size, 0.0, 0.0], [0.0, size, 0.0]])
    triangle_instances = vkray.Scene(meshes=[{"vertices": triangle, "triangles": [[0, 1, 2]]},
                                             {"vertices": vertices - [0.0, 2.0 * size, 0.0], "triangles": triangles}],
                                     instances=[{"mesh": 0, "transform": m} for m in transforms])
    best = {"model": (np.inf, np.inf), "triangle": (np.inf, np.inf)}
    for _ in range(3):
        for name, scene in (("model", model_instances), ("triangle", triangle_instances)):
            seconds, upload_ms, _ = setup_time(scene)
            best[name] = (min(best[name][0], seconds), min(best[name][1], upload_ms))
    print(f"{count} instances of {sys.argv[1]} ({len(triangles)} triangles): Renderer() {best['model'][0]:.2f} s, "
          f"upload {best['model'][1]:.0f} ms")
    print(f"{count} instances of one triangle and the model once: Renderer() {best['triangle'][0]:.2f} s, "
          f"upload {best['triangle'][1]:.0f} ms")
    moving = vkray.Scene(meshes=[{"vertices": vertices, "triangles": triangles}],
                         instances=[{"mesh": 0, "transform": m} for m in transforms[:10000]])
    renderer = vkray.Renderer(moving)
    times = []
    for k in range(3):
        renderer.set_vertices(0, vertices * (1.0 + 0.01 * (k + 1)))
        times.append(renderer.timings["scene_update_ms"])
    print(f"set_vertices of the model under {min(count, 10000)} instances: {min(times):.0f} ms (best of 3)")


if __name__ == "__main__":
    main()
