"""Point queries from Python (docs/points.md): the Renderer against the Reference point by point, the
outputs' shapes and types, the shorthands, the largest distance, masks and bad input. The device's
arithmetic over every search, instance and extreme case is tests/point_queries_test.cpp's; here the
package over the C API."""
import os
import subprocess

import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES

# The cube [-1, 1]^3 (mask 1), a sphere of radius 1 at (4, 0, 0) (mask 2) and an open sheet, the
# square [-1, 1]^2 at z = 3 (mask 1): closed, curved and open surfaces.
SHEET = np.array([[-1.0, -1.0, 3.0], [1.0, -1.0, 3.0], [1.0, 1.0, 3.0], [-1.0, 1.0, 3.0]])


@pytest.fixture(scope="module")
def scene():
    return vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES},
                               {"vertices": SHEET, "triangles": [[0, 1, 2], [0, 2, 3]]}],
                       spheres=[[4.0, 0.0, 0.0, 1.0]], masks=[1, 1, 2])


def points_around(count, seed=1):
    rng = np.random.default_rng(seed)
    return rng.uniform([-3.0, -3.0, -3.0], [7.0, 3.0, 5.0], size=(count, 3))


def distance_bound(distance):
    """tests/point_queries_test.cpp's bound for float32 shaders: 16 units of roundoff of the distance
    plus the largest primitive (here the sphere's diameter and the cube's face diagonal, under 3)."""
    return 16.0 * 2.0**-24 * (distance + 3.0)


def test_distances_agree_with_the_reference(renderer, reference):
    points = points_around(4000)
    found = renderer.distance(points)
    exact = reference.distance(points)
    assert found.dtype == np.float32 and exact.dtype == np.float64 and found.shape == (4000,)
    error = np.abs(found - exact)
    assert np.all(error <= distance_bound(exact)), f"worst {error.max()} at point {error.argmax()}"


def test_closest_points_give_every_output_in_the_points_shape(renderer, reference):
    points = points_around(600).reshape(20, 30, 3)
    found = renderer.closest_points(points)
    exact = reference.closest_points(points)
    assert set(found) == set(vkray.CLOSEST_POINT_OUTPUTS)
    assert found["position"].shape == (20, 30, 3) and found["barycentric"].shape == (20, 30, 2)
    assert found["mesh_id"].shape == (20, 30) and found["mesh_id"].dtype == np.uint32
    assert all(array.flags.c_contiguous for array in found.values())
    # The nearest point is where the distance says, on the object the reference names (no ties here:
    # random points of float64 are nowhere equidistant within the bound).
    bound = distance_bound(exact["distance"])
    assert np.all(np.abs(np.linalg.norm(found["position"] - points, axis=-1) - exact["distance"]) <= 2 * bound)
    assert np.array_equal(found["mesh_id"], exact["mesh_id"])
    assert np.all(np.abs(np.linalg.norm(found["normal"], axis=-1) - 1.0) < 1e-5)
    assert np.all(found["instance_id"] == vkray.NO_HIT)


def test_sign_and_occupancy_follow_the_winding_number(renderer, reference):
    points = points_around(3000, seed=2)
    answers = renderer.query_points(points, ["distance", "signed_distance", "winding_number", "occupancy"])
    inside = answers["winding_number"] >= 0.5
    assert np.array_equal(answers["occupancy"].astype(bool), inside)
    assert np.array_equal(answers["signed_distance"], np.where(inside, -answers["distance"], answers["distance"]))
    assert np.array_equal(renderer.occupancy(points), inside)
    # Against the reference where the winding number is not near 1/2: inside the cube and the sphere
    # (1), outside both (0) and beside the open sheet (between), a point at least 0.05 from every
    # surface, where the winding number's bound (tests/point_queries_test.cpp) is under 1e-4.
    exact = reference.winding_number(points)
    away = reference.distance(points) > 0.05
    assert np.all(np.abs(answers["winding_number"][away] - exact[away]) < 1e-4)
    assert np.array_equal(inside[away], exact[away] >= 0.5)
    # Just above the sheet's centre it covers nearly half the sphere of directions: its winding number
    # is near -1/2 on the side its normal (+z, by its winding) faces, +1/2 below: the mesh is open.
    near_sheet = renderer.winding_number([[0.0, 0.0, 3.001], [0.0, 0.0, 2.999]])
    assert -0.5 < near_sheet[0] < -0.49 and 0.49 < near_sheet[1] < 0.5


def test_largest_distance_and_masks(renderer, reference):
    points = np.array([[0.0, 0.0, 1.5], [4.0, 0.0, 2.0], [10.0, 0.0, 0.0]])
    found = renderer.closest_points(points, max_distance=[0.5, 1.0, 1.0])
    assert np.allclose(found["distance"][:2], [0.5, 1.0], atol=1e-6)  # at exactly its bound: found
    assert np.isinf(found["distance"][2]) and np.all(np.isnan(found["position"][2]))
    assert found["mesh_id"][2] == vkray.NO_HIT and found["primitive_id"][2] == vkray.NO_HIT
    assert np.isinf(renderer.distance(points, max_distance=0.25)).all()
    # The sphere alone (mask 2): the cube and the sheet are not there.
    assert np.allclose(renderer.distance(points, mask=2), reference.distance(points, mask=2), atol=1e-5)
    assert np.allclose(renderer.distance([[0.0, 0.0, 0.0]], mask=2), [3.0], atol=1e-6)


