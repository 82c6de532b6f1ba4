#include "engine/reference.hpp"

#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <thread>

namespace vkray {

// Same formulation as shaders/intersect.glsl (Ray Tracing Gems ch. 7): discriminant from the
// perpendicular offset and roots without cancellation. Double precision makes even the
// tiny-far-sphere case exact to ~1e-16 relative.
double intersect_sphere(const glm::dvec3& f, double radius, const glm::dvec3& dir, double t_max) {
  const double a = glm::dot(dir, dir);
  const double b = glm::dot(f, dir);
  const glm::dvec3 f_perp = f - (b / a) * dir;
  const double disc = radius * radius - glm::dot(f_perp, f_perp);
  if (disc < 0.0) return t_max;
  const double c = glm::dot(f, f) - radius * radius;
  const double q = -(b + std::copysign(std::sqrt(a * disc), b));
  if (q == 0.0) return t_max;
  const double t0 = c / q;
  const double t1 = q / a;
  const double t = std::min(t0, t1) > 0.0 ? std::min(t0, t1) : std::max(t0, t1);
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// In double the plane's point is subtracted first, which keeps large world coordinates exact; the
// GPU receives the offset relative to the scene anchor instead (engine/gpu_scene.cpp).
double intersect_plane(const glm::dvec3& normal, const glm::dvec3& point, const glm::dvec3& origin,
                       const glm::dvec3& dir, double t_max) {
  const double denom = glm::dot(normal, dir);
  if (denom == 0.0) return t_max;
  const double t = glm::dot(normal, point - origin) / denom;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013 (see the GLSL
// version for why): rays through a shared edge never fall between the two triangles.
double intersect_triangle(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, const glm::dvec3& origin,
                          const glm::dvec3& dir, double t_max) {
  const glm::dvec3 ad = glm::abs(dir);
  const int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (dir[kz] < 0.0) std::swap(kx, ky);
  const double sx = dir[kx] / dir[kz], sy = dir[ky] / dir[kz], sz = 1.0 / dir[kz];
  auto to_ray_frame = [&](const glm::dvec3& vertex) {
    const glm::dvec3 p = vertex - origin;
    return glm::dvec3(p[kx] - sx * p[kz], p[ky] - sy * p[kz], p[kz]);
  };
  const glm::dvec3 a = to_ray_frame(v0), b = to_ray_frame(v1), c = to_ray_frame(v2);
  const double u = c.x * b.y - c.y * b.x;
  const double v = a.x * c.y - a.y * c.x;
  const double w = b.x * a.y - b.y * a.x;
  if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return t_max;
  const double det = u + v + w;
  if (det == 0.0) return t_max;
  const double t = sz * (u * a.z + v * b.z + w * c.z) / det;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

ReferenceScene::ReferenceScene(const Scene& scene) : spheres_(scene.spheres), planes_(scene.planes) {
  uint32_t index = 0;
  for (const auto& mesh : scene.meshes) {
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3& v0 = mesh.positions[corners[0]];
      const glm::dvec3& v1 = mesh.positions[corners[1]];
      const glm::dvec3& v2 = mesh.positions[corners[2]];
      const glm::dvec3 cross = glm::cross(v1 - v0, v2 - v0);
      if (cross != glm::dvec3(0.0)) triangles_.push_back({v0, v1, v2, unit_vector(cross), index});
      ++index;
    }
  }
}

ReferenceHit ReferenceScene::trace(const glm::dvec3& origin, const glm::dvec3& dir) const {
  ReferenceHit hit;
  for (uint32_t i = 0; i < spheres_.size(); ++i) {
    const glm::dvec3 f = origin - spheres_[i].center;
    const double t = intersect_sphere(f, spheres_[i].radius, dir, hit.t);
    if (t < hit.t) hit = {t, (f + t * dir) / spheres_[i].radius, PrimitiveKind::sphere, i};
  }
  for (uint32_t i = 0; i < planes_.size(); ++i) {
    const double t = intersect_plane(planes_[i].normal, planes_[i].point, origin, dir, hit.t);
    if (t < hit.t) hit = {t, planes_[i].normal, PrimitiveKind::plane, i};
  }
  for (const auto& triangle : triangles_) {
    const double t = intersect_triangle(triangle.v0, triangle.v1, triangle.v2, origin, dir, hit.t);
    if (t < hit.t) hit = {t, triangle.normal, PrimitiveKind::triangle, triangle.index};
  }
  if (hit.kind != PrimitiveKind::none) {
    hit.normal = glm::normalize(hit.normal);
    if (glm::dot(hit.normal, dir) > 0.0) hit.normal = -hit.normal;
  }
  return hit;
}

std::vector<ReferenceHit> render_reference_hits(const ReferenceScene& scene, const CameraBasis& camera,
                                                uint32_t width, uint32_t height) {
  std::vector<ReferenceHit> hits(size_t{width} * height);
  const unsigned workers = std::max(1u, std::min(std::thread::hardware_concurrency(), height));
  std::vector<std::jthread> threads;
  for (unsigned worker = 0; worker < workers; ++worker) {
    threads.emplace_back([&, worker] {
      for (uint32_t j = worker; j < height; j += workers) {
        for (uint32_t i = 0; i < width; ++i) {
          hits[size_t{j} * width + i] = scene.trace(camera.origin, camera.direction(pixel_uv(i, j, width, height)));
        }
      }
    });
  }
  return hits;
}

Frame reference_frame(const std::vector<ReferenceHit>& hits, uint32_t width, uint32_t height, AovSet aovs) {
  Frame frame{width, height, aovs, {}, {}, {}};
  frame.allocate();
  const size_t pixels = frame.pixel_count();
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      const size_t p = size_t{j} * width + i;
      if (aovs.has(Aov::depth)) frame.depth[p] = static_cast<float>(hits[p].t);
      if (aovs.has(Aov::normal)) {
        for (size_t c = 0; c < 3; ++c) frame.normal[c * pixels + p] = static_cast<float>(hits[p].normal[int(c)]);
      }
      if (aovs.has(Aov::uv)) {
        const glm::dvec2 uv = pixel_uv(i, j, width, height);
        frame.uv[p] = static_cast<float>(uv.x);
        frame.uv[pixels + p] = static_cast<float>(uv.y);
      }
    }
  }
  return frame;
}

}  // namespace vkray
