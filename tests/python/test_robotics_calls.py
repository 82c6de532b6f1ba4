"""What a robotics user of the Python package tripped over (issue 48), each against the reference or the
render it must agree with: pipelines made at first use or all at once, the peers' t, bad rays as misses, rays of any
shape, the surface outputs of given rays, and batches of poses on the packet walk. Every test here
failed on the module before the C API (pybind11, one CPython)."""
import os

import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES

EPS = 2.0**-24  # float32 unit roundoff


@pytest.fixture(scope="module")
def scene():
    # A closed box (12 triangles, texture coordinates through a glTF-free mesh: none) and a sphere.
    return vkray.Scene(CUBE_CORNERS, CUBE_FACES, spheres=np.array([[3.0, 0.0, 0.0, 0.75]]),
                       camera={"from": [0.5, 0.8, 6.0], "to": [0.5, 0.0, 0.0], "fovy": 40}, width=96, height=72)


def sensor_rays(origin, count, seed=1):
    """A sensor's rays from one origin, every direction over the sphere, of lengths 0.5 to 2."""
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(count, 3))
    directions *= rng.uniform(0.5, 2.0, size=(count, 1)) / np.linalg.norm(directions, axis=1, keepdims=True)
    return np.hstack([np.broadcast_to(np.asarray(origin, float), (count, 3)), directions])


def sensor_rings(origin, rings=32, azimuths=2048):
    """A spinning sensor's rays from one origin, ring by ring: consecutive rays point nearly the same way."""
    elevation = np.radians(np.linspace(-15.0, 15.0, rings))[:, None]
    azimuth = np.linspace(0.0, 2.0 * np.pi, azimuths, endpoint=False)[None, :]
    directions = np.stack([np.cos(elevation) * np.sin(azimuth), np.sin(elevation) * np.ones_like(azimuth),
                           -np.cos(elevation) * np.cos(azimuth)], axis=-1).reshape(-1, 3)
    return np.hstack([np.broadcast_to(np.asarray(origin, float), directions.shape), directions])


def first_calls(renderer):
    """One call of each kind the pipelines differ by: render, cast_rays from one origin and from many,
    occluded from many and from one, ranges given."""
    many_origins = np.vstack([sensor_rays([0, 0, 5], 64), sensor_rays([5, 0, 0], 64)])
    return [lambda: renderer.render(), lambda: renderer.cast_rays(sensor_rays([0.5, 0.8, 6.0], 5000)),
            lambda: renderer.cast_rays(many_origins), lambda: renderer.occluded(many_origins),
            lambda: renderer.occluded(sensor_rays([0.5, 0.8, 6.0], 5000), t_max=3.0),
            lambda: renderer.cast_rays(sensor_rays([0.5, 0.8, 6.0], 5000), t_min=0.1)]


def test_each_call_makes_its_pipeline_at_its_first_use(scene):
    """The constructor makes no pipeline a call takes (every one of them cost a Python process 5 s on
    lavapipe before the first result, issue 64): the first call of a kind makes and first runs its own
    (timings['pipeline_ms']), the same call again makes none, and timings speak of the last call alone,
    the constructor's under 'setup'."""
    renderer = vkray.Renderer(scene)
    assert set(renderer.timings) == {"setup"} and renderer.timings["setup"]["upload_ms"] > 0
    for call in first_calls(renderer):
        call()
        assert renderer.timings["pipeline_ms"] > 0.0, renderer.timings
        assert "upload_ms" not in renderer.timings  # the constructor's, under setup
        call()
        assert renderer.timings["pipeline_ms"] == 0.0, renderer.timings


def test_no_call_makes_a_pipeline_after_prepare(scene):
    """prepare() makes every pipeline the calls take, and its time joins the setup's: the first render,
    cast and occlusion query each make none."""
    renderer = vkray.Renderer(scene)
    constructor_ms = renderer.timings["setup"]["pipeline_ms"]
    renderer.prepare()
    assert renderer.timings["setup"]["pipeline_ms"] > constructor_ms
    for call in first_calls(renderer):
        call()
        assert renderer.timings["pipeline_ms"] == 0.0, renderer.timings


