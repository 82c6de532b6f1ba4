"""Ray masks from Python: a Scene's masks (by mesh_id, or a scene file's "mask") and mask= on each call,
against the reference with the same mask; what a mask hides is never hit, and bad masks are refused."""
import json

import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES

EPS = 2.0**-24  # float32 unit roundoff


def robot_and_room():
    """A sensor's own robot (a box about the origin, mask 2) inside a room's walls (a box 10 wide,
    mask 1), and a sphere on the floor (mask 4)."""
    meshes = [{"vertices": 5.0 * CUBE_CORNERS, "triangles": CUBE_FACES}, {"vertices": 0.5 * CUBE_CORNERS, "triangles": CUBE_FACES}]
    return vkray.Scene(meshes=meshes, spheres=[[2.5, -4.0, 1.0, 1.0]], masks={0: 1, 1: 2, 2: 4},
                       camera={"from": [0.0, 0.0, 0.0], "to": [0.0, 0.0, -1.0], "fovy": 100}, width=64, height=48)


@pytest.fixture(scope="module")
def scene():
    return robot_and_room()


def sensor_rays(count, seed=7):
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(count, 3))
    return np.hstack([np.zeros((count, 3)), directions])


@pytest.mark.parametrize("mask", [1, 2, 4, 5, 6, 255])
def test_a_call_s_mask_hides_what_shares_no_bit_with_it(scene, renderer, reference, mask):
    """The sensor inside its robot: with the robot's bit off, its rays reach the room and the sphere. Each
    ray's t is the reference's within float32's error, its mesh_id the reference's, and never one the
    mask hides; occluded is True exactly where cast_rays hit."""
    assert scene.masks == [1, 2, 4]
    rays = sensor_rays(20000)
    got = renderer.cast_rays(rays, mask=mask, outputs=("t", "mesh_id"))
    want = reference.cast_rays(rays, mask=mask, outputs=("t", "mesh_id"))
    hidden = [object_id for object_id, object_mask in enumerate(scene.masks) if object_mask & mask == 0]
    assert not np.isin(got["mesh_id"], hidden).any()
    hit = np.isfinite(want["t"])
    assert np.array_equal(np.isfinite(got["t"]), hit)
    assert np.array_equal(got["mesh_id"], want["mesh_id"])
    # Within a few float32 roundings of the distance: the walls are 5 to 9 away, the robot 0.5 to 0.9.
    assert np.all(np.abs(got["t"][hit] - want["t"][hit]) <= 16 * EPS * want["t"][hit])
    assert np.array_equal(renderer.occluded(rays, mask=mask), hit)
    image = renderer.render(aovs=("depth", "mesh_id"), mask=mask)
    assert not np.isin(image["mesh_id"], hidden).any()
    expected = reference.render(aovs=("depth", "mesh_id"), mask=mask)
    assert np.mean(image["mesh_id"] == expected["mesh_id"]) > 0.99  # edges of the sphere may differ


def test_every_bit_by_default_and_per_call(renderer):
    """A call without mask= sees everything, whatever mask the call before took."""
    rays = sensor_rays(1000)
    assert set(np.unique(renderer.cast_rays(rays, mask=1)["mesh_id"])) == {0}
    assert set(np.unique(renderer.cast_rays(rays)["mesh_id"])) == {1}  # the robot's box holds the sensor


def test_a_scene_file_s_masks(tmp_path):
    path = tmp_path / "masks.json"
    path.write_text(json.dumps({
        "camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "mask": 4}],
        "planes": [{"point": [0, -1, 0], "normal": [0, 1, 0]}],
        "meshes": [{"positions": [[0, 0, 2], [1, 0, 2], [0, 1, 2]], "triangles": [[0, 1, 2]], "mask": 3}]}))
    scene = vkray.load(path)
    assert scene.masks == [3, 4, 255]
    depth = vkray.Renderer(scene).render(aovs="mesh_id", mask=4)["mesh_id"]
    assert 0 not in depth and 1 in depth and 2 in depth


@pytest.mark.parametrize("mask", [0, 256, -1, 1.5, True, "1"])
def test_bad_masks_are_refused(renderer, mask):
    with pytest.raises(ValueError, match="mask"):
        renderer.cast_rays(sensor_rays(4), mask=mask)
    if mask != 0:  # an object's mask may be 0: no ray hits it
        with pytest.raises(ValueError, match="masks"):
            vkray.Scene(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles=[[0, 1, 2]], masks=[mask])
    with pytest.raises(ValueError, match="no object 3"):
        vkray.Scene(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles=[[0, 1, 2]], masks={3: 1})
