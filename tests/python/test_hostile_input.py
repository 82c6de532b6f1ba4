"""Hostile input from Python (the third campaign: instances, masks, rays cast in place, threads): each
case ends as the contract says, a ValueError of one line naming the input and the place, or the right
result; never a signal, from any input or thread."""
import json
import threading

import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES

CAMERA = {"from": [0, 1, 6], "to": [0, 0, 0], "fovy": 50}


@pytest.fixture(scope="module")
def scene():
    """The cube alone, for the tests that cast rays (conftest.py makes its renderer once)."""
    return vkray.Scene(CUBE_CORNERS, CUBE_FACES, camera=CAMERA)


def leaf_scene_file(folder, transform, extra_meshes=""):
    """A scene file: a named cube placed at home and by `transform`."""
    meshes = [{"name": "cube", "positions": CUBE_CORNERS.tolist(), "triangles": CUBE_FACES.tolist()}]
    scene = {"camera": CAMERA, "meshes": meshes,
             "instances": [{"mesh": "cube"}, {"mesh": "cube", "transform": transform}]}
    path = folder / "scene.json"
    path.write_text(json.dumps(scene))
    return path


@pytest.mark.parametrize("transform, detail", [
    ({"scale": 1e39}, "within 1e15"),            # crashed Embree's builder under --check
    ({"scale": 1e38}, "within 1e15"),            # rendered every ray a miss, exit 0
    ({"translate": [1e16, 0, 0]}, "within 1e15"),
    ({"scale": 1e-120}, "cannot be inverted"),
    ({"scale": [1, 1, 1e-39]}, "flattens the mesh"),  # vanished on the device
])
def test_a_scene_files_instances_are_checked_as_it_loads(tmp_path, transform, detail):
    path = leaf_scene_file(tmp_path, transform)
    with pytest.raises(ValueError, match=r"scene\.json: instances\[1\]\.transform: .*" + detail):
        vkray.load(path)


def test_placements_float32_cannot_walk_are_refused():
    """A scale of 1e-38 on one axis passed the determinant's check and vanished on the device; an
    ill-conditioned matrix lost every ray."""
    flat = np.diag([1.0, 1.0, 1e-38, 1.0])
    turn = np.eye(4)
    turn[:3, :3] = [[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]
    ill = turn @ np.diag([2e6, 1.0, 5e-7, 1.0])
    for transform, detail in [(flat, "flattens the mesh"), (ill, "flattens the mesh")]:
        with pytest.raises(ValueError, match=r"instances\[0\]\.transform: .*" + detail):
            vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}],
                        instances=[{"mesh": 0, "transform": transform}], camera=CAMERA)


def test_moved_vertices_are_checked_where_instances_place_them():
    scene = vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}],
                        instances=[{"mesh": 0, "transform": np.diag([1e10, 1e10, 1e10, 1.0])}], camera=CAMERA)
    renderer = vkray.Renderer(scene)
    with pytest.raises(ValueError, match=r"instances\[0\]\.transform: the mesh's box placed"):
        renderer.set_vertices(0, CUBE_CORNERS * 1e6)  # each within 1e15; placed, 1e16


def test_rays_rewritten_by_another_thread_never_crash(renderer):
    """The check of the rays named a bad ray by checking it again: a ray the caller's other thread had
    mended meanwhile gave no message, and the process fell (SIGSEGV). The
    GIL is released during calls, so a plain program does this."""
    rays = np.zeros((64, 6))
    rays[:, 2], rays[:, 5] = 5.0, -1.0
    stop = threading.Event()

    def flip():
        while not stop.is_set():
            rays[7, 3] = np.nan
            rays[7, 3] = 0.0

    flipper = threading.Thread(target=flip)
    flipper.start()
    refused = 0
    try:
        for _ in range(400):
            for call in (lambda: renderer.cast_rays(rays, bad_rays="raise"),
                         lambda: renderer.count_intersections(rays, bad_rays="raise")):
                try:
                    call()
                except ValueError as error:
                    assert str(error).startswith("ray 7: the direction is not finite"), str(error)
                    refused += 1
    finally:
        stop.set()
        flipper.join()
    assert refused > 0, "the other thread never broke ray 7 during a call: the test tested nothing"


