"""vkray: exact depth and normals by ray casting on a Vulkan device, numpy arrays in and out.

A package in Python over vkray's C API (libvkray.so, engine/api/vkray.h): one wheel for every
CPython 3.9 or later and numpy 1.22 to 2.x. Bad input raises ValueError with its one-line message
(naming the key, the file and line, or the ray), a device failure vkray.Error. The device works
without the GIL: other Python threads run meanwhile, and threads may share a Renderer (its calls
take turns).

Units: world units for positions and distances; a ray's t runs along its unit direction unless a
call says t_along="direction" (then in units of the direction as given, as Embree's and Open3D's t);
fovy in degrees; sizes in pixels.
"""
from __future__ import annotations

import ctypes
import json
import os
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

__all__ = ["Error", "NO_HIT", "HITS_MAX", "outputs", "point_outputs", "traversals", "Scene", "load", "Renderer", "Reference", "__version__"]

__version__: str = _native.lib.vkray_version().decode()


class Error(RuntimeError):
    """A device failure: no device, a device lost, out of device memory (the message says which)."""


#: mesh_id and primitive_id of a ray or pixel that hit nothing.
NO_HIT: int = 0xFFFFFFFF
#: The most first hits cast_rays lists a ray (VKRAY_HITS_MAX).
HITS_MAX: int = 16


def _outputs() -> Tuple[Dict[str, Any], ...]:
    listed = []
    info = _native.OutputInfo()
    index = 0
    while _native.lib.vkray_output(index, ctypes.byref(info)):
        listed.append({"name": info.name.decode().replace("-", "_"), "components": info.components,
                       "dtype": "uint32" if info.is_integer else "float32",
                       "channels": [info.channels[c].decode() for c in range(info.components)],
                       "description": info.description.decode()})
        index += 1
    return tuple(listed)


#: The outputs render() gives, by key: each a dict of its name, components, dtype, the EXR channels
#: `vkray render` writes it to and what it is.
outputs: Tuple[Dict[str, Any], ...] = _outputs()
_output_by_name = {output["name"]: output for output in outputs}


def _traversals() -> Tuple[str, ...]:
    names = []
    while (name := _native.lib.vkray_traversal(len(names))) is not None:
        names.append(name.decode())
    return tuple(names)


#: The searches Renderer's traversal= takes besides "auto".
traversals: Tuple[str, ...] = _traversals()


def _check(status: int) -> None:
    if status == _native.OK:
        return
    message = _native.lib.vkray_last_error().decode(errors="replace")
    if status == _native.INPUT_ERROR:
        raise ValueError(message)
    if status == _native.DEVICE_ERROR:
        raise Error(message)
    if status == _native.OUT_OF_MEMORY:
        raise MemoryError(message)
    raise RuntimeError(message)


def _pointer(array: Optional[np.ndarray], kind=ctypes.c_double):
    return None if array is None else array.ctypes.data_as(ctypes.POINTER(kind))


def _shape_text(shape: Sequence[int]) -> str:
    return "(" + ", ".join(str(d) for d in shape) + ")"


def _array(value: Any, what: str, expected: str) -> np.ndarray:
    """`value` as an array of real numbers, as given (booleans, complex numbers, strings, objects and
    ragged lists refused, naming `what`)."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):  # ragged nested lists: numpy's own message names no argument
        raise ValueError(f"{what}: expected an array of numbers, {expected} (rows of different lengths?)") from None
    if array.dtype.kind not in "fiu":
        hint = " (an Open3D tensor: pass tensor.numpy())" if type(value).__module__.startswith("open3d") else ""
        raise ValueError(f"{what}: expected an array of numbers, {expected}{hint}")
    return array


def _numbers(value: Any, what: str, expected: str) -> np.ndarray:
    """`value` as float64, C order: any real dtype (booleans, complex numbers and objects refused)."""
    return np.ascontiguousarray(_array(value, what, expected), dtype=np.float64)


def _rows(value: Any, what: str, columns: int) -> np.ndarray:
    """An N x `columns` float64 array, C order."""
    array = _numbers(value, what, f"N x {columns}")
    if array.ndim != 2 or array.shape[1] != columns:
        raise ValueError(f"{what}: expected an N x {columns} array, got shape {_shape_text(np.shape(value))}")
    return array


def _camera_json(camera: Optional[Mapping[str, Any]]) -> Optional[bytes]:
    """A camera in the scene file's form as JSON, its numbers checked finite, key by key."""
    if camera is None:
        return None
    if not isinstance(camera, Mapping):
        raise ValueError("camera: expected a dict in the scene file's form, {'from': [0, 1, 5], 'to': [0, 0, 0], 'fovy': 40}")

    def plain(value):
        if hasattr(value, "tolist"):
            return value.tolist()
        raise TypeError("camera: values must be numbers or lists of three numbers")

    for key, value in camera.items():
        try:
            json.dumps(value, default=plain, allow_nan=False)
        except ValueError:
            raise ValueError(f"camera: {key}: every number must be finite") from None
    return json.dumps(dict(camera), default=plain, allow_nan=False).encode()


