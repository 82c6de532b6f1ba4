"""The Python module against the command line and the double-precision reference (ctest runs this
with pytest: tests/CMakeLists.txt sets VKRAY_CLI, VKRAY_MODELS_DIR and PYTHONPATH)."""
import math
import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import OpenImageIO as oiio
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES

EPS = 2.0**-24  # float32 unit roundoff
MODELS = os.environ.get("VKRAY_MODELS_DIR", "")
BUNNY = os.path.join(MODELS, "stanford-bunny.obj")
TEAPOT = os.path.join(MODELS, "teapot-vn.obj")
SPOT = os.path.join(MODELS, "spot.obj")


def need_model(path):
    if not os.path.exists(path):
        pytest.skip(f"{path} is absent: the shared models folder (../shared/models) is not beside the project")
    return path


@pytest.fixture(scope="module")
def default_scene():
    return vkray.load("", 96, 72)


@pytest.fixture(scope="module")
def default_renderer(default_scene):
    return vkray.Renderer(default_scene)


def read_exr(path):
    image = oiio.ImageInput.open(str(path))
    assert image, oiio.geterror()
    names = image.spec().channelnames
    pixels = image.read_image(oiio.FLOAT)
    image.close()
    return {name: pixels[:, :, k] for k, name in enumerate(names)}


def cli_render(tmp_path, scene_path, width, height, *extra):
    output = tmp_path / "cli.exr"
    command = [os.environ["VKRAY_CLI"], "render", *([scene_path] if scene_path else []), "--width", str(width),
               "--height", str(height), "-o", str(output), "--no-preview", *extra]
    subprocess.run(command, check=True, capture_output=True)
    return read_exr(output)


def expect_same_as_cli(arrays, channels):
    """Every pixel bit for bit: the same engine, device and shader made both."""
    assert np.array_equal(arrays["depth"], channels["Z"])  # inf on a miss in both
    normal = np.stack([channels["N.X"], channels["N.Y"], channels["N.Z"]], axis=-1)
    assert np.array_equal(arrays["normal"], normal)


def test_render_matches_the_command_lines_exr(tmp_path, default_scene, default_renderer):
    arrays = default_renderer.render()
    assert arrays["depth"].shape == (72, 96) and arrays["depth"].dtype == np.float32
    assert arrays["normal"].shape == (72, 96, 3) and arrays["normal"].dtype == np.float32
    expect_same_as_cli(arrays, cli_render(tmp_path, "", 96, 72))


def test_render_of_a_model_with_a_moved_camera_matches_the_command_line(tmp_path):
    scene = vkray.load(need_model(BUNNY), 160, 120)
    camera = dict(scene.camera, **{"from": [0.1, 0.2, 0.25], "fovy": 35})
    arrays = vkray.Renderer(scene).render(camera)
    cli = cli_render(tmp_path, BUNNY, 160, 120, "--camera", "from=0.1,0.2,0.25 fovy=35")
    expect_same_as_cli(arrays, cli)


def test_outputs_subset_and_size_per_call(default_renderer):
    uv_only = default_renderer.render(width=31, height=17, aovs=["uv"])
    assert list(uv_only) == ["uv"] and uv_only["uv"].shape == (17, 31, 2)
    # The image-plane coordinates of pixel centres: the shorter side spans [-1, 1].
    assert uv_only["uv"][8, 15, 0] == 0.0 and uv_only["uv"][8, 15, 1] == 0.0
    assert np.isclose(uv_only["uv"][0, 0, 1], (17 - 1) / 17)


def test_scene_from_arrays_renders_as_the_same_scene_file(tmp_path):
    vertices = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1], [0, 1.5, 0]], dtype=np.float64)
    triangles = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1], [0, 3, 2]], dtype=np.int32)
    transform = np.array([[2, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, -1], [0, 0, 0, 1]])
    camera = {"from": [3, 2, 4], "to": [0.5, 0.5, -1], "fovy": 45}
    scene = vkray.Scene(meshes=[{"vertices": vertices, "triangles": triangles, "transform": transform}],
                        spheres=np.array([[0.5, 0.5, -4, 1]]), planes=np.array([[0, -0.25, 0, 0, 3, 0]]),
                        camera=camera, width=64, height=48)
    moved = [list(transform[:3, :3] @ v + transform[:3, 3]) for v in vertices]
    scene_file = tmp_path / "scene.json"
    scene_file.write_text(vkray_scene_json(camera, moved, triangles))
    expect_same_as_cli(vkray.Renderer(scene).render(), cli_render(tmp_path, str(scene_file), 64, 48))


def vkray_scene_json(camera, positions, triangles):
    import json
    return json.dumps({"camera": camera, "image": {"width": 64, "height": 48},
                       "spheres": [{"center": [0.5, 0.5, -4], "radius": 1}],
                       "planes": [{"point": [0, -0.25, 0], "normal": [0, 1, 0]}],
                       "meshes": [{"positions": positions, "triangles": triangles.tolist()}]})


