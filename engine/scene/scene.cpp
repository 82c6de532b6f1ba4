#include "engine/scene/scene.hpp"

#include "engine/fnv1a.hpp"
#include "engine/parallel.hpp"
#include "engine/scene/model_loader.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_access.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <string>

namespace vkray {

std::string one_line_message(const std::string& text) {
  std::string escaped;
  escaped.reserve(std::min(text.size(), 4 * max_message_bytes));
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte >= 0x20 && byte != 0x7f) || c == '\t') {
      escaped += c;
    } else {
      constexpr char hex[] = "0123456789abcdef";
      escaped += {'\\', 'x', hex[byte >> 4], hex[byte & 15]};
    }
  }
  if (escaped.size() <= max_message_bytes) return escaped;
  // The start names the file and the place, the end often the remedy: both kept, whole UTF-8
  // characters on either side of the cut.
  const auto character_start = [&](size_t at) {
    while (at > 0 && (static_cast<unsigned char>(escaped[at]) & 0xc0) == 0x80) --at;
    return at;
  };
  const size_t head = character_start(2 * max_message_bytes / 3), tail = character_start(escaped.size() - max_message_bytes / 4);
  return escaped.substr(0, head) + " [... " + std::to_string(tail - head) + " bytes left out ...] " + escaped.substr(tail);
}

size_t Scene::triangle_count() const {
  size_t count = 0;
  for (const auto& mesh : meshes) count += mesh.triangles.size();
  return count;
}

size_t Scene::drawn_triangle_count() const {
  std::vector<uint8_t> placed(meshes.size(), 0);
  for (const Instance& instance : instances) placed[instance.mesh] = 1;
  size_t count = 0;
  for (size_t m = 0; m < meshes.size(); ++m) count += (!meshes[m].instanced || placed[m]) ? meshes[m].triangles.size() : 0;
  return count;
}

size_t Scene::zero_area_triangle_count() const {
  size_t count = 0;
  for (const auto& mesh : meshes) {
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3& v0 = mesh.positions[corners[0]];
      count += glm::cross(mesh.positions[corners[1]] - v0, mesh.positions[corners[2]] - v0) == glm::dvec3(0.0);
    }
  }
  return count;
}

void check_image_size(uint32_t width, uint32_t height) {
  if (width < 1 || height < 1 || width > max_image_side || height > max_image_side ||
      uint64_t{width} * height > max_image_pixels) {
    throw InputError("image size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1x1 .. " + std::to_string(max_image_side) + " per side and " +
                     std::to_string(max_image_pixels) + " pixels");
  }
}

namespace {

std::string item(const char* list, size_t index) { return std::string(list) + "[" + std::to_string(index) + "]"; }

}  // namespace

