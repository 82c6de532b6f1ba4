"""Many views in one run of `vkray render` (--views, --orbit, --sphere): shards, resuming after a
kill, the manifest, the errors a batch user meets, and the Slurm script and Kubernetes Job of
docs/many-views.md run locally with the environment their schedulers set. ctest runs this with pytest
(tests/CMakeLists.txt sets VKRAY_CLI and VKRAY_SOURCE_DIR); nothing is written outside tmp_path."""
import json
import math
import os
import re
import signal
import subprocess
import time

import numpy as np
import OpenImageIO as oiio
import pytest
import yaml

VKRAY = os.environ["VKRAY_CLI"]
SOURCE = os.environ["VKRAY_SOURCE_DIR"]
SIZE = ["--width", "64", "--height", "48"]


def vkray(*arguments, check=True, env=None, cwd=None):
    result = subprocess.run([VKRAY, *arguments], capture_output=True, text=True, env=env, cwd=cwd)
    if check and result.returncode != 0:
        raise AssertionError(f"vkray {' '.join(arguments)}: exit {result.returncode}\n{result.stderr}")
    return result


def pixels(path):
    image = oiio.ImageInput.open(str(path))
    assert image, oiio.geterror()
    names = image.spec().channelnames
    data = image.read_image(oiio.FLOAT)
    image.close()
    return names, data


def same_pixels(a, b):
    names_a, data_a = pixels(a)
    names_b, data_b = pixels(b)
    return names_a == names_b and np.array_equal(data_a, data_b)


def manifest_records(path):
    """A manifest's records by index (writers append them as views complete, in any order)."""
    with open(path) as manifest:
        lines = manifest.read().splitlines()
    records = [json.loads(line) for line in lines]
    assert all(isinstance(record["index"], int) for record in records)
    return sorted(records, key=lambda record: record["index"])


def views_in(folder):
    """The EXRs in place (a write in progress has a hidden temporary name)."""
    return sorted(name for name in os.listdir(folder) if name.endswith(".exr") and not name.startswith("."))


@pytest.fixture(scope="module")
def whole_run(tmp_path_factory):
    """12 orbiting views of the built-in scene, unsharded: what every other run must reproduce."""
    folder = tmp_path_factory.mktemp("whole")
    vkray("render", *SIZE, "--orbit", "12", "-o", str(folder / "view-{index:05}.exr"))
    return folder


def test_the_orbit_turns_the_camera_about_up_through_to(whole_run):
    records = manifest_records(whole_run / "manifest.jsonl")
    assert [record["index"] for record in records] == list(range(12))
    first, third = records[0]["camera"], records[3]["camera"]  # 90 degrees apart
    to = np.array(first["to"])
    a, b = np.array(first["from"]) - to, np.array(third["from"]) - to
    up = np.array(first["up"]) / np.linalg.norm(first["up"])
    assert abs(np.linalg.norm(a) - np.linalg.norm(b)) < 1e-12 * np.linalg.norm(a)
    assert abs(a @ up - b @ up) < 1e-12 * np.linalg.norm(a)  # the same height
    flat_a, flat_b = a - (a @ up) * up, b - (b @ up) * up
    assert abs(flat_a @ flat_b) < 1e-12 * (flat_a @ flat_a)  # a quarter turn
    assert np.cross(flat_a, flat_b) @ up > 0  # counterclockwise seen from above


def test_the_manifest_reprojects_each_views_depth(whole_run):
    """K [R t] of a record maps each pixel's hit point (from, plus depth along its ray) back to that
    pixel: the intrinsics and world-to-camera matrix describe the image that was written."""
    record = manifest_records(whole_run / "manifest.jsonl")[5]
    names, data = pixels(whole_run / record["exr"])
    depth = data[:, :, names.index("Z")]
    height, width = depth.shape
    k = record["intrinsics"]
    rt = np.array(record["world_to_camera"])
    eye = np.array(record["camera"]["from"])
    j, i = np.nonzero(np.isfinite(depth))
    # The pixel's ray in camera coordinates, from the intrinsics; then into the world.
    rays = np.stack([(i - k["cx"]) / k["fx"], (j - k["cy"]) / k["fy"], np.ones_like(i, dtype=float)], axis=-1)
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    points = eye + (rays @ rt[:3, :3]) * depth[j, i, None]
    camera = points @ rt[:3, :3].T + rt[:3, 3]
    u = k["fx"] * camera[:, 0] / camera[:, 2] + k["cx"]
    v = k["fy"] * camera[:, 1] / camera[:, 2] + k["cy"]
    assert len(i) > 100
    assert np.max(np.abs(u - i)) < 1e-3 and np.max(np.abs(v - j)) < 1e-3


def quaternion_matrix(w, x, y, z):
    """The rotation of a unit quaternion (Hamilton's convention, as COLMAP writes it)."""
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def hit_points(path):
    """A view's planar depth and world hit points (P) where it hits, and those pixels' (i, j)."""
    names, data = pixels(path)
    planar = data[:, :, names.index("planar.Z")]
    j, i = np.nonzero(np.isfinite(planar))
    points = np.stack([data[j, i, names.index(f"P.{axis}")] for axis in "XYZ"], axis=-1).astype(np.float64)
    return i, j, planar[j, i].astype(np.float64), points