def test_t_along_the_direction_as_given_is_embree_and_open3d_t(renderer, reference):
    """t_along='direction': t, t_min and t_max in units of the direction as given (hit = origin + t *
    direction), as Embree and Open3D count them; Open3D's test_occlusions of segments p -> q is
    occluded(p, q - p, t_max=1)."""
    rays = sensor_rays([0.3, 0.2, 1.5], 2000)
    length = np.linalg.norm(rays[:, 3:], axis=1)
    unit = renderer.cast_rays(rays)["t"].astype(float)
    given = renderer.cast_rays(rays, t_along="direction")["t"].astype(float)
    hit = np.isfinite(unit)
    assert hit.sum() > 200
    assert np.array_equal(np.isfinite(given), hit)
    assert np.allclose(given[hit] * length[hit], unit[hit], rtol=4 * EPS, atol=0)
    # Segments from p to q: occluded exactly where the reference finds a hit before q.
    rng = np.random.default_rng(3)
    p, q = rng.uniform(-3, 3, size=(4000, 3)), rng.uniform(-3, 3, size=(4000, 3))
    segments = np.hstack([p, q - p])
    expected = reference.occluded(segments, t_max=1.0, t_along="direction")
    assert 400 < expected.sum() < 3600
    got = renderer.occluded(segments, t_max=1.0, t_along="direction")
    # Where the nearest hit lies within float32's rounding of a segment's end, either answer is right.
    t_exact = reference.cast_rays(segments, t_along="direction")["t"]
    near_end = np.abs(t_exact - 1.0) < 1e-5
    assert np.array_equal(got[~near_end], expected[~near_end])
    with pytest.raises(ValueError, match="t_along: 'unit'"):
        renderer.cast_rays(rays, t_along="length")


def test_bad_rays_are_misses_unless_asked_to_raise(renderer):
    """A dead beam (zero or non-finite direction, an origin past 1e15, a range below itself) among a
    million is a miss, its neighbours traced as they would be without it; bad_rays='raise' names it."""
    rays = sensor_rays([0.5, 0.3, 4.0], 1000)
    bad = rays.copy()
    bad[10, 3:] = 0.0
    bad[20, 4] = np.nan
    bad[30, 0] = 1e16
    t_max = np.full(1000, np.inf)
    t_max[40] = -1.0
    hits = renderer.cast_rays(bad, t_max=t_max)
    dead = np.zeros(1000, bool)
    dead[[10, 20, 30, 40]] = True
    assert np.all(np.isinf(hits["t"][dead])) and np.all(hits["mesh_id"][dead] == vkray.NO_HIT)
    assert np.all(hits["normal"][dead] == 0)
    alone = renderer.cast_rays(rays[~dead], t_max=t_max[~dead])
    for key in ("t", "normal", "mesh_id", "primitive_id"):
        assert np.array_equal(hits[key][~dead], alone[key]), key
    assert not renderer.occluded(bad, t_max=t_max)[dead].any()
    with pytest.raises(ValueError, match="ray 10: the direction is 0"):
        renderer.cast_rays(bad, bad_rays="raise")
    with pytest.raises(ValueError, match="ray 40: t_max is NaN or below t_min"):
        renderer.occluded(rays, t_max=t_max, bad_rays="raise")


def test_rays_of_any_leading_shape_give_outputs_of_that_shape(renderer):
    """(B, N, 6) rays give (B, N) and (B, N, 3) outputs, one (6,) ray scalars and (3,), every array
    C-contiguous, render's too (its normal came back strided (2560, 4, 1228800))."""
    rays = sensor_rays([0.5, 0.3, 4.0], 600).reshape(4, 150, 6)
    hits = renderer.cast_rays(rays, t_max=np.full((4, 1), 10.0), outputs=["t", "normal", "position"])
    assert hits["t"].shape == (4, 150) and hits["normal"].shape == (4, 150, 3) and hits["position"].shape == (4, 150, 3)
    flat = renderer.cast_rays(rays.reshape(-1, 6), t_max=10.0, outputs=["t", "normal", "position"])
    for key in hits:
        assert hits[key].flags["C_CONTIGUOUS"], key
        assert np.array_equal(hits[key].reshape(flat[key].shape), flat[key]), key
    one = renderer.cast_rays(rays[1, 7])
    assert one["t"].shape == () and one["normal"].shape == (3,) and one["t"] == flat["t"][157]
    assert renderer.occluded(rays).shape == (4, 150)
    for name, array in renderer.render(aovs=["depth", "normal", "uv", "mesh_id"]).items():
        assert array.flags["C_CONTIGUOUS"], name