void check_coordinates(const glm::dvec3& p, const std::string& path) {
  if (!within_coordinate_bound(p)) {
    throw InputError(path + ": every coordinate must be finite and within 1e15, got (" + std::to_string(p.x) + ", " +
                     std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
  }
}

void check_camera_reach(const Camera& camera, uint32_t width, uint32_t height, const std::string& what) {
  if (camera.projection != Projection::orthographic) return;
  // An orthographic ray starts at its pixel of the image plane (pixel_ray): the corners reach
  // farthest, and vkray's coordinates end at max_coordinate.
  const CameraBasis basis = make_camera_basis(camera, width, height);
  for (const auto& [i, j] : {std::pair{0u, 0u}, {width - 1, 0u}, {0u, height - 1}, {width - 1, height - 1}}) {
    const glm::dvec3 corner = pixel_ray(camera, basis, i, j, width, height).origin;
    if (within_coordinate_bound(corner)) continue;
    char text[200];
    std::snprintf(text, sizeof text, ": an orthographic view_height of %g at %ux%u puts the image's corner at (%g, %g, %g), beyond "
                  "vkray's coordinates (1e15 on each axis)", camera.view_height, width, height, corner.x, corner.y, corner.z);
    throw InputError(what + text);
  }
}

void check_scene(Scene& scene) {
  check_coordinates(scene.camera.from, "camera.from");
  check_coordinates(scene.camera.to, "camera.to");
  if (scene.camera.from == scene.camera.to) throw InputError("camera.to: must differ from camera.from");
  if (!within_coordinate_bound(scene.camera.up) || scene.camera.up == glm::dvec3(0.0)) {
    throw InputError("camera.up: must be finite and non-zero");
  }
  if (!(scene.camera.fovy_degrees > 0.0 && scene.camera.fovy_degrees < 180.0)) {
    throw InputError("camera.fovy: field of view must be in (0, 180) degrees, got " + std::to_string(scene.camera.fovy_degrees));
  }
  check_image_size(scene.width, scene.height);
  check_camera_reach(scene.camera, scene.width, scene.height, "camera");
  for (size_t k = 0; k < scene.spheres.size(); ++k) {
    check_coordinates(scene.spheres[k].center, item("spheres", k) + ".center");
    const double radius = scene.spheres[k].radius;
    if (!(radius > 0.0 && radius <= max_coordinate)) {
      throw InputError(item("spheres", k) + ".radius: must be > 0 and within 1e15, got " + std::to_string(radius));
    }
  }
  for (size_t k = 0; k < scene.planes.size(); ++k) {
    Plane& plane = scene.planes[k];
    check_coordinates(plane.point, item("planes", k) + ".point");
    if (!within_coordinate_bound(plane.normal) || plane.normal == glm::dvec3(0.0)) {
      throw InputError(item("planes", k) + ".normal: must be finite and non-zero");
    }
    plane.normal = unit_vector(plane.normal);
  }
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    const std::string path = item("meshes", m);
    if (mesh.triangles.empty()) throw InputError(path + ".triangles: a mesh needs at least one triangle");
    for (size_t v = 0; v < mesh.positions.size(); ++v) check_coordinates(mesh.positions[v], path + "." + item("positions", v));
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (size_t c = 0; c < 3; ++c) {
        if (mesh.triangles[t][c] >= mesh.positions.size()) {
          throw InputError(path + "." + item("triangles", t) + "[" + std::to_string(c) + "]: vertex index " +
                           std::to_string(mesh.triangles[t][c]) + " is out of range (the mesh has " +
                           std::to_string(mesh.positions.size()) + " positions)");
        }
      }
    }
  }
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (scene.meshes[m].instanced && scene.meshes[m].mask != every_mask_bit) {
      throw InputError(item("meshes", m) + ".mask: the mesh is drawn by its instances, whose masks stand for its own: give "
                       "each instance the mask");
    }
  }
  // Each placement against its mesh's box: the placed corners bound every placed vertex, for eight
  // points an instance rather than every vertex (1e5 placements of a 35k-vertex model).
  std::vector<Bounds> mesh_boxes;
  for (size_t k = 0; k < scene.instances.size(); ++k) {
    const Instance& instance = scene.instances[k];
    const std::string path = item("instances", k);
    if (instance.mesh >= scene.meshes.size() || !scene.meshes[instance.mesh].instanced) {
      throw InputError(path + ".mesh: " + std::to_string(instance.mesh) + " is not an instanced mesh of the scene's " +
                       std::to_string(scene.meshes.size()));
    }
    if (mesh_boxes.empty()) mesh_boxes = instanced_mesh_boxes(scene);
    check_transform(instance, mesh_boxes[instance.mesh], path);
  }
}