def _mask(value: Any, what: str, least: int = 1) -> int:
    """A ray mask: a whole number of 8 bits (rays' masks from 1: 0 would hit nothing)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not least <= value <= 255:
        raise ValueError(f"{what}: expected a mask, a whole number {least}..255, got {value!r}")
    return int(value)


def _matrices(value: Any, what: str, one: bool = False) -> np.ndarray:
    """4 x 4 matrices of real numbers (N x 4 x 4, or with `one` a single 4 x 4) as float64 rows, C
    order: N x 16."""
    array = _array(value, what, "a 4 x 4 matrix" if one else "N x 4 x 4")
    if array.shape == (4, 4) or (not one and array.shape == (0,)):
        array = array.reshape(-1, 4, 4)
    if array.ndim != 3 or array.shape[1:] != (4, 4) or (one and len(array) != 1):
        expected = "a 4 x 4 matrix" if one else "a 4 x 4 matrix or N x 4 x 4"
        raise ValueError(f"{what}: expected {expected}, got shape {_shape_text(array.shape)}")
    return np.ascontiguousarray(array.reshape(-1, 16), dtype=np.float64)


def _whole(value: Any, what: str, least: int, most: int) -> int:
    """A whole number in least .. most (booleans and fractions refused: never wrapped or rounded)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not least <= value <= most:
        raise ValueError(f"{what}: expected a whole number in {least} .. {most}, got {value!r}")
    return int(value)


def _size(value: Optional[int], what: str) -> int:
    """A side in pixels, 0 for the default."""
    return 0 if value is None else _whole(value, what, 1, 65536)


