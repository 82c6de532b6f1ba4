// `import vkray`: the engine from Python, numpy arrays in and out. A front end as thin as the CLI:
// it converts arguments and results and maps errors; scenes are checked, rendered and traced by the
// engine. Bad input raises ValueError (the engine's InputError, with its one-line message), device
// failures vkray.Error. The GIL is released while the engine works.
#include "engine/scene/framing.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/scene/scene_or_model.hpp"
#include "engine/typed_names.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;

namespace vkray::python {
namespace {

// A numpy array over `values` without copying them: the vector moves into a capsule that numpy
// frees with the last view. `strides` in elements.
template <typename T, typename Allocator>
py::array array_over(std::vector<T, Allocator>&& values, const std::vector<py::ssize_t>& shape, const std::vector<py::ssize_t>& strides) {
  auto* owned = new std::vector<T, Allocator>(std::move(values));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T, Allocator>*>(p); });
  std::vector<py::ssize_t> byte_strides;
  for (py::ssize_t stride : strides) byte_strides.push_back(stride * static_cast<py::ssize_t>(sizeof(T)));
  return py::array_t<T>(shape, byte_strides, owned->data(), owner);
}

// One value a pixel or ray: shape (rows, columns), or (count,) when rows is 0.
template <typename T, typename Allocator>
py::array scalar_plane(std::vector<T, Allocator>&& values, py::ssize_t rows, py::ssize_t columns) {
  if (rows == 0) return array_over(std::move(values), {columns}, {1});
  return array_over(std::move(values), {rows, columns}, {columns, 1});
}

// `components` planes of rows x columns (the engine's layout) as (rows, columns, components), or
// (count, components) when rows is 0: a strided view, not a copy.
template <typename T, typename Allocator>
py::array planes_as_last_axis(std::vector<T, Allocator>&& values, py::ssize_t rows, py::ssize_t columns, py::ssize_t components) {
  const py::ssize_t plane = (rows == 0 ? 1 : rows) * columns;
  if (rows == 0) return array_over(std::move(values), {columns, components}, {1, plane});
  return array_over(std::move(values), {rows, columns, components}, {columns, 1, plane});
}

