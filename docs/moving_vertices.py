"""A deforming mesh (docs/python.md): the bunny with every vertex moved by up to 1% of its size,
through Renderer.set_vertices, which refits the tree (keeps its shape, recomputes its boxes; from the
second call on in place), against the same call where one triangle also collapses to a point or
opens again, which builds the tree anew. Then the render after a refit against a Renderer made from
the moved bunny (its tree built for it): GPU time, and the depth's relative error against the
double-precision reference. Best of CALLS.

Run from the repository root after building:
    PYTHONPATH=build/python /usr/bin/python3 docs/moving_vertices.py [MODEL.obj] [CALLS]
"""
import sys

import numpy as np

import vkray
from obj_arrays import load_obj

MODEL = sys.argv[1] if len(sys.argv) > 1 else "../shared/models/stanford-bunny.obj"
CALLS = int(sys.argv[2]) if len(sys.argv) > 2 else 5

scene = vkray.load(MODEL, 1920, 1080)  # for its framed camera
vertices, triangles = load_obj(MODEL)
scene = vkray.Scene(vertices, triangles, camera=scene.camera, width=1920, height=1080)
size = np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0))
rng = np.random.default_rng(1)


def moved_bunny():
    return vertices + rng.uniform(-0.01 * size, 0.01 * size, size=vertices.shape)


def best_render(renderer):
    return min(renderer.render(aovs="depth") and renderer.timings["dispatch_gpu_ms"] for _ in range(CALLS))


# Two renderers: one refits at every call; the other collapses one triangle at every other call and
# restores it at the next, so that its primitives change at each and every call builds the tree.
renderer, rebuilder = vkray.Renderer(scene), vkray.Renderer(scene)
refit, rebuild = [], []
for call in range(2 * CALLS):
    renderer.set_vertices(0, moved_bunny())
    assert renderer.timings["tree_refitted"]
    refit.append(renderer.timings["scene_update_ms"])
    positions = moved_bunny()
    if call % 2 == 0:
        positions[triangles[0, 1]] = positions[triangles[0, 2]] = positions[triangles[0, 0]]
    rebuilder.set_vertices(0, positions)
    assert not rebuilder.timings["tree_refitted"]
    rebuild.append(rebuilder.timings["scene_update_ms"])
del rebuilder
print(f"set_vertices of {len(vertices)} vertices: refit {min(refit):.1f} ms, rebuild {min(rebuild):.1f} ms "
      f"(refit / rebuild {min(refit) / min(rebuild):.2f}; best of {CALLS})")

positions = moved_bunny()
renderer.set_vertices(0, positions)
moved_scene = vkray.Scene(meshes=[{"vertices": positions, "triangles": triangles}], camera=scene.camera,
                          width=1920, height=1080)
built = vkray.Renderer(moved_scene)
truth = vkray.Reference(moved_scene).render(aovs="depth")["depth"]
for name, caster in (("refitted tree", renderer), ("tree built for it", built)):
    gpu_ms = best_render(caster)
    depth = caster.render(aovs="depth")["depth"]
    hit = np.isfinite(truth) & np.isfinite(depth)
    error = np.abs(depth[hit] - truth[hit]) / truth[hit]
    flips = int(np.sum(np.isfinite(truth) != np.isfinite(depth)))
    print(f"render 1920x1080 after the move, {name}: {gpu_ms:.1f} ms GPU time (best of {CALLS}); depth rel. error "
          f"p99 {np.percentile(error, 99):.2e} max {error.max():.2e} (a silhouette's pixel may meet the surface behind), "
          f"{flips} hit/miss flips")