class Scene:
    """A scene from arrays: one mesh (vertices N x 3, triangles M x 3), or meshes, a list of dicts
    {'vertices', 'triangles', 'transform' (4 x 4, optional)}; spheres K x 4 (centre, radius); planes
    P x 6 (point, normal); camera in the scene file's form ({'from': [0, 1, 5], 'to': [0, 0, 0],
    'fovy': 40}, degrees), or None to frame the geometry; width and height in pixels. masks: ray masks
    (0..255) by mesh_id, {mesh_id: mask} or one for every mesh, sphere and plane in that order: a call's
    rays (mask=) hit only what shares a bit with theirs; every bit (255) where none is given.
    instances: a list of dicts {'mesh' (a mesh_id), 'transform' (4 x 4 affine, optional), 'mask'
    (optional)}, numbered in order (instance_id): a mesh they name is stored once and drawn only where
    they place it (Renderer.set_transforms moves them)."""

    def __init__(self, vertices: Any = None, triangles: Any = None, *, meshes: Optional[Iterable[Mapping[str, Any]]] = None,
                 spheres: Any = None, planes: Any = None, camera: Optional[Mapping[str, Any]] = None,
                 width: int = 800, height: int = 600, masks: Union[None, Mapping[int, int], Sequence[int]] = None,
                 instances: Optional[Iterable[Mapping[str, Any]]] = None):
        handle = ctypes.c_void_p()
        _check(_native.lib.vkray_scene_new(_size(width, "width"), _size(height, "height"), ctypes.byref(handle)))
        self._handle = handle
        given = []
        if vertices is not None or triangles is not None:
            if vertices is None or triangles is None:
                raise ValueError("give both vertices and triangles, or meshes")
            given.append({"vertices": vertices, "triangles": triangles})
        for mesh in meshes or []:
            path = f"meshes[{len(given)}]"
            if not isinstance(mesh, Mapping):
                raise ValueError(f"{path}: expected a dict with vertices, triangles and transform")
            for key in mesh:
                if key not in ("vertices", "triangles", "transform"):
                    raise ValueError(f"{path}: unknown key '{key}' (known: vertices, triangles, transform)")
            if "vertices" not in mesh or "triangles" not in mesh:
                raise ValueError(f"{path}: needs vertices and triangles")
            given.append(mesh)
        for k, mesh in enumerate(given):
            self._add_mesh(mesh, f"meshes[{k}]")
        if spheres is not None:
            rows = _rows(spheres, "spheres", 4)
            _check(_native.lib.vkray_scene_add_spheres(self._handle, _pointer(rows), len(rows)))
        if planes is not None:
            rows = _rows(planes, "planes", 6)
            _check(_native.lib.vkray_scene_add_planes(self._handle, _pointer(rows), len(rows)))
        if masks is not None:
            by_id = masks.items() if isinstance(masks, Mapping) else enumerate(masks)
            for object_id, mask in by_id:
                if isinstance(object_id, bool) or not isinstance(object_id, (int, np.integer)) or not 0 <= object_id < 2**32:
                    raise ValueError(f"masks: expected mesh_ids as keys, got {object_id!r}")
                _check(_native.lib.vkray_scene_set_mask(self._handle, int(object_id), _mask(mask, f"masks[{object_id}]", 0)))
        for k, instance in enumerate(instances or []):
            path = f"instances[{k}]"
            if not isinstance(instance, Mapping) or "mesh" not in instance:
                raise ValueError(f"{path}: expected a dict with mesh, and transform and mask where wanted")
            for key in instance:
                if key not in ("mesh", "transform", "mask"):
                    raise ValueError(f"{path}: unknown key '{key}' (known: mesh, transform, mask)")
            mesh = instance["mesh"]
            if isinstance(mesh, bool) or not isinstance(mesh, (int, np.integer)) or not 0 <= mesh < 2**32:
                raise ValueError(f"{path}.mesh: expected a mesh_id, got {mesh!r}")
            transform = _matrices(instance["transform"], f"{path}.transform", one=True)[0] if "transform" in instance else None
            mask = _mask(instance.get("mask", 255), f"{path}.mask", 0)
            _check(_native.lib.vkray_scene_add_instance(self._handle, int(mesh), None if transform is None else _pointer(transform), mask))
        if camera is not None:
            _check(_native.lib.vkray_scene_set_camera(self._handle, _camera_json(camera)))
        _check(_native.lib.vkray_scene_finish(self._handle))
        self._describe()

    def _add_mesh(self, mesh: Mapping[str, Any], path: str) -> None:
        vertices = _rows(mesh["vertices"], f"{path}.vertices", 3)
        corners = np.asarray(mesh["triangles"])
        if corners.dtype.kind not in "iu":
            raise ValueError(f"{path}.triangles: expected an M x 3 array of integer vertex indices")
        if corners.ndim != 2 or corners.shape[1] != 3:
            raise ValueError(f"{path}.triangles: expected an M x 3 array")
        # Signed and unsigned indices each in their own width: an unsigned index past 2^63 must not wrap.
        unsigned = corners.dtype.kind == "u"
        corners = np.ascontiguousarray(corners, dtype=np.uint64 if unsigned else np.int64)
        transform = mesh.get("transform")
        if transform is not None:
            transform = _matrices(transform, f"{path}.transform", one=True)[0]
        _check(_native.lib.vkray_scene_add_mesh(self._handle, _pointer(vertices), len(vertices), corners.ctypes.data_as(ctypes.c_void_p),
                                                1 if unsigned else 0, len(corners), _pointer(transform)))

    def _describe(self) -> None:
        described = json.loads(_native.lib.vkray_scene_describe(self._handle).decode())
        self._width, self._height = described["width"], described["height"]
        self._counts = (described["meshes"], described["triangles"], described["spheres"], described["planes"])
        self._camera = described["camera"]
        self._object_names = described["object_names"]
        self._masks = described["masks"]

    @classmethod
    def _loaded(cls, handle: ctypes.c_void_p) -> "Scene":
        scene = cls.__new__(cls)
        scene._handle = handle
        scene._describe()
        return scene

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.lib.vkray_scene_free(handle)
            self._handle = None

    @property
    def camera(self) -> Dict[str, Any]:
        """The scene's camera in the scene file's form (from, to, up; fovy in degrees, or intrinsics, or projection)."""
        return dict(self._camera)

    @property
    def width(self) -> int:
        """The scene's image width in pixels."""
        return self._width

    @property
    def height(self) -> int:
        """The scene's image height in pixels."""
        return self._height

    @property
    def mesh_count(self) -> int:
        return self._counts[0]

    @property
    def triangle_count(self) -> int:
        return self._counts[1]

    @property
    def sphere_count(self) -> int:
        return self._counts[2]

    @property
    def plane_count(self) -> int:
        return self._counts[3]

    @property
    def object_names(self) -> list:
        """What each mesh_id stands for, by id: each mesh's source (its model file, a glTF's
        'file#node', 'meshes[i]' for arrays), then 'spheres[i]', then 'planes[i]'."""
        return list(self._object_names)

    @property
    def masks(self) -> list:
        """Each object's ray mask, by mesh_id (a scene file's "mask"; 255, every bit, by default)."""
        return list(self._masks)

    def _mesh_arrays(self, mesh: int, vertices: bool) -> np.ndarray:
        if isinstance(mesh, bool) or not isinstance(mesh, (int, np.integer)) or not 0 <= mesh < 2**32:
            raise ValueError(f"mesh: expected a mesh_id, a whole number from 0, got {mesh!r}")
        counts = (ctypes.c_uint64(), ctypes.c_uint64())
        _check(_native.lib.vkray_scene_mesh(self._handle, int(mesh), None, None, ctypes.byref(counts[0]), ctypes.byref(counts[1])))
        if vertices:
            positions = np.empty((counts[0].value, 3), dtype=np.float64)
            _check(_native.lib.vkray_scene_mesh(self._handle, int(mesh), _pointer(positions), None, None, None))
            return positions
        triangles = np.empty((counts[1].value, 3), dtype=np.uint32)
        _check(_native.lib.vkray_scene_mesh(self._handle, int(mesh), None, _pointer(triangles, ctypes.c_uint32), None, None))
        return triangles

    def vertices(self, mesh: int = 0) -> np.ndarray:
        """Mesh `mesh`'s (a mesh_id) vertex positions, N x 3 float64, in the order Renderer.set_vertices
        takes them: a model's every vertex in its file's order (used by a face or not), moved by its transform."""
        return self._mesh_arrays(mesh, True)

    def triangles(self, mesh: int = 0) -> np.ndarray:
        """Mesh `mesh`'s triangles, M x 3 uint32 indices into its vertices(mesh)."""
        return self._mesh_arrays(mesh, False)

    def __repr__(self) -> str:
        meshes, triangles, spheres, planes = self._counts
        return (f"<vkray.Scene: {meshes} meshes, {triangles} triangles, {spheres} spheres, {planes} planes, "
                f"{self._width}x{self._height}>")