double smallest_scale(const glm::dmat3& linear) {
  // One over the inverse's largest singular value: the square root of the largest eigenvalue of the
  // symmetric m = A^T A, A the inverse, in closed form (Smith, "Eigenvalues of a symmetric 3x3
  // matrix", CACM 4(4), 1961: the roots of its characteristic polynomial as q + 2 p cos(angle + 2 pi k
  // / 3), the largest at k = 0). The largest eigenvalue comes to a few ulps of itself however
  // ill-conditioned the placement (the least would not: their ratio reaches 2^64).
  const glm::dmat3 inverse = glm::inverse(linear);
  const glm::dmat3 m = glm::transpose(inverse) * inverse;
  const double q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
  const double off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
  const double p2 = (m[0][0] - q) * (m[0][0] - q) + (m[1][1] - q) * (m[1][1] - q) + (m[2][2] - q) * (m[2][2] - q) + 2.0 * off;
  double largest = q;
  if (p2 > 0.0) {
    const double p = std::sqrt(p2 / 6.0);
    const glm::dmat3 b = (m - q * glm::dmat3(1.0)) / p;
    const double r = std::clamp(glm::determinant(b) / 2.0, -1.0, 1.0);
    largest = q + 2.0 * p * std::cos(std::acos(r) / 3.0);
  }
  // A relative 1e-12 below, for that rounding: never above the true factor.
  return (1.0 - 1e-12) / std::sqrt(largest);
}

std::string float32_placement_fault(const glm::dmat3& linear) {
  const glm::dmat3 to_mesh = glm::inverse(linear);
  double spread = 0.0, linear_norm = 0.0, to_mesh_norm = 0.0;
  std::array<double, 3> largest{};  // in each row of the inverse
  for (int i = 0; i < 3; ++i) {
    const glm::dvec3 row = glm::row(to_mesh, i);
    spread += glm::length(linear[i]) * glm::length(row);
    linear_norm += glm::dot(linear[i], linear[i]);
    to_mesh_norm += glm::dot(row, row);
    largest[i] = std::max({std::abs(row.x), std::abs(row.y), std::abs(row.z)});
  }
  const double condition = std::sqrt(linear_norm * to_mesh_norm);
  char text[300];
  if (!(condition <= max_placement_condition)) {
    std::snprintf(text, sizeof text, "it flattens the mesh by %.3g along some axis (its condition number), beyond the 2^32 "
                  "that float32 mesh coordinates hold: flatten the mesh itself", condition);
    return text;
  }
  for (int i = 0; i < 3; ++i) {
    if (!(largest[i] >= 0x1p-100 && largest[i] <= 0x1p100)) {
      std::snprintf(text, sizeof text, "its inverse's row %d reaches %.3g, outside the 2^-100 .. 2^100 that float32 mesh "
                    "coordinates hold", i, largest[i]);
      return text;
    }
  }
  if (!(spread <= max_placement_spread)) {
    std::snprintf(text, sizeof text, "it scales or shears across rotated axes so that float32 mesh coordinates place the mesh "
                  "up to %.3g roundings off (a rotation and scale: 3, vkray takes up to %g): give the mesh its own "
                  "positions, or scale along its axes before rotating", spread, max_placement_spread);
    return text;
  }
  return {};
}

void check_transform(const Instance& instance, const Bounds& mesh_box, const std::string& path) {
  for (int column = 0; column < 3; ++column) check_coordinates(instance.linear[column], path + ".transform");
  check_coordinates(instance.translation, path + ".transform");
  // Invertible: a ray is taken into the mesh's coordinates by the inverse (a zero determinant, or
  // one that underflows, flattens the mesh into a plane or less).
  const double determinant = glm::determinant(instance.linear);
  if (!(std::abs(determinant) >= std::numeric_limits<double>::min()) || !std::isfinite(determinant)) {
    throw InputError(path + ".transform: cannot be inverted (its determinant is " + std::to_string(determinant) + ")");
  }
  if (const std::string fault = float32_placement_fault(instance.linear); !fault.empty()) {
    throw InputError(path + ".transform: " + fault);
  }
  if (mesh_box.empty()) return;
  for (int corner = 0; corner < 8; ++corner) {
    check_coordinates(placed(instance, mesh_box.corner(corner)), path + ".transform: the mesh's box placed");
  }
}