def test_double_precision_answers_in_float64(scene):
    renderer = vkray.Renderer(scene, precision="double")
    reference = vkray.Reference(scene)
    points = points_around(500, seed=3)
    found = renderer.distance(points)
    assert found.dtype == np.float64
    assert np.all(np.abs(found - reference.distance(points)) <= 16.0 * 2.0**-53 * (reference.distance(points) + 3.0))


def test_bad_input_is_named(renderer):
    points = np.zeros((5, 3))
    points[3, 1] = np.nan
    with pytest.raises(ValueError, match="point 3"):
        renderer.distance(points)
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\)"):
        renderer.distance(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="not a point output"):
        renderer.query_points(np.zeros((1, 3)), "depth")
    with pytest.raises(ValueError, match="max_distance"):
        renderer.distance(np.zeros((4, 3)), max_distance=np.ones(3))
    with pytest.raises(ValueError, match="max_distance"):
        renderer.distance(np.zeros((2, 3)), max_distance=[1.0, -1.0])
    assert renderer.distance(np.zeros((0, 3))).shape == (0,)


def write_cube(path):
    with open(path, "w") as obj:
        obj.writelines(f"v {x} {y} {z}\n" for x, y, z in CUBE_CORNERS)
        obj.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in CUBE_FACES)


def vkray_points(*arguments):
    return subprocess.run([os.environ["VKRAY_CLI"], "points", *map(str, arguments)], capture_output=True, text=True)


def test_the_command_line_writes_a_grid_and_samples_as_npy(tmp_path):
    cube = tmp_path / "cube.obj"
    write_cube(cube)
    prefix = tmp_path / "grid"
    run = vkray_points(cube, "--grid", 12, "--output", "signed-distance,occupancy,position", "-o", prefix)
    assert run.returncode == 0, run.stderr
    points = np.load(f"{prefix}.points.npy")
    sdf, occupancy = np.load(f"{prefix}.signed-distance.npy"), np.load(f"{prefix}.occupancy.npy")
    assert points.shape == (12, 12, 12, 3) and sdf.shape == (12, 12, 12) and occupancy.dtype == np.uint32
    assert np.load(f"{prefix}.position.npy").shape == (12, 12, 12, 3)
    # [x][y][z]: z runs fastest; the box is the cube's, 1.1 times.
    assert points[0, 0, 1, 2] > points[0, 0, 0, 2] and points[1, 0, 0, 0] > points[0, 0, 0, 0]
    assert np.allclose(points.min(axis=(0, 1, 2)), -1.1 + 2.2 / 24)
    exact = vkray.Reference(vkray.load(str(cube))).signed_distance(points)
    assert np.all(np.abs(sdf - exact) <= distance_bound(np.abs(exact)))
    assert np.array_equal(occupancy == 1, exact < 0)

    prefix = tmp_path / "samples"
    run = vkray_points(cube, "--uniform", 300, "--near-surface", 700, "--sigma", 0.01, "--seed", 5, "-o", prefix, "--reference")
    assert run.returncode == 0, run.stderr
    points, sdf = np.load(f"{prefix}.points.npy"), np.load(f"{prefix}.signed-distance.npy")
    assert points.shape == (1000, 3) and sdf.dtype == np.float64
    # Near the surface: within a few sigma of it (5 sigma: one in 1.7 million leaves).
    assert np.all(np.abs(sdf[300:]) < 0.05) and np.abs(sdf[:300]).max() > 0.2
    given = tmp_path / "given.npy"
    np.save(given, points.astype(np.float32).reshape(10, 100, 3))
    run = vkray_points(cube, "--points", given, "--output", "distance", "-o", tmp_path / "given")
    assert run.returncode == 0, run.stderr
    assert np.load(tmp_path / "given.distance.npy").shape == (1000,)


def test_the_command_line_names_bad_points(tmp_path):
    cube = tmp_path / "cube.obj"
    write_cube(cube)
    bad = tmp_path / "bad.npy"
    np.save(bad, np.zeros((4, 2)))
    out = tmp_path / "p"
    run = vkray_points(cube, "--points", bad, "-o", out)
    assert run.returncode == 2 and "bad.npy" in run.stderr and "last dimension" in run.stderr and run.stderr.count("\n") == 1
    np.save(bad, np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]))
    run = vkray_points(cube, "--points", bad, "-o", out)
    assert run.returncode == 2 and "point 1" in run.stderr
    run = vkray_points(cube, "--grid", 4, "--uniform", 10, "-o", out)
    assert run.returncode == 2 and "one way" in run.stderr
    run = vkray_points(cube, "--grid", 4, "--output", "depth", "-o", out)
    assert run.returncode == 2 and "unknown point output" in run.stderr
    assert not list(tmp_path.glob("p.*"))
