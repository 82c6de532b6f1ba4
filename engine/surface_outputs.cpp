#include "engine/surface_outputs.hpp"

#include "engine/parallel.hpp"
#include "engine/scene/camera.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace vkray {
namespace {

// (b1, b2) of point `p` projected onto triangle (a, b, c)'s plane: the normal equations of
// p - a = b1 (b - a) + b2 (c - a) (Ericson, "Real-Time Collision Detection", 2005, 3.4).
glm::dvec2 projected_weights(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& p) {
  const glm::dvec3 e1 = b - a, e2 = c - a, v = p - a;
  const double d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
  const double v1 = glm::dot(v, e1), v2 = glm::dot(v, e2);
  const double determinant = d11 * d22 - d12 * d12;
  if (!(determinant > 0.0)) return glm::dvec2(0.0);  // zero area: the device never hits one
  return glm::dvec2(d22 * v1 - d12 * v2, d11 * v2 - d12 * v1) / determinant;
}

// (b1, b2) where the ray (origin, unit dir) meets the plane of triangle (a, b, c), by Cramer's rule
// on origin + t dir = a + b1 (b - a) + b2 (c - a) (Moeller and Trumbore, 1997); none where the ray
// lies in the plane.
std::optional<glm::dvec2> ray_weights(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                      const glm::dvec3& origin, const glm::dvec3& dir) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 p = glm::cross(dir, e2);
  const double determinant = glm::dot(e1, p);
  if (determinant == 0.0) return std::nullopt;
  const glm::dvec3 s = origin - a;
  const glm::dvec3 q = glm::cross(s, e1);
  return glm::dvec2(glm::dot(s, p), glm::dot(dir, q)) / determinant;
}

// The weights moved onto the triangle: each at least 0, their sum at most 1.
glm::dvec2 clamped_to_triangle(glm::dvec2 w) {
  w = glm::max(w, glm::dvec2(0.0));
  if (const double sum = w.x + w.y; sum > 1.0) w /= sum;
  return w;
}

bool corners_given(const std::vector<std::array<uint32_t, 3>>& corners, uint32_t triangle) {
  return !corners.empty() && corners[triangle][0] != no_attribute && corners[triangle][1] != no_attribute &&
         corners[triangle][2] != no_attribute;
}

SurfaceAt triangle_surface(const Mesh& mesh, uint32_t triangle, const glm::dvec3& origin, const glm::dvec3& dir, double t) {
  const auto& corners = mesh.triangles[triangle];
  const glm::dvec3 &a = mesh.positions[corners[0]], &b = mesh.positions[corners[1]], &c = mesh.positions[corners[2]];
  const std::optional<glm::dvec2> crossing = ray_weights(a, b, c, origin, dir);
  SurfaceAt surface;
  surface.barycentric = clamped_to_triangle(crossing ? *crossing : projected_weights(a, b, c, origin + t * dir));
  const double w1 = surface.barycentric.x, w2 = surface.barycentric.y, w0 = 1.0 - w1 - w2;
  const glm::dvec3 face = unit_vector(glm::cross(b - a, c - a));
  // The face's normal is that of the counter-clockwise winding: the ray meets the front where it
  // points against the ray.
  const bool front = glm::dot(face, dir) < 0.0;
  surface.front = front;
  surface.shading_normal = front ? face : -face;
  if (corners_given(mesh.normal_corners, triangle)) {
    const auto& n = mesh.normal_corners[triangle];
    const glm::dvec3 interpolated = w0 * mesh.normals[n[0]] + w1 * mesh.normals[n[1]] + w2 * mesh.normals[n[2]];
    if (interpolated != glm::dvec3(0.0)) surface.shading_normal = (front ? 1.0 : -1.0) * unit_vector(interpolated);
  }
  if (corners_given(mesh.texcoord_corners, triangle)) {
    const auto& uv = mesh.texcoord_corners[triangle];
    surface.texcoord = w0 * mesh.texcoords[uv[0]] + w1 * mesh.texcoords[uv[1]] + w2 * mesh.texcoords[uv[2]];
  }
  return surface;
}

glm::dvec3 facing(const glm::dvec3& normal, const glm::dvec3& dir) { return glm::dot(normal, dir) > 0.0 ? -normal : normal; }

}  // namespace

