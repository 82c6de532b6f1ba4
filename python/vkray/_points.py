"""Point queries (vkray_query_points of the C API): closest points, distances, signed distances,
occupancy and winding numbers, for Renderer and Reference alike (docs/points.md)."""
from __future__ import annotations

import ctypes
from typing import Any, Dict, Iterable, Tuple, Union

import numpy as np

from . import _native, _array, _check, _mask, _pointer, _shape_text


def _point_outputs() -> Tuple[Dict[str, Any], ...]:
    listed = []
    info = _native.OutputInfo()
    while _native.lib.vkray_point_output(len(listed), ctypes.byref(info)):
        listed.append({"name": info.name.decode().replace("-", "_"), "components": info.components,
                       "dtype": "uint32" if info.is_integer else "float32", "description": info.description.decode()})
    return tuple(listed)


#: The outputs query_points gives, by key: each a dict of its name, components, dtype (float32 ones
#: are float64 in double precision) and what it is.
point_outputs: Tuple[Dict[str, Any], ...] = _point_outputs()
_point_output_by_name = {output["name"]: output for output in point_outputs}
#: What closest_points gives (Open3D's compute_closest_points, with the distance beside).
CLOSEST_POINT_OUTPUTS = ("position", "distance", "normal", "barycentric", "mesh_id", "primitive_id", "instance_id")


class PointQueries:
    """The point queries of Renderer and Reference (through their vkray_renderer handle)."""

    def query_points(self, points: Any, outputs: Union[str, Iterable[str]] = ("distance",), *, max_distance: Any = None,
                     mask: int = 255) -> Dict[str, np.ndarray]:
        """points: any shape (..., 3), world coordinates. outputs: any of vkray.point_outputs' names:
        distance (to the nearest point of the scene's surfaces), signed_distance (negative inside),
        winding_number (the generalized winding number: 1 inside a closed mesh, 0 outside, between where
        a mesh is open), occupancy (uint32, 1 inside: winding number 1/2 or more), position (3, the
        nearest point), normal (3, the outward normal there), barycentric (2), mesh_id, primitive_id,
        instance_id (uint32, NO_HIT where none). max_distance: None (no bound), a number or one value a
        point: beyond it no point is found (distance inf, position NaN, ids NO_HIT). mask: as cast_rays',
        the surfaces of that mask alone. A dict of C-contiguous arrays of shape (...) or (..., C); float32,
        float64 in double precision. ValueError for a point not finite or beyond 1e15, naming it."""
        names = [outputs] if isinstance(outputs, str) else list(outputs)
        given = _array(points, "points", "of shape (..., 3)")
        if given.ndim == 0 or given.shape[-1] != 3:
            raise ValueError(f"points: expected an array of shape (..., 3), got shape {_shape_text(given.shape)}")
        leading = given.shape[:-1]
        flat = np.ascontiguousarray(given, dtype=np.float64).reshape(-1, 3)
        most = None
        if max_distance is not None:
            bound = _array(max_distance, "max_distance", "None, a number or one value a point")
            try:
                most = np.ascontiguousarray(np.broadcast_to(bound.astype(np.float64), leading)).reshape(-1)
            except ValueError:
                raise ValueError(f"max_distance: expected None, a number or one value a point (the points' shape "
                                 f"{_shape_text(leading)}), got shape {_shape_text(bound.shape)}") from None
        doubles = bool(_native.lib.vkray_renderer_doubles(self._handle))
        results, keys = [], []
        for name in names:
            key = str(name).replace("-", "_")
            output = _point_output_by_name.get(key)
            if output is None:
                raise ValueError(f"outputs: '{name}' is not a point output (they are {', '.join(_point_output_by_name)})")
            dtype = np.uint32 if output["dtype"] == "uint32" else np.float64 if doubles else np.float32
            shape = leading + ((output["components"],) if output["components"] > 1 else ())
            results.append(np.empty(shape, dtype=dtype))
            keys.append(key)
        c_names = (ctypes.c_char_p * max(1, len(keys)))(*[key.replace("_", "-").encode() for key in keys])
        c_results = (ctypes.c_void_p * max(1, len(keys)))(*[array.ctypes.data for array in results])
        _check(_native.lib.vkray_query_points(self._handle, _pointer(flat), len(flat), _pointer(most), _mask(mask, "mask"),
                                              len(keys), c_names, c_results))
        return dict(zip(keys, results))

    def closest_points(self, points: Any, *, max_distance: Any = None, mask: int = 255) -> Dict[str, np.ndarray]:
        """The nearest point of the scene to each point, as query_points' CLOSEST_POINT_OUTPUTS (Open3D's
        compute_closest_points: its points are 'position', its geometry_ids 'mesh_id')."""
        return self.query_points(points, CLOSEST_POINT_OUTPUTS, max_distance=max_distance, mask=mask)

    def distance(self, points: Any, *, max_distance: Any = None, mask: int = 255) -> np.ndarray:
        """The unsigned distance to the scene's surfaces, of the points' leading shape (inf beyond max_distance)."""
        return self.query_points(points, "distance", max_distance=max_distance, mask=mask)["distance"]

    def signed_distance(self, points: Any, *, max_distance: Any = None, mask: int = 255) -> np.ndarray:
        """The distance, negative inside: where the generalized winding number is 1/2 or more, which holds
        on meshes with holes, several shells and self-intersections (docs/points.md)."""
        return self.query_points(points, "signed_distance", max_distance=max_distance, mask=mask)["signed_distance"]

    def occupancy(self, points: Any, *, mask: int = 255) -> np.ndarray:
        """A bool array of the points' leading shape: True inside (winding number 1/2 or more)."""
        return self.query_points(points, "occupancy", mask=mask)["occupancy"].astype(np.bool_)

    def winding_number(self, points: Any, *, mask: int = 255) -> np.ndarray:
        """The generalized winding number at each point (1 inside, 0 outside, between near holes)."""
        return self.query_points(points, "winding_number", mask=mask)["winding_number"]
