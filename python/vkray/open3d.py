"""Open3D's RaycastingScene on vkray: a script written for `open3d.t.geometry.RaycastingScene` runs
with its import changed to `from vkray.open3d import RaycastingScene` (docs/open3d.md).

Open3D's names, arguments, conventions and result keys: t in units of the ray's direction as given,
`primitive_normals` the triangle's own normal by its winding (right-handed, not turned to face the
ray), `primitive_uvs` the weights of its second and third vertices, misses `inf`, `INVALID_ID` and
zeros, `create_rays_pinhole` looking through pixel centres at (x + 0.5, y + 0.5). Inputs are numpy
arrays, anything with a `.numpy()` (Open3D tensors) or a `t.geometry.TriangleMesh`; results are numpy
arrays that also answer `.numpy()`, as Open3D's tensors do. Where Open3D's behaviour is a fault, vkray's
stays: a NaN or zero direction is a miss (Open3D's process aborts or the ray is undefined), and the
sign of `compute_signed_distance` and `compute_occupancy` is the generalized winding number's, which
holds on meshes with holes where Open3D's ray parity votes fail.
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from . import HITS_MAX, NO_HIT, Renderer, Scene, _array

__all__ = ["RaycastingScene", "INVALID_ID", "Tensor"]

#: The geometry and primitive id of a miss (Open3D's RaycastingScene.INVALID_ID, Embree's invalid id).
INVALID_ID: int = NO_HIT


class Tensor(np.ndarray):
    """A numpy array that also answers `.numpy()`, as the Open3D tensors a script reads results from do."""

    def numpy(self) -> np.ndarray:
        return self.view(np.ndarray)


def _tensor(array: np.ndarray) -> Tensor:
    return np.ascontiguousarray(array).view(Tensor)


def _numbers(value: Any, what: str) -> np.ndarray:
    """An array from numpy, a sequence or anything with `.numpy()` (an Open3D tensor)."""
    if not isinstance(value, np.ndarray) and callable(getattr(value, "numpy", None)):
        value = value.numpy()
    return _array(value, what, "numpy, or an Open3D tensor")


def _rows(value: Any, what: str, width: int) -> np.ndarray:
    array = _numbers(value, what)
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{what}: expected an array of shape (..., {width}), got shape {array.shape}")
    return array


def _votes(nsamples: int) -> None:
    if isinstance(nsamples, bool) or not isinstance(nsamples, (int, np.integer)) or nsamples < 1 or nsamples % 2 != 1:
        raise ValueError(f"nsamples: must be odd and >= 1, got {nsamples!r}")


class RaycastingScene:
    """Open3D's `open3d.t.geometry.RaycastingScene` over a vkray Renderer, made at the first query after
    triangles are added (and made again only when more are)."""

    INVALID_ID = INVALID_ID

    def __init__(self, nthreads: int = 0, device: Optional[str] = None):
        """nthreads: Open3D's, taken and unused (the device runs the queries). device: as Renderer's."""
        self._device = device
        self._meshes: List[Tuple[np.ndarray, np.ndarray]] = []
        self._normals: List[np.ndarray] = []  # each mesh's triangles' normals, by their winding
        self._renderer: Optional[Renderer] = None

    def add_triangles(self, vertex_positions: Any, triangle_indices: Any = None) -> int:
        """Adds a mesh: vertex_positions (N, 3) and triangle_indices (M, 3), or an Open3D
        t.geometry.TriangleMesh (its vertex positions and triangle indices). Returns its geometry id,
        0, 1, ... in the order added."""
        if triangle_indices is None:
            mesh = vertex_positions
            try:
                vertex_positions, triangle_indices = mesh.vertex.positions, mesh.triangle.indices
            except AttributeError:
                raise ValueError("add_triangles: expected vertex_positions and triangle_indices, or a "
                                 "t.geometry.TriangleMesh with vertex positions and triangle indices") from None
        vertices = _rows(vertex_positions, "vertex_positions", 3).reshape(-1, 3).astype(np.float64)
        triangles = _rows(triangle_indices, "triangle_indices", 3).reshape(-1, 3)
        if not len(triangles):
            raise ValueError("triangle_indices: a mesh needs at least one triangle (Open3D keeps an empty one; vkray refuses it)")
        if triangles.dtype.kind == "f" or triangles.min() < 0 or triangles.max() >= len(vertices):
            raise ValueError(f"triangle_indices: expected whole numbers from 0 to {len(vertices) - 1} (the vertices)")
        triangles = triangles.astype(np.uint32)
        corners = vertices[triangles]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        self._normals.append(np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0).astype(np.float32))
        self._meshes.append((vertices, triangles))
        self._renderer = None
        return len(self._meshes) - 1

    def _caster(self) -> Optional[Renderer]:
        """The renderer of the triangles added so far; None while there are none."""
        if self._renderer is None and self._meshes:
            # The queries never render: the smallest image the framing takes.
            scene = Scene(meshes=[{"vertices": vertices, "triangles": triangles} for vertices, triangles in self._meshes],
                          width=1, height=1)
            self._renderer = Renderer(scene, device=self._device)
        return self._renderer

    def _winding_normals(self, mesh_ids: np.ndarray, primitive_ids: np.ndarray) -> np.ndarray:
        """The normals Open3D gives: normalize((v1 - v0) x (v2 - v0)) of each hit's triangle, 0 for none."""
        normals = np.zeros(mesh_ids.shape + (3,), dtype=np.float32)
        for mesh, mesh_normals in enumerate(self._normals):
            on = mesh_ids == mesh
            normals[on] = mesh_normals[primitive_ids[on]]
        return normals

    @staticmethod
    def _misses(leading: Tuple[int, ...]) -> Dict[str, np.ndarray]:
        return {"t_hit": np.full(leading, np.inf, np.float32), "geometry_ids": np.full(leading, INVALID_ID, np.uint32),
                "primitive_ids": np.full(leading, INVALID_ID, np.uint32),
                "primitive_uvs": np.zeros(leading + (2,), np.float32), "primitive_normals": np.zeros(leading + (3,), np.float32)}

    def cast_rays(self, rays: Any, nthreads: int = 0) -> Dict[str, Tensor]:
        """Each ray's nearest hit at 0 < t: rays (..., 6), origin and direction, t in units of the
        direction. 't_hit', 'geometry_ids', 'primitive_ids', 'primitive_uvs', 'primitive_normals'."""
        given = _rows(rays, "rays", 6)
        caster = self._caster()
        if caster is None:
            return {key: _tensor(value) for key, value in self._misses(given.shape[:-1]).items()}
        hits = caster.cast_rays(given, outputs=("t", "mesh_id", "primitive_id", "barycentric"), t_along="direction")
        return {"t_hit": _tensor(hits["t"]), "geometry_ids": _tensor(hits["mesh_id"]), "primitive_ids": _tensor(hits["primitive_id"]),
                "primitive_uvs": _tensor(hits["barycentric"]),
                "primitive_normals": _tensor(self._winding_normals(hits["mesh_id"], hits["primitive_id"]))}

    def test_occlusions(self, rays: Any, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0) -> Tensor:
        """Whether each ray hits anything at tnear < t < tfar (units of its direction): bool (...)."""
        given = _rows(rays, "rays", 6)
        caster = self._caster()
        if caster is None:
            return _tensor(np.zeros(given.shape[:-1], np.bool_))
        return _tensor(caster.occluded(given, t_min=tnear, t_max=tfar, t_along="direction"))

    def count_intersections(self, rays: Any, nthreads: int = 0) -> Tensor:
        """How many surfaces each ray crosses at 0 < t (an edge passed exactly through once): int32 (...)."""
        given = _rows(rays, "rays", 6)
        caster = self._caster()
        if caster is None:
            return _tensor(np.zeros(given.shape[:-1], np.int32))
        return _tensor(caster.count_intersections(given, t_along="direction").astype(np.int32))

    def list_intersections(self, rays: Any, nthreads: int = 0) -> Dict[str, Tensor]:
        """Every hit of every ray, in order along each ray: 'ray_splits' (rays + 1: ray k's hits are
        ray_splits[k] to ray_splits[k + 1]), 'ray_ids', 'geometry_ids', 'primitive_ids', 'primitive_uvs',
        't_hit', the rays flattened in C order."""
        flat = _rows(rays, "rays", 6).reshape(-1, 6).astype(np.float64)
        caster = self._caster()
        hits: List[List[Dict[str, np.ndarray]]] = [[] for _ in range(len(flat))]
        if caster is not None and len(flat):
            counts = caster.count_intersections(flat, t_along="direction")
            # Passes of up to HITS_MAX hits a ray; a ray with more goes on from its last hit's t.
            pending, start = np.flatnonzero(counts > 0), np.zeros(len(flat))
            while len(pending):
                layers = int(min(HITS_MAX, counts[pending].max()))
                found = caster.cast_rays(flat[pending], t_min=start[pending], outputs=("t", "mesh_id", "primitive_id", "barycentric"),
                                         t_along="direction", hits=layers)
                if layers == 1:  # the nearest hit alone comes without the hits' axis
                    found = {key: value[:, None] for key, value in found.items()}
                got = np.isfinite(found["t"]).sum(axis=1)
                for row, ray in enumerate(pending):
                    hits[ray].append({key: value[row, :got[row]] for key, value in found.items()})
                counts[pending] -= np.minimum(counts[pending], got.astype(counts.dtype))
                more = (got == layers) & (counts[pending] > 0)
                start[pending[more]] = found["t"][more, layers - 1]
                pending = pending[more]
        per_ray = [sum(len(part["t"]) for part in parts) for parts in hits]
        splits = np.concatenate([[0], np.cumsum(per_ray)]).astype(np.uint32)
        joined = {key: np.concatenate([part[key] for parts in hits for part in parts]) if splits[-1] else np.zeros(
            (0, 2) if key == "barycentric" else 0, np.float32 if key in ("t", "barycentric") else np.uint32)
            for key in ("t", "mesh_id", "primitive_id", "barycentric")}
        return {"ray_splits": _tensor(splits), "ray_ids": _tensor(np.repeat(np.arange(len(flat), dtype=np.uint32), per_ray)),
                "geometry_ids": _tensor(joined["mesh_id"]), "primitive_ids": _tensor(joined["primitive_id"]),
                "primitive_uvs": _tensor(joined["barycentric"].reshape(-1, 2)), "t_hit": _tensor(joined["t"])}

    def compute_closest_points(self, query_points: Any, nthreads: int = 0) -> Dict[str, Tensor]:
        """Each point's nearest point of the triangles: 'points', 'geometry_ids', 'primitive_ids',
        'primitive_uvs', 'primitive_normals' (of the point's leading shape)."""
        given = _rows(query_points, "query_points", 3)
        caster = self._caster()
        leading = given.shape[:-1]
        if caster is None:
            return {"points": _tensor(np.full(leading + (3,), np.inf, np.float32)), "geometry_ids": _tensor(np.full(leading, INVALID_ID, np.uint32)),
                    "primitive_ids": _tensor(np.full(leading, INVALID_ID, np.uint32)),
                    "primitive_uvs": _tensor(np.zeros(leading + (2,), np.float32)),
                    "primitive_normals": _tensor(np.zeros(leading + (3,), np.float32))}
        nearest = caster.query_points(given, ("position", "mesh_id", "primitive_id", "barycentric"))
        return {"points": _tensor(nearest["position"]), "geometry_ids": _tensor(nearest["mesh_id"]),
                "primitive_ids": _tensor(nearest["primitive_id"]), "primitive_uvs": _tensor(nearest["barycentric"]),
                "primitive_normals": _tensor(self._winding_normals(nearest["mesh_id"], nearest["primitive_id"]))}

    def _point_query(self, query_points: Any, output: str, empty: float) -> Tensor:
        given = _rows(query_points, "query_points", 3)
        caster = self._caster()
        if caster is None:
            return _tensor(np.full(given.shape[:-1], empty, np.float32))
        return _tensor(caster.query_points(given, output)[output].astype(np.float32))

    def compute_distance(self, query_points: Any, nthreads: int = 0) -> Tensor:
        """The distance to the nearest point of the triangles: float32 (...)."""
        return self._point_query(query_points, "distance", np.inf)

    def compute_signed_distance(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> Tensor:
        """The distance, negative inside: float32 (...). nsamples (odd, as Open3D checks it) is taken; the
        sign is the generalized winding number's (inside where it is 1/2 or more), not a vote of rays."""
        _votes(nsamples)
        return self._point_query(query_points, "signed_distance", np.inf)

    def compute_occupancy(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> Tensor:
        """1 inside, 0 outside: float32 (...), by the generalized winding number (nsamples as
        compute_signed_distance's)."""
        _votes(nsamples)
        return self._point_query(query_points, "occupancy", 0.0)

    @staticmethod
    def create_rays_pinhole(*args: Any, **kwargs: Any) -> Tensor:
        """Rays (height_px, width_px, 6), float32, through each pixel's centre, in Open3D's two forms:
        create_rays_pinhole(intrinsic_matrix, extrinsic_matrix, width_px, height_px): K (3 x 3) and the
        world-to-camera [R | t] (4 x 4); the origin -R^T t, the direction R^T K^-1 (x + 0.5, y + 0.5, 1),
        not normalized (t counts in its units). create_rays_pinhole(fov_deg, center, eye, up, width_px,
        height_px): fov_deg the horizontal field of view; K with focal 0.5 width / tan(fov / 2) and
        principal point (width / 2, height / 2), R's rows x = normalize(up x forward), y = forward x x,
        z = forward (from eye to center)."""
        names = ("intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px")
        if len(args) == 6 or "fov_deg" in kwargs:
            names = ("fov_deg", "center", "eye", "up", "width_px", "height_px")
        if len(args) > len(names):
            raise ValueError(f"create_rays_pinhole: takes {', '.join(names)}")
        given = dict(zip(names, args))
        for key, value in kwargs.items():
            if key not in names or key in given:
                raise ValueError(f"create_rays_pinhole: unexpected or repeated argument '{key}' (it takes {', '.join(names)})")
            given[key] = value
        missing = [name for name in names if name not in given]
        if missing:
            raise ValueError(f"create_rays_pinhole: missing {', '.join(missing)}")
        width, height = (int(given[key]) for key in ("width_px", "height_px"))
        if width < 1 or height < 1:
            raise ValueError(f"create_rays_pinhole: width_px and height_px must be at least 1, got {width} x {height}")
        if "fov_deg" in given:
            fov = float(given["fov_deg"])
            if not 0.0 < fov < 180.0:
                raise ValueError(f"fov_deg: expected an angle between 0 and 180 degrees, got {fov!r}")
            center, eye, up = (_numbers(given[key], key).astype(np.float64).reshape(3) for key in ("center", "eye", "up"))
            focal = 0.5 * width / math.tan(math.radians(0.5 * fov))
            intrinsic = np.array([[focal, 0.0, 0.5 * width], [0.0, focal, 0.5 * height], [0.0, 0.0, 1.0]])
            forward = (center - eye) / np.linalg.norm(center - eye)
            right = np.cross(up / np.linalg.norm(up), forward)
            right /= np.linalg.norm(right)
            rotation = np.stack([right, np.cross(forward, right), forward])
            extrinsic = np.eye(4)
            extrinsic[:3, :3], extrinsic[:3, 3] = rotation, -rotation @ eye
        else:
            intrinsic = _numbers(given["intrinsic_matrix"], "intrinsic_matrix").astype(np.float64)
            extrinsic = _numbers(given["extrinsic_matrix"], "extrinsic_matrix").astype(np.float64)
            if intrinsic.shape != (3, 3) or extrinsic.shape != (4, 4):
                raise ValueError(f"create_rays_pinhole: intrinsic_matrix 3 x 3 and extrinsic_matrix 4 x 4, got "
                                 f"{intrinsic.shape} and {extrinsic.shape}")
        to_world = extrinsic[:3, :3].T
        x, y = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
        pixels = np.stack([x, y, np.ones_like(x)], axis=-1)
        rays = np.empty((height, width, 6), np.float32)
        rays[..., :3] = -to_world @ extrinsic[:3, 3]
        rays[..., 3:] = pixels @ (to_world @ np.linalg.inv(intrinsic)).T
        return _tensor(rays)
