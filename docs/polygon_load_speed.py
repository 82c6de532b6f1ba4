"""How fast hostile polygons load (docs/scene-format.md): binary PLYs of 64 faces of 4096 corners
each, in the shapes that make ear clipping slow (combs with their teeth along either axis, stars,
one with a tiny inner radius, spirals, random corners), each timed by `vkray render --timings`'s
scene load (reading, triangulating and checking), in MB/s of the file.

    /usr/bin/python3 docs/polygon_load_speed.py [build/vkray]
"""
import pathlib
import re
import struct
import subprocess
import sys
import tempfile

import numpy as np

CORNERS, FACES = 4096, 64


def comb(n, along_y=False):
    teeth = [(0.0, -1.0)]
    for k in range((n - 2) // 4):
        teeth += [(2 * k, 0), (2 * k, 10), (2 * k + 1, 10), (2 * k + 1, 0)]
    teeth.append((2 * ((n - 2) // 4) - 1, -1.0))
    points = np.array(teeth, float)
    return points[:, ::-1].copy() if along_y else points


def star(n, inner):
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
    radius = np.where(np.arange(n) % 2 == 0, 1.0, inner)
    return np.c_[radius * np.cos(angle), radius * np.sin(angle)]


def spiral(n):
    t = np.linspace(0, 30 * np.pi, n // 2)
    outer = np.c_[np.exp(0.1 * t) * np.cos(t), np.exp(0.1 * t) * np.sin(t)]
    return np.r_[outer, 0.9 * outer[::-1]]


SHAPES = {"comb, teeth along x": comb(CORNERS), "comb, teeth along y": comb(CORNERS, True), "star": star(CORNERS, 0.5),
          "star of inner radius 0.001": star(CORNERS, 1e-3), "log spiral": spiral(CORNERS),
          "random corners": np.random.default_rng(1).uniform(size=(CORNERS, 2))}


def write_ply(path, points):
    n = len(points)
    with open(path, "wb") as out:
        out.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
                   f"property float z\nelement face {FACES}\nproperty list ushort int vertex_indices\nend_header\n").encode())
        out.write(np.c_[points, np.zeros(n)].astype("<f4").tobytes())
        face = struct.pack("<H", n) + np.arange(n, dtype="<i4").tobytes()
        out.write(face * FACES)


vkray = sys.argv[1] if len(sys.argv) > 1 else "build/vkray"
with tempfile.TemporaryDirectory() as folder:
    for name, points in SHAPES.items():
        path = pathlib.Path(folder) / "shape.ply"
        write_ply(path, points)
        result = subprocess.run([vkray, "render", str(path), "--width", "64", "--height", "48", "--no-preview", "--timings",
                                 "-o", str(pathlib.Path(folder) / "shape.exr")], capture_output=True, text=True, check=True)
        load_ms = float(re.search(r"scene load\s+([0-9.]+) ms", result.stdout).group(1))
        size = path.stat().st_size
        print(f"{name:28s} {size / 1e6:.2f} MB in {load_ms:7.1f} ms: {size / 1e3 / load_ms:5.2f} MB/s")