def test_nerf_and_colmap_exports_reproject_each_views_planar_depth(tmp_path):
    """`manifest export` read back with each format's published conventions: NeRF's
    transform_matrix is camera-to-world in OpenGL axes (x right, y up, looking down -z) and its
    intrinsics put pixel centres at +0.5; COLMAP's images.txt holds world-to-camera as a quaternion
    and translation in OpenCV axes, its PINHOLE camera the same +0.5 centres. Each view's planar
    depth, back-projected through NeRF's camera, lands on the view's hit points (P), and each hit
    point, projected through COLMAP's camera, lands on its own pixel's centre at its planar depth.
    P and planar.Z come from one double hit point rounded to float32 once each: a few roundings,
    2^-21 of the distances involved."""
    run = tmp_path / "run"
    vkray("render", *SIZE, "--orbit", "6", "--aov", "planar-depth,position", "-o", str(run / "view-{index}.exr"))
    vkray("manifest", "export", str(run / "manifest.jsonl"), "--format", "nerf", "-o", str(tmp_path / "nerf"))
    vkray("manifest", "export", str(run / "manifest.jsonl"), "--format", "colmap", "-o", str(tmp_path / "colmap"))
    rounding = 2.0 ** -21

    transforms = json.loads((tmp_path / "nerf" / "transforms.json").read_text())
    assert len(transforms["frames"]) == 6
    for frame in transforms["frames"]:
        camera = {key: frame.get(key, transforms.get(key)) for key in ("fl_x", "fl_y", "cx", "cy", "w", "h")}
        assert (camera["w"], camera["h"]) == (64, 48)
        c2w = np.array(frame["transform_matrix"])
        i, j, depth, points = hit_points(tmp_path / "nerf" / frame["file_path"])
        assert len(i) > 100
        x, y = i + 0.5, j + 0.5
        in_camera = np.stack([(x - camera["cx"]) / camera["fl_x"] * depth, -(y - camera["cy"]) / camera["fl_y"] * depth,
                              -depth], axis=-1)
        world = in_camera @ c2w[:3, :3].T + c2w[:3, 3]
        scale = np.linalg.norm(points, axis=-1) + np.linalg.norm(c2w[:3, 3])
        assert np.all(np.linalg.norm(world - points, axis=-1) <= rounding * scale), frame["file_path"]

    cameras = {}
    for line in (tmp_path / "colmap" / "cameras.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            fields = line.split()
            assert fields[1] == "PINHOLE"
            cameras[fields[0]] = [float(value) for value in fields[2:]]
    lines = [line for line in (tmp_path / "colmap" / "images.txt").read_text().split("\n") if not line.startswith("#")]
    images = [line.split() for line in lines[0::2] if line]
    assert len(images) == 6 and all(line == "" for line in lines[1::2])
    assert (tmp_path / "colmap" / "points3D.txt").exists()
    for image in images:
        w, x, y, z, tx, ty, tz = (float(value) for value in image[1:8])
        width, height, fx, fy, cx, cy = cameras[image[8]]
        rotation, translation = quaternion_matrix(w, x, y, z), np.array([tx, ty, tz])
        i, j, depth, points = hit_points(tmp_path / "colmap" / image[9])
        in_camera = points @ rotation.T + translation
        u = fx * in_camera[:, 0] / in_camera[:, 2] + cx
        v = fy * in_camera[:, 1] / in_camera[:, 2] + cy
        scale = np.linalg.norm(points, axis=-1) + np.linalg.norm(translation)
        assert np.all(np.abs(in_camera[:, 2] - depth) <= rounding * scale), image[9]
        # A hit point off by `rounding * scale` moves its projection by that times f / depth pixels.
        pixel_tolerance = rounding * scale * max(fx, fy) / depth
        assert np.all(np.abs(u - (i + 0.5)) <= pixel_tolerance) and np.all(np.abs(v - (j + 0.5)) <= pixel_tolerance)


def test_manifest_export_refuses_a_short_set_views_without_a_pinhole_and_colmap_names_with_spaces(tmp_path):
    vkray("render", *SIZE, "--orbit", "4", "--shard", "0/2", "-o", str(tmp_path / "short" / "view-{index}.exr"))
    part = next((tmp_path / "short").glob("manifest-shard-*.jsonl"))
    result = vkray("manifest", "export", str(part), "--format", "nerf", "-o", str(tmp_path / "out"), check=False)
    assert result.returncode == 2 and "view" in result.stderr and len(result.stderr.splitlines()) == 1, result.stderr
    assert not (tmp_path / "out" / "transforms.json").exists()
    panorama = tmp_path / "panorama.json"
    panorama.write_text(json.dumps({"camera": {"from": [0, 0, 0], "to": [0, 0, -1], "projection": "equirectangular"},
                                    "spheres": [{"center": [0, 0, -3], "radius": 1}]}))
    vkray("render", str(panorama), *SIZE, "--orbit", "2", "-o", str(tmp_path / "pano" / "view-{index}.exr"))
    result = vkray("manifest", "export", str(tmp_path / "pano" / "manifest.jsonl"), "--format", "colmap", "-o",
                   str(tmp_path / "out"), check=False)
    assert result.returncode == 2 and "no pinhole camera" in result.stderr, result.stderr
    result = vkray("manifest", "export", str(tmp_path / "pano" / "manifest.jsonl"), "--format", "ply", "-o",
                   str(tmp_path / "out"), check=False)
    assert result.returncode == 2 and "nerf, colmap" in result.stderr, result.stderr
    # COLMAP ends a name at its first space: such a name is refused, where NeRF's JSON holds it.
    vkray("render", *SIZE, "--orbit", "2", "-o", str(tmp_path / "spaced" / "view {index}.exr"))
    result = vkray("manifest", "export", str(tmp_path / "spaced" / "manifest.jsonl"), "--format", "colmap", "-o",
                   str(tmp_path / "spaced-colmap"), check=False)
    assert result.returncode == 2 and "view 0.exr' holds one" in result.stderr and len(result.stderr.splitlines()) == 1, result.stderr
    assert not (tmp_path / "spaced-colmap" / "images.txt").exists()
    vkray("manifest", "export", str(tmp_path / "spaced" / "manifest.jsonl"), "--format", "nerf", "-o", str(tmp_path / "spaced-nerf"))
    frames = json.loads((tmp_path / "spaced-nerf" / "transforms.json").read_text())["frames"]
    assert [os.path.basename(frame["file_path"]) for frame in frames] == ["view 0.exr", "view 1.exr"]


def channel_formats(path):
    image = oiio.ImageInput.open(str(path))
    spec = image.spec()
    formats = dict(zip(spec.channelnames, [str(f) for f in spec.channelformats] or [str(spec.format)] * spec.nchannels))
    image.close()
    return formats


def test_half_outputs_are_the_float_channels_rounded_to_half(tmp_path):
    """--half normal stores N.X, N.Y, N.Z as half floats: each value is the float32 file's rounded to
    the nearest half (numpy's float16 rounds to nearest even, as OpenEXR does), the other channels
    untouched; in one view and in many. --check then reports the stored error, within 2^-11."""
    for many in (False, True):
        where = tmp_path / ("many" if many else "one")
        where.mkdir()
        views = ["--orbit", "2"] if many else []
        names = [where / "float-{index}.exr", where / "half-{index}.exr"] if many else [where / "float.exr", where / "half.exr"]
        # Two datasets, each with its manifest: one manifest refuses a run that stores values otherwise.
        manifests = [["--manifest", str(where / f"{kind}.jsonl")] if many else [] for kind in ("float", "half")]
        vkray("render", *SIZE, *views, "--aov", "depth,normal", "-o", str(names[0]), *manifests[0])
        vkray("render", *SIZE, *views, "--aov", "depth,normal", "--half", "normal", "-o", str(names[1]), *manifests[1])
        pairs = [(where / f"float-{k}.exr", where / f"half-{k}.exr") for k in range(2)] if many else [tuple(names)]
        for whole, half in pairs:
            formats = channel_formats(half)
            assert [formats[c] for c in ("N.X", "N.Y", "N.Z")] == ["half"] * 3 and formats["Z"] == "float", formats
            names_whole, data_whole = pixels(whole)
            names_half, data_half = pixels(half)
            assert names_whole == names_half
            for channel, name in enumerate(names_whole):
                expected = data_whole[..., channel]
                if name.startswith("N."):
                    expected = expected.astype(np.float16).astype(np.float32)
                assert np.array_equal(data_half[..., channel], expected), name
    checked = vkray("render", *SIZE, "--aov", "depth,normal", "--half", "depth", "--check", "-o", str(tmp_path / "c.exr"))
    stored = re.search(r"as stored, with --half depth: .*depth rel. error p50 \S+ p99 \S+ max (\S+);", checked.stdout)
    assert stored, checked.stdout
    assert float(stored.group(1)) <= 2.0 ** -11 + 2e-6  # half's rounding on top of the depth's own error
    refused = vkray("render", *SIZE, "--aov", "depth,mesh-id", "--half", "mesh-id", "-o", str(tmp_path / "r.exr"), check=False)
    assert refused.returncode == 2 and "holds integers" in refused.stderr, refused.stderr


def test_npy_outputs_are_the_exr_channels_bit_for_bit_and_png16_their_depth_in_steps(tmp_path):
    """--format npy writes one .npy an output holding exactly the EXR's channels (the ids too, misses
    at --miss, half where --half says), in one view and in many, named in the manifest's "files";
    --format png16 writes depth in steps of --depth-step, 0 where there is none."""
    outputs = "depth,normal,planar-depth,mesh-id"
    for many in (False, True):
        where = tmp_path / ("many" if many else "one")
        where.mkdir()
        views = ["--orbit", "2"] if many else []
        exr = where / ("v-{index}.exr" if many else "v.exr")
        vkray("render", *SIZE, *views, "--aov", outputs, "--miss", "0", "-o", str(exr))
        npy = ["render", *SIZE, *views, "--aov", outputs, "--miss", "0", "--format", "npy", "--half", "normal", "-o", str(exr)]
        if many:  # the manifest records EXRs: a run writing npy files is another run
            refused = vkray(*npy, check=False)
            assert refused.returncode == 2 and "the format: exr then, npy now" in refused.stderr, refused.stderr
            npy.append("--overwrite")
        vkray(*npy)
        for k in range(2 if many else 1):
            name = f"v-{k}" if many else "v"
            names, data = pixels(where / f"{name}.exr")
            channels = {channel: data[..., i] for i, channel in enumerate(names)}
            assert np.array_equal(np.load(where / f"{name}.depth.npy"), channels["Z"])
            assert np.array_equal(np.load(where / f"{name}.planar-depth.npy"), channels["planar.Z"])
            normal = np.load(where / f"{name}.normal.npy")
            assert normal.dtype == np.float16 and normal.shape == (*channels["Z"].shape, 3)
            stacked = np.stack([channels["N.X"], channels["N.Y"], channels["N.Z"]], axis=-1)
            assert np.array_equal(normal, stacked.astype(np.float16))
            ids = np.load(where / f"{name}.mesh-id.npy")
            assert ids.dtype == np.uint32 and np.array_equal(ids, read_ids(where / f"{name}.exr"))
        if many:
            records = sorted(manifest_records(where / "manifest.jsonl"), key=lambda r: r["index"])
            assert [r["files"] for r in records] == [{output: f"v-{k}.{output}.npy" for output in outputs.split(",")} for k in range(2)]
    step = 2.0**-10
    vkray("render", *SIZE, "--aov", "depth", "--format", "png16", "--depth-step", str(step), "-o", str(tmp_path / "d.exr"))
    depth = pixels(tmp_path / "one" / "v.exr")[1][..., pixels(tmp_path / "one" / "v.exr")[0].index("Z")]
    image = oiio.ImageInput.open(str(tmp_path / "d.depth.png"))
    assert image.spec().format == oiio.UINT16 and image.spec().getattribute("vkray:depth_step") == repr(step)
    steps = image.read_image(oiio.UINT16)[..., 0].astype(np.float64)
    image.close()
    held = (depth > 0) & (depth / step <= 65535)  # a hit within 65535 steps (the ground plane goes on past them)
    assert np.all(steps[~held] == 0) and np.all(steps[held] > 0) and np.count_nonzero(held) > 1000
    assert np.max(np.abs(steps[held] * step - depth[held])) <= step / 2
    refused = vkray("render", *SIZE, "--aov", "depth,normal", "--format", "png16", "-o", str(tmp_path / "r.exr"), check=False)
    assert refused.returncode == 2 and "'normal' is not a depth" in refused.stderr, refused.stderr


def read_ids(path):
    image = oiio.ImageInput.open(str(path))
    channel = list(image.spec().channelnames).index("mesh_id")
    ids = image.read_image(0, 0, channel, channel + 1, oiio.UINT)[..., 0]
    image.close()
    return ids


def test_shards_together_are_the_whole_run(whole_run, tmp_path):
    for shard in range(3):
        vkray("render", *SIZE, "--orbit", "12", "-o", str(tmp_path / "view-{index:05}.exr"), "--shard", f"{shard}/3")
    assert views_in(tmp_path) == views_in(whole_run)
    for name in views_in(whole_run):
        assert same_pixels(tmp_path / name, whole_run / name), name
    parts = sorted(str(tmp_path / name) for name in os.listdir(tmp_path) if name.startswith("manifest-shard-"))
    assert len(parts) == 3
    for shard, part in enumerate(parts):
        assert [record["index"] for record in manifest_records(part)] == list(range(shard, 12, 3))
    vkray("manifest", "merge", *parts, "-o", str(tmp_path / "manifest.jsonl"))
    assert manifest_records(tmp_path / "manifest.jsonl") == manifest_records(whole_run / "manifest.jsonl")


def test_a_manifest_merged_into_another_folder_names_files_that_open(tmp_path):
    """Its records' file names are rewritten relative to the merged manifest, wherever it is."""
    renders = tmp_path / "renders"
    for shard in range(2):
        vkray("render", *SIZE, "--orbit", "4", "-o", str(renders / "v-{index}.exr"), "--preview", str(renders / "v-{index}.png"),
              "--shard", f"{shard}/2")
    parts = sorted(str(renders / name) for name in os.listdir(renders) if name.startswith("manifest-shard-"))
    for merged in (tmp_path / "elsewhere" / "deeper" / "all.jsonl", tmp_path / "all.jsonl"):
        merged.parent.mkdir(parents=True, exist_ok=True)
        result = vkray("manifest", "merge", *parts, "-o", str(merged))
        assert result.stdout == f"vkray: {merged} holds 4 views from 2 parts\n"
        records = manifest_records(merged)
        assert [record["index"] for record in records] == [0, 1, 2, 3]
        for record in records:
            for key in ("exr", "png"):
                assert (merged.parent / record[key]).resolve() == (renders / f"v-{record['index']}.{key}").resolve()
                assert (merged.parent / record[key]).is_file()
    vkray("render", *SIZE, "--orbit", "1", "-o", str(tmp_path / "single" / "v-{index}.exr"))
    result = vkray("manifest", "merge", str(tmp_path / "single" / "manifest.jsonl"), "-o", str(tmp_path / "one.jsonl"))
    assert result.stdout.endswith("holds 1 view from 1 part\n")


def test_a_killed_run_started_again_completes_the_set(tmp_path):
    command = [VKRAY, "render", "--width", "160", "--height", "120", "--orbit", "120", "-o", str(tmp_path / "v-{index:05}.exr")]
    run = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    manifest = tmp_path / "manifest.jsonl"
    deadline = time.monotonic() + 300
    while run.poll() is None and time.monotonic() < deadline:
        if manifest.exists() and manifest.read_text().count("\n") >= 5:
            break
        time.sleep(0.002)
    run.send_signal(signal.SIGKILL)
    run.wait()
    # A view counts once recorded: one whose file the kill left unrecorded is rendered again.
    done_before = len(manifest_records(manifest))
    assert 5 <= done_before < 120, f"the kill came at {done_before} of 120 views: the test tested nothing"
    # What a kill can leave: a temporary file of a write in progress, from a process that is gone.
    (tmp_path / f".v-00119.vkray-{run.pid}-7.exr").write_bytes(b"half an EXR")
    result = vkray(*command[1:])
    assert f"{120 - done_before} views written, {done_before} complete already" in result.stdout
    assert len(views_in(tmp_path)) == 120
    assert not [name for name in os.listdir(tmp_path) if ".vkray-" in name]
    assert [record["index"] for record in manifest_records(manifest)] == list(range(120))
    whole = tmp_path / "whole"
    vkray("render", "--width", "160", "--height", "120", "--orbit", "120", "-o", str(whole / "v-{index:05}.exr"))
    for name in views_in(whole):
        assert same_pixels(tmp_path / name, whole / name), name


def test_a_temporary_file_is_stale_by_its_lock_not_its_process_id(tmp_path):
    """A writer on another node of a shared file system, or a restarted container, can have the process
    id of a live process here: a temporary file no one holds locked is stale whatever its name says,
    and one a live writer holds locked is left alone."""
    import fcntl
    out = str(tmp_path / "v-{index}.exr")
    vkray("render", *SIZE, "--orbit", "4", "-o", out)
    for index in (1, 2):
        (tmp_path / f"v-{index}.exr").unlink()
    # Named with a live process's id (this test's): left by a writer that is gone all the same.
    left = tmp_path / f".v-1.vkray-{os.getpid()}-0.exr"
    left.write_bytes(b"half an EXR")
    # Held locked, as a live writer holds its file, under the id of a process that does not exist here.
    held = tmp_path / ".v-2.vkray-999999999-0.exr"
    held.write_bytes(b"being written")
    with open(held, "rb") as writer:
        fcntl.flock(writer, fcntl.LOCK_EX)
        result = vkray("render", *SIZE, "--orbit", "4", "-o", out)
        assert "2 views written, 2 complete already" in result.stdout
        assert not left.exists()
        assert held.read_bytes() == b"being written"
    assert views_in(tmp_path) == ["v-0.exr", "v-1.exr", "v-2.exr", "v-3.exr"]


def test_the_manifest_keeps_one_record_a_view_and_one_writer(tmp_path):
    """A view rendered again after its file vanished is not recorded twice; a manifest another vkray
    holds (two shards given one --manifest) is refused; a merge takes a part's cut-off last line as
    resuming does, as a view missing, not as a broken file."""
    import fcntl
    out = str(tmp_path / "v-{index}.exr")
    vkray("render", *SIZE, "--orbit", "4", "-o", out)
    (tmp_path / "v-2.exr").unlink()
    assert "1 views written, 3 complete already" in vkray("render", *SIZE, "--orbit", "4", "-o", out).stdout
    assert [record["index"] for record in manifest_records(tmp_path / "manifest.jsonl")] == [0, 1, 2, 3]
    with open(tmp_path / "manifest.jsonl", "rb") as other_writer:
        fcntl.flock(other_writer, fcntl.LOCK_EX)
        result = vkray("render", *SIZE, "--orbit", "4", "-o", out, check=False)
        assert result.returncode == 2 and "another vkray is writing this manifest" in result.stderr, result.stderr
    lines = (tmp_path / "manifest.jsonl").read_text().splitlines()
    (tmp_path / "cut.jsonl").write_text("\n".join(lines[:3]) + "\n" + lines[3][:40])  # killed mid-line
    result = vkray("manifest", "merge", str(tmp_path / "cut.jsonl"), "-o", str(tmp_path / "all.jsonl"), check=False)
    missing = json.loads(lines[3])["index"]
    assert result.returncode == 2 and f"missing: {missing} " in result.stderr, result.stderr


def test_a_device_lost_mid_batch_ends_the_run_and_keeps_the_views_before_it(tmp_path):
    """A failed render used to leave the writers waiting on an open queue: the process never exited.
    Now it exits 1 with one line naming the view, the views before it written and recorded, no
    temporary file left; run again, it completes the set."""
    out = str(tmp_path / "v-{index:02}.exr")
    env = dict(os.environ, VKRAY_TEST_LOSE_DEVICE_AT_VIEW="7")
    result = subprocess.run([VKRAY, "render", *SIZE, "--orbit", "20", "-o", out], capture_output=True, text=True, env=env,
                            timeout=120)
    assert result.returncode == 1, result.stderr
    errors = [line for line in result.stderr.splitlines() if not line.startswith("vkray: note: ")]  # lavapipe's note
    assert len(errors) == 1 and errors[0].startswith("vkray: view 7 could not be rendered: the device was lost"), result.stderr
    assert views_in(tmp_path) == [f"v-{index:02}.exr" for index in range(7)]
    assert [record["index"] for record in manifest_records(tmp_path / "manifest.jsonl")] == list(range(7))
    assert not [name for name in os.listdir(tmp_path) if name.startswith(".")]
    vkray("render", *SIZE, "--orbit", "20", "-o", out)
    assert views_in(tmp_path) == [f"v-{index:02}.exr" for index in range(20)]
    assert [record["index"] for record in manifest_records(tmp_path / "manifest.jsonl")] == list(range(20))


def test_a_run_resumed_with_other_settings_is_refused_unless_it_overwrites(tmp_path):
    """Files from a run at another size (or with other outputs, or rays of another mask) are not this run's views: the same
    command again says what changed and exits 2; --overwrite renders every view anew."""
    out = str(tmp_path / "v-{index}.exr")
    vkray("render", *SIZE, "--orbit", "4", "-o", out)
    for options, change in [(["--width", "80", "--height", "48"], "the size: 64x48 then, 80x48 now"),
                            ([*SIZE, "--aov", "depth"], "the outputs: depth,normal then, depth now"),
                            ([*SIZE, "--mask", "1"], "mask: 255 then, 1 now")]:
        result = vkray("render", *options, "--orbit", "4", "-o", out, check=False)
        assert result.returncode == 2, result.stderr
        assert f"view 0 was rendered with other settings ({change}): --overwrite renders every view again" in result.stderr
        assert "the camera" not in result.stderr, result.stderr
    vkray("render", "--width", "80", "--height", "48", "--orbit", "4", "-o", out, "--overwrite")
    records = manifest_records(tmp_path / "manifest.jsonl")
    assert [(record["index"], record["width"]) for record in records] == [(index, 80) for index in range(4)]
    names, data = pixels(tmp_path / "v-3.exr")
    assert data.shape[:2] == (48, 80)
    vkray("render", "--width", "80", "--height", "48", "--orbit", "4", "-o", out)  # the same again: nothing to do


def test_overwrite_renders_all_again_and_starts_the_manifest_afresh(tmp_path):
    arguments = ["render", *SIZE, "--orbit", "3", "-o", str(tmp_path / "v{index}.exr")]
    vkray(*arguments)
    assert "0 views written, 3 complete already" in vkray(*arguments).stdout
    assert "3 views written, 0 complete already" in vkray(*arguments, "--overwrite").stdout
    assert len(manifest_records(tmp_path / "manifest.jsonl")) == 3


def test_the_default_names_work_in_the_working_folder(tmp_path):
    """No -o and no --manifest: view-NNNNN.exr and manifest.jsonl, named without a folder."""
    vkray("render", "--orbit", "3", *SIZE, cwd=tmp_path)
    assert views_in(tmp_path) == ["view-00000.exr", "view-00001.exr", "view-00002.exr"]
    records = manifest_records(tmp_path / "manifest.jsonl")
    assert [record["exr"] for record in records] == views_in(tmp_path)
    again = vkray("render", "--orbit", "3", *SIZE, cwd=tmp_path)  # resumes: every view is there
    assert manifest_records(tmp_path / "manifest.jsonl") == records, again.stderr


def test_a_manifest_option_naming_another_file_is_refused_and_leaves_it(tmp_path):
    """--manifest naming the views file or a model (a slip of the shell's completion) changes nothing."""
    views = tmp_path / "cams.jsonl"
    views.write_text(json.dumps({"from": [0, 1.8, 6], "to": [0, 0.7, 0], "fovy": 45}) + "\n")
    before = views.read_text()
    for overwrite in ([], ["--overwrite"]):
        result = vkray("render", *SIZE, "--views", str(views), "-o", str(tmp_path / "v{index}.exr"),
                       "--manifest", str(views), *overwrite, check=False)
        assert result.returncode == 2, result.stderr
        assert result.stderr == f"vkray: {views}: is not a manifest (its first line is no view record): " \
                                "--manifest names a manifest to continue or a new file\n"
        assert views.read_text() == before and not views_in(tmp_path)


def test_names_that_give_two_views_one_file_are_refused_before_rendering(tmp_path):
    out = tmp_path / "out"
    for options, message in [
        (["-o", str(out / "d{index}/../same.exr")], "view 0's EXR and view 1's EXR would write this one file"),
        (["-o", str(out / "v-{index}.exr"), "--manifest", str(out / "v-2.exr")], "view 2's EXR and the manifest"),
        (["-o", str(out / "v-{index}.exr"), "--preview", str(out / "p{index}/../p.png")], "view 1's preview"),
        (["-o", str(out / ("n" * 251 + "{index}.exr"))], "the name of view 2's EXR is longer than the 255 bytes"),
    ]:
        result = vkray("render", *SIZE, "--orbit", "3", *options, check=False)
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
        assert message in result.stderr
        assert not out.exists()  # no folder made, nothing written
    names = vkray("render", *SIZE, "--orbit", "3", "-o", str(out / "v{index:032}.exr"))  # 32 digits, never cut
    assert views_in(out) == [f"v{index:032}.exr" for index in range(3)], names.stderr


def test_manifest_merge_finishes_when_the_reader_of_its_output_is_gone(tmp_path):
    vkray("render", *SIZE, "--orbit", "2", "-o", str(tmp_path / "v{index}.exr"))
    reader, writer = os.pipe()
    os.close(reader)  # as `vkray manifest merge ... | head -0` leaves it
    try:
        result = subprocess.run([VKRAY, "manifest", "merge", str(tmp_path / "manifest.jsonl"), "-o", str(tmp_path / "all.jsonl")],
                                stdout=writer, stderr=subprocess.PIPE, text=True)
    finally:
        os.close(writer)
    assert result.returncode == 0, (result.returncode, result.stderr)  # not killed by SIGPIPE (-13)
    assert [record["index"] for record in manifest_records(tmp_path / "all.jsonl")] == [0, 1]


def test_views_file_as_json_array_and_as_json_lines(tmp_path):
    cameras = [{"from": [0, 1.8, 6], "to": [0, 0.7, 0], "fovy": 45}, {"from": [3, 2, 5], "to": [0, 0.7, 0], "fovy": 30}]
    (tmp_path / "views.json").write_text(json.dumps(cameras, indent=2))
    (tmp_path / "views.jsonl").write_text("".join(json.dumps(camera) + "\n" for camera in cameras))
    for name in ("views.json", "views.jsonl"):
        folder = tmp_path / name.replace(".", "-")
        vkray("render", *SIZE, "--views", str(tmp_path / name), "-o", str(folder / "v{index:03}.exr"))
        records = manifest_records(folder / "manifest.jsonl")
        assert [record["camera"]["fovy"] for record in records] == [45, 30]
        assert views_in(folder) == ["v000.exr", "v001.exr"]
    assert same_pixels(tmp_path / "views-json" / "v001.exr", tmp_path / "views-jsonl" / "v001.exr")


def test_a_bad_camera_is_named_by_its_line(tmp_path):
    lines = [json.dumps({"from": [0, 1, 5 + k], "to": [0, 0, 0], "fovy": 40}) for k in range(60)]
    lines[56] = json.dumps({"from": [0, 1, 5], "to": [0, 0, 0], "fovy": 190})
    (tmp_path / "views.jsonl").write_text("\n".join(lines) + "\n")
    result = vkray("render", *SIZE, "--views", str(tmp_path / "views.jsonl"), "-o", str(tmp_path / "v{index}.exr"),
                   check=False)
    assert result.returncode == 2
    assert result.stderr.startswith(f"vkray: {tmp_path / 'views.jsonl'}:57: fovy: ")
    assert result.stderr.count("\n") == 1
    array = "[\n" + ",\n".join(lines) + "\n]\n"  # camera k on line k + 2
    (tmp_path / "views.json").write_text(array)
    result = vkray("render", *SIZE, "--views", str(tmp_path / "views.json"), "-o", str(tmp_path / "v{index}.exr"),
                   check=False)
    assert result.returncode == 2 and f"views.json:58: fovy: " in result.stderr
    (tmp_path / "broken.jsonl").write_text(lines[0] + "\n" + lines[1][:-3] + "\n")
    result = vkray("render", *SIZE, "--views", str(tmp_path / "broken.jsonl"), "-o", str(tmp_path / "v{index}.exr"),
                   check=False)
    assert result.returncode == 2 and re.search(r"broken.jsonl:2:\d+: invalid JSON: syntax error", result.stderr)
    assert not views_in(tmp_path)


def test_json_lines_errors_give_line_column_and_reason(tmp_path):
    """What Python's json.dumps writes for a NaN, and a trailing comma: the line, the column and why,
    as a JSON array gets them."""
    good = json.dumps({"from": [0, 1, 5], "to": [0, 0, 0], "fovy": 40})
    nan = json.dumps({"from": [0, 1, float("nan")], "to": [0, 0, 0], "fovy": 40})
    comma = good[:-1] + ", }"
    for name, line, column, reason in [
            ("nan.jsonl", nan, nan.index("NaN") + 1, "JSON has no NaN or Infinity"),
            ("comma.jsonl", comma, len(comma), "unexpected '}'; expected string literal")]:
        (tmp_path / name).write_text(good + "\n" + line + "\n")
        result = vkray("render", *SIZE, "--views", str(tmp_path / name), "-o", str(tmp_path / "v{index}.exr"), check=False)
        assert result.returncode == 2, result.stderr
        assert result.stderr.startswith(f"vkray: {tmp_path / name}:2:{column}: invalid JSON: "), result.stderr
        assert reason in result.stderr and result.stderr.count("\n") == 1, result.stderr


def test_an_output_name_without_the_index_is_refused_before_rendering(tmp_path):
    result = vkray("render", *SIZE, "--orbit", "4", "-o", str(tmp_path / "view.exr"), check=False)
    assert result.returncode == 2
    assert "has no {index}" in result.stderr and "4 views would overwrite one file" in result.stderr
    for bad in ("v{idx}.exr", "v{index:5}.exr", "v{index.exr", "v}.exr"):
        result = vkray("render", *SIZE, "--orbit", "4", "-o", str(tmp_path / bad), check=False)
        assert result.returncode == 2 and "-o: " in result.stderr, bad
    assert not os.listdir(tmp_path)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_an_unwritable_output_folder_is_found_before_rendering(tmp_path):
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    result = vkray("render", *SIZE, "--orbit", "4", "-o", str(folder / "v{index}.exr"), check=False)
    assert result.returncode == 1 and "read-only" in result.stderr
    assert not os.listdir(folder)


def test_an_output_folder_that_is_a_file_is_found_before_rendering(tmp_path):
    (tmp_path / "taken").write_text("a file where the folder should be")
    result = vkray("render", *SIZE, "--orbit", "4", "-o", str(tmp_path / "taken" / "v{index}.exr"), check=False)
    assert result.returncode == 1 and "taken" in result.stderr
    assert sorted(os.listdir(tmp_path)) == ["taken"]


def test_shard_options_are_checked(tmp_path):
    out = str(tmp_path / "v{index}.exr")
    for shard, message in [("3/3", "numbered from 0"), ("1-3", "is not I/N"), ("0/0", "0 shards"), ("auto", "neither"),
                           ("0/4294967296", "whole numbers to 4294967295")]:
        env = {key: value for key, value in os.environ.items() if not key.startswith(("SLURM_", "JOB_COMPLETION"))}
        result = vkray("render", *SIZE, "--orbit", "4", "-o", out, "--shard", shard, check=False, env=env)
        assert result.returncode == 2 and message in result.stderr, (shard, result.stderr)
    env = dict(os.environ, JOB_COMPLETION_INDEX="1")
    result = vkray("render", *SIZE, "--orbit", "4", "-o", out, "--shard", "auto", check=False, env=env)
    assert result.returncode == 2 and "--shard-count" in result.stderr
    slurm = dict(os.environ, SLURM_ARRAY_TASK_ID="1", SLURM_ARRAY_TASK_COUNT="2")
    for extra, options, message in [({"SLURM_ARRAY_TASK_STEP": "0"}, [], "SLURM_ARRAY_TASK_STEP=0 is no array's step"),
                                    ({}, ["--shard-count", "3"], "under Slurm the array gives the count")]:
        result = vkray("render", *SIZE, "--orbit", "4", "-o", out, "--shard", "auto", *options, check=False,
                       env={**slurm, **extra})
        assert result.returncode == 2 and message in result.stderr, result.stderr
    assert not views_in(tmp_path)


def test_the_slurm_array_script_runs_as_slurm_would_run_it(whole_run, tmp_path):
    script = os.path.join(SOURCE, "docs", "slurm-views.sh")
    with open(script) as text:
        array = next(line for line in text if line.startswith("#SBATCH --array="))
    first, last = (int(n) for n in array.split("=")[1].split("-"))
    tasks = last - first + 1
    for task in range(first, last + 1):
        env = dict(os.environ, VKRAY=VKRAY, MODEL="", OUT=str(tmp_path), VIEWS="12", WIDTH="64", HEIGHT="48",
                   SLURM_ARRAY_TASK_ID=str(task), SLURM_ARRAY_TASK_MIN=str(first), SLURM_ARRAY_TASK_COUNT=str(tasks))
        subprocess.run(["bash", script], check=True, capture_output=True, env=env)
    check_sharded_views(whole_run, tmp_path, tasks)


def test_the_slurm_script_passes_render_options_to_every_task(tmp_path):
    """`sbatch docs/slurm-views.sh -- OPTIONS`: the options reach each task's render, in place of
    the script's default views, size and names."""
    script = os.path.join(SOURCE, "docs", "slurm-views.sh")
    out = tmp_path / "sphere" / "s-{index:03}.exr"
    for task in range(3):
        env = dict(os.environ, VKRAY=VKRAY, MODEL="", OUT=str(tmp_path / "unused"), SHARDS="3",
                   SLURM_ARRAY_TASK_ID=str(task), SLURM_ARRAY_TASK_MIN="0", SLURM_ARRAY_TASK_COUNT="3")
        subprocess.run(["bash", script, "--", "--sphere", "6", "--aov", "depth,planar-depth", "--width", "40", "--height=30",
                        "-o", str(out)], check=True, capture_output=True, env=env)
    assert views_in(tmp_path / "sphere") == [f"s-{index:03}.exr" for index in range(6)]
    assert not (tmp_path / "unused").exists()
    names, data = pixels(tmp_path / "sphere" / "s-004.exr")
    assert data.shape[:2] == (30, 40) and "Z" in names and any(name.startswith("planar") for name in names), names


def test_one_slurm_task_run_again_alone_renders_its_own_shard(tmp_path):
    """Shards 0-3 of 8 views, task 2 failing after its first view; the merge names the view missing;
    task 2 submitted again alone (sbatch --array=2: an array of that one task) renders its shard, not
    every view; the merge is then the unsharded run, file for file."""
    script = os.path.join(SOURCE, "docs", "slurm-views.sh")
    whole = tmp_path / "whole"
    vkray("render", *SIZE, "--orbit", "8", "-o", str(whole / "view-{index:05}.exr"))
    out = tmp_path / "sharded"
    base = dict(os.environ, VKRAY=VKRAY, MODEL="", OUT=str(out), VIEWS="8", WIDTH="64", HEIGHT="48")
    for task in range(4):
        env = dict(base, SLURM_ARRAY_TASK_ID=str(task), SLURM_ARRAY_TASK_MIN="0", SLURM_ARRAY_TASK_MAX="3",
                   SLURM_ARRAY_TASK_COUNT="4")
        if task == 2:
            env["VKRAY_TEST_LOSE_DEVICE_AT_VIEW"] = "6"  # its second view
        result = subprocess.run(["bash", script], capture_output=True, text=True, env=env)
        assert result.returncode == (1 if task == 2 else 0), result.stderr
    parts = [str(out / f"manifest-shard-{task}-of-4.jsonl") for task in range(4)]
    result = vkray("manifest", "merge", *parts, "-o", str(out / "manifest.jsonl"), check=False)
    assert result.returncode == 2 and "the parts hold 7 of the run's 8 views; missing: 6" in result.stderr, result.stderr
    result = vkray("manifest", "merge", *parts[:3], "-o", str(out / "manifest.jsonl"), check=False)
    assert result.returncode == 2 and "missing: 3, 6, 7" in result.stderr, result.stderr
    assert not (out / "manifest.jsonl").exists()
    again = dict(base, SLURM_ARRAY_TASK_ID="2", SLURM_ARRAY_TASK_MIN="2", SLURM_ARRAY_TASK_MAX="2", SLURM_ARRAY_TASK_COUNT="1")
    result = subprocess.run(["bash", script], capture_output=True, text=True, env=again)
    assert result.returncode == 0, result.stderr
    assert "1 views written, 1 complete already (shard 2 of 4" in result.stdout, result.stdout
    check_sharded_views(whole, out, 4)
    # --shard auto itself cannot tell such an array from a run of one task: it asks.
    result = vkray("render", *SIZE, "--orbit", "8", "-o", str(out / "view-{index:05}.exr"), "--shard", "auto",
                   env={**again, "VKRAY_TEST_LOSE_DEVICE_AT_VIEW": ""}, check=False)
    assert result.returncode == 2 and "give --shard 2/N" in result.stderr, result.stderr


def test_the_kubernetes_indexed_job_runs_as_its_pods_would(whole_run, tmp_path):
    with open(os.path.join(SOURCE, "docs", "kubernetes-views-job.yaml")) as text:
        job = yaml.safe_load(text)
    assert job["apiVersion"] == "batch/v1" and job["kind"] == "Job"
    spec = job["spec"]
    assert spec["completionMode"] == "Indexed"
    assert spec["template"]["spec"]["restartPolicy"] in ("Never", "OnFailure")
    (container,) = spec["template"]["spec"]["containers"]
    command = container["command"] + container["args"]  # what a pod runs: the command, then its arguments
    assert command[:2] == ["vkray", "render"]
    assert command[command.index("--shard") + 1] == "auto"
    assert int(command[command.index("--shard-count") + 1]) == spec["completions"]
    mount = container["volumeMounts"][0]["mountPath"]
    output = command[command.index("-o") + 1]
    assert output.startswith(mount + "/") and "{index:05}" in output
    # Each pod's command, with the test's model, size, views and folder in place of the Job's.
    local = command[2:]
    assert container["args"][0].startswith(mount + "/")  # the model, first of the render's own options
    local[len(container["command"]) - 2] = ""  # the built-in scene for the model
    for option, value in (("--width", "64"), ("--height", "48"), ("--orbit", "12"), ("-o", str(tmp_path / "view-{index:05}.exr"))):
        local[local.index(option) + 1] = value
    for index in range(spec["completions"]):
        vkray("render", *local, env=dict(os.environ, JOB_COMPLETION_INDEX=str(index)))
    check_sharded_views(whole_run, tmp_path, spec["completions"])


def test_the_dockerfile_adds_the_bundle_the_job_runs():
    """No Docker engine runs here: the image docs/Dockerfile makes holds the bundle that
    cmake/make-bundle.sh names, with its bin/vkray on the PATH, which the Job's command uses."""
    with open(os.path.join(SOURCE, "CMakeLists.txt")) as text:
        version = re.search(r"project\(vkray VERSION ([0-9.]+)", text.read()).group(1)
    bundle = f"vkray-{version}-linux-x86_64"
    with open(os.path.join(SOURCE, "docs", "Dockerfile")) as text:
        lines = [line.strip() for line in text if not line.startswith("#")]
    assert f"ADD build/{bundle}.tar.gz /opt/" in lines
    (path,) = [line for line in lines if line.startswith("ENV PATH=")]
    assert path.startswith(f"ENV PATH=/opt/{bundle}/bin:$PATH")
    with open(os.path.join(SOURCE, "cmake", "make-bundle.sh")) as text:
        script = text.read()
    assert 'name="vkray-$version-linux-$(uname -m)"' in script and '"$stage/bin/vkray"' in script
    with open(os.path.join(SOURCE, "docs", "kubernetes-views-job.yaml")) as text:
        assert yaml.safe_load(text)["spec"]["template"]["spec"]["containers"][0]["command"][0] == "vkray"


def check_sharded_views(whole_run, folder, shards):
    parts = sorted(str(folder / name) for name in os.listdir(folder) if name.startswith(f"manifest-shard-"))
    assert len(parts) == shards
    vkray("manifest", "merge", *parts, "-o", str(folder / "manifest.jsonl"))
    assert manifest_records(folder / "manifest.jsonl") == manifest_records(whole_run / "manifest.jsonl")
    assert views_in(folder) == views_in(whole_run)
    for name in views_in(whole_run):
        assert same_pixels(folder / name, whole_run / name), name


def test_sphere_views_spread_evenly_and_look_at_the_target(tmp_path):
    vkray("render", *SIZE, "--sphere", "50", "-o", str(tmp_path / "s{index:02}.exr"))
    records = manifest_records(tmp_path / "manifest.jsonl")
    to = np.array(records[0]["camera"]["to"])
    directions = np.array([np.array(record["camera"]["from"]) - to for record in records])
    distances = np.linalg.norm(directions, axis=1)
    assert np.ptp(distances) < 1e-12 * distances[0]
    directions /= distances[:, None]
    up = np.array(records[0]["camera"]["up"]) / np.linalg.norm(records[0]["camera"]["up"])
    heights = directions @ up  # evenly spaced from near +1 to near -1: equal areas per view
    assert np.allclose(np.sort(heights)[::-1], 1 - (2 * np.arange(50) + 1) / 50, atol=1e-12)
    nearest = [np.max(np.delete(directions @ d, k)) for k, d in enumerate(directions)]
    assert math.degrees(math.acos(max(nearest))) > 15  # no two views crowd together
