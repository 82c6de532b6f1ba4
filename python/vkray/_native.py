"""libvkray.so, vkray's C API (engine/api/vkray.h), through ctypes: one library for every CPython.

The library is found beside this package (vkray/lib/, as the wheel and the build tree hold it) or in
the relocatable bundle's lib/ two folders up. ctypes releases the GIL for every call into it.
"""
import ctypes
import pathlib

API_VERSION = 6  # VKRAY_API_VERSION of the header this file declares


def _find_library():
    here = pathlib.Path(__file__).resolve().parent
    places = [here / "lib" / "libvkray.so", here.parent.parent / "lib" / "libvkray.so"]
    for place in places:
        if place.is_file():
            return place
    raise ImportError("vkray: libvkray.so is not beside the package (looked in " + ", ".join(map(str, places)) +
                      "): install the wheel, or use the bundle's python/ folder")


lib = ctypes.CDLL(str(_find_library()))

Status = ctypes.c_int
OK, INPUT_ERROR, DEVICE_ERROR, OUT_OF_MEMORY, INTERNAL_ERROR = range(5)
T_ALONG_DIRECTION, BAD_RAYS_FAIL = 1, 2


class OutputInfo(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char_p), ("description", ctypes.c_char_p), ("components", ctypes.c_uint32),
                ("is_integer", ctypes.c_uint32), ("channels", ctypes.c_char_p * 3)]


_scene = ctypes.c_void_p
_renderer = ctypes.c_void_p
_doubles = ctypes.POINTER(ctypes.c_double)
_names = ctypes.POINTER(ctypes.c_char_p)
_pointers = ctypes.POINTER(ctypes.c_void_p)

_signatures = {
    "vkray_api_version": (ctypes.c_uint32, []),
    "vkray_version": (ctypes.c_char_p, []),
    "vkray_last_error": (ctypes.c_char_p, []),
    "vkray_output": (ctypes.c_int, [ctypes.c_uint32, ctypes.POINTER(OutputInfo)]),
    "vkray_traversal": (ctypes.c_char_p, [ctypes.c_uint32]),
    "vkray_scene_load": (Status, [ctypes.c_char_p, ctypes.c_uint32, ctypes.c_uint32, ctypes.c_char_p, _doubles,
                                  ctypes.POINTER(_scene)]),
    "vkray_scene_new": (Status, [ctypes.c_uint32, ctypes.c_uint32, ctypes.POINTER(_scene)]),
    "vkray_scene_add_mesh": (Status, [_scene, _doubles, ctypes.c_uint64, ctypes.c_void_p, ctypes.c_int, ctypes.c_uint64, _doubles]),
    "vkray_scene_add_instance": (Status, [_scene, ctypes.c_uint32, _doubles, ctypes.c_uint32]),
    "vkray_scene_add_spheres": (Status, [_scene, _doubles, ctypes.c_uint64]),
    "vkray_scene_add_planes": (Status, [_scene, _doubles, ctypes.c_uint64]),
    "vkray_scene_set_mask": (Status, [_scene, ctypes.c_uint32, ctypes.c_uint32]),
    "vkray_scene_set_camera": (Status, [_scene, ctypes.c_char_p]),
    "vkray_scene_finish": (Status, [_scene]),
    "vkray_scene_describe": (ctypes.c_char_p, [_scene]),
    "vkray_scene_free": (None, [_scene]),
    "vkray_scene_mesh": (Status, [_scene, ctypes.c_uint32, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint32),
                                  ctypes.POINTER(ctypes.c_uint64), ctypes.POINTER(ctypes.c_uint64)]),
    "vkray_renderer_new": (Status, [_scene, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.POINTER(_renderer)]),
    "vkray_reference_new": (Status, [_scene, ctypes.POINTER(_renderer)]),
    "vkray_renderer_doubles": (ctypes.c_int, [_renderer]),
    "vkray_renderer_device_name": (ctypes.c_char_p, [_renderer]),
    "vkray_renderer_set_vertices": (Status, [_renderer, ctypes.c_uint32, _doubles, ctypes.c_uint64]),
    "vkray_renderer_set_transforms": (Status, [_renderer, ctypes.POINTER(ctypes.c_uint32), _doubles, ctypes.c_uint64]),
    "vkray_renderer_timings": (ctypes.c_char_p, [_renderer]),
    "vkray_renderer_free": (None, [_renderer]),
    "vkray_renderer_prepare": (Status, [_renderer]),
    "vkray_render": (Status, [_renderer, ctypes.c_char_p, ctypes.c_uint32, ctypes.c_uint32, ctypes.c_uint32, ctypes.c_uint32,
                              _names, _pointers]),
    "vkray_cast_rays": (Status, [_renderer, _doubles, ctypes.c_uint64, _doubles, _doubles, ctypes.c_uint32, ctypes.c_uint32,
                                 ctypes.c_uint32, ctypes.c_uint32, _names, _pointers]),
    "vkray_occluded": (Status, [_renderer, _doubles, ctypes.c_uint64, _doubles, _doubles, ctypes.c_uint32, ctypes.c_uint32,
                                ctypes.POINTER(ctypes.c_uint8)]),
    "vkray_count_intersections": (Status, [_renderer, _doubles, ctypes.c_uint64, _doubles, _doubles, ctypes.c_uint32,
                                           ctypes.c_uint32, ctypes.POINTER(ctypes.c_uint32)]),
    "vkray_point_output": (ctypes.c_int, [ctypes.c_uint32, ctypes.POINTER(OutputInfo)]),
    "vkray_query_points": (Status, [_renderer, _doubles, ctypes.c_uint64, _doubles, ctypes.c_uint32, ctypes.c_uint32, _names,
                                    _pointers]),
}
for _name, (_result, _arguments) in _signatures.items():
    _function = getattr(lib, _name)
    _function.restype = _result
    _function.argtypes = _arguments

if lib.vkray_api_version() != API_VERSION:
    raise ImportError(f"vkray: libvkray.so speaks C API version {lib.vkray_api_version()}, this package {API_VERSION}: "
                      "the package and the library come from different builds")
