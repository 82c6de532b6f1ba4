"""Instances from Python: Scene(instances=...) places a mesh stored once; Renderer.set_transforms moves
them; cast_rays and render name the instance hit (instance_id), as the Reference does, before and
after a move; bad instances and transforms are refused with the entry named."""
import numpy as np
import pytest

import vkray
from shapes import CUBE_CORNERS, CUBE_FACES


def turned(degrees, scale=1.0, at=(0.0, 0.0, 0.0)):
    """A 4 x 4 affine matrix: a turn about y, a uniform scale (negative: mirrored), a translation."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    m = np.eye(4)
    m[:3, :3] = scale * np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    m[:3, 3] = at
    return m


@pytest.fixture(scope="module")
def scene():
    """A plain cube at x = 6, and a cube placed three times (the second mirrored), the third mask 2."""
    meshes = [{"vertices": CUBE_CORNERS, "triangles": CUBE_FACES},
              {"vertices": CUBE_CORNERS + [6.0, 0.0, 0.0], "triangles": CUBE_FACES}]
    instances = [{"mesh": 0, "transform": turned(30, 0.8, (-3.0, 0.0, 0.0))},
                 {"mesh": 0, "transform": turned(-20, -0.6, (0.0, 0.5, 0.0))},
                 {"mesh": 0, "transform": turned(45, 0.5, (3.0, -0.5, 0.0)), "mask": 2}]
    return vkray.Scene(meshes=meshes, instances=instances, camera={"from": [0, 2, 12], "to": [0, 0, 0], "fovy": 50},
                       width=96, height=48)


def grid_rays():
    """Rays toward -z from a grid in front of every object, each from its own origin."""
    xs, ys = np.meshgrid(np.linspace(-4.5, 7.5, 61), np.linspace(-1.5, 1.5, 15))
    rays = np.zeros(xs.shape + (6,))
    rays[..., 0], rays[..., 1], rays[..., 2], rays[..., 5] = xs, ys, 10.0, -1.0
    return rays


def expect_as_reference(renderer, reference, mask=255):
    """cast_rays against the Reference's: the same mesh, primitive and instance where both hit the
    same primitive (elsewhere an edge or a silhouette, which rounding decides), t to float32."""
    outputs = ("t", "mesh_id", "primitive_id", "instance_id")
    got = renderer.cast_rays(grid_rays(), outputs=outputs, mask=mask)
    want = reference.cast_rays(grid_rays(), outputs=outputs, mask=mask)
    same = (got["mesh_id"] == want["mesh_id"]) & (got["primitive_id"] == want["primitive_id"])
    assert same.mean() > 0.97
    assert np.array_equal(got["instance_id"][same], want["instance_id"][same])
    hit = same & np.isfinite(want["t"])
    assert np.allclose(got["t"][hit], want["t"][hit], rtol=1e-5)
    return got


def test_instances_as_the_reference_and_moved(scene):
    renderer, reference = vkray.Renderer(scene), vkray.Reference(scene)
    got = expect_as_reference(renderer, reference)
    assert set(np.unique(got["instance_id"])) == {0, 1, 2, vkray.NO_HIT}
    assert np.all(got["instance_id"][got["mesh_id"] == 1] == vkray.NO_HIT), "the plain mesh is no instance"
    assert np.all(got["mesh_id"][got["instance_id"] != vkray.NO_HIT] == 0), "each instance places mesh 0"
    assert 2 not in expect_as_reference(renderer, reference, mask=1)["instance_id"], "the masked instance was hit"

    moved = np.stack([turned(80, 0.7, (-2.0, 0.0, 0.0)), turned(10, 0.9, (2.5, 0.0, 0.0))])
    for caster in (renderer, reference):
        caster.set_transforms([2, 0], moved)
    assert renderer.timings["scene_update_ms"] > 0
    got = expect_as_reference(renderer, reference)
    image = renderer.render(aovs=("depth", "instance_id"))["instance_id"]
    assert image.shape == (48, 96) and set(np.unique(image)) == {0, 1, 2, vkray.NO_HIT}


def test_first_hits_name_each_hit_s_instance(scene):
    """hits=4 along rays through the placed cubes (in and out of each): per hit, the Reference's mesh,
    primitive and instance where both hit the same primitive, t to float32."""
    outputs = ("t", "mesh_id", "primitive_id", "instance_id")
    rays = grid_rays().reshape(-1, 6)
    rays[:, 3:] = [0.3, 0.1, -1.0]  # askew: through the cubes' sides too
    got = vkray.Renderer(scene).cast_rays(rays, outputs=outputs, hits=4)
    want = vkray.Reference(scene).cast_rays(rays, outputs=outputs, hits=4)
    assert got["instance_id"].shape == (len(rays), 4)
    same = (got["mesh_id"] == want["mesh_id"]) & (got["primitive_id"] == want["primitive_id"])
    assert same.mean() > 0.97
    assert np.array_equal(got["instance_id"][same], want["instance_id"][same])
    hit = same & np.isfinite(want["t"])
    assert np.allclose(got["t"][hit], want["t"][hit], rtol=1e-5)
    assert (got["instance_id"][:, 1] != vkray.NO_HIT).sum() > 50, "second hits inside the instances"


def test_bad_instances_and_transforms_are_refused(scene):
    cube = {"vertices": CUBE_CORNERS, "triangles": CUBE_FACES}
    with pytest.raises(ValueError, match=r"instances\[0\]\.mesh: 3 is not a mesh_id"):
        vkray.Scene(meshes=[cube], instances=[{"mesh": 3}])
    with pytest.raises(ValueError, match=r"instances\[0\]: unknown key 'scale'"):
        vkray.Scene(meshes=[cube], instances=[{"mesh": 0, "scale": 2}])
    with pytest.raises(ValueError, match=r"instances\[0\]\.transform: cannot be inverted"):
        vkray.Scene(meshes=[cube], instances=[{"mesh": 0, "transform": np.diag([1.0, 0.0, 1.0, 1.0])}])
    renderer = vkray.Renderer(scene)
    with pytest.raises(ValueError, match=r"instances\[1\]: 7 is not an instance"):
        renderer.set_transforms([0, 7], np.stack([np.eye(4)] * 2))
    not_affine = np.eye(4)
    not_affine[3, 0] = 1.0
    with pytest.raises(ValueError, match=r"transforms\[0\]: expected a 4 x 4 affine matrix"):
        renderer.set_transforms([0], not_affine)
    with pytest.raises(ValueError, match="2 instances but 1 transforms"):
        renderer.set_transforms([0, 1], np.eye(4))
