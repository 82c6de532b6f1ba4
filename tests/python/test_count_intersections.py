"""Renderer.count_intersections: how many surfaces each ray crosses, as the Reference counts them; odd
exactly where a ray starts inside a closed mesh, whichever way it points (an edge or vertex passed
exactly through counts once); ranges, t_along, masks, bad rays and the rays' shape as cast_rays takes them."""
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


def test_ranges_masks_and_bad_rays(renderer):
    """From x = -3 along +x the ray crosses the first cube at -1 and 1, the sphere at -0.5 and 0.5, the
    second cube at 3 and 5. A range counts what lies within it, along the unit direction or, with
    t_along='direction', the direction as given (Open3D's segments p to q: t_max=1); the mask leaves out
    the second cube; a bad ray counts 0, or raises with bad_rays='raise'."""
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