// An N x `columns` float64 array (any real dtype converted), or ValueError naming `what`.
py::array_t<double, py::array::c_style> float_rows(py::handle value, const char* what, py::ssize_t columns) {
  py::array array = py::array::ensure(value);
  if (!array || (array.dtype().kind() != 'f' && array.dtype().kind() != 'i' && array.dtype().kind() != 'u')) {
    throw InputError(std::string(what) + ": expected an array of numbers, N x " + std::to_string(columns));
  }
  // The converting constructor, not ensure(): a conversion numpy cannot allocate raises its
  // MemoryError here, where ensure() would clear it and hand back an empty handle.
  const py::array_t<double, py::array::c_style | py::array::forcecast> rows(array);
  if (rows.ndim() != 2 || rows.shape(1) != columns) {
    std::string shape;
    for (py::ssize_t d = 0; d < array.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(array.shape(d));
    throw InputError(std::string(what) + ": expected an N x " + std::to_string(columns) + " array, got shape (" + shape + ")");
  }
  return rows;
}

glm::dvec3 row_vec3(const py::array_t<double, py::array::c_style>& rows, py::ssize_t r, py::ssize_t first = 0) {
  return {rows.at(r, first), rows.at(r, first + 1), rows.at(r, first + 2)};
}

// A camera in the scene file's form ({"from": [0, 1, 5], "to": [0, 0, 0], "up": [0, 1, 0],
// "fovy": 40}, every key optional over `base`), checked by the engine as the scene file is.
Camera camera_from(py::handle camera, const Camera& base) {
  if (camera.is_none()) return base;
  if (!py::isinstance<py::dict>(camera)) {
    throw InputError("camera: expected a dict in the scene file's form, {'from': [0, 1, 5], 'to': [0, 0, 0], 'fovy': 40}");
  }
  const py::object to_list = py::cpp_function([](py::handle value) -> py::object {
    if (py::hasattr(value, "tolist")) return value.attr("tolist")();
    throw py::type_error("camera: values must be numbers or lists of three numbers");
  });
  std::string json;
  try {
    json = py::module_::import("json").attr("dumps")(camera, py::arg("default") = to_list, py::arg("allow_nan") = false)
               .cast<std::string>();
  } catch (const py::error_already_set& error) {
    if (!error.matches(PyExc_ValueError)) throw;
    // json.dumps says only "Out of range float values are not JSON compliant": find the key.
    for (const auto& [key, value] : camera.cast<py::dict>()) {
      try {
        py::module_::import("json").attr("dumps")(value, py::arg("default") = to_list, py::arg("allow_nan") = false);
      } catch (const py::error_already_set&) {
        throw InputError("camera: " + py::str(key).cast<std::string>() + ": every number must be finite");
      }
    }
    throw InputError("camera: every number must be finite");
  }
  return parse_camera_override(json, "camera", base);
}

py::dict camera_dict(const Camera& camera) {
  py::dict dict;
  dict["from"] = std::vector<double>{camera.from.x, camera.from.y, camera.from.z};
  dict["to"] = std::vector<double>{camera.to.x, camera.to.y, camera.to.z};
  dict["up"] = std::vector<double>{camera.up.x, camera.up.y, camera.up.z};
  if (camera.projection != Projection::perspective) {
    dict["projection"] = projection_name(camera.projection);
    if (camera.projection == Projection::orthographic) dict["view_height"] = camera.view_height;
  } else if (camera.intrinsics) {
    const PinholeIntrinsics& k = *camera.intrinsics;
    py::dict intrinsics;
    intrinsics["fx"] = k.fx, intrinsics["fy"] = k.fy, intrinsics["cx"] = k.cx, intrinsics["cy"] = k.cy;
    dict["intrinsics"] = intrinsics;
  } else {
    dict["fovy"] = camera.fovy_degrees;
  }
  return dict;
}

// Output names as a list, or one string, comma-separated as --aov takes them ("depth,normal").
AovSet aovs_from(py::handle argument) {
  std::vector<std::string> names;
  if (py::isinstance<py::str>(argument)) {
    names = split_list(argument.cast<std::string>());
    std::erase(names, "");  // "depth," names one output
  } else {
    try {
      names = argument.cast<std::vector<std::string>>();
    } catch (const py::cast_error&) {
      throw InputError("aovs: expected a list of output names or one string, as ['depth', 'normal'] or 'depth,normal'");
    }
  }
  AovSet aovs;
  for (const std::string& name : names) {
    const auto aov = aov_from_name(name);
    if (!aov) throw InputError("aovs: " + unknown_output_message(name));
    aovs.add(*aov);
  }
  if (aovs.empty()) throw InputError("aovs: name at least one output (" + output_names() + ")");
  return aovs;
}

// The outputs of `frame` in `aovs` into `result`, keyed by python_key, as the EXR has them
// (float32; ids and flags uint32), a component on the last axis; `doubles`: depth and normal as the
// float64 shader left them.
void add_outputs(Frame& frame, AovSet aovs, py::dict& result) {
  const auto rows = static_cast<py::ssize_t>(frame.height), columns = static_cast<py::ssize_t>(frame.width);
  const bool doubles = !frame.depth64.empty() || !frame.normal64.empty();
  for (const OutputInfo& output : outputs()) {
    if (!aovs.has(output.aov)) continue;
    auto array = [&](auto&& planes) {
      return output.components == 1 ? scalar_plane(std::move(planes), rows, columns)
                                    : planes_as_last_axis(std::move(planes), rows, columns, output.components);
    };
    if (doubles && output.aov == Aov::depth) {
      result[python_key(output).c_str()] = array(std::move(frame.depth64));
    } else if (doubles && output.aov == Aov::normal) {
      result[python_key(output).c_str()] = array(std::move(frame.normal64));
    } else if (output.integers) {
      result[python_key(output).c_str()] = array(std::move(frame.*output.integers));
    } else {
      result[python_key(output).c_str()] = array(std::move(frame.*output.floats));
    }
  }
}

// render()'s docstring: every output it gives, by its key (kept for the module's life: pybind11
// keeps the pointer).
const std::string& render_help() {
  static const std::string text = [] {
    std::string help = "camera: a dict as the scene file's, each key optional over the scene's; aovs: a list of "
                       "output names (or one string, comma-separated). A dict of arrays, H x W, with a last axis of "
                       "the components where there are several:";
    for (const OutputInfo& output : outputs()) {
      help += " " + python_key(output) + " (" + output.description +
              (output.components > 1 ? ", " + std::to_string(output.components) + " components" : "") +
              (output.integers ? ", uint32" : "") + ");";
    }
    help.back() = '.';
    return help;
  }();
  return text;
}

// Reference.render()'s: the same, depth and normal in float64.
const std::string& reference_render_help() {
  static const std::string text = render_help() + " Depth and normal in float64.";
  return text;
}

// The rays argument of cast_rays: N x 6 (origin, direction), any real dtype.
std::span<const GivenRay> given_rays(const py::array_t<double, py::array::c_style>& rays) {
  static_assert(sizeof(GivenRay) == 6 * sizeof(double));
  return {reinterpret_cast<const GivenRay*>(rays.data()), static_cast<size_t>(rays.shape(0))};
}

// One end of cast_rays' or occluded's ranges, `what` (t_min or t_max): None (empty: the default), a
// number for every ray, or one value a ray.
std::vector<double> range_values(py::handle value, const char* what, size_t ray_count) {
  if (value.is_none()) return {};
  py::array array = py::array::ensure(value);
  const std::string expected = std::string(what) + ": expected None, a number or one value a ray (" + std::to_string(ray_count) + ")";
  if (!array || array.ndim() > 1) throw InputError(expected);
  const auto column = float_rows(array.reshape({-1, 1}), what, 1);  // any real dtype, as rays
  if (array.ndim() == 0) return std::vector<double>(ray_count, column.at(0, 0));  // a number, numpy's too
  if (static_cast<size_t>(column.shape(0)) != ray_count) {
    throw InputError(expected + ", got " + std::to_string(column.shape(0)));
  }
  return {column.data(), column.data() + column.shape(0)};
}

// cast_rays' and occluded's arguments: the rays and their ranges, owned.
struct RayArguments {
  py::array_t<double, py::array::c_style> rays;
  std::vector<double> t_min, t_max;
  RayArguments(py::handle rays_argument, py::handle t_min_argument, py::handle t_max_argument)
      : rays(float_rows(rays_argument, "rays", 6)),
        t_min(range_values(t_min_argument, "t_min", static_cast<size_t>(rays.shape(0)))),
        t_max(range_values(t_max_argument, "t_max", static_cast<size_t>(rays.shape(0)))) {}
  std::span<const GivenRay> given() const { return given_rays(rays); }
  RayRanges ranges() const { return {t_min, t_max}; }
};

// occluded()'s answer: a bool a ray.
py::array_t<bool> bool_array(const std::vector<uint8_t>& values) {
  py::array_t<bool> array(static_cast<py::ssize_t>(values.size()));
  static_assert(sizeof(bool) == sizeof(uint8_t));
  if (!values.empty()) std::memcpy(array.mutable_data(), values.data(), values.size());
  return array;
}

// A mesh given as arrays: {"vertices": N x 3, "triangles": M x 3 integers, "transform": 4 x 4}.
Mesh mesh_from(py::handle vertices, py::handle triangles, py::handle transform, const std::string& path) {
  Mesh mesh;
  const auto positions = float_rows(vertices, (path + ".vertices").c_str(), 3);
  for (py::ssize_t r = 0; r < positions.shape(0); ++r) {
    mesh.positions.push_back(row_vec3(positions, r));
    check_coordinates(mesh.positions.back(), path + ".vertices[" + std::to_string(r) + "]");
  }
  py::array corners = py::array::ensure(triangles);
  if (!corners || (corners.dtype().kind() != 'i' && corners.dtype().kind() != 'u')) {
    throw InputError(path + ".triangles: expected an M x 3 array of integer vertex indices");
  }
  // Signed and unsigned indices each in their own width: an unsigned index past 2^63 must not wrap.
  auto read_triangles = [&]<typename Index>() {
    auto indices = py::array_t<Index, py::array::c_style | py::array::forcecast>::ensure(corners);
    if (indices.ndim() != 2 || indices.shape(1) != 3) throw InputError(path + ".triangles: expected an M x 3 array");
    for (py::ssize_t t = 0; t < indices.shape(0); ++t) {
      std::array<uint32_t, 3> triangle{};
      for (py::ssize_t c = 0; c < 3; ++c) {
        const Index index = indices.at(t, c);
        if (index < 0 || static_cast<uint64_t>(index) >= mesh.positions.size()) {
          throw InputError(path + ".triangles[" + std::to_string(t) + "][" + std::to_string(c) + "]: vertex index " +
                           std::to_string(index) + " is out of range (the mesh has " + std::to_string(mesh.positions.size()) +
                           " vertices)");
        }
        triangle[static_cast<size_t>(c)] = static_cast<uint32_t>(index);
      }
      mesh.triangles.push_back(triangle);
    }
  };
  if (corners.dtype().kind() == 'u') {
    read_triangles.operator()<uint64_t>();
  } else {
    read_triangles.operator()<int64_t>();
  }
  if (!transform.is_none()) {
    const std::string affine = path + ".transform: expected a 4 x 4 affine matrix of finite numbers (last row 0, 0, 0, 1)";
    const py::array given = py::array::ensure(transform);
    if (!given || given.ndim() != 2 || given.shape(0) != 4 || given.shape(1) != 4) throw InputError(affine);
    const auto matrix = float_rows(transform, (path + ".transform").c_str(), 4);
    for (py::ssize_t i = 0; i < 16; ++i) {
      if (!std::isfinite(matrix.at(i / 4, i % 4))) throw InputError(affine);
    }
    if (matrix.at(3, 0) != 0.0 || matrix.at(3, 1) != 0.0 || matrix.at(3, 2) != 0.0 || matrix.at(3, 3) != 1.0) {
      throw InputError(affine);
    }
    for (auto& p : mesh.positions) {
      p = glm::dvec3(matrix.at(0, 0) * p.x + matrix.at(0, 1) * p.y + matrix.at(0, 2) * p.z + matrix.at(0, 3),
                     matrix.at(1, 0) * p.x + matrix.at(1, 1) * p.y + matrix.at(1, 2) * p.z + matrix.at(1, 3),
                     matrix.at(2, 0) * p.x + matrix.at(2, 1) * p.y + matrix.at(2, 2) * p.z + matrix.at(2, 3));
    }
  }
  return mesh;
}

Scene scene_from_arrays(py::handle vertices, py::handle triangles, py::handle meshes, py::handle spheres, py::handle planes,
                        py::handle camera, uint32_t width, uint32_t height) {
  Scene scene;
  scene.width = width;
  scene.height = height;
  if (!vertices.is_none() || !triangles.is_none()) {
    if (vertices.is_none() || triangles.is_none()) throw InputError("give both vertices and triangles, or meshes");
    scene.meshes.push_back(mesh_from(vertices, triangles, py::none(), "meshes[0]"));
  }
  if (!meshes.is_none()) {
    for (py::handle mesh : meshes) {
      const std::string path = "meshes[" + std::to_string(scene.meshes.size()) + "]";
      if (!py::isinstance<py::dict>(mesh)) throw InputError(path + ": expected a dict with vertices, triangles and transform");
      const py::dict dict = py::reinterpret_borrow<py::dict>(mesh);
      for (auto [key, value] : dict) {
        const std::string name = py::str(key);
        if (name != "vertices" && name != "triangles" && name != "transform") {
          throw InputError(path + ": unknown key '" + name + "' (known: vertices, triangles, transform)");
        }
      }
      if (!dict.contains("vertices") || !dict.contains("triangles")) throw InputError(path + ": needs vertices and triangles");
      scene.meshes.push_back(mesh_from(dict["vertices"], dict["triangles"],
                                       dict.contains("transform") ? py::object(dict["transform"]) : py::none(), path));
    }
  }
  if (!spheres.is_none()) {
    const auto rows = float_rows(spheres, "spheres", 4);
    for (py::ssize_t r = 0; r < rows.shape(0); ++r) scene.spheres.push_back({row_vec3(rows, r), rows.at(r, 3)});
  }
  if (!planes.is_none()) {
    const auto rows = float_rows(planes, "planes", 6);
    for (py::ssize_t r = 0; r < rows.shape(0); ++r) scene.planes.push_back({row_vec3(rows, r), row_vec3(rows, r, 3)});
  }
  // A camera the scene names is checked below; none frames the geometry, as for a model file.
  if (!camera.is_none()) scene.camera = camera_from(camera, Camera{});
  check_scene(scene);
  if (camera.is_none()) scene.camera = frame_scene(scene, scene.width, scene.height);
  return scene;
}

std::optional<uint32_t> size_argument(std::optional<int64_t> value, const char* what) {
  if (!value) return std::nullopt;
  if (*value < 1 || *value > max_image_side) {
    throw InputError(std::string(what) + ": must be in 1 .. " + std::to_string(max_image_side) + ", got " + std::to_string(*value));
  }
  return static_cast<uint32_t>(*value);
}

// What a render call asks: its camera and size, defaults from the scene.
struct View {
  Camera camera;
  uint32_t width, height;
};

View view_from(const Scene& scene, py::handle camera, std::optional<int64_t> width, std::optional<int64_t> height) {
  View view{camera_from(camera, scene.camera), size_argument(width, "width").value_or(scene.width),
            size_argument(height, "height").value_or(scene.height)};
  check_image_size(view.width, view.height);
  return view;
}

class PyRenderer {
 public:
  PyRenderer(const Scene& scene, const std::optional<std::string>& device, const std::string& precision,
             const std::string& traversal)
      : scene_(scene) {
    RendererOptions options;
    double_precision_ = precision == "double";
    if (double_precision_) {
      options.shader.precision = Precision::float64;
    } else if (precision != "float") {
      throw InputError("precision: 'float' or 'double', got '" + precision + "'");
    }
    const std::optional<PrimitiveSearch> search = traversal_from_name(traversal);
    if (!search) throw InputError("traversal: one of " + traversal_names() + ", got '" + traversal + "'");
    options.scene.search = *search;
    py::gil_scoped_release released;
    device_ = std::make_unique<GpuDevice>(device.value_or(""));
    renderer_ = std::make_unique<Renderer>(*device_, scene_, options);
  }

  py::dict render(py::handle camera, std::optional<int64_t> width, std::optional<int64_t> height,
                  py::handle aov_names) {
    const View view = view_from(scene_, camera, width, height);
    const AovSet aovs = aovs_from(aov_names);
    Frame frame;
    {
      py::gil_scoped_release released;
      const std::lock_guard one_call_at_a_time(busy_);
      frame = renderer_->render(view.camera, view.width, view.height, aovs);
    }
    py::dict result;
    add_outputs(frame, aovs, result);
    return result;
  }

  py::dict cast_rays(py::handle rays_argument, py::handle t_min, py::handle t_max) {
    const RayArguments arguments(rays_argument, t_min, t_max);
    RayHits hits;
    {
      py::gil_scoped_release released;
      const std::lock_guard one_call_at_a_time(busy_);
      hits = renderer_->cast_rays(arguments.given(), arguments.ranges());
    }
    const auto count = static_cast<py::ssize_t>(hits.count);
    py::dict result;
    const bool doubles = !hits.t64.empty() || (hits.count == 0 && double_precision_);
    result["t"] = doubles ? scalar_plane(std::move(hits.t64), 0, count) : scalar_plane(std::move(hits.t), 0, count);
    result["normal"] = doubles ? planes_as_last_axis(std::move(hits.normal64), 0, count, 3)
                               : planes_as_last_axis(std::move(hits.normal), 0, count, 3);
    result["primitive_id"] = scalar_plane(std::move(hits.primitive), 0, count);
    result["mesh_id"] = scalar_plane(std::move(hits.object), 0, count);
    return result;
  }

  py::array_t<bool> occluded(py::handle rays_argument, py::handle t_min, py::handle t_max) {
    const RayArguments arguments(rays_argument, t_min, t_max);
    std::vector<uint8_t> blocked;
    {
      py::gil_scoped_release released;
      const std::lock_guard one_call_at_a_time(busy_);
      blocked = renderer_->occluded(arguments.given(), arguments.ranges());
    }
    return bool_array(blocked);
  }

  std::string device_name() const { return device_->info().name; }

  py::dict timings() {
    const std::lock_guard one_call_at_a_time(busy_);
    const RenderTimings& t = renderer_->timings();
    py::dict dict;
    dict["upload_ms"] = t.upload_ms;
    dict["pipeline_ms"] = t.pipeline_ms;
    if (t.has_gpu_times) dict["dispatch_gpu_ms"] = t.dispatch_gpu_ms;
    dict["readback_ms"] = t.readback_ms;
    dict["rays_ms"] = t.rays_ms;
    if (t.given_walk != GivenRayWalk::none) {
      dict["rays_walk"] = given_ray_walk_name(t.given_walk);
    }
    dict["dispatches"] = t.tiles;
    dict["cpu_finished_rays"] = t.unfinished_rays;
    return dict;
  }

 private:
  Scene scene_;
  bool double_precision_ = false;
  std::unique_ptr<GpuDevice> device_;
  std::unique_ptr<Renderer> renderer_;
  // The engine's Renderer serves one call at a time; Python threads may call it together, since
  // each call releases the GIL.
  std::mutex busy_;
};

// The double-precision CPU reference with the Renderer's signatures; float64 arrays.
class PyReference {
 public:
  explicit PyReference(const Scene& scene) : scene_(scene) {
    py::gil_scoped_release released;
    reference_ = std::make_unique<ReferenceScene>(scene_);
  }

  py::dict render(py::handle camera, std::optional<int64_t> width, std::optional<int64_t> height,
                  py::handle aov_names) {
    const View view = view_from(scene_, camera, width, height);
    const AovSet aovs = aovs_from(aov_names);
    py::dict result;
    Frame frame;
    {
      py::gil_scoped_release released;
      const std::vector<ReferenceHit> hits = render_reference_hits(*reference_, view.camera, view.width, view.height);
      // Depth and normal in double, the reference's own; the other outputs as `vkray render
      // --reference` writes them.
      frame = reference_frame(*reference_, scene_, hits, view.camera, view.width, view.height, aovs, true);
    }
    add_outputs(frame, aovs, result);
    return result;
  }

  py::dict cast_rays(py::handle rays_argument, py::handle t_min, py::handle t_max) {
    const RayArguments arguments(rays_argument, t_min, t_max);
    std::vector<ReferenceHit> hits;
    {
      py::gil_scoped_release released;
      hits = trace_reference_rays(*reference_, arguments.given(), arguments.ranges());
    }
    const size_t count = hits.size();
    std::vector<double> t(count), normal(3 * count);
    std::vector<uint32_t> primitive(count), object(count);
    for (size_t k = 0; k < count; ++k) {
      t[k] = hits[k].t;
      for (size_t c = 0; c < 3; ++c) normal[c * count + k] = hits[k].normal[int(c)];
      const ObjectPrimitive source = reference_->source(hits[k]);
      primitive[k] = source.primitive;
      object[k] = source.object;
    }
    const auto n = static_cast<py::ssize_t>(count);
    py::dict result;
    result["t"] = scalar_plane(std::move(t), 0, n);
    result["normal"] = planes_as_last_axis(std::move(normal), 0, n, 3);
    result["primitive_id"] = scalar_plane(std::move(primitive), 0, n);
    result["mesh_id"] = scalar_plane(std::move(object), 0, n);
    return result;
  }

  // The nearest hit decides: exactly whether any hit lies in the range.
  py::array_t<bool> occluded(py::handle rays_argument, py::handle t_min, py::handle t_max) {
    const RayArguments arguments(rays_argument, t_min, t_max);
    std::vector<uint8_t> blocked;
    {
      py::gil_scoped_release released;
      const std::vector<ReferenceHit> hits = trace_reference_rays(*reference_, arguments.given(), arguments.ranges());
      blocked.resize(hits.size());
      for (size_t k = 0; k < hits.size(); ++k) blocked[k] = hits[k].kind != PrimitiveKind::none ? 1 : 0;
    }
    return bool_array(blocked);
  }

 private:
  Scene scene_;
  std::unique_ptr<ReferenceScene> reference_;
};

}  // namespace
}  // namespace vkray::python