def test_scene_without_a_camera_is_framed_like_a_model():
    scene = vkray.Scene(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    assert scene.camera["to"] != scene.camera["from"]
    depth = vkray.Renderer(scene).render(width=32, height=32)["depth"]
    assert np.isfinite(depth).any()


def camera_rays(camera, width, height):
    """The pixel rays of a look-at camera in double, as docs/outputs.md's output contract defines them."""
    eye, target, up = (np.array(camera[k], dtype=np.float64) for k in ("from", "to", "up"))
    forward = (eye - target) / np.linalg.norm(eye - target)
    right = np.cross(up, forward)
    right /= np.linalg.norm(right)
    true_up = np.cross(forward, right)
    distance = 1.0 / math.tan(math.radians(camera["fovy"]) / 2)
    shorter = min(width, height)
    u = (2 * np.arange(width) + 1 - width) / shorter
    v = (height - 2 * np.arange(height) - 1) / shorter
    uu, vv = np.meshgrid(u, v)
    directions = uu[..., None] * right + vv[..., None] * true_up - distance * forward
    origins = np.broadcast_to(eye, directions.shape)
    return np.concatenate([origins, directions], axis=-1).reshape(-1, 6)


def test_cast_rays_of_a_cameras_pixels_agree_with_its_image(default_scene, default_renderer):
    rays = camera_rays(default_scene.camera, 96, 72)
    hits = default_renderer.cast_rays(rays)
    image = default_renderer.render()
    assert hits["t"].shape == (96 * 72,) and hits["normal"].shape == (96 * 72, 3)
    assert hits["primitive_id"].dtype == np.uint32 and hits["mesh_id"].dtype == np.uint32
    depth = image["depth"].reshape(-1)
    hit = np.isfinite(depth)
    # Both rays are rounded to float32 (each direction within a few eps), so the same surfaces
    # are hit except within a few eps of a silhouette: at most a pixel row's worth here.
    assert np.count_nonzero(hit != np.isfinite(hits["t"])) <= 2
    both = hit & np.isfinite(hits["t"])
    assert np.median(np.abs(hits["t"][both] - depth[both]) / depth[both]) < 64 * EPS
    missed = ~np.isfinite(hits["t"])
    assert np.all(hits["mesh_id"][missed] == vkray.NO_HIT) and np.all(hits["primitive_id"][missed] == vkray.NO_HIT)
    assert np.all(hits["normal"][missed] == 0)


def centroid_rays(vertices, triangles, origins, rng):
    """Rays from `origins` aimed at random triangles' centroids: far from the triangle's edges in
    angle, so rounding cannot move the hit off it when it is the nearest."""
    chosen = rng.integers(0, len(triangles), len(origins))
    centroids = vertices[triangles[chosen]].mean(axis=1)
    return np.concatenate([origins, centroids - origins], axis=1), chosen


def angle_between(a, b):
    """Row by row, accurate near 0 (arccos of a dot product is not: 1 - 3e-8 gives 2e-4 rad)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def expect_rays_agree_with_reference(renderer, reference, rays, reach, radius, curvature=None):
    """Ray by ray against the reference, with the error bounds of engine/reference/envelope.cpp for
    rays whose nearest hit is stable (the callers choose such rays): the same object and primitive;
    the distance within 16 eps (t + reach) + 2^-44 radius over cos(theta) (positions) plus
    2 eps t tan(theta) (the direction rounded to float); the normal within 16 eps, plus, on a surface
    of curvature radius rho, the hit's displacement over rho."""
    gpu, exact = renderer.cast_rays(rays), reference.cast_rays(rays)
    hit = np.isfinite(exact["t"])
    np.testing.assert_array_equal(np.isfinite(gpu["t"]), hit)
    np.testing.assert_array_equal(gpu["mesh_id"], exact["mesh_id"])
    np.testing.assert_array_equal(gpu["primitive_id"], exact["primitive_id"])
    directions = rays[:, 3:] / np.linalg.norm(rays[:, 3:], axis=1, keepdims=True)
    cos_theta = np.clip(np.abs(np.einsum("ij,ij->i", exact["normal"], directions)), 1e-12, 1.0)[hit]
    t = exact["t"][hit]
    displacement = (16 * EPS * (t + reach[hit]) + 2.0**-44 * radius) / cos_theta
    turn = 2 * EPS * t * np.sqrt(1 - cos_theta**2) / cos_theta
    error = np.abs(gpu["t"][hit] - t)
    assert np.all(error <= displacement + turn), f"ray {np.argmax(error - displacement - turn)}: {error.max()} beyond the bound"
    rho = np.full(len(t), np.inf) if curvature is None else curvature[hit]
    normal_bound = 16 * EPS + (displacement + 2 * EPS * t / cos_theta) / rho
    normal_error = angle_between(gpu["normal"][hit].astype(np.float64), exact["normal"][hit])
    assert np.all(normal_error <= normal_bound), f"ray {np.argmax(normal_error - normal_bound)}: normal {normal_error.max()} rad off"


def test_cast_rays_against_the_reference_from_outside_and_inside_a_model():
    scene = vkray.load(need_model(BUNNY))
    vertices, triangles = read_obj(BUNNY)
    centre = vertices.mean(axis=0)
    radius = np.linalg.norm(vertices - centre, axis=1).max()
    rng = np.random.default_rng(7)
    outside = centre + radius * 3 * unit_rows(rng.normal(size=(3000, 3)))
    inside = centre + 0.05 * radius * rng.normal(size=(3000, 3))  # the bunny's body holds its centre
    rays, aimed = centroid_rays(vertices, triangles, np.concatenate([outside, inside]), rng)
    reference = vkray.Reference(scene)
    exact = reference.cast_rays(rays)
    # Keep the rays whose nearest hit is the triangle they aim at: elsewhere the nearest hit may lie
    # anywhere, next to an edge included.
    keep = exact["primitive_id"] == aimed
    assert keep.sum() > 1000
    rays = rays[keep]
    reach = np.linalg.norm(vertices[triangles[aimed[keep]]] - rays[:, None, :3], axis=2).max(axis=1)
    expect_rays_agree_with_reference(vkray.Renderer(scene), reference, rays, reach, radius + np.abs(rays[:, :3] - centre).max())


def test_cast_rays_at_spheres_and_planes_including_parallel_rays():
    spheres = np.array([[0, 0, -5, 1], [3, 0, -5, 0.5], [0, 0, 0, 10]])
    planes = np.array([[0, -2, 0, 0, 1, 0]])
    scene = vkray.Scene(spheres=spheres, planes=planes, camera={"from": [0, 0, 5], "to": [0, 0, 0]})
    rng = np.random.default_rng(3)
    origins = rng.uniform(-4, 4, size=(2000, 3))
    origins[:, 1] = np.maximum(origins[:, 1], -1.5)
    targets = spheres[rng.integers(0, 2, len(origins)), :3]  # aimed at a small sphere's centre
    rays = np.concatenate([origins, targets - origins], axis=1)
    parallel = np.concatenate([origins[:500], rng.normal(size=(500, 3)) * [1, 0, 1]], axis=1)  # parallel to the plane
    rays = np.concatenate([rays, parallel])
    reference = vkray.Reference(scene)
    exact = reference.cast_rays(rays)
    assert not np.any(exact["mesh_id"][2000:] == 3), "no ray parallel to the plane hits it"
    reach = np.full(len(rays), 20.0)  # every sphere's far side and the plane's foot point lie within 20 of any origin
    curvature = np.where(exact["mesh_id"] < 3, spheres[np.minimum(exact["mesh_id"], 2), 3], np.inf)
    expect_rays_agree_with_reference(vkray.Renderer(scene), reference, rays, reach, 20.0, curvature)
    # Inside the big sphere every ray hits something; sphere k is mesh_id k (there are no meshes).
    assert set(np.unique(exact["mesh_id"])) <= {0, 1, 2, 3}


def unit_rows(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def read_obj(path):
    vertices, faces = [], []
    with open(path) as obj:
        for line in obj:
            parts = line.split()
            if parts and parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts and parts[0] == "f":
                corners = [int(p.split("/")[0]) - 1 for p in parts[1:]]
                faces.extend([corners[0], corners[k], corners[k + 1]] for k in range(1, len(corners) - 1))
    return np.array(vertices), np.array(faces)


@pytest.mark.parametrize("call, message", [
    (lambda r: r.cast_rays(np.zeros((4, 5))), "rays: expected an array of shape (..., 6), got shape (4, 5)"),
    (lambda r: r.cast_rays(np.zeros((2, 3, 7))), "rays: expected an array of shape (..., 6), got shape (2, 3, 7)"),
    (lambda r: r.cast_rays(np.array([["a"] * 6])), "rays: expected an array of numbers, of shape (..., 6)"),
    (lambda r: r.cast_rays(np.array([[0, 0, 0, 0, 0, 1], [np.nan, 0, 0, 0, 0, 1]]), bad_rays="raise"), "ray 1: the origin is not finite"),
    (lambda r: r.cast_rays(np.array([[0, 0, 0, 0, 0, 0.0]]), bad_rays="raise"), "ray 0: the direction is 0"),
    (lambda r: r.render({"from": [0, 0]}), "camera: from: expected 3 numbers [x, y, z], got [0,0]"),
    (lambda r: r.render({"fov": 30}), "camera: fov: unknown key 'fov' (did you mean 'fovy'?)"),
    (lambda r: r.render({"fovy": 200}), "camera: fovy: field of view must be in (0, 180) degrees"),
    (lambda r: r.render("front"), "camera: expected a dict"),
    (lambda r: r.render(width=0), "width: expected a whole number in 1 .. 65536, got 0"),
    (lambda r: r.render(aovs=["depht"]), "aovs: unknown output 'depht'"),
    (lambda r: r.render(aovs=[]), "aovs: name at least one output"),
])
def test_bad_calls_raise_value_error_with_the_place(default_renderer, call, message):
    with pytest.raises(ValueError) as raised:
        call(default_renderer)
    assert message in str(raised.value)


@pytest.mark.parametrize("arguments, message", [
    ({"vertices": np.zeros((3, 2)), "triangles": [[0, 1, 2]]}, "meshes[0].vertices: expected an N x 3 array, got shape (3, 2)"),
    ({"vertices": np.eye(3), "triangles": np.array([[0, 1, 3]])}, "meshes[0].triangles[0][2]: vertex index 3 is out of range"),
    ({"vertices": np.eye(3), "triangles": np.array([[0, -1, 2]])}, "meshes[0].triangles[0][1]: vertex index -1 is out of range"),
    ({"vertices": np.eye(3), "triangles": np.array([[0.0, 1, 2]])}, "meshes[0].triangles: expected an M x 3 array of integer"),
    ({"vertices": np.array([[0, 0, np.inf], [1, 0, 0], [0, 1, 0]]), "triangles": [[0, 1, 2]]},
     "meshes[0].vertices[0]: every coordinate must be finite"),
    ({"vertices": np.eye(3)}, "give both vertices and triangles, or meshes"),
    ({"spheres": np.array([[0, 0, 0, -1]]), "camera": {"from": [0, 0, 5], "to": [0, 0, 0]}}, "spheres[0].radius: must be > 0"),
    ({"planes": np.array([[0, 0, 0, 0, 0, 0]]), "camera": {"from": [0, 0, 5], "to": [0, 0, 0]}}, "planes[0].normal: must be finite and non-zero"),
    ({"meshes": [{"vertices": np.eye(3), "triangles": [[0, 1, 2]], "scale": 2}]}, "meshes[0]: unknown key 'scale'"),
    ({"meshes": [{"vertices": np.eye(3), "triangles": [[0, 1, 2]], "transform": np.eye(3)}]}, "meshes[0].transform: expected a 4 x 4 matrix, got shape (3, 3)"),
    ({}, "nothing to frame: the scene has no mesh, sphere or plane"),
])
def test_bad_scenes_raise_value_error_with_the_place(arguments, message):
    with pytest.raises(ValueError) as raised:
        vkray.Scene(**arguments)
    assert message in str(raised.value)


def test_planes_alone_need_no_camera():
    """A ground plane made only to cast rays at (issue 64: refused as "nothing to frame"): the scene
    frames it at a slant from one unit along its normal, rays hit it where the plane's formula says,
    and its render sees the plane below the horizon."""
    scene = vkray.Scene(planes=np.array([[0.0, -2.0, 0.0, 0.0, 1.0, 0.0]]), width=32, height=24)
    assert np.allclose(scene.camera["to"], [0, -2, 0]) and scene.camera["from"][1] == pytest.approx(-1.0)
    renderer = vkray.Renderer(scene)
    t = renderer.cast_rays(np.array([[0.3, 1.0, 0.2, 0.0, -1.0, 0.0], [0.3, 1.0, 0.2, 0.0, 1.0, 0.0]]))["t"]
    assert t[0] == pytest.approx(3.0, rel=2**-22) and t[1] == np.inf
    depth = renderer.render()["depth"]
    assert np.isfinite(depth[-1]).all() and np.isfinite(depth).mean() < 1.0


def test_an_array_too_large_to_convert_raises_memory_error():
    """A float64 copy of 10^12 broadcast rows (24 TB) cannot be made: numpy's MemoryError, no crash."""
    with pytest.raises(MemoryError):
        vkray.Scene(np.broadcast_to(np.zeros(3, dtype=np.float32), (10**12, 3)), [[0, 1, 2]])


def test_bad_files_raise_value_error_naming_the_file(tmp_path):
    broken = tmp_path / "broken.obj"
    broken.write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match=r"broken\.obj:3: vertex index 3 is out of range"):
        vkray.load(str(broken))
    with pytest.raises(ValueError, match=r"unknown kind of file '\.txt'"):
        vkray.load(str(tmp_path / "scene.txt"))


def test_a_device_that_does_not_exist_raises_vkray_error(default_scene):
    with pytest.raises(vkray.Error, match="no-such-device"):
        vkray.Renderer(default_scene, device="no-such-device")


def test_the_gil_is_released_while_the_device_works(default_renderer):
    """A second thread counts only while render runs: holding the GIL, render would let it count
    nothing (C++ code gives the GIL up only where it releases it)."""
    ticks = []
    calling = threading.Event()
    stop = threading.Event()

    def count():
        while not stop.is_set():
            if calling.is_set():
                ticks.append(1)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        time.sleep(0.05)  # the counter is running
        calling.set()
        default_renderer.render(width=640, height=480)
        calling.clear()
    finally:
        stop.set()
        counter.join()
    assert len(ticks) > 100


def test_threads_may_share_a_renderer(default_scene, default_renderer):
    expected = default_renderer.render()["depth"]
    results = [None] * 4

    def render(k):
        results[k] = default_renderer.render()["depth"]

    threads = [threading.Thread(target=render, args=(k,)) for k in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert all(np.array_equal(result, expected) for result in results)


def test_double_precision_rounds_to_the_command_lines_exr(tmp_path):
    scene = vkray.load("", 48, 36)
    arrays = vkray.Renderer(scene, precision="double").render()
    assert arrays["depth"].dtype == np.float64 and arrays["normal"].dtype == np.float64
    cli = cli_render(tmp_path, "", 48, 36, "--precision", "double")
    expect_same_as_cli({k: v.astype(np.float32) for k, v in arrays.items()}, cli)
    with pytest.raises(ValueError, match="precision: 'float' or 'double', got 'half'"):
        vkray.Renderer(scene, precision="half")


def test_double_precision_casts_rays_in_double():
    scene = vkray.load("", 48, 36)
    rays = camera_rays(scene.camera, 48, 36)
    hits = vkray.Renderer(scene, precision="double").cast_rays(rays)
    assert hits["t"].dtype == np.float64 and hits["normal"].dtype == np.float64
    exact = vkray.Reference(scene).cast_rays(rays)
    assert np.array_equal(hits["mesh_id"], exact["mesh_id"])
    hit = np.isfinite(exact["t"])
    assert hit.sum() > 500
    assert np.max(np.abs(hits["t"][hit] - exact["t"][hit]) / exact["t"][hit]) < 1e-12
    assert vkray.Renderer(scene, precision="double").cast_rays(np.zeros((0, 6)))["t"].dtype == np.float64


@pytest.mark.parametrize("traversal", vkray.traversals)
def test_each_traversal_matches_the_command_lines_exr(tmp_path, traversal):
    scene = vkray.load("", 48, 36)
    try:
        renderer = vkray.Renderer(scene, traversal=traversal)
    except vkray.Error as error:
        # A device may refuse the packet walk (a GPU: it takes double edge functions, which only CPU
        # devices choose) or ray queries (none on it), saying why; lavapipe as the suite runs it
        # refuses neither (tests/CMakeLists.txt; the Mesa cmake/install-deps.sh installs has ray queries).
        assert traversal in ("packet", "ray-query") and f"traversal '{traversal}' cannot run on" in str(error), str(error)
        lavapipe_as_it_is = "llvmpipe" in str(error) and not os.environ.get("VKRAY_DEVICE_OVERRIDE")
        assert not (lavapipe_as_it_is and "VKRAY_REQUIRE_RAY_QUERY" in os.environ), str(error)
        pytest.skip(str(error))
    expect_same_as_cli(renderer.render(), cli_render(tmp_path, "", 48, 36, "--traversal", traversal))


def test_the_traversals_are_the_command_lines():
    """vkray.traversals (engine/render/search.hpp's table) holds what `vkray render --traversal` takes."""
    help_text = subprocess.run([os.environ["VKRAY_CLI"], "render", "--help"], check=True, capture_output=True, text=True).stdout
    assert len(vkray.traversals) == 4
    for name in vkray.traversals:
        assert name in help_text, name


def test_an_unknown_traversal_raises_value_error():
    with pytest.raises(ValueError, match="traversal: one of auto, brute-force, per-ray, packet, ray-query, got 'bvh'"):
        vkray.Renderer(vkray.load("", 8, 8), traversal="bvh")


def test_mesh_ids_count_meshes_then_spheres_then_planes():
    triangle = np.array([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0, 0.5, 0]])
    meshes = [{"vertices": triangle + [4 * k, 0, 0], "triangles": [[0, 1, 2], [0, 2, 1]]} for k in range(2)]
    spheres = np.array([[8, 0, 0, 0.5], [12, 0, 0, 0.5]])
    planes = np.array([[0, 0, -3, 0, 0, 1]])
    scene = vkray.Scene(meshes=meshes, spheres=spheres, planes=planes, camera={"from": [6, 0, 10], "to": [6, 0, 0], "fovy": 60})
    targets = np.array([[0, 0, 0], [4, 0, 0], [8, 0, 0], [12, 0, 0], [20, 0, 0], [2, 0, 0]])
    origins = targets + [0, 0, 10]
    rays = np.concatenate([origins, targets - origins], axis=1)
    rays[5] = [2, 0, 10, 0, 1, 0]  # away from everything
    for tracer in (vkray.Renderer(scene), vkray.Reference(scene)):
        hits = tracer.cast_rays(rays)
        assert hits["mesh_id"].tolist() == [0, 1, 2, 3, 4, vkray.NO_HIT]
        assert hits["primitive_id"].tolist()[2:5] == [0, 1, 0]  # spheres and planes by their own index
        assert hits["primitive_id"][0] in (0, 1)  # a triangle of the first mesh (two copies, either winding)


def test_rays_from_inside_a_closed_mesh_meet_its_walls_from_inside():
    scene = vkray.Scene(CUBE_CORNERS, CUBE_FACES, camera={"from": [0, 0, 0.5], "to": [0, 0, 0], "fovy": 90})
    rng = np.random.default_rng(11)
    origins = rng.uniform(-0.9, 0.9, size=(3000, 3))
    directions = rng.normal(size=(3000, 3))
    rays = np.concatenate([origins, directions], axis=1)
    hits = vkray.Renderer(scene).cast_rays(rays)
    exact = vkray.Reference(scene).cast_rays(rays)
    assert np.all(np.isfinite(hits["t"]))  # no ray escapes the closed cube
    assert np.all(np.einsum("ij,ij->i", hits["normal"], directions) <= 0)  # normals face the ray: inward
    # The wall is at most sqrt(3) * 1.9 away: float32 positions and direction rounding bound the error.
    assert np.max(np.abs(hits["t"] - exact["t"])) < 64 * EPS * 4


def test_uv_is_the_exrs_u_and_v(tmp_path, default_scene, default_renderer):
    arrays = default_renderer.render(width=37, height=29, aovs="uv,depth")
    cli = cli_render(tmp_path, "", 37, 29, "--aov", "uv,depth")
    assert np.array_equal(arrays["uv"][..., 0], cli["U"]) and np.array_equal(arrays["uv"][..., 1], cli["V"])
    assert np.array_equal(arrays["depth"], cli["Z"])


@pytest.mark.parametrize("arguments, message", [
    ({"vertices": np.eye(3), "triangles": np.array([[0, 1]])}, "meshes[0].triangles: expected an M x 3 array"),
    ({"spheres": np.zeros((1, 3))}, "spheres: expected an N x 4 array, got shape (1, 3)"),
    ({"planes": np.zeros((1, 5))}, "planes: expected an N x 6 array, got shape (1, 5)"),
    ({"vertices": np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]), "triangles": [[0, 1, 2]]}, "meshes[0].vertices[0]"),
    ({"spheres": np.array([[0, 0, np.nan, 1]])}, "spheres[0].center"),
    ({"spheres": np.array([[0, 0, 0, np.inf]])}, "spheres[0].radius"),
    ({"planes": np.array([[0, np.nan, 0, 0, 1, 0]]), "camera": {"from": [0, 0, 5], "to": [0, 0, 0]}}, "planes[0].point"),
    ({"meshes": [{"vertices": np.eye(3), "triangles": [[0, 1, 2]], "transform": np.full((4, 4), np.nan)}]},
     "meshes[0].transform"),
    ({"vertices": np.eye(3).astype(complex), "triangles": [[0, 1, 2]]}, "meshes[0].vertices: expected an array of numbers"),
    ({"vertices": np.ones((3, 3), dtype=bool), "triangles": [[0, 1, 2]]}, "meshes[0].vertices: expected an array of numbers"),
    ({"vertices": np.array([[object()] * 3] * 3), "triangles": [[0, 1, 2]]}, "meshes[0].vertices: expected an array of numbers"),
    ({"vertices": np.eye(3), "triangles": np.array([[0, 1, 2**63]], dtype=np.uint64)}, "vertex index 9223372036854775808 is out of range"),
])
def test_more_bad_scenes_raise_value_error_with_the_place(arguments, message):
    with pytest.raises(ValueError) as raised:
        vkray.Scene(**arguments)
    assert message in str(raised.value)