std::vector<Bounds> instanced_mesh_boxes(const Scene& scene) {
  std::vector<Bounds> boxes(scene.meshes.size());
  for (size_t mesh = 0; mesh < scene.meshes.size(); ++mesh) {
    if (!scene.meshes[mesh].instanced) continue;
    for (const glm::dvec3& p : scene.meshes[mesh].positions) boxes[mesh].add(p);
  }
  return boxes;
}

void set_instance_transforms(Scene& scene, std::span<const uint32_t> instances, std::span<const glm::dmat4> transforms,
                             const std::vector<Bounds>* mesh_boxes) {
  if (instances.size() != transforms.size()) {
    throw InputError("set_transforms: " + std::to_string(instances.size()) + " instances but " +
                     std::to_string(transforms.size()) + " transforms");
  }
  std::vector<Instance> placed_instances = scene.instances;
  std::vector<Bounds> found_boxes;
  std::vector<uint32_t> listed_at(placed_instances.size(), UINT32_MAX);  // each instance's entry
  for (size_t k = 0; k < instances.size(); ++k) {
    const std::string path = "transforms[" + std::to_string(k) + "]";
    if (instances[k] >= placed_instances.size()) {
      throw InputError("instances[" + std::to_string(k) + "]: " + std::to_string(instances[k]) +
                       " is not an instance of the scene's " + std::to_string(placed_instances.size()));
    }
    if (listed_at[instances[k]] != UINT32_MAX) {
      throw InputError("instances[" + std::to_string(k) + "]: instance " + std::to_string(instances[k]) +
                       " is placed twice (entries " + std::to_string(listed_at[instances[k]]) + " and " + std::to_string(k) +
                       "): one transform an instance");
    }
    listed_at[instances[k]] = static_cast<uint32_t>(k);
    const glm::dmat4& m = transforms[k];
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
      throw InputError(path + ": not an affine map (its last row is not 0 0 0 1)");
    }
    Instance& instance = placed_instances[instances[k]];
    place_by(instance, m);
    if (!mesh_boxes && found_boxes.empty()) found_boxes = instanced_mesh_boxes(scene);
    check_transform(instance, (mesh_boxes ? *mesh_boxes : found_boxes)[instance.mesh], path);
  }
  scene.instances = std::move(placed_instances);
}

const char* given_ray_fault(const GivenRay& ray) {
  if (!std::all_of(ray.begin(), ray.begin() + 3, [](double v) { return std::isfinite(v); })) return "the origin is not finite";
  if (!std::all_of(ray.begin() + 3, ray.end(), [](double v) { return std::isfinite(v); })) return "the direction is not finite";
  if (std::any_of(ray.begin(), ray.begin() + 3, [](double v) { return std::abs(v) > max_coordinate; })) {
    return "the origin is farther than 1e15 from the world origin on some axis";
  }
  if (ray[3] == 0.0 && ray[4] == 0.0 && ray[5] == 0.0) return "the direction is 0";
  return nullptr;
}

namespace {

// Throws InputError naming the first k < count for which fault(k) is not null, with that fault as
// found: the caller's rays may change meanwhile (another thread of theirs), and a second look could
// find another fault or none. On every core (a million rays took 4 ms on one, a tenth of their casting).
template <typename Fault>
void check_each_ray(size_t count, Fault&& fault, const char* item = "ray") {
  std::mutex first_lock;
  size_t first_fault = count;
  const char* first_message = nullptr;
  parallel_for_chunks(count, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      if (const char* message = fault(k)) {
        const std::lock_guard keep(first_lock);
        if (k < first_fault) first_fault = k, first_message = message;
        return;
      }
    }
  });
  if (first_message) throw InputError(std::string(item) + " " + std::to_string(first_fault) + ": " + first_message);
}

}  // namespace

void check_given_rays(std::span<const GivenRay> rays) {
  check_each_ray(rays.size(), [&](size_t k) { return given_ray_fault(rays[k]); });
}

GivenRay range_start_ray(const GivenRay& ray, double t_min) {
  const glm::dvec3 direction = unit_vector({ray[3], ray[4], ray[5]});
  const glm::dvec3 start = glm::dvec3(ray[0], ray[1], ray[2]) + t_min * direction;
  return {start.x, start.y, start.z, direction.x, direction.y, direction.z};
}