def load(path: Union[str, os.PathLike], width: Optional[int] = None, height: Optional[int] = None,
         view: Union[None, str, Sequence[float]] = None) -> Scene:
    """A scene file (.json) or a model (.obj, .ply, .gltf, .glb: seen from a glTF's camera, else framed
    as `vkray render MODEL` frames it); width and height in pixels override the file's. view: frame the
    scene from a side ('front', 'back', 'left', 'right', 'top', 'bottom') or a direction [x, y, z] from
    its centre to the eye, as `vkray render --view`."""
    side, direction = None, None
    if isinstance(view, str):
        side = view.encode()
    elif view is not None:
        direction = np.asarray(view)
        if direction.dtype.kind not in "fiu" or direction.size != 3:
            raise ValueError("view: a side or a direction [x, y, z] from the centre to the eye")
        direction = np.ascontiguousarray(direction, dtype=np.float64).reshape(3)
    handle = ctypes.c_void_p()
    _check(_native.lib.vkray_scene_load(os.fsencode(path), _size(width, "width"), _size(height, "height"), side,
                                        _pointer(direction), ctypes.byref(handle)))
    return Scene._loaded(handle)


def _output_names(names: Union[str, Iterable[str]], what: str) -> list:
    """Output names from a list, or one string comma-separated as --aov takes them."""
    if isinstance(names, str):
        listed = [name for name in names.split(",") if name]
    else:
        try:
            listed = list(names)
        except TypeError:
            raise ValueError(f"{what}: expected a list of output names or one string, as ['depth', 'normal'] or 'depth,normal'") from None
        if not all(isinstance(name, str) for name in listed):
            raise ValueError(f"{what}: expected a list of output names or one string, as ['depth', 'normal'] or 'depth,normal'")
    return listed