@pytest.mark.parametrize("call, message", [
    (lambda r: r.cast_rays(np.array([[0, 0, 0, np.nan, 0, 1]]), bad_rays="raise"), "ray 0: the direction is not finite"),
    (lambda r: r.cast_rays(np.array([[0, 0, 0, 0, 0, 1]], dtype=complex)), "rays: expected an array of numbers"),
    (lambda r: r.render({"from": [0, np.nan, 5]}), "camera: from: every number must be finite"),
    (lambda r: r.render({"to": [0, 0, 0], "fovy": float("inf")}), "camera: fovy: every number must be finite"),
    (lambda r: r.render(aovs=3), "aovs: expected a list of output names or one string"),
])
def test_more_bad_calls_raise_value_error_with_the_place(default_renderer, call, message):
    with pytest.raises(ValueError) as raised:
        call(default_renderer)
    assert message in str(raised.value)


def test_ranges_and_occlusion_queries_on_a_sphere_against_the_reference():
    """A unit sphere 4 in front of each ray (5 from its origin, as the scene is 2 across): its near side at 4, its
    far side at 6. Float32 places them within a few ulps; the bounds lie 0.05 away, far outside that."""
    scene = vkray.Scene(spheres=np.array([[0.0, 0.0, 0.0, 1.0]]))
    rays = np.array([[0, 0, 5, 0, 0, -1], [0, 5, 0, 0, -3, 0], [5, 0, 0, -2, 0, 0], [0, 0, 5, 0, 0, 1]], dtype=float)
    t_min = np.array([0.0, 4.05, 6.05, 0.0])
    t_max = np.array([3.95, np.inf, np.inf, np.inf])
    for caster, tolerance in ((vkray.Reference(scene), 0.0), (vkray.Renderer(scene), 8 * EPS)):
        t = caster.cast_rays(rays, t_min=t_min, t_max=t_max)["t"]
        assert t[0] == np.inf and t[2] == np.inf and t[3] == np.inf  # before the sphere, past it, away from it
        assert abs(t[1] - 6.0) <= tolerance * 6.0  # its far side
        assert caster.cast_rays(rays, t_max=4.05)["t"][:3] == pytest.approx([4.0] * 3, rel=max(tolerance, 1e-15))
        assert caster.occluded(rays, t_min=t_min, t_max=t_max).tolist() == [False, True, False, False]
        assert caster.occluded(rays, t_max=3.95).tolist() == [False] * 4
        assert caster.occluded(rays, t_max=np.float32(4.05)).tolist() == [True, True, True, False]  # numpy numbers too
        assert caster.occluded(rays, t_min=np.int64(5), t_max=7).tolist() == [True, True, True, False]
        assert caster.occluded(rays).tolist() == [True, True, True, False]
        assert caster.occluded(rays).dtype == np.bool_
    renderer = vkray.Renderer(scene)
    # A range the engine refuses makes its ray a miss, or fails the call where asked to.
    assert renderer.occluded(rays, t_min=1.0, t_max=[5.0, 0.5, 5.0, 5.0]).tolist() == [True, False, True, False]
    with pytest.raises(ValueError, match=r"ray 1: t_max is NaN or below t_min"):
        renderer.occluded(rays, t_min=1.0, t_max=[2.0, 0.5, 2.0, 2.0], bad_rays="raise")
    with pytest.raises(ValueError, match=r"t_min: expected None, a number or one value a ray \(4: .*got shape \(3\)"):
        renderer.cast_rays(rays, t_min=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"t_max: expected None, a number or one value a ray \(4: .*got shape \(4, 1\)"):
        vkray.Reference(scene).occluded(rays, t_max=np.ones((4, 1)))
    with pytest.raises(ValueError, match=r"t_max: expected an array of numbers"):
        renderer.cast_rays(rays, t_max=["far"] * 4)
    assert renderer.occluded(np.zeros((0, 6)), t_max=1.0).shape == (0,)