def test_cast_rays_gives_the_surface_outputs_render_gives(renderer, scene):
    """Rays from the camera through its pixels' hit points name the same primitives and give the same
    surface outputs render gives there: barycentric weights, front-facing flags, shading normals,
    positions (within float32's rounding of the hit points the rays were aimed at)."""
    names = ["position", "mesh_id", "primitive_id", "barycentric", "front_facing", "shading_normal"]
    image = renderer.render(aovs=names)
    hit = image["mesh_id"] != vkray.NO_HIT
    assert hit.sum() > 500
    eye = np.array(scene.camera["from"])
    targets = image["position"][hit].astype(float)
    rays = np.hstack([np.broadcast_to(eye, targets.shape), targets - eye])
    cast = renderer.cast_rays(rays, outputs=["t", "primitive_id", "mesh_id", "barycentric", "front_facing", "shading_normal", "position"])
    same = (cast["mesh_id"] == image["mesh_id"][hit]) & (cast["primitive_id"] == image["primitive_id"][hit])
    assert same.mean() > 0.95  # a ray aimed at a rounded hit point may cross to the next triangle at an edge
    scale = np.linalg.norm(targets - eye, axis=1)
    assert np.all(np.linalg.norm(cast["position"][same] - targets[same], axis=1) <= 64 * EPS * (scale[same] + 3))
    assert np.array_equal(cast["front_facing"][same], image["front_facing"][hit][same])
    assert np.allclose(cast["barycentric"][same], image["barycentric"][hit][same], atol=1e-4)
    assert np.allclose(cast["shading_normal"][same], image["shading_normal"][hit][same], atol=1e-4)
    with pytest.raises(ValueError, match="outputs: 'uv' is not an output of given rays"):
        renderer.cast_rays(rays, outputs=["uv"])


def test_a_batch_of_poses_walks_in_packets_as_one_pose_does(renderer, reference):
    """Four poses of a sensor in one call walk each pose's rays in packets from its origin (they walked
    one by one: the rays share no one origin), with the hits of four calls."""
    poses = [[0.5, 0.3, 4.0], [-3.0, 0.5, 2.0], [2.5, -0.5, -3.5], [0.0, 4.0, 0.5]]
    rays = np.vstack([sensor_rays(pose, 8192, seed=k) for k, pose in enumerate(poses)])
    batch = renderer.cast_rays(rays)
    assert renderer.timings["rays_walk"] != "one by one", renderer.timings
    for k in range(4):
        one = renderer.cast_rays(rays[8192 * k:8192 * (k + 1)])
        for key in batch:
            assert np.array_equal(batch[key][8192 * k:8192 * (k + 1)], one[key]), key
    exact = reference.cast_rays(rays)["t"]
    clear = np.isfinite(exact) == np.isfinite(batch["t"])
    assert clear.mean() > 0.999


def test_a_sensor_s_rays_are_read_and_hits_written_in_place(renderer):
    """A sensor's rays from one origin, ring by ring: where the device imports host memory and reads
    doubles in its float32 shader (lavapipe), the shader reads the caller's array and writes the
    returned arrays itself (timings 'rays_in_place'), with the hits of the host's way bit for bit (an
    output the shader does not write, 'position', takes that way); a dead beam among them is a miss,
    its neighbours as they were, or with bad_rays='raise' named by its index."""
    rays = sensor_rings([0.5, 0.3, 4.0])
    hits = renderer.cast_rays(rays)
    in_place = renderer.timings["rays_in_place"]
    host = renderer.cast_rays(rays, outputs=["t", "normal", "primitive_id", "mesh_id", "position"])
    assert not renderer.timings["rays_in_place"]
    for key in hits:
        assert np.array_equal(hits[key], host[key]), key
    assert (hits["mesh_id"] != vkray.NO_HIT).mean() > 0.05
    importing = "llvmpipe" in renderer.device_name and "no-host-import" not in os.environ.get("VKRAY_DEVICE_OVERRIDE", "")
    assert in_place == importing, renderer.timings
    bad = rays.copy()
    bad[10, 3:] = 0.0
    dead = renderer.cast_rays(bad)
    assert np.isinf(dead["t"][10]) and dead["mesh_id"][10] == vkray.NO_HIT and np.all(dead["normal"][10] == 0)
    for key in hits:
        assert np.array_equal(np.delete(dead[key], 10, axis=0), np.delete(hits[key], 10, axis=0)), key
    with pytest.raises(ValueError, match="ray 10: the direction is 0"):
        renderer.cast_rays(bad, bad_rays="raise")
