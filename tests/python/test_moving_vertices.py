"""Renderer.set_vertices and Reference.set_vertices (a deforming mesh): after the move, every call
gives what a renderer (or reference) made from the moved scene gives, bit for bit; the GPU's tree is
refitted while the triangles keep their areas; bad input raises ValueError and changes nothing."""
import numpy as np
import pytest

import vkray


def grid(cells):
    """A wavy square of cells x cells quads in the plane y = 0, facing the camera from above."""
    u, v = np.meshgrid(np.linspace(-1, 1, cells + 1), np.linspace(-1, 1, cells + 1))
    vertices = np.stack([u.ravel(), 0.05 * np.sin(3 * u.ravel()), v.ravel()], axis=1)
    a = (np.arange(cells)[:, None] * (cells + 1) + np.arange(cells)[None, :]).ravel()
    triangles = np.concatenate([np.stack([a, a + 1, a + cells + 2], 1), np.stack([a, a + cells + 2, a + cells + 1], 1)])
    return vertices, triangles


CAMERA = {"from": [0.3, 2.5, 1.5], "to": [0.0, 0.0, 0.0], "fovy": 50}


def scene_of(vertices, triangles):
    return vkray.Scene(meshes=[{"vertices": vertices, "triangles": triangles}],
                       spheres=np.array([[0.0, 0.4, 0.0, 0.2]]), camera=CAMERA, width=80, height=60)


def rays_from_above(count=4096, seed=3):
    rng = np.random.default_rng(seed)
    origins = np.column_stack([rng.uniform(-1, 1, count), np.full(count, 2.0), rng.uniform(-1, 1, count)])
    return np.hstack([origins, np.tile([0.0, -1.0, 0.0], (count, 1)) + rng.normal(scale=0.05, size=(count, 3))])


@pytest.mark.parametrize("make", [vkray.Renderer, vkray.Reference], ids=["renderer", "reference"])
def test_a_moved_mesh_answers_as_the_moved_scene(make):
    vertices, triangles = grid(24)
    caster = make(scene_of(vertices, triangles))
    rays = rays_from_above()
    before = caster.cast_rays(rays)
    moved = vertices.copy()
    moved[:, 1] += 0.2 * np.cos(2 * moved[:, 0]) * np.cos(2 * moved[:, 2])  # a wave through the sheet
    caster.set_vertices(0, moved)
    if make is vkray.Renderer:
        assert caster.timings["tree_refitted"] is True
        assert caster.timings["scene_update_ms"] > 0
    fresh = make(scene_of(moved, triangles))
    after, expected = caster.cast_rays(rays), fresh.cast_rays(rays)
    assert not np.array_equal(after["t"], before["t"])
    for key in ("t", "normal", "mesh_id", "primitive_id"):
        np.testing.assert_array_equal(after[key], expected[key])
    for key in ("depth", "normal"):
        np.testing.assert_array_equal(caster.render()[key], fresh.render()[key])
    # The surface outputs of given rays read the moved mesh too.
    np.testing.assert_array_equal(caster.cast_rays(rays, outputs="barycentric")["barycentric"],
                                  fresh.cast_rays(rays, outputs="barycentric")["barycentric"])


def test_a_triangle_of_zero_area_builds_the_tree_anew():
    vertices, triangles = grid(8)
    renderer = vkray.Renderer(scene_of(vertices, triangles))
    moved = vertices.copy()
    moved[triangles[3, 1]] = moved[triangles[3, 0]]
    moved[triangles[3, 2]] = moved[triangles[3, 0]]
    renderer.set_vertices(0, moved)
    assert renderer.timings["tree_refitted"] is False
    rays = rays_from_above()
    expected = vkray.Renderer(scene_of(moved, triangles)).cast_rays(rays)
    np.testing.assert_array_equal(renderer.cast_rays(rays)["t"], expected["t"])


def test_bad_input_raises_and_changes_nothing():
    vertices, triangles = grid(8)
    renderer = vkray.Renderer(scene_of(vertices, triangles))
    rays = rays_from_above()
    before = renderer.cast_rays(rays)["t"]
    with pytest.raises(ValueError, match="the scene has 1 meshes"):
        renderer.set_vertices(1, vertices)
    with pytest.raises(ValueError, match="80 positions for its 81 vertices"):
        renderer.set_vertices(0, vertices[:80])
    with pytest.raises(ValueError, match="N x 3"):
        renderer.set_vertices(0, vertices[:, :2])
    for bad in (np.nan, 1e16):
        moved = vertices.copy()
        moved[5, 0] = bad
        with pytest.raises(ValueError, match="vertex 5"):
            renderer.set_vertices(0, moved)
    with pytest.raises(ValueError, match="mesh: expected a mesh_id"):
        renderer.set_vertices(-1, vertices)
    np.testing.assert_array_equal(renderer.cast_rays(rays)["t"], before)


def test_a_loaded_model_gives_the_vertices_set_vertices_takes(tmp_path):
    """A model opened with vkray.load is deformed from its own arrays (issue 64: a Scene showed no
    vertices, and a count of the vertices the faces use, 34834 of the bunny's 35947, was refused):
    Scene.vertices(mesh) is every vertex of the file in its order, used or not, triangles(mesh) the
    faces' indices into them, and set_vertices of them moved answers as the moved scene."""
    model = tmp_path / "quad.obj"
    model.write_text("v -1 -1 0\nv 1 -1 0\nv 9 9 9\nv 1 1 0\nv -1 1 0\nf 1 2 4\nf 1 4 5\n")
    scene = vkray.load(str(model), width=40, height=30)
    vertices, triangles = scene.vertices(0), scene.triangles(0)
    assert vertices.dtype == np.float64 and triangles.dtype == np.uint32
    assert np.array_equal(vertices, [[-1, -1, 0], [1, -1, 0], [9, 9, 9], [1, 1, 0], [-1, 1, 0]])
    assert np.array_equal(triangles, [[0, 1, 3], [0, 3, 4]])
    reference = vkray.Reference(scene)
    ray = np.array([[0.2, 0.3, 5.0, 0.0, 0.0, -1.0]])
    assert reference.cast_rays(ray)["t"][0] == pytest.approx(5.0, rel=4 * 2.0**-52)
    reference.set_vertices(0, vertices + [0.0, 0.0, 1.5])
    assert reference.cast_rays(ray)["t"][0] == pytest.approx(3.5, rel=4 * 2.0**-52)  # a few fp64 roundings
    with pytest.raises(ValueError, match="mesh 1: the scene has 1 meshes"):
        scene.vertices(1)