PYBIND11_MODULE(vkray, m) {
  using namespace vkray;
  using namespace vkray::python;
  m.doc() = "vkray: exact depth and normals by ray casting on a Vulkan device, numpy arrays in and out";
  static py::exception<GpuError> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InputError& input) {
      PyErr_SetString(PyExc_ValueError, input.what());
    } catch (const GpuError& gpu) {
      error(gpu.what());
    }
  });
  m.attr("NO_HIT") = py::int_(no_object);
  // The outputs render() gives (engine/frame.hpp, outputs()): each as a dict of its key, components,
  // dtype, the EXR channels `vkray render` writes it to and what it is.
  py::list output_list;
  for (const OutputInfo& output : outputs()) {
    py::list channels;
    for (size_t c = 0; c < output.components; ++c) channels.append(output.channels[c]);
    py::dict entry;
    entry["name"] = python_key(output);
    entry["components"] = output.components;
    entry["dtype"] = output.integers ? "uint32" : "float32";
    entry["channels"] = channels;
    entry["description"] = output.description;
    output_list.append(entry);
  }
  m.attr("outputs") = py::tuple(output_list);
  // The searches Renderer's traversal= takes besides "auto" (engine/render/search.hpp).
  py::list traversal_list;
  for (const SearchInfo& search : searches()) traversal_list.append(search.name);
  m.attr("traversals") = py::tuple(traversal_list);

  py::class_<Scene>(m, "Scene",
                    "A scene from arrays: one mesh (vertices N x 3, triangles M x 3), or meshes, a list of dicts "
                    "{'vertices', 'triangles', 'transform' (4 x 4, optional)}; spheres K x 4 (centre, radius); "
                    "planes P x 6 (point, normal); camera in the scene file's form, or None to frame the geometry.")
      .def(py::init(&scene_from_arrays), py::arg("vertices") = py::none(), py::arg("triangles") = py::none(),
           py::kw_only(), py::arg("meshes") = py::none(), py::arg("spheres") = py::none(), py::arg("planes") = py::none(),
           py::arg("camera") = py::none(), py::arg("width") = default_image_width,
           py::arg("height") = default_image_height)
      .def_property_readonly("camera", [](const Scene& scene) { return camera_dict(scene.camera); })
      .def_readonly("width", &Scene::width)
      .def_readonly("height", &Scene::height)
      .def_property_readonly("triangle_count", &Scene::triangle_count)
      .def_property_readonly("mesh_count", [](const Scene& scene) { return scene.meshes.size(); })
      .def_property_readonly("sphere_count", [](const Scene& scene) { return scene.spheres.size(); })
      .def_property_readonly("plane_count", [](const Scene& scene) { return scene.planes.size(); })
      .def_property_readonly("object_names", &object_names,
                             "What each mesh_id stands for, by id: each mesh's source (its model file, a glTF's "
                             "'file#node', 'meshes[i]' for arrays), then 'spheres[i]', then 'planes[i]'.")
      .def("__repr__", [](const Scene& scene) {
        return "<vkray.Scene: " + std::to_string(scene.meshes.size()) + " meshes, " + std::to_string(scene.triangle_count()) +
               " triangles, " + std::to_string(scene.spheres.size()) + " spheres, " + std::to_string(scene.planes.size()) +
               " planes, " + std::to_string(scene.width) + "x" + std::to_string(scene.height) + ">";
      });

  m.def(
      "load",
      [](const std::filesystem::path& path, std::optional<int64_t> width, std::optional<int64_t> height, py::handle view) {
        const auto w = size_argument(width, "width"), h = size_argument(height, "height");
        std::optional<FramingView> side;
        if (py::isinstance<py::str>(view)) {
          side = framing_view_from_name(view.cast<std::string>());
          if (!side) throw InputError("view: unknown side '" + view.cast<std::string>() + "' (" + framing_view_names + ")");
        } else if (!view.is_none()) {
          const auto direction = float_rows(py::array::ensure(view).reshape({1, -1}), "view", 3);
          side = FramingView{row_vec3(direction, 0), {0.0, 1.0, 0.0}};
          if (side->from_direction == glm::dvec3(0.0) || !std::isfinite(glm::length(side->from_direction))) {
            throw InputError("view: the direction from the centre to the eye must be finite and not 0");
          }
        }
        py::gil_scoped_release released;
        Scene scene = load_scene_or_model(path, w, h);
        if (side) scene.camera = frame_scene(scene, scene.width, scene.height, *side);
        return scene;
      },
      py::arg("path"), py::arg("width") = py::none(), py::arg("height") = py::none(), py::arg("view") = py::none(),
      "A scene file (.json) or a model (.obj, .ply, .gltf, .glb: seen from a glTF's camera, else framed as `vkray render MODEL` frames it). view: frame the "
      "scene from a side ('front', 'back', 'left', 'right', 'top', 'bottom') or a direction [x, y, z] from its "
      "centre to the eye, as `vkray render --view`.");

  py::class_<PyRenderer>(m, "Renderer",
                         "Opens the device, uploads the scene and makes the pipeline once; then renders and casts "
                         "rays any number of times. device: part of a device name (`vkray info`); precision: "
                         "'float' or 'double'; traversal: as `vkray render --traversal`, 'auto' or one of "
                         "vkray.traversals.")
      .def(py::init<const Scene&, const std::optional<std::string>&, const std::string&, const std::string&>(),
           py::arg("scene"), py::arg("device") = py::none(), py::arg("precision") = "float",
           py::arg("traversal") = "auto")
      .def("render", &PyRenderer::render, py::arg("camera") = py::none(), py::arg("width") = py::none(),
           py::arg("height") = py::none(), py::arg("aovs") = py::make_tuple("depth", "normal"),
           render_help().c_str())
      .def("cast_rays", &PyRenderer::cast_rays, py::arg("rays"), py::kw_only(), py::arg("t_min") = py::none(),
           py::arg("t_max") = py::none(),
           "rays: N x 6 (origin, direction); t_min, t_max: None, a number or N values, hits counting only at "
           "t_min < t < t_max (default 0 and inf). A dict of arrays: t (distance from the origin along the "
           "normalized direction, inf on a miss), normal N x 3, primitive_id and mesh_id (uint32, NO_HIT on a miss).")
      .def("occluded", &PyRenderer::occluded, py::arg("rays"), py::kw_only(), py::arg("t_min") = py::none(),
           py::arg("t_max") = py::none(),
           "Occlusion queries: the same arguments as cast_rays; a bool array, True where a ray hits anything at "
           "t_min < t < t_max. Each ray's search stops at the first hit it meets.")
      .def_property_readonly("device_name", &PyRenderer::device_name, "The name of the device it opened (`vkray info`).")
      .def_property_readonly("timings", &PyRenderer::timings, "Where the last call's time went, in milliseconds.");

  py::class_<PyReference>(m, "Reference", "The double-precision CPU reference, with the Renderer's methods (float64).")
      .def(py::init<const Scene&>(), py::arg("scene"))
      .def("render", &PyReference::render, py::arg("camera") = py::none(), py::arg("width") = py::none(),
           py::arg("height") = py::none(), py::arg("aovs") = py::make_tuple("depth", "normal"),
           reference_render_help().c_str())
      .def("cast_rays", &PyReference::cast_rays, py::arg("rays"), py::kw_only(), py::arg("t_min") = py::none(),
           py::arg("t_max") = py::none())
      .def("occluded", &PyReference::occluded, py::arg("rays"), py::kw_only(), py::arg("t_min") = py::none(),
           py::arg("t_max") = py::none());
}
