"""vkray.open3d's RaycastingScene against Open3D's documented conventions (docs/open3d.md): a script
written for open3d.t.geometry.RaycastingScene runs with its import changed. Each test encodes what
Open3D documents or computes (t in units of the direction, the winding normal, Embree's u and v, the
pinhole's pixel centres at x + 0.5), checked against geometry whose answers are known exactly or
against vkray's double-precision reference; Open3D itself is not needed."""
from types import SimpleNamespace

import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES
from vkray.open3d import INVALID_ID, RaycastingScene

EPS = 2.0**-24  # float32 unit roundoff


class FakeTensor:
    """What a script passes in: an Open3D tensor, which numpy reads through .numpy()."""

    def __init__(self, array):
        self.array = np.asarray(array)

    def numpy(self):
        return self.array


def cube_scene():
    scene = RaycastingScene()
    assert scene.add_triangles(FakeTensor(CUBE_CORNERS.astype(np.float32)), FakeTensor(CUBE_FACES.astype(np.uint32))) == 0
    return scene


def test_cast_rays_gives_open3d_keys_t_in_direction_units_and_winding_normals():
    """t_hit counts in units of the direction as given; primitive_normals is the triangle's own normal
    by its winding (the cube's outward, the inside-out copy's inward), whichever side the ray meets;
    primitive_uvs are the weights of the second and third vertices; a miss is inf, INVALID_ID and zeros."""
    scene = cube_scene()
    inside_out = SimpleNamespace(vertex=SimpleNamespace(positions=FakeTensor(CUBE_CORNERS + [0.0, 0.0, -10.0])),
                                 triangle=SimpleNamespace(indices=FakeTensor(CUBE_FACES[:, ::-1])))
    assert scene.add_triangles(inside_out) == 1
    rays = np.array([[0.2, 0.3, 5.0, 0.0, 0.0, -2.0],      # the cube's +z face from outside, at t = 4 / 2
                     [0.2, 0.3, 0.0, 0.0, 0.0, 2.0],       # the same face from inside, at t = 1 / 2
                     [0.2, 0.3, -5.0, 0.0, 0.0, -0.5],     # the copy's +z face from outside, at t = 4 / 0.5
                     [0.2, 0.3, 5.0, 0.0, 3.0, 0.0]], np.float32)  # a miss
    result = scene.cast_rays(FakeTensor(rays))
    assert set(result) == {"t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    t = result["t_hit"].numpy()
    assert type(t) is np.ndarray and t.dtype == np.float32 and t.shape == (4,)
    assert np.allclose(t[:3], [2.0, 0.5, 8.0], rtol=16 * EPS, atol=0) and t[3] == np.inf
    assert list(result["geometry_ids"].numpy()) == [0, 0, 1, INVALID_ID]
    assert result["primitive_ids"].numpy()[3] == INVALID_ID
    normals = result["primitive_normals"].numpy()
    # The winding's normal whichever side is met: (0, 0, 1) from outside and inside alike, and the
    # inside-out copy's (0, 0, -1) though its ray meets it from above.
    assert np.allclose(normals[:3], [[0, 0, 1], [0, 0, 1], [0, 0, -1]], atol=EPS)
    assert np.all(normals[3] == 0) and np.all(result["primitive_uvs"].numpy()[3] == 0)
    # The hit point from the uvs: (1 - u - v) v0 + u v1 + v v2 is origin + t direction.
    for k, corners in ((0, CUBE_CORNERS), (1, CUBE_CORNERS), (2, CUBE_CORNERS + [0.0, 0.0, -10.0])):
        faces = CUBE_FACES if k < 2 else CUBE_FACES[:, ::-1]
        v0, v1, v2 = corners[faces[result["primitive_ids"].numpy()[k]]]
        u, v = result["primitive_uvs"].numpy()[k].astype(float)
        assert np.allclose((1 - u - v) * v0 + u * v1 + v * v2, rays[k, :3] + t[k] * rays[k, 3:], atol=8 * EPS * 10)


def test_cast_rays_agrees_with_the_reference_on_rays_of_any_shape():
    """Rays of shape (H, W, 6), directions of any length: t_hit within float32's rounding of the fp64
    reference's t along the direction (a few roundings of coordinates up to 4 away: 16 EPS * 4 / |d|)."""
    scene = cube_scene()
    rng = np.random.default_rng(7)
    origins = rng.uniform(-4, 4, size=(12, 16, 3))
    # Aimed at points around the cube, of lengths 0.2 to 3 times the way there: most hit, some miss.
    directions = (rng.uniform(-1.4, 1.4, size=(12, 16, 3)) - origins) * rng.uniform(0.2, 3.0, size=(12, 16, 1))
    rays = np.concatenate([origins, directions], axis=-1).astype(np.float32)
    result = scene.cast_rays(rays)
    assert result["t_hit"].shape == (12, 16) and result["primitive_normals"].shape == (12, 16, 3)
    reference = vkray.Reference(vkray.Scene(CUBE_CORNERS, CUBE_FACES, camera={"from": [0, 0, 5], "to": [0, 0, 0]}))
    expected = reference.cast_rays(rays.astype(np.float64), t_along="direction", outputs=["t", "primitive_id"])
    hit = np.isfinite(expected["t"])
    assert 40 < hit.sum() < 180
    length = np.linalg.norm(rays[..., 3:].astype(float), axis=-1)
    t = result["t_hit"].numpy()
    both_miss = ~hit & (t == np.inf)
    with np.errstate(invalid="ignore"):  # inf - inf where both miss
        close = hit & (np.abs(t - expected["t"]) <= 16 * EPS * 4 / length)
    assert np.all(both_miss | close), (t[~(both_miss | close)], expected["t"][~(both_miss | close)])


def test_test_occlusions_takes_segments_and_count_intersections_is_int32():
    """test_occlusions(rays, tnear, tfar) in units of the direction: a segment p to q is the ray
    (p, q - p) up to tfar = 1; count_intersections gives int32 counts, odd from inside."""
    scene = cube_scene()
    p = np.array([[0.1, 0.2, 3.0], [0.1, 0.2, 3.0], [0.0, 0.0, 0.0], [3.0, 3.0, 3.0]])
    q = np.array([[0.1, 0.2, 1.5], [0.1, 0.2, 0.5], [0.0, 0.0, 3.0], [4.0, 3.0, 3.0]])
    rays = np.hstack([p, q - p]).astype(np.float32)
    assert list(scene.test_occlusions(rays, tfar=1.0).numpy()) == [False, True, True, False]
    assert list(scene.test_occlusions(rays, tnear=0.9, tfar=1.0).numpy()) == [False, False, False, False]
    counts = scene.count_intersections(rays).numpy()
    assert counts.dtype == np.int32 and list(counts) == [2, 2, 1, 0]


def test_list_intersections_lists_every_hit_past_sixteen_in_order():
    """Every hit of every ray, in order along it: a ray through 20 stacked squares lists 20 (more than
    one pass of HITS_MAX), ray_splits bounds each ray's, ray_ids name them, a miss lists none."""
    squares = RaycastingScene()
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    for level in range(20):
        squares.add_triangles(corners + [0, 0, level], np.array([[0, 1, 2], [0, 2, 3]]))
    rays = np.array([[0.1, 0.2, -1.0, 0, 0, 0.5], [5, 5, -1, 0, 0, 1], [0.3, -0.4, 4.5, 0, 0, -1]], np.float32)
    listed = squares.list_intersections(rays)
    assert list(listed["ray_splits"].numpy()) == [0, 20, 20, 25]
    assert list(listed["ray_ids"].numpy()) == [0] * 20 + [2] * 5
    t = listed["t_hit"].numpy()
    assert np.allclose(t[:20], (np.arange(20) + 1.0) / 0.5, rtol=8 * EPS) and np.all(np.diff(t[:20]) > 0)
    assert np.allclose(t[20:], 4.5 - np.arange(4, -1, -1), rtol=8 * EPS)
    assert list(listed["geometry_ids"].numpy()) == list(range(20)) + [4, 3, 2, 1, 0]
    assert listed["primitive_uvs"].shape == (25, 2)
    assert list(squares.count_intersections(rays).numpy()) == [20, 0, 5]


def test_point_queries_give_open3d_keys_and_the_cube_exact_answers():
    """compute_closest_points, compute_distance, compute_signed_distance (negative inside) and
    compute_occupancy (1.0 inside) on the cube, whose nearest points are the points clamped to it
    (outside) or pushed to the nearest face (inside)."""
    scene = cube_scene()
    points = np.array([[3.0, 0.5, 0.2], [0.2, 0.1, 0.5], [2.0, 2.0, 2.0]], np.float32)
    nearest = scene.compute_closest_points(points)
    assert set(nearest) == {"points", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    assert np.allclose(nearest["points"].numpy(), [[1.0, 0.5, 0.2], [0.2, 0.1, 1.0], [1.0, 1.0, 1.0]], atol=4 * EPS)
    assert list(nearest["geometry_ids"].numpy()) == [0, 0, 0]
    assert np.allclose(nearest["primitive_normals"].numpy()[:2], [[1, 0, 0], [0, 0, 1]], atol=EPS)
    assert np.allclose(scene.compute_distance(points).numpy(), [2.0, 0.5, np.sqrt(3.0)], rtol=4 * EPS)
    assert np.allclose(scene.compute_signed_distance(points).numpy(), [2.0, -0.5, np.sqrt(3.0)], rtol=4 * EPS)
    occupancy = scene.compute_occupancy(points, nsamples=3).numpy()
    assert occupancy.dtype == np.float32 and list(occupancy) == [0.0, 1.0, 0.0]
    with pytest.raises(ValueError, match="nsamples: must be odd"):
        scene.compute_occupancy(points, nsamples=2)


def test_create_rays_pinhole_looks_through_pixel_centres():
    """The intrinsic form: projecting any point of the ray through pixel (x, y) with K [R | t] lands at
    (x + 0.5, y + 0.5), and the origin is the camera's centre (R c + t = 0). The fov form is the
    intrinsic form of K = [[f, 0, W/2], [0, f, H/2]] (f = W / 2 / tan(fov / 2)) and the rotation whose
    rows are normalize(up x forward), forward x that, and forward."""
    intrinsic = np.array([[500.0, 0.0, 319.5], [0.0, 480.0, 241.0], [0.0, 0.0, 1.0]])
    angle = 0.3
    rotation = np.array([[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]])
    extrinsic = np.eye(4)
    extrinsic[:3, :3], extrinsic[:3, 3] = rotation, [0.2, -0.1, 3.0]
    rays = RaycastingScene.create_rays_pinhole(FakeTensor(intrinsic), extrinsic, 64, 48).numpy()
    assert rays.shape == (48, 64, 6) and rays.dtype == np.float32
    assert np.allclose(rotation @ rays[0, 0, :3].astype(float) + extrinsic[:3, 3], 0, atol=8 * EPS)
    seen = (rays[..., :3] + 2.5 * rays[..., 3:]).astype(float) @ rotation.T + extrinsic[:3, 3]
    pixels = seen @ intrinsic.T
    x, y = np.meshgrid(np.arange(64) + 0.5, np.arange(48) + 0.5)
    assert np.allclose(pixels[..., 0] / pixels[..., 2], x, atol=1e-3) and np.allclose(pixels[..., 1] / pixels[..., 2], y, atol=1e-3)

    eye, center, up = np.array([2.0, 3.0, 0.0]), np.array([0.0, 0.0, 2.0]), np.array([0.0, 1.0, 0.0])
    by_fov = RaycastingScene.create_rays_pinhole(fov_deg=90, center=center, eye=eye, up=up, width_px=32, height_px=24).numpy()
    forward = (center - eye) / np.linalg.norm(center - eye)
    right = np.cross(up, forward) / np.linalg.norm(np.cross(up, forward))
    looking = np.eye(4)
    looking[:3, :3] = np.stack([right, np.cross(forward, right), forward])
    looking[:3, 3] = -looking[:3, :3] @ eye
    focal = 16 / np.tan(np.radians(45))
    by_matrix = RaycastingScene.create_rays_pinhole([[focal, 0, 16], [0, focal, 12], [0, 0, 1]], looking, 32, 24).numpy()
    assert np.allclose(by_fov, by_matrix, atol=4 * EPS)
    assert np.allclose(by_fov[0, 0, :3], eye, atol=8 * EPS)
    with pytest.raises(ValueError, match="missing"):
        RaycastingScene.create_rays_pinhole(fov_deg=90, center=center, eye=eye, width_px=32, height_px=24)


def test_the_renderer_is_made_at_the_first_query_and_again_when_triangles_are_added():
    """A scene without triangles answers misses; triangles added after a query are hit by the next."""
    scene = RaycastingScene()
    ray = np.array([[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]], np.float32)
    assert scene.cast_rays(ray)["t_hit"].numpy()[0] == np.inf
    assert scene.add_triangles(CUBE_CORNERS + [0.0, 0.0, -10.0], CUBE_FACES) == 0
    assert scene.cast_rays(ray)["geometry_ids"].numpy()[0] == 0
    assert scene.add_triangles(CUBE_CORNERS, CUBE_FACES) == 1
    result = scene.cast_rays(ray)
    assert result["geometry_ids"].numpy()[0] == 1 and result["t_hit"].numpy()[0] == pytest.approx(4.0, rel=4 * EPS)


def test_bad_input_raises_one_clear_line():
    scene = RaycastingScene()
    with pytest.raises(ValueError, match="a mesh needs at least one triangle"):
        scene.add_triangles(CUBE_CORNERS, np.zeros((0, 3), np.uint32))
    with pytest.raises(ValueError, match="triangle_indices: expected whole numbers from 0 to 7"):
        scene.add_triangles(CUBE_CORNERS, CUBE_FACES + 1)
    with pytest.raises(ValueError, match=r"rays: expected an array of shape \(\.\.\., 6\)"):
        cube_scene().cast_rays(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="expected an array of numbers"):
        cube_scene().compute_distance(np.array([["a", "b", "c"]]))