def _render_help() -> str:
    text = ("camera: a dict as the scene file's, each key optional over the scene's; width, height in pixels; aovs: a "
            "list of output names (or one string, comma-separated); mask: the rays' mask, 1..255, as cast_rays'. A dict of arrays, H x W, C-contiguous, with a last "
            "axis of the components where there are several:")
    for output in outputs:
        parts = [output["description"]]
        if output["components"] > 1:
            parts.append(f"{output['components']} components")
        if output["dtype"] == "uint32":
            parts.append("uint32")
        text += f" {output['name']} ({', '.join(parts)});"
    return text[:-1] + "."


#: cast_rays' outputs besides the distance: what each ray gives, by key.
RAY_OUTPUTS = ("t", "normal", "primitive_id", "mesh_id", "instance_id", "position", "barycentric", "front_facing", "shading_normal", "texcoord")


from ._points import CLOSEST_POINT_OUTPUTS, PointQueries as _PointQueries, point_outputs  # noqa: E402 (it uses the helpers above)


class _Caster(_PointQueries):
    """What Renderer and Reference share: calls into a vkray_renderer of the C API."""

    _handle: Optional[ctypes.c_void_p] = None

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.lib.vkray_renderer_free(handle)
            self._handle = None

    @property
    def _doubles(self) -> bool:
        return bool(_native.lib.vkray_renderer_doubles(self._handle))

    def render(self, camera: Optional[Mapping[str, Any]] = None, width: Optional[int] = None, height: Optional[int] = None,
               aovs: Union[str, Iterable[str]] = ("depth", "normal"), mask: int = 255) -> Dict[str, np.ndarray]:
        names = _output_names(aovs, "aovs")
        ray_mask = _mask(mask, "mask")
        camera_json = _camera_json(camera)
        w = _size(width, "width") or self._scene_size[0]
        h = _size(height, "height") or self._scene_size[1]
        results, keys = [], []
        for name in names:
            key = name.replace("-", "_")
            output = _output_by_name.get(key)
            if output is None:
                break  # the library names it unknown, with the nearest name
            dtype = np.uint32 if output["dtype"] == "uint32" else np.float64 if self._doubles and key in ("depth", "normal") else np.float32
            shape = (h, w) if output["components"] == 1 else (h, w, output["components"])
            results.append(np.empty(shape, dtype=dtype))
            keys.append(key)
        c_names = (ctypes.c_char_p * max(1, len(names)))(*[name.replace("_", "-").encode() for name in names])
        c_results = (ctypes.c_void_p * max(1, len(names)))(*[array.ctypes.data for array in results])
        _check(_native.lib.vkray_render(self._handle, camera_json, w if width is not None else 0, h if height is not None else 0,
                                        ray_mask, len(names), c_names, c_results))
        return dict(zip(keys, results))

    def _rays_and_ranges(self, rays: Any, t_min: Any, t_max: Any):
        given = _array(rays, "rays", "of shape (..., 6)")
        if given.ndim == 0 or given.shape[-1] != 6:
            raise ValueError(f"rays: expected an array of shape (..., 6), got shape {_shape_text(given.shape)}")
        leading = given.shape[:-1]
        flat = np.ascontiguousarray(given, dtype=np.float64).reshape(-1, 6)
        count = len(flat)

        def one_end(value, what):
            if value is None:
                return None
            array = _array(value, what, "None, a number or one value a ray")
            # One number for every ray that cannot be right would make every ray a miss under
            # bad_rays='miss' (meant for a dead beam among many): refused, naming it.
            if array.ndim == 0:
                number = float(array)
                if what == "t_min" and not (np.isfinite(number) and number >= 0.0):
                    raise ValueError(f"t_min: {number!r} for every ray: a range starts at a finite t >= 0")
                if what == "t_max" and not number > 0.0:
                    raise ValueError(f"t_max: {number!r} for every ray: a range ends at a t > 0 (inf for no end)")
            try:
                spread = np.broadcast_to(array.astype(np.float64), leading)
            except ValueError:
                raise ValueError(f"{what}: expected None, a number or one value a ray ({count}: the rays' shape "
                                 f"{_shape_text(leading)}), got shape {_shape_text(array.shape)}") from None
            return np.ascontiguousarray(spread).reshape(-1)

        lo, hi = one_end(t_min, "t_min"), one_end(t_max, "t_max")
        if np.ndim(t_min) == 0 and np.ndim(t_max) == 0 and lo is not None and hi is not None and count and not hi[0] > lo[0]:
            raise ValueError(f"t_max: {float(hi[0])!r} is not above t_min {float(lo[0])!r}: every ray's range would be empty")
        return flat, leading, lo, hi

    @staticmethod
    def _flags(t_along: str, bad_rays: str) -> int:
        if t_along not in ("unit", "direction"):
            raise ValueError(f"t_along: 'unit' (along the normalized direction) or 'direction' (in units of the direction as given), got {t_along!r}")
        if bad_rays not in ("miss", "raise"):
            raise ValueError(f"bad_rays: 'miss' or 'raise', got {bad_rays!r}")
        return (_native.T_ALONG_DIRECTION if t_along == "direction" else 0) | (_native.BAD_RAYS_FAIL if bad_rays == "raise" else 0)

    def cast_rays(self, rays: Any, *, t_min: Any = None, t_max: Any = None,
                  outputs: Union[str, Iterable[str]] = ("t", "normal", "primitive_id", "mesh_id"),
                  t_along: str = "unit", bad_rays: str = "miss", mask: int = 255, hits: int = 1) -> Dict[str, np.ndarray]:
        """rays: any shape (..., 6), each an origin and a direction (any length but 0). t_min, t_max: None
        (0 and inf), a number, or one value a ray (broadcast over the leading shape): a hit counts at
        t_min < t < t_max. t_along: 'unit' (default), distances along the normalized direction; or
        'direction', in units of the direction as given, as Embree's and Open3D's (hit = origin + t *
        direction), for t, t_min and t_max alike. bad_rays: 'miss' (default), a ray with a zero or
        non-finite direction, an origin beyond 1e15 or a bad range is a miss; 'raise', ValueError naming
        the first. outputs: any of t (float32; float64 in double precision; inf on a miss), normal (3, the
        geometric normal facing the ray; 0 on a miss), primitive_id and mesh_id (uint32, NO_HIT on a
        miss), position (3, the hit point), barycentric (2), front_facing (uint32), shading_normal (3),
        texcoord (2): as render() gives them. mask: the rays' mask, 1..255 (every bit by default): they hit
        only the meshes, spheres and planes whose mask (Scene's masks) shares a bit with it. A dict of
        C-contiguous arrays of shape (...) or (..., C). hits: 1 (default) for the nearest hit; 2 to
        HITS_MAX for each ray's first hits in order of distance (every surface it crosses, a sphere's
        far side too, an edge passed exactly through once; misses past the last: multi-return LiDAR,
        layered depth), each array then of shape (..., hits) or (..., hits, C)."""
        names = _output_names(outputs, "outputs")
        ray_mask = _mask(mask, "mask")
        if isinstance(hits, bool) or not isinstance(hits, (int, np.integer)) or not 1 <= hits <= HITS_MAX:
            raise ValueError(f"hits: expected a whole number from 1 to {HITS_MAX}, got {hits!r}")
        layers = () if hits == 1 else (int(hits),)
        flat, leading, lo, hi = self._rays_and_ranges(rays, t_min, t_max)
        flags = self._flags(t_along, bad_rays)
        results, keys = [], []
        for name in names:
            key = name.replace("-", "_")
            output = _output_by_name.get("depth" if key == "t" else key)
            if key not in RAY_OUTPUTS or output is None:
                raise ValueError(f"outputs: '{name}' is not an output of given rays (they have {', '.join(RAY_OUTPUTS)})")
            dtype = np.uint32 if output["dtype"] == "uint32" else np.float64 if self._doubles and key in ("t", "normal") else np.float32
            shape = leading + layers + ((output["components"],) if output["components"] > 1 else ())
            results.append(np.empty(shape, dtype=dtype))
            keys.append(key)
        c_names = (ctypes.c_char_p * max(1, len(names)))(*[key.replace("_", "-").encode() for key in keys])
        c_results = (ctypes.c_void_p * max(1, len(names)))(*[array.ctypes.data for array in results])
        _check(_native.lib.vkray_cast_rays(self._handle, _pointer(flat), len(flat), _pointer(lo), _pointer(hi), flags,
                                           ray_mask, int(hits), len(keys), c_names, c_results))
        return dict(zip(keys, results))

    def occluded(self, rays: Any, *, t_min: Any = None, t_max: Any = None, t_along: str = "unit",
                 bad_rays: str = "miss", mask: int = 255) -> np.ndarray:
        """Occlusion queries, with cast_rays' rays, t_min, t_max, t_along, bad_rays and mask: a bool array of the
        rays' leading shape, True where a ray hits anything at t_min < t < t_max (a bad ray: False). Each
        ray's search stops at the first hit it meets. Open3D's test_occlusions of segments p to q is
        occluded(np.concatenate([p, q - p], axis=-1), t_max=1, t_along='direction')."""
        flat, leading, lo, hi = self._rays_and_ranges(rays, t_min, t_max)
        flags = self._flags(t_along, bad_rays)
        blocked = np.empty(leading, dtype=np.uint8)
        _check(_native.lib.vkray_occluded(self._handle, _pointer(flat), len(flat), _pointer(lo), _pointer(hi), flags,
                                          _mask(mask, "mask"), _pointer(blocked, ctypes.c_uint8)))
        return blocked.view(np.bool_)

    def count_intersections(self, rays: Any, *, t_min: Any = None, t_max: Any = None, t_along: str = "unit",
                            bad_rays: str = "miss", mask: int = 255) -> np.ndarray:
        """How many times each ray crosses a surface at t_min < t < t_max, with cast_rays' rays, t_min, t_max,
        t_along, bad_rays and mask: a uint32 array of the rays' leading shape (a bad ray: 0). Every
        triangle, sphere root and plane counts; an edge or vertex a ray passes exactly through counts once,
        so the count is odd where a ray starts inside a closed mesh, farther from its surface than float32's
        rounding (Open3D's count_intersections: inside = renderer.count_intersections(rays) % 2 == 1)."""
        flat, leading, lo, hi = self._rays_and_ranges(rays, t_min, t_max)
        flags = self._flags(t_along, bad_rays)
        crossings = np.empty(leading, dtype=np.uint32)
        _check(_native.lib.vkray_count_intersections(self._handle, _pointer(flat), len(flat), _pointer(lo), _pointer(hi),
                                                     flags, _mask(mask, "mask"), _pointer(crossings, ctypes.c_uint32)))
        return crossings

    def set_vertices(self, mesh: int, positions: Any) -> None:
        """Moves the vertices of mesh `mesh` (its mesh_id) to `positions`, an N x 3 array of the mesh's N
        vertices in its order (a skinned arm, cloth): the next call renders the moved scene, as a
        renderer made from it would. The tree keeps its shape and only its boxes are recomputed while
        every triangle keeps a non-zero area, else it is built anew; where the centre of the scene's box
        stays (an object moving within a room's walls) and the mesh shares no vertex position with
        another, only this mesh's part is redone (timings: 'scene_update_ms',
        'tree_refitted', 'refit_mesh_alone'). ValueError for a bad mesh, count or coordinate, the scene unchanged."""
        if isinstance(mesh, bool) or not isinstance(mesh, (int, np.integer)) or not 0 <= mesh < 2**32:
            raise ValueError(f"mesh: expected a mesh_id (0 for the first mesh), got {mesh!r}")
        moved = _rows(positions, "positions", 3)
        _check(_native.lib.vkray_renderer_set_vertices(self._handle, int(mesh), _pointer(moved), len(moved)))

    def set_transforms(self, instances: Any, transforms: Any) -> None:
        """Moves instances: instances[k] (an instance_id, in the order the Scene's instances were given)
        takes transforms[k], a 4 x 4 affine matrix (last row 0 0 0 1); transforms is N x 4 x 4. The
        top level (the tree over the instances) is built anew where they now stand, the meshes' trees
        kept; the next call renders the moved scene (timings: 'scene_update_ms'). ValueError for a bad
        instance or transform, the scene unchanged."""
        ids = np.atleast_1d(_array(instances, "instances", "a list of instance_ids"))
        if ids.size == 0:
            ids = ids.astype(np.uint32)  # [] reads as float64: nothing to move
        if ids.dtype.kind not in "iu" or ids.ndim != 1 or (ids.size and (ids.min() < 0 or ids.max() >= 2**32)):
            raise ValueError("instances: expected a list of instance_ids, whole numbers from 0")
        ids = np.ascontiguousarray(ids, dtype=np.uint32)
        matrices = _matrices(transforms, "transforms")
        if len(matrices) != len(ids):
            raise ValueError(f"set_transforms: {len(ids)} instances but {len(matrices)} transforms")
        _check(_native.lib.vkray_renderer_set_transforms(self._handle, ids.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)),
                                                          _pointer(matrices), len(ids)))

    @property
    def timings(self) -> Dict[str, Any]:
        """Where the last call's time went, in milliseconds; what the constructor took (upload, BVH
        build, pipelines) under 'setup'."""
        return json.loads(_native.lib.vkray_renderer_timings(self._handle).decode())


