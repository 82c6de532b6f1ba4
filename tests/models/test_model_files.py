"""PLY and glTF models against the same geometry as OBJ (ctest runs this with pytest: VKRAY_CLI and
VKRAY_MODELS_DIR). Each file is written here from float32 values, so every format holds exactly the
same numbers and the renders must agree bit for bit."""
import base64
import json
import os
import pathlib
import struct
import subprocess

import numpy as np
import OpenImageIO as oiio
import pytest

CLI = os.environ["VKRAY_CLI"]
MODELS = pathlib.Path(os.environ.get("VKRAY_MODELS_DIR", ""))


def need_bunny():
    path = MODELS / "stanford-bunny.obj"
    if not path.exists():
        pytest.skip(f"{path} is absent: the shared models folder (../shared/models) is not beside the project")
    return path


def read_obj(path):
    """The triangles of an all-triangle OBJ, its unreferenced vertices left out, as float32."""
    positions, faces = [], []
    for line in open(path):
        if line.startswith("v "):
            positions.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            faces.append([int(token.split("/")[0]) - 1 for token in line.split()[1:]])
    positions, faces = np.array(positions, np.float32), np.array(faces, np.uint32)
    used, faces = np.unique(faces, return_inverse=True)
    return positions[used], faces.reshape(-1, 3).astype(np.uint32)


def write_obj(path, positions, faces):
    """Each float32 in the shortest decimal that reads back as that very number in double too
    (vkray reads OBJ in double, PLY and glTF through assimp in float32)."""
    with open(path, "w") as out:
        out.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in positions.tolist())
        out.writelines("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces)


def ply_header(kind, positions, faces):
    return (f"ply\nformat {kind} 1.0\ncomment written by vkray's tests\nelement vertex {len(positions)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")


def write_ply_ascii(path, positions, faces):
    with open(path, "w") as out:
        out.write(ply_header("ascii", positions, faces))
        out.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in positions.tolist())
        out.writelines(f"{len(face)} " + " ".join(map(str, face)) + "\n" for face in faces)


def write_ply_binary(path, positions, faces):
    with open(path, "wb") as out:
        out.write(ply_header("binary_little_endian", positions, faces).encode())
        out.write(positions.astype("<f4").tobytes())
        for face in faces:
            out.write(struct.pack(f"<B{len(face)}i", len(face), *face))