namespace {

// What is wrong with ray k's range; null for nothing.
const char* ray_range_fault(std::span<const GivenRay> rays, const RayRanges& ranges, size_t k) {
  const double t_min = ranges.start(k), t_max = ranges.end(k);
  if (!std::isfinite(t_min) || t_min < 0.0) return "t_min is negative or not finite";
  if (std::isnan(t_max) || t_max < t_min) return "t_max is NaN or below t_min";
  if (t_min > 0.0) {
    const GivenRay start = range_start_ray(rays[k], t_min);
    if (std::any_of(start.begin(), start.begin() + 3, [](double v) { return !(std::abs(v) <= max_coordinate); })) {
      return "the range starts farther than 1e15 from the world origin on some axis";
    }
  }
  return nullptr;
}

void check_range_sizes(std::span<const GivenRay> rays, const RayRanges& ranges) {
  for (const auto& [span, name] : {std::pair{ranges.t_min, "t_min"}, std::pair{ranges.t_max, "t_max"}}) {
    if (!span.empty() && span.size() != rays.size()) {
      throw InputError(std::string(name) + ": " + std::to_string(span.size()) + " values for " +
                       std::to_string(rays.size()) + " rays (one a ray, or none)");
    }
  }
}

}  // namespace

void check_ray_ranges(std::span<const GivenRay> rays, const RayRanges& ranges) {
  check_range_sizes(rays, ranges);
  if (ranges.t_min.empty() && ranges.t_max.empty()) return;
  check_each_ray(rays.size(), [&](size_t k) { return ray_range_fault(rays, ranges, k); });
}

void check_query_points(std::span<const glm::dvec3> points, std::span<const double> max_distances) {
  check_each_ray(points.size(), [&](size_t k) {
    return within_coordinate_bound(points[k]) ? nullptr : "a coordinate is not finite or is farther than 1e15 from the world origin";
  }, "point");
  if (!max_distances.empty() && max_distances.size() != 1 && max_distances.size() != points.size()) {
    throw InputError("max_distance: " + std::to_string(max_distances.size()) + " values for " + std::to_string(points.size()) +
                     " points (one for all, one a point, or none)");
  }
  check_each_ray(max_distances.size(), [&](size_t k) { return max_distances[k] >= 0.0 ? nullptr : "is negative or NaN (+inf for none)"; },
                 "max_distance");
}

std::vector<uint8_t> refused_rays(std::span<const GivenRay> rays, const RayRanges& ranges) {
  check_range_sizes(rays, ranges);
  std::vector<uint8_t> refused(rays.size());
  const bool ranged = !ranges.t_min.empty() || !ranges.t_max.empty();
  parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      refused[k] = given_ray_fault(rays[k]) || (ranged && ray_range_fault(rays, ranges, k)) ? 1 : 0;
    }
  });
  return refused;
}

Bounds placed_box(const Bounds& mesh_box, const Instance& instance) {
  Bounds bounds;
  glm::dvec3 magnitude = glm::abs(instance.translation);
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 placed_corner = placed(instance, mesh_box.corner(corner));
    bounds.add(placed_corner);
    magnitude = glm::max(magnitude, glm::abs(placed_corner));
  }
  const glm::dvec3 margin = 1e-12 * magnitude;
  return {bounds.lower - margin, bounds.upper + margin};
}

Bounds finite_bounds(const Scene& scene) {
  Bounds bounds;
  for (const auto& sphere : scene.spheres) {
    bounds.add(sphere.center - sphere.radius);
    bounds.add(sphere.center + sphere.radius);
  }
  for (const auto& mesh : scene.meshes) {
    if (mesh.instanced) continue;
    for (const auto& position : mesh.positions) bounds.add(position);
  }
  const std::vector<Bounds> mesh_boxes = scene.instances.empty() ? std::vector<Bounds>{} : instanced_mesh_boxes(scene);
  for (const auto& instance : scene.instances) {
    if (mesh_boxes[instance.mesh].empty()) continue;
    for (int corner = 0; corner < 8; ++corner) bounds.add(placed(instance, mesh_boxes[instance.mesh].corner(corner)));
  }
  return bounds;
}

