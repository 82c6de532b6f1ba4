"""Every hit along a ray. Renderer.count_intersections: how many surfaces each ray crosses, as the
Reference counts them; odd exactly where a ray starts inside a closed mesh, whichever way it points (an
edge or vertex passed exactly through counts once). cast_rays(hits=K): the first K of those crossings in
order, as the Reference lists them. Ranges, t_along, masks, bad rays and the rays' shape as cast_rays
takes them."""
import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES


@pytest.fixture(scope="module")
def scene():
    """Two closed cubes (the second, mask 2, beside the first) and a sphere inside the first."""
    meshes = [{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}, {"vertices": CUBE_CORNERS + [4.0, 0.0, 0.0], "triangles": CUBE_FACES}]
    return vkray.Scene(meshes=meshes, spheres=[[0.0, 0.0, 0.0, 0.5]], masks={1: 2})


def test_odd_exactly_inside_a_closed_mesh(renderer, reference):
    """Points in and around the cubes at odd multiples of a quarter (never on a face or the sphere),
    each with rays along the axes and diagonals, many through the cubes' edges and corners (each face
    is two triangles along a diagonal): the count is the Reference's, and odd exactly where the point
    lies inside one closed surface (a cube or the sphere) and not the other."""
    x = np.arange(-1.75, 6.0, 0.5)
    yz = np.arange(-1.75, 2.0, 0.5)
    points = np.stack(np.meshgrid(x, yz, yz, indexing="ij"), axis=-1).reshape(-1, 3)
    directions = np.array([[1, 0, 0], [0, -1, 0], [0, 0, 1], [1, 1, 1], [-1, 1, -1], [1, 1, 0], [0, -1, 1]], dtype=float)
    rays = np.concatenate(np.broadcast_arrays(points[:, None, :], directions[None, :, :]), axis=-1)
    counts = renderer.count_intersections(rays)
    assert counts.shape == rays.shape[:-1] and counts.dtype == np.uint32
    assert np.array_equal(counts, reference.count_intersections(rays))
    inside_cube = np.all(np.abs(points) < 1, axis=1) | np.all(np.abs(points - [4.0, 0.0, 0.0]) < 1, axis=1)
    inside_sphere = np.linalg.norm(points, axis=1) < 0.5
    assert inside_sphere.any() and (inside_cube & ~inside_sphere).any()
    assert np.array_equal(counts % 2 == 1, np.repeat((inside_cube ^ inside_sphere)[:, None], len(directions), axis=1))