def gltf_document(meshes, nodes, cameras=(), uri="buffer.bin"):
    """A glTF 2.0 document and its one buffer: `meshes` as (positions, triangles) pairs, `nodes` and
    `cameras` as the glTF's own objects, the scene's nodes all at its root."""
    blob, views, accessors, gltf_meshes = b"", [], [], []
    for positions, triangles in meshes:
        for data, target, kind, component in ((positions.astype("<f4"), 34962, "VEC3", 5126),
                                              (triangles.astype("<u4").reshape(-1), 34963, "SCALAR", 5125)):
            views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes, "target": target})
            accessor = {"bufferView": len(views) - 1, "componentType": component, "count": len(data), "type": kind}
            if kind == "VEC3":
                accessor.update(min=data.min(axis=0).tolist(), max=data.max(axis=0).tolist())
            accessors.append(accessor)
            blob += data.tobytes()
        gltf_meshes.append({"primitives": [{"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1}]})
    document = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}],
                "nodes": nodes, "meshes": gltf_meshes, "accessors": accessors, "bufferViews": views,
                "buffers": [{"byteLength": len(blob)} | ({"uri": uri} if uri else {})]}
    if cameras:
        document["cameras"] = list(cameras)
    return document, blob


def write_gltf(path, meshes, nodes, cameras=()):
    document, blob = gltf_document(meshes, nodes, cameras, uri=path.stem + ".bin")
    path.with_suffix(".bin").write_bytes(blob)
    path.write_text(json.dumps(document))


def write_glb(path, meshes, nodes, cameras=()):
    document, blob = gltf_document(meshes, nodes, cameras, uri=None)
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def render(tmp_path, scene, name, *extra, size="160x120"):
    width, height = size.split("x")
    output = tmp_path / f"{name}.exr"
    result = subprocess.run([CLI, "render", str(scene), "-o", str(output), "--no-preview", "--width", width,
                             "--height", height, "--aov", "depth,normal,mesh-id,primitive-id", *extra],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    image = oiio.ImageInput.open(str(output))
    spec = image.spec()
    planes = {}
    for k, channel in enumerate(spec.channelnames):
        planes[channel] = image.read_image(0, 0, k, k + 1, oiio.UINT if channel.endswith("_id") else oiio.FLOAT)[:, :, 0]
    image.close()
    return planes, spec


def expect_same_pixels(a, b):
    assert a.keys() == b.keys()
    for channel in a:
        assert np.array_equal(a[channel], b[channel], equal_nan=True), channel


def scene_file(path, camera, meshes):
    path.write_text(json.dumps({"camera": camera, "meshes": meshes}))
    return path


CAMERA = {"from": [0.125, 0.25, 0.75], "to": [0.0, 0.125, 0.0], "up": [0, 1, 0], "fovy": 40}
# Exact in float32 and double alike, so that an OBJ through the scene file's transform and a glTF
# through its node's give the same bits.
SCALE, TRANSLATE = 2.0, [0.5, -0.25, 0.125]


def test_the_bunny_as_ply_and_gltf_renders_the_pixels_of_the_obj(tmp_path):
    positions, faces = read_obj(need_bunny())
    write_obj(tmp_path / "bunny.obj", positions, faces)
    write_ply_ascii(tmp_path / "bunny-ascii.ply", positions, faces)
    write_ply_binary(tmp_path / "bunny-binary.ply", positions, faces)
    write_gltf(tmp_path / "bunny.gltf", [(positions, faces)],
               [{"name": "Bunny", "mesh": 0, "scale": [SCALE] * 3, "translation": TRANSLATE}])
    transform = {"scale": SCALE, "translate": TRANSLATE}
    camera = {"from": [0.5, 0.125, 0.875], "to": [0.5, 0.0, 0.125], "up": [0, 1, 0], "fovy": 30}
    obj, _ = render(tmp_path, scene_file(tmp_path / "obj.json", camera, [{"model": "bunny.obj", "transform": transform}]), "obj")
    assert np.count_nonzero(np.isfinite(obj["Z"])) > 3000  # the bunny fills much of the image
    for model in ("bunny-ascii.ply", "bunny-binary.ply"):
        same, spec = render(tmp_path, scene_file(tmp_path / "ply.json", camera, [{"model": model, "transform": transform}]), "ply")
        expect_same_pixels(same, obj)
        assert json.loads(spec.getattribute("vkray:objects")) == [str(tmp_path / model)]
    gltf, spec = render(tmp_path, scene_file(tmp_path / "gltf.json", camera, [{"model": "bunny.gltf"}]), "gltf")
    expect_same_pixels(gltf, obj)
    assert json.loads(spec.getattribute("vkray:objects")) == [str(tmp_path / "bunny.gltf") + "#Bunny"]
    # Alone on the command line each is framed as the OBJ with the transform is.
    write_obj(tmp_path / "moved.obj", positions.astype(np.float64) * SCALE + TRANSLATE, faces)  # exact in double
    expect_same_pixels(render(tmp_path, tmp_path / "bunny.gltf", "framed-gltf")[0],
                       render(tmp_path, tmp_path / "moved.obj", "framed-obj")[0])


def test_a_big_endian_ply_of_doubles_keeps_every_bit_of_them(tmp_path):
    positions, faces = polygons()
    positions = positions.astype(np.float64) + 0.1  # 0.1 has no float32: only doubles hold these
    write_obj(tmp_path / "doubles.obj", positions, faces)
    with open(tmp_path / "doubles.ply", "wb") as out:
        out.write(ply_header("binary_big_endian", positions, faces).replace("property float", "property double").encode())
        out.write(positions.astype(">f8").tobytes())
        for face in faces:
            out.write(struct.pack(f">B{len(face)}i", len(face), *face))
    expect_same_pixels(render(tmp_path, tmp_path / "doubles.ply", "ply")[0], render(tmp_path, tmp_path / "doubles.obj", "obj")[0])


def polygons():
    """A quad, a concave pentagon and a triangle, as an OBJ and a PLY write them."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                          [2, 0, 0], [3, 0, 0], [3, 1, 0], [2.5, 0.25, 0], [2, 1, 0],
                          [0, 0, -1], [3, 0, -1], [1.5, 1.5, -1]], np.float32)
    return positions, [[0, 1, 2, 3], [4, 5, 6, 7, 8], [9, 10, 11]]


def test_ply_polygons_are_triangulated_as_the_objs_are(tmp_path):
    positions, faces = polygons()
    write_obj(tmp_path / "polygons.obj", positions, faces)
    write_ply_ascii(tmp_path / "polygons.ply", positions, faces)
    obj, _ = render(tmp_path, tmp_path / "polygons.obj", "obj")
    ply, _ = render(tmp_path, tmp_path / "polygons.ply", "ply")
    assert np.count_nonzero(np.isfinite(obj["Z"])) > 100
    expect_same_pixels(ply, obj)
    assert set(np.unique(ply["primitive_id"])) >= {0, 1, 2, 3, 4, 5}  # 2 + 3 + 1 triangles, all seen


def two_meshes_and_a_camera():
    ground = (np.array([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], np.float32), np.array([[0, 2, 1], [0, 3, 2]], np.uint32))
    box = (np.array([[x, y, z] for x in (-0.5, 0.5) for y in (0, 1) for z in (-0.5, 0.5)], np.float32),
           np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.uint32))
    # Turned 30 degrees about y and lifted: a camera node with a rotation the float matrix rounds.
    half = np.radians(15.0)
    nodes = [{"name": "Ground", "mesh": 0}, {"name": "Box", "mesh": 1, "translation": [0.5, 0.0, -0.25]},
             {"name": "Eye", "camera": 0, "translation": [1.5, 1.5, 3.0],
              "rotation": [0.0, float(np.sin(half)), 0.0, float(np.cos(half))]}]
    cameras = [{"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.01}}]
    return [ground, box], nodes, cameras


@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_a_gltf_with_two_meshes_renders_from_its_camera_with_named_ids(tmp_path, suffix):
    meshes, nodes, cameras = two_meshes_and_a_camera()
    path = tmp_path / f"two{suffix}"
    (write_gltf if suffix == ".gltf" else write_glb)(path, meshes, nodes, cameras)
    output = tmp_path / "views" / "view-{index}.exr"
    result = subprocess.run([CLI, "render", str(path), "--orbit", "2", "-o", str(output), "--height", "60",
                             "--aov", "depth,mesh-id"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    records = sorted((json.loads(line) for line in open(tmp_path / "views" / "manifest.jsonl")), key=lambda r: r["index"])
    assert [r["objects"] for r in records] == [[f"{path}#Ground", f"{path}#Box"]] * 2
    # The camera's aspect ratio sets the width at the height given; its yfov is the vertical field.
    first = records[0]
    assert (first["width"], first["height"]) == (90, 60)
    camera = first["camera"]
    assert camera["fovy"] == pytest.approx(np.degrees(0.7), rel=2**-22)
    turn = np.radians(30.0)
    assert camera["from"] == pytest.approx([1.5, 1.5, 3.0], rel=2**-22)
    direction = np.subtract(camera["to"], camera["from"])
    assert direction / np.linalg.norm(direction) == pytest.approx([-np.sin(turn), 0, -np.cos(turn)], abs=2**-21)
    # The same meshes from a scene file with that camera: the same pixels, ids in the same order.
    write_obj(tmp_path / "ground.obj", *meshes[0])
    write_obj(tmp_path / "box.obj", *meshes[1])
    scene = scene_file(tmp_path / "same.json", camera, [{"model": "ground.obj"}, {"model": "box.obj", "transform": {"translate": [0.5, 0, -0.25]}}])
    from_gltf, _ = render(tmp_path, path, "gltf", size="90x60")
    from_json, _ = render(tmp_path, scene, "json", size="90x60")
    expect_same_pixels(from_gltf, from_json)
    assert set(np.unique(from_gltf["mesh_id"])) == {0, 1, 0xFFFFFFFF}  # both meshes and the sky seen


def test_python_loads_a_gltf_and_names_its_meshes(tmp_path):
    import vkray  # the module under test, on PYTHONPATH (tests/CMakeLists.txt)
    meshes, nodes, cameras = two_meshes_and_a_camera()
    write_glb(tmp_path / "two.glb", meshes, nodes, cameras)
    scene = vkray.load(str(tmp_path / "two.glb"), None, 60)
    assert (scene.width, scene.height) == (90, 60) and scene.triangle_count == 14
    assert scene.object_names == [f"{tmp_path / 'two.glb'}#Ground", f"{tmp_path / 'two.glb'}#Box"]
    ids = vkray.Renderer(scene).render(aovs=["mesh-id"])["mesh_id"]
    assert set(np.unique(ids)) == {0, 1, vkray.NO_HIT}
    assert vkray.Scene(meshes[0][0], meshes[0][1]).object_names == ["meshes[0]"]


def run_cli(*arguments):
    return subprocess.run([CLI, *map(str, arguments)], capture_output=True, text=True)


def test_bad_ply_and_gltf_files_get_one_line_and_exit_2(tmp_path):
    positions, faces = polygons()
    write_ply_binary(tmp_path / "whole.ply", positions, faces)
    data = (tmp_path / "whole.ply").read_bytes()
    (tmp_path / "cut.ply").write_bytes(data[:-7])
    (tmp_path / "words.ply").write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\nbanana\n")
    (tmp_path / "points.ply").write_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                         "property float z\nend_header\n1 2 3\n")
    (tmp_path / "nan.ply").write_text(ply_header("ascii", [0, 1, 2], [0]) + "0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n")
    (tmp_path / "broken.gltf").write_text('{"asset": {"version": "2.0"}, "meshes": [')
    meshes, nodes, cameras = two_meshes_and_a_camera()
    write_gltf(tmp_path / "lost.gltf", meshes, nodes, cameras)
    (tmp_path / "lost.bin").unlink()
    write_glb(tmp_path / "whole.glb", meshes, nodes, cameras)
    (tmp_path / "cut.glb").write_bytes((tmp_path / "whole.glb").read_bytes()[:200])
    for name in ("cut.ply", "words.ply", "points.ply", "nan.ply", "broken.gltf", "lost.gltf", "cut.glb", "absent.ply"):
        result = run_cli("render", tmp_path / name, "-o", tmp_path / "x.exr", "--no-preview")
        assert result.returncode == 2, (name, result.stderr)
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"vkray: {tmp_path / name}:"), (name, result.stderr)
    assert not (tmp_path / "x.exr").exists()