namespace {

// The centre of `bounds` (finite_bounds); the camera for a scene of planes alone, which has none. The
// camera is otherwise left out, so a Renderer gives the same bits whatever camera it was built with.
glm::dvec3 centre_of(const Bounds& bounds, const Scene& scene) {
  return bounds.empty() ? scene.camera.from : 0.5 * (bounds.lower + bounds.upper);
}

}  // namespace

glm::dvec3 scene_centre(const Scene& scene) { return centre_of(finite_bounds(scene), scene); }

glm::dvec3 scene_anchor(const Scene& scene) {
  const Bounds bounds = finite_bounds(scene);  // one pass over the vertices: set_vertices finds it every call
  const glm::dvec3 centre = centre_of(bounds, scene);
  if (bounds.empty()) return centre;
  const glm::dvec3 half = 0.5 * (bounds.upper - bounds.lower);
  const double largest = std::max({half.x, half.y, half.z});
  if (!(largest > 0.0)) return centre;
  // A power of two: centre / spacing and the product back are exact, so the anchor is an exact
  // multiple of it, the same on every machine.
  const double spacing = std::ldexp(1.0, std::ilogb(largest) - 4);
  return glm::round(centre / spacing) * spacing;
}

double scene_radius(const Scene& scene, const glm::dvec3& anchor) {
  double radius = 0.0;
  for (const auto& sphere : scene.spheres) radius = std::max(radius, glm::length(sphere.center - anchor) + sphere.radius);
  for (const auto& mesh : scene.meshes) {
    if (mesh.instanced) continue;
    for (const auto& position : mesh.positions) radius = std::max(radius, glm::length(position - anchor));
  }
  const std::vector<Bounds> mesh_boxes = scene.instances.empty() ? std::vector<Bounds>{} : instanced_mesh_boxes(scene);
  for (const auto& instance : scene.instances) {
    if (mesh_boxes[instance.mesh].empty()) continue;
    for (int corner = 0; corner < 8; ++corner) {
      radius = std::max(radius, glm::length(placed(instance, mesh_boxes[instance.mesh].corner(corner)) - anchor));
    }
  }
  return radius;
}

void move_vertices(Scene& scene, uint32_t mesh, std::span<const glm::dvec3> positions) {
  if (mesh >= scene.meshes.size()) {
    throw InputError("mesh " + std::to_string(mesh) + ": the scene has " + std::to_string(scene.meshes.size()) + " meshes");
  }
  Mesh& moved = scene.meshes[mesh];
  if (positions.size() != moved.positions.size()) {
    throw InputError("mesh " + std::to_string(mesh) + " (" + moved.source + "): " + std::to_string(positions.size()) +
                     " positions for its " + std::to_string(moved.positions.size()) + " vertices");
  }
  std::vector<glm::dvec3> before(positions.begin(), positions.end());
  std::swap(moved.positions, before);
  try {
    check_mesh_values(moved, 0);
    if (moved.instanced) {  // where its instances now place it: the new box's corners, each placement's
      Bounds box;
      for (const glm::dvec3& p : moved.positions) box.add(p);
      for (size_t k = 0; k < scene.instances.size(); ++k) {
        if (scene.instances[k].mesh == mesh) check_transform(scene.instances[k], box, "instances[" + std::to_string(k) + "]");
      }
    }
  } catch (const InputError&) {
    std::swap(moved.positions, before);
    throw;
  }
}

SceneExtent scene_extent(const Scene& scene) {
  const glm::dvec3 anchor = scene_anchor(scene);
  return {anchor, scene_radius(scene, anchor)};
}