def test_no_rays_give_empty_arrays(default_renderer):
    hits = default_renderer.cast_rays(np.zeros((0, 6)))
    assert hits["t"].shape == (0,) and hits["normal"].shape == (0, 3) and hits["mesh_id"].shape == (0,)


def test_arrays_outlive_the_renderer():
    scene = vkray.load("", 16, 12)
    depth = vkray.Renderer(scene).render()["depth"]
    assert np.isfinite(depth).any()  # the renderer is gone; the array owns its memory


# Every output render() offers beside depth and normal, and its EXR channels (`vkray render --aov`).
def read_exr_native(path):
    """Every channel in its own type (the ids as uint32), and the header."""
    image = oiio.ImageInput.open(str(path))
    assert image, oiio.geterror()
    spec = image.spec()
    channels = {}
    for k, name in enumerate(spec.channelnames):
        kind = oiio.UINT if spec.channelformat(k) == oiio.UINT else oiio.FLOAT
        channels[name] = image.read_image(0, 0, k, k + 1, kind)[:, :, 0]
    image.close()
    return channels, spec


@pytest.mark.parametrize("model", [SPOT, TEAPOT])
def test_every_output_is_the_command_lines_exr_channel(tmp_path, model):
    """Renderer and Reference give every output of vkray.outputs (the engine's table of outputs)
    exactly as `vkray render --aov` (and --reference) writes its channels: spot has texture
    coordinates, the teapot normals. The Reference's depth and normal are its float64 values, which
    the file holds rounded to float32."""
    scene = vkray.load(need_model(model), 120, 90)
    names = [output["name"] for output in vkray.outputs]
    assert {"depth", "normal", "uv", "mesh_id"} <= set(names)
    aov_option = ",".join(name.replace("_", "-") for name in names)
    for make, extra in ((vkray.Renderer, []), (vkray.Reference, ["--reference"])):
        arrays = make(scene).render(aovs=names)
        assert sorted(arrays) == sorted(names)
        output = tmp_path / "all.exr"
        subprocess.run([os.environ["VKRAY_CLI"], "render", model, "--width", "120", "--height", "90", "--aov", aov_option,
                        "-o", str(output), "--no-preview", *extra], check=True, capture_output=True)
        channels, _ = read_exr_native(output)
        assert set(channels) == {c for o in vkray.outputs for c in o["channels"]} | {"A"}
        for entry in vkray.outputs:
            name = entry["name"]
            expected = np.stack([channels[c] for c in entry["channels"]], axis=-1)
            expected = expected.squeeze(-1) if entry["components"] == 1 else expected
            assert expected.dtype == entry["dtype"], name
            got = arrays[name]
            if make is vkray.Reference and name in ("depth", "normal"):
                assert got.dtype == np.float64, name
                got = got.astype(np.float32)
            assert got.dtype == expected.dtype and got.shape == expected.shape, name
            assert np.array_equal(got, expected), name
    # The file's attributes are there: texture coordinates on spot, normals apart from the faces' on the teapot.
    arrays = vkray.Renderer(scene).render(aovs=["normal", "mesh_id", "shading_normal", "texcoord"])
    hit = arrays["mesh_id"] != vkray.NO_HIT
    if model == SPOT:
        assert np.mean(np.any(arrays["texcoord"][hit] != 0, axis=-1)) > 0.5
    else:
        assert np.mean(np.linalg.norm(arrays["shading_normal"][hit] - arrays["normal"][hit], axis=-1) > 1e-3) > 0.5