@pytest.mark.parametrize("caster", ["renderer", "reference"])
def test_ranges_masks_and_bad_rays(caster, request):
    """From x = -3 along +x the ray crosses the first cube at -1 and 1, the sphere at -0.5 and 0.5, the
    second cube at 3 and 5. A range counts what lies within it, along the unit direction or, with
    t_along='direction', the direction as given (Open3D's segments p to q: t_max=1); the mask leaves out
    the second cube; a bad ray counts 0, or raises with bad_rays='raise'. The Renderer and the Reference alike."""
    renderer = request.getfixturevalue(caster)
    ray = [-3.0, 0.1, 0.2, 1.0, 0.0, 0.0]
    assert renderer.count_intersections(ray) == 6
    assert renderer.count_intersections(ray, t_max=2.75) == 2
    assert renderer.count_intersections(ray, t_min=2.75, t_max=7.0) == 3
    assert renderer.count_intersections(ray, mask=1) == 4
    segment = [-3.0, 0.1, 0.2, 4.5, 0.0, 0.0]  # from x = -3 to x = 1.5, past the first cube's far face
    assert renderer.count_intersections(segment, t_max=1, t_along="direction") == 4
    bad = np.array([ray, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    assert list(renderer.count_intersections(bad)) == [6, 0]
    with pytest.raises(ValueError, match="ray 1"):
        renderer.count_intersections(bad, bad_rays="raise")


EPS = 2.0**-24  # float32 unit roundoff


def test_first_hits_as_the_reference(renderer, reference):
    """Rays along +x through both cubes and the sphere (6 crossings, met head on, away from the cubes'
    edges): the first 4 and the first 8 (misses past the 6th) are the Reference's, in order: the same
    meshes and primitives, t within a few float32 roundings of the distance from the scene's far side
    (positions and directions good to 2 eps, head-on hits), normals within 32 eps, the positions on the
    ray; arrays of shape (..., hits) and (..., hits, 3)."""
    rng = np.random.default_rng(5)
    offsets = rng.uniform(-0.35, 0.35, size=(400, 2))  # within the sphere (radius 0.5)
    offsets = offsets[np.abs(np.abs(offsets[:, 0]) - np.abs(offsets[:, 1])) > 0.02][:300]  # off the faces' diagonals
    count = len(offsets) // 2
    offsets = offsets[:2 * count].reshape(2, count, 2)
    rays = np.zeros((2, count, 6))
    rays[..., 0] = -3.0
    rays[..., 1:3] = offsets
    rays[..., 3] = 1.0
    for hits in (4, 8):
        got = renderer.cast_rays(rays, hits=hits, outputs=("t", "normal", "mesh_id", "primitive_id", "position"))
        want = reference.cast_rays(rays, hits=hits, outputs=("t", "normal", "mesh_id", "primitive_id"))
        assert got["t"].shape == (2, count, hits) and got["normal"].shape == (2, count, hits, 3)
        assert np.array_equal(got["mesh_id"], want["mesh_id"]) and np.array_equal(got["primitive_id"], want["primitive_id"])
        assert list(want["mesh_id"][0, 0]) == [0, 2, 2, 0, 1, 1, vkray.NO_HIT, vkray.NO_HIT][:hits]
        hit = np.isfinite(want["t"])
        assert np.array_equal(np.isfinite(got["t"]), hit) and hit.sum() == 2 * count * min(hits, 6)
        assert np.all(np.abs(got["t"][hit] - want["t"][hit]) <= 8 * EPS * (want["t"][hit] + 8.0))
        assert np.all(np.linalg.norm(got["normal"] - want["normal"], axis=-1)[hit] <= 32 * EPS)  # the chord: the angle
        along = rays[..., None, :3] + np.where(hit, got["t"], 0.0)[..., None] * rays[..., None, 3:]
        assert np.allclose(got["position"][hit], along[hit], atol=1e-5) and not got["position"][~hit].any()


@pytest.mark.parametrize("traversal", vkray.traversals)
def test_first_hits_of_two_triangles_in_every_traversal(traversal):
    """Two triangles, one behind the other (a tree of a single leaf, which the walk must visit once):
    the near one at 5, the far one at 6, then misses; the first of them is the nearest hit."""
    def triangle(z):
        return {"vertices": np.array([[-1.0, -1.0, z], [1.0, -1.0, z], [0.0, 1.0, z]]), "triangles": np.array([[0, 1, 2]])}
    scene = vkray.Scene(meshes=[triangle(0.0), triangle(-1.0)])
    try:
        renderer = vkray.Renderer(scene, traversal=traversal)
    except vkray.Error as error:
        pytest.skip(f"{traversal}: {error}")
    got = renderer.cast_rays([0.0, 0.0, 5.0, 0.0, 0.0, -1.0], hits=3, outputs=("t", "mesh_id"))
    assert list(got["mesh_id"]) == [0, 1, vkray.NO_HIT]
    assert list(got["t"]) == [5.0, 6.0, np.inf]


def test_hits_out_of_range_are_refused(renderer):
    for hits in (0, vkray.HITS_MAX + 1, True, 2.5):
        with pytest.raises(ValueError, match="hits"):
            renderer.cast_rays([0.0, 0.0, 5.0, 0.0, 0.0, -1.0], hits=hits)