void add_geometry(Fnv1a& fnv, const Scene& scene) {
  fnv.add(uint64_t{scene.spheres.size()});
  for (const auto& sphere : scene.spheres) fnv.add(sphere.center), fnv.add(sphere.radius);
  fnv.add(uint64_t{scene.planes.size()});
  for (const auto& plane : scene.planes) fnv.add(plane.point), fnv.add(plane.normal);
  fnv.add(uint64_t{scene.meshes.size()});
  for (const auto& mesh : scene.meshes) {
    fnv.add(uint64_t{mesh.positions.size()});
    for (const auto& position : mesh.positions) fnv.add(position);
    fnv.add(uint64_t{mesh.triangles.size()});
    fnv.add_bytes(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
  }
  // Instances and masks change what a call sees; a scene without them keeps the hash it had before
  // either existed.
  if (!scene.instances.empty()) {
    fnv.add(uint64_t{scene.instances.size()});
    for (const auto& mesh : scene.meshes) fnv.add(uint64_t{mesh.instanced});
    for (const auto& instance : scene.instances) {
      fnv.add(uint64_t{instance.mesh});
      for (int column = 0; column < 3; ++column) fnv.add(instance.linear[column]);
      fnv.add(instance.translation);
      fnv.add(uint64_t{instance.mask});
    }
  }
  if (scene.has_masks()) {
    for (uint32_t object = 0; object < scene.object_count(); ++object) fnv.add(uint64_t{object_mask(scene, object)});
  }
}

bool Scene::has_masks() const {
  const auto masked = [](const auto& item) { return item.mask != every_mask_bit; };
  return std::ranges::any_of(meshes, masked) || std::ranges::any_of(instances, masked) || std::ranges::any_of(spheres, masked) ||
         std::ranges::any_of(planes, masked);
}

namespace {
// The mask field of object `object`, null out of range.
template <typename SceneType>
auto* object_mask_field(SceneType& scene, uint32_t object) {
  size_t index = object;
  if (index < scene.meshes.size()) return &scene.meshes[index].mask;
  index -= scene.meshes.size();
  if (index < scene.spheres.size()) return &scene.spheres[index].mask;
  index -= scene.spheres.size();
  return index < scene.planes.size() ? &scene.planes[index].mask : nullptr;
}
}  // namespace

Mask object_mask(const Scene& scene, uint32_t object) {
  const Mask* mask = object_mask_field(scene, object);
  if (!mask) throw std::out_of_range("object_mask: no object " + std::to_string(object));
  return *mask;
}

void set_object_mask(Scene& scene, uint32_t object, Mask mask) {
  Mask* field = object_mask_field(scene, object);
  if (!field) {
    throw InputError("mask: no object " + std::to_string(object) + " (the scene has " +
                     std::to_string(scene.object_count()) +
                     ": its meshes, then spheres, then planes)");
  }
  *field = mask;
}

std::vector<Mask> drawn_masks(const Scene& scene) {
  std::vector<Mask> masks;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (!scene.meshes[m].instanced) masks.push_back(scene.meshes[m].mask);
  }
  for (const Instance& instance : scene.instances) masks.push_back(instance.mask);
  for (const Sphere& sphere : scene.spheres) masks.push_back(sphere.mask);
  for (const Plane& plane : scene.planes) masks.push_back(plane.mask);
  return masks;
}

std::vector<std::string> object_names(const Scene& scene) {
  std::vector<std::string> names;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    names.push_back(scene.meshes[i].source.empty() ? "meshes[" + std::to_string(i) + "]" : scene.meshes[i].source);
  }
  for (size_t i = 0; i < scene.spheres.size(); ++i) names.push_back("spheres[" + std::to_string(i) + "]");
  for (size_t i = 0; i < scene.planes.size(); ++i) names.push_back("planes[" + std::to_string(i) + "]");
  return names;
}

std::string geometry_hash(const Scene& scene) {
  Fnv1a fnv;
  add_geometry(fnv, scene);
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(fnv.hash));
  return hex;
}

}  // namespace vkray