def test_timings_read_from_two_threads_stay_whole(renderer):
    """The timings' text was returned after the renderer's lock was released: another thread's call
    rewrote it under the reader (UnicodeDecodeError, 14 to 214 of 40,000 reads)."""
    renderer.render(width=8, height=8)
    failures = []

    def read():
        for _ in range(20000):
            try:
                assert "setup" in renderer.timings
            except Exception as error:  # noqa: BLE001: any failure counts
                failures.append(repr(error))

    threads = [threading.Thread(target=read) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert failures == []


@pytest.mark.parametrize("arguments, message", [
    ({"width": 2**32 + 64}, r"width: expected a whole number in 1 \.\. 65536"),
    ({"height": True}, r"height: expected a whole number"),
    ({"width": 64.5}, r"width: expected a whole number"),
])
def test_sizes_are_never_wrapped(arguments, message):
    """Scene(width=2**32+64).width was 64."""
    with pytest.raises(ValueError, match=message):
        vkray.Scene(CUBE_CORNERS, CUBE_FACES, **arguments)


@pytest.mark.parametrize("transform, message", [
    (np.stack([np.eye(4), np.eye(4)]), r"instances\[0\]\.transform: expected a 4 x 4 matrix, got shape \(2, 4, 4\)"),
    (np.eye(4) * (1 + 1j), r"instances\[0\]\.transform: expected an array of numbers"),
    ([["1", "0", "0", "0"]] * 4, r"instances\[0\]\.transform: expected an array of numbers"),
    (np.eye(4, dtype=bool), r"instances\[0\]\.transform: expected an array of numbers"),
])
def test_transforms_are_taken_as_given_or_refused(transform, message):
    """A (2, 4, 4) transform lost its second matrix; complex ones their imaginary part; strings and
    booleans were taken as numbers."""
    with pytest.raises(ValueError, match=message):
        vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}],
                    instances=[{"mesh": 0, "transform": transform}], camera=CAMERA)


def test_a_named_mesh_no_instance_places_is_drawn_nowhere(tmp_path):
    """It failed with "build_bvh: no primitives" where the reference drew the scene."""
    scene_file = tmp_path / "unplaced.json"
    scene_file.write_text(json.dumps({
        "camera": CAMERA,
        "meshes": [{"name": "cube", "positions": CUBE_CORNERS.tolist(), "triangles": CUBE_FACES.tolist()}],
        "planes": [{"point": [0, -2, 0], "normal": [0, 1, 0]}]}))
    scene = vkray.load(scene_file)
    rays = np.array([[0.0, 0.0, 5.0, 0.0, 0.0, -1.0], [0.0, 0.0, 5.0, 0.0, -1.0, -1.0]])
    got = vkray.Renderer(scene).cast_rays(rays, outputs=("t", "mesh_id"))
    want = vkray.Reference(scene).cast_rays(rays, outputs=("t", "mesh_id"))
    assert np.array_equal(got["mesh_id"], want["mesh_id"]) and got["mesh_id"][0] == vkray.NO_HIT
    assert got["mesh_id"][1] == 1 and np.isclose(got["t"][1], want["t"][1], rtol=1e-6)


def test_set_transforms_takes_each_instance_once_and_nothing_at_all():
    scene = vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}],
                        instances=[{"mesh": 0}, {"mesh": 0, "transform": np.diag([0.5, 0.5, 0.5, 1.0])}], camera=CAMERA)
    renderer = vkray.Renderer(scene)
    with pytest.raises(ValueError, match=r"instances\[1\]: instance 0 is placed twice \(entries 0 and 1\)"):
        renderer.set_transforms([0, 0], np.stack([np.eye(4), np.eye(4)]))
    renderer.set_transforms([], np.zeros((0, 4, 4)))  # nothing to move: no error


def test_ragged_rays_and_masks_of_placed_meshes_are_named(renderer):
    with pytest.raises(ValueError, match=r"^rays: expected an array of numbers"):
        renderer.cast_rays([[0, 0, 5, 0, 0, -1], [0, 0, 5, 0, -1]])
    with pytest.raises(ValueError, match=r"meshes\[0\]\.mask: the mesh is drawn by its instances"):
        vkray.Scene(meshes=[{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}], instances=[{"mesh": 0}], masks={0: 2},
                    camera=CAMERA)


@pytest.mark.parametrize("ranges, message", [
    ({"t_min": -1e-6}, r"t_min: -1e-06 for every ray"),
    ({"t_max": float("nan")}, r"t_max: nan for every ray"),
    ({"t_max": 0.0}, r"t_max: 0\.0 for every ray"),
    ({"t_min": 2.0, "t_max": 1.0}, r"t_max: 1\.0 is not above t_min 2\.0"),
])
def test_a_call_wide_range_that_cannot_be_right_is_refused(renderer, ranges, message):
    """A scalar t_min=-1e-6 or t_max=nan turned every ray into a miss under bad_rays='miss', which is
    meant for one dead beam among many; per-ray values stay misses."""
    rays = np.array([[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]] * 3)
    with pytest.raises(ValueError, match=message):
        renderer.cast_rays(rays, **ranges)
    per_ray = renderer.cast_rays(rays, t_min=[0.0, -1.0, 0.0], outputs=("t",))["t"]
    assert np.isfinite(per_ray[0]) and np.isinf(per_ray[1]) and np.isfinite(per_ray[2])