SurfaceAt surface_at(const Scene& scene, ObjectPrimitive hit, const glm::dvec3& origin, const glm::dvec3& dir, double t,
                     uint32_t instance) {
  const size_t meshes = scene.meshes.size(), spheres = scene.spheres.size();
  SurfaceAt surface;
  if (hit.object < meshes && instance != no_object) {
    const Instance& placement = scene.instances[instance];
    const glm::dmat3 to_mesh = glm::inverse(placement.linear);
    const auto [mesh_origin, mesh_dir] = ray_in_mesh(placement.translation, to_mesh, origin, dir);
    surface = triangle_surface(scene.meshes[hit.object], hit.primitive, mesh_origin, mesh_dir, t);
    surface.shading_normal = unit_vector(glm::transpose(to_mesh) * surface.shading_normal);
    if (glm::determinant(placement.linear) < 0.0) surface.front = !surface.front;
    return surface;
  }
  if (hit.object < meshes) return triangle_surface(scene.meshes[hit.object], hit.primitive, origin, dir, t);
  if (hit.object < meshes + spheres) {
    // A sphere's front is its outside: the ray starts outside it.
    const Sphere& sphere = scene.spheres[hit.object - meshes];
    surface.shading_normal = facing(unit_vector(origin + t * dir - sphere.center), dir);
    surface.front = glm::length(origin - sphere.center) >= sphere.radius;
  } else if (hit.object < meshes + spheres + scene.planes.size()) {
    // A plane's front is the side its normal points to.
    const glm::dvec3& normal = scene.planes[hit.object - meshes - spheres].normal;
    surface.shading_normal = facing(normal, dir);
    surface.front = glm::dot(normal, dir) < 0.0;
  }
  return surface;
}

PointSurface point_surface(const Scene& scene, ObjectPrimitive found, uint32_t instance, const glm::dvec3& nearest) {
  const size_t meshes = scene.meshes.size(), spheres = scene.spheres.size();
  PointSurface surface;
  if (found.object < meshes) {
    const Mesh& mesh = scene.meshes[found.object];
    const auto& corners = mesh.triangles[found.primitive];
    const glm::dvec3 &a = mesh.positions[corners[0]], &b = mesh.positions[corners[1]], &c = mesh.positions[corners[2]];
    const glm::dvec3 face = unit_vector(glm::cross(b - a, c - a));
    if (instance == no_object) {
      surface.barycentric = clamped_to_triangle(projected_weights(a, b, c, nearest));
      surface.normal = face;
      return surface;
    }
    const Instance& placement = scene.instances[instance];
    const glm::dmat3 to_mesh = glm::inverse(placement.linear);
    surface.barycentric = clamped_to_triangle(projected_weights(a, b, c, to_mesh * (nearest - placement.translation)));
    const double mirrored = glm::determinant(placement.linear) < 0.0 ? -1.0 : 1.0;
    surface.normal = mirrored * unit_vector(glm::transpose(to_mesh) * face);
  } else if (found.object < meshes + spheres) {
    surface.normal = unit_vector(nearest - scene.spheres[found.object - meshes].center);
  } else if (found.object < meshes + spheres + scene.planes.size()) {
    surface.normal = scene.planes[found.object - meshes - spheres].normal;
  }
  return surface;
}

void add_surface_outputs(Frame& frame, const Scene& scene) {
  if (!frame.aovs.has_surface_outputs()) return;
  if (!frame.camera || frame.depth.empty() || frame.mesh_id.empty() || frame.primitive_id.empty()) {
    throw std::logic_error("add_surface_outputs: the frame has no camera, depth or ids");
  }
  const CameraBasis basis = make_camera_basis(*frame.camera, frame.width, frame.height);
  const size_t pixels = frame.pixel_count();
  parallel_for_chunks(frame.height, [&](size_t first_row, size_t end_row) {
    for (auto j = static_cast<uint32_t>(first_row); j < end_row; ++j) {
      for (uint32_t i = 0; i < frame.width; ++i) {
        const size_t p = size_t{j} * frame.width + i;
        const uint32_t object = frame.mesh_id[p], primitive = frame.primitive_id[p];
        if (object == no_object) continue;  // the outputs stay 0
        const PixelRay ray = pixel_ray(*frame.camera, basis, i, j, frame.width, frame.height);
        const double t = frame.depth64.empty() ? double{frame.depth[p]} : frame.depth64[p];
        const uint32_t instance = frame.instance_id.empty() ? no_object : frame.instance_id[p];
        const SurfaceAt surface = surface_at(scene, {object, primitive}, ray.origin, ray.direction, t, instance);
        for (int c = 0; c < 2; ++c) {
          if (!frame.barycentric.empty()) frame.barycentric[c * pixels + p] = static_cast<float>(surface.barycentric[c]);
          if (!frame.texcoord.empty()) frame.texcoord[c * pixels + p] = static_cast<float>(surface.texcoord[c]);
        }
        if (!frame.shading_normal.empty()) {
          for (int c = 0; c < 3; ++c) frame.shading_normal[c * pixels + p] = static_cast<float>(surface.shading_normal[c]);
        }
        if (!frame.front_facing.empty()) frame.front_facing[p] = surface.front ? 1u : 0u;
      }
    }
  }, 16);
}

}  // namespace vkray