_Caster.render.__doc__ = _render_help()


class Renderer(_Caster):
    """Opens the device and uploads the scene; then renders and casts rays any number of times, each
    kind of call making its pipeline at its first use (prepare() makes them all at once)."""

    def __init__(self, scene: Scene, device: Optional[str] = None, precision: str = "float", traversal: str = "auto"):
        """device: part of a device name (`vkray info`), None for the first; precision: 'float' or
        'double' (the float64 shader: depth, normal and t in float64); traversal: as `vkray render
        --traversal`, 'auto' or one of vkray.traversals."""
        if not isinstance(scene, Scene):
            raise ValueError("scene: expected a vkray.Scene (vkray.load or vkray.Scene)")
        handle = ctypes.c_void_p()
        _check(_native.lib.vkray_renderer_new(scene._handle, None if device is None else str(device).encode(), str(precision).encode(),
                                              str(traversal).encode(), ctypes.byref(handle)))
        self._handle = handle
        self._scene_size = (scene.width, scene.height)

    @property
    def device_name(self) -> str:
        """The name of the device it opened (`vkray info`)."""
        return _native.lib.vkray_renderer_device_name(self._handle).decode()

    def prepare(self) -> None:
        """Makes and first runs every pipeline that render (of the scene's camera), cast_rays and
        occluded take, several at once, so that no later call of theirs pays for a first use (its time
        in timings['setup']['pipeline_ms']): for a process that answers calls as they come."""
        _check(_native.lib.vkray_renderer_prepare(self._handle))


class Reference(_Caster):
    """The double-precision CPU reference, with the Renderer's methods (depth, normal and t in float64)."""

    def __init__(self, scene: Scene):
        if not isinstance(scene, Scene):
            raise ValueError("scene: expected a vkray.Scene (vkray.load or vkray.Scene)")
        handle = ctypes.c_void_p()
        _check(_native.lib.vkray_reference_new(scene._handle, ctypes.byref(handle)))
        self._handle = handle
        self._scene_size = (scene.width, scene.height)