def test_the_help_names_every_output_and_argument():
    """help(vkray.Renderer.render) lists every output of vkray.outputs by its key, and the
    constructor's help its every argument, as the Python page's API lines show them."""
    render_help = vkray.Renderer.render.__doc__
    missing = [o["name"] for o in vkray.outputs if f" {o['name']} (" not in render_help]
    assert not missing, missing
    for argument in ("device", "precision", "traversal"):
        assert f"{argument}:" in vkray.Renderer.__init__.__doc__, argument
    assert "device it opened" in vkray.Renderer.device_name.__doc__
    page = (pathlib.Path(__file__).parents[2] / "docs" / "python.md").read_text()
    assert 'vkray.Renderer(scene, device=None, precision="float", traversal="auto")' in page


def test_planar_depth_reprojects_to_the_position_channel_with_the_headers_camera(tmp_path):
    """What the EXR's header says of the camera is enough to reproject its planar depth to its P channel:
    OpenEXR's worldToCamera (float32, row vectors: p_camera = p_world M, x right, y up, z along the view)
    and vkray:camera's OpenCV intrinsics."""
    model = need_model(SPOT)
    output = tmp_path / "spot.exr"
    subprocess.run([os.environ["VKRAY_CLI"], "render", model, "--width", "160", "--height", "120", "--aov",
                    "planar-depth,position", "-o", str(output), "--no-preview"], check=True, capture_output=True)
    channels, spec = read_exr_native(output)
    world_to_camera = np.array(spec.getattribute("worldToCamera"), dtype=np.float64).reshape(4, 4)
    intrinsics = __import__("json").loads(spec.getattribute("vkray:camera"))["intrinsics"]
    z = channels["planar.Z"].astype(np.float64)
    hit = np.isfinite(z)
    v, u = np.nonzero(hit)
    z = z[hit]
    # OpenCV's pixel coordinates (x right, y down) to OpenEXR's camera space (y up).
    x = (u - intrinsics["cx"]) / intrinsics["fx"] * z
    y = -(v - intrinsics["cy"]) / intrinsics["fy"] * z
    camera_points = np.stack([x, y, z, np.ones_like(z)], axis=-1)
    world = (camera_points @ np.linalg.inv(world_to_camera))[:, :3]
    position = np.stack([channels["P.X"], channels["P.Y"], channels["P.Z"]], axis=-1)[hit].astype(np.float64)
    # Float32 roundings: of the planar depth (moves the point by |point - eye| 2^-24), of each P
    # component, and of the matrix' entries (rotation and translation, each 2^-24 of its size, times
    # the point's camera coordinates and the translation): a few 2^-24 of those magnitudes.
    eye = -world_to_camera[3, :3] @ world_to_camera[:3, :3].T
    scale = np.linalg.norm(position - eye, axis=-1) + np.linalg.norm(camera_points[:, :3], axis=-1) + \
        np.linalg.norm(world_to_camera[3, :3]) + np.abs(position).max(axis=-1)
    error = np.abs(world - position).max(axis=-1)
    assert len(z) > 1000
    assert np.all(error <= 4 * EPS * scale), (error / (EPS * scale)).max()


def test_load_frames_from_the_side_asked_for():
    """view= frames as `vkray render --view` does: the eye on that side of the centre, at the same distance."""
    front = vkray.load("", 64, 48, view="front").camera
    back = vkray.load("", 64, 48, view="back").camera
    right = vkray.load("", 64, 48, view=[1, 0.25, 0]).camera
    centre = np.array(front["to"])
    assert np.allclose(back["to"], centre) and np.allclose(right["to"], centre)
    distance = np.linalg.norm(np.array(front["from"]) - centre)
    for camera, axis, sign in ((front, 2, 1), (back, 2, -1), (right, 0, 1)):
        offset = np.array(camera["from"]) - centre
        assert np.isclose(np.linalg.norm(offset), distance)
        assert sign * offset[axis] > 0.9 * distance
    with pytest.raises(ValueError, match="view: unknown side 'behind'"):
        vkray.load("", 64, 48, view="behind")
    with pytest.raises(ValueError, match="must be finite and not 0"):
        vkray.load("", 64, 48, view=[0, 0, 0])
