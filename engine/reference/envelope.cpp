// How far may a float32 GPU pixel be from the double-precision reference?
//
// Error model (eps = 2^-24, the float32 unit roundoff):
// - Direction. The GPU rounds the pixel's uv (one division, within 2.5 ulp), the camera basis (1 per
//   component), forms x*right + y*up + forward_scaled (2 products, 2 sums) and normalizes (~3
//   roundings). Each rounding is relative to the component it rounds, so the error of component i is
//   within ~8 eps (|x right_i| + |y up_i| + |forward_scaled_i|); the part of that error vector
//   across the ray, over the vector's length, bounds the angle. In general position that is ~8 eps;
//   for a camera along an axis the small components round relative to themselves and it is far
//   smaller (a narrow view of a far sphere straight ahead). We take eta = twice that bound, plus
//   eps^2 (directions never exact to more than that).
// - Positions. Geometry and camera are stored relative to the scene anchor, split into hi and lo
//   floats (~48 bits: within 2^-48 R of exact, R bounding the distance of anything from the
//   anchor), and the shader subtracts the camera's parts from a point's before adding them, so a
//   point relative to the camera is within ~2 eps of its distance from the camera, plus the
//   2^-47 R of the split. The primitive hit therefore moves by up to ~4 eps E + 2^-46 R, where E is
//   the distance from the camera of the farthest point that defines it: a sphere's far side
//   (|c - o| + r), a triangle's farthest vertex, a plane's foot point (its height, computed with
//   Dot2). We take 16 eps E + 2^-44 R. (Beyond two radii of the anchor the shader leaves the lo
//   parts out, engine/render/gpu_scene.cpp needs_lo_parts: positions are then within 1.5 eps of their
//   distance from the camera, inside the same bound.)
//
// The reference therefore traces five rays per pixel: the exact one and four turned towards +-right
// and +-up by eta plus the angle the position error subtends, 2 eps (t + E) / t. Where all five hit the same primitive (or all miss), the pixel is "stable" and
// the GPU must agree closely:
// - hit/miss identical;
// - depth within [min, max] of the five depths, widened by the position error seen along the ray:
//   (16 eps (t + E) + 2^-44 R) / cos(theta), theta the angle of incidence (a surface shifted by d
//   moves the hit by d / cos(theta) along the ray);
// - normal within the spread of the five normals plus 16 eps (1 + E / (rho cos(theta))) +
//   2^-44 R / (rho cos(theta)), rho the radius of curvature (a sphere's radius; planes and triangles
//   have constant normals, computed in double and rounded once): the hit moves along the surface
//   by the position error over cos(theta), and the normal turns by that over rho.
// Elsewhere the pixel lies on a silhouette or an edge between primitives, where which primitive is
// hit legitimately depends on rounding. There the GPU must reproduce one of the five outcomes: miss
// only if a sample missed; a depth inside the samples' range widened by sqrt(2 eta) relative (the
// depth along a ray grazing a convex surface changes like the square root of the angle) plus the
// position term; a normal within the samples' spread of one of the sample normals, and where the
// samples hit a sphere's silhouette, of any normal between theirs and the silhouette's (a ray in
// between grazes it: its normal is across the ray, asin |n.d| from a sample's).
#include "engine/reference/envelope.hpp"

#include "engine/parallel.hpp"
#include "engine/reference/reference.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>

namespace vkray {
namespace {

constexpr double eps = 0x1p-24;
// eta for the ray through `uv` (the direction bound above).
double direction_uncertainty(const CameraBasis& camera, const glm::dvec2& uv) {
  const glm::dvec3 right = camera.right_step(), up = camera.up_step(), forward_scaled = camera.centre_direction();
  const glm::dvec3 ray = uv.x * right + uv.y * up + forward_scaled;
  const glm::dvec3 bound = 8 * eps * (glm::abs(uv.x * right) + glm::abs(uv.y * up) + glm::abs(forward_scaled));
  const glm::dvec3 unit = glm::normalize(ray);
  // The worst error vector within the component bounds, across the ray: bound minus its part along it.
  const glm::dvec3 across = bound - glm::dot(bound, glm::abs(unit)) * glm::abs(unit);
  return 2 * glm::length(across) / glm::length(ray) + eps * eps;
}

bool same_primitive(const ReferenceHit& a, const ReferenceHit& b) {
  return a.kind == b.kind && a.index == b.index && a.instance == b.instance;
}

// The max-row-sum norm of a 3x3 matrix, which bounds what it does to componentwise errors.
double row_sum_norm(const glm::dmat3& m) {
  double norm = 0.0;
  for (int row = 0; row < 3; ++row) norm = std::max(norm, std::abs(m[0][row]) + std::abs(m[1][row]) + std::abs(m[2][row]));
  return norm;
}

// The distance from the camera of the farthest point that defines `hit`'s primitive (E above).
// `triangle_reach` holds it for every triangle of the world's, numbered as the reference numbers them.
// A triangle an instance places is hit in its mesh's coordinates: the ray goes there in float32 as
// A (o - T) and A d (A the inverse of the linear map L, rounded to float), each within a few eps of
// |A| times what it transforms, and the vertices relative to that origin round as the world's do,
// in mesh units. Back in the world, L multiplies all of it: the errors are those of a world triangle
// times kappa = |L| |A| (row-sum norms), on a reach of |o - T| + E + t <= |o - T| + 2 E (the hit is
// no farther than the triangle's farthest vertex).
double primitive_reach(const Scene& scene, const std::vector<double>& triangle_reach, const ReferenceScene& reference,
                       const ReferenceHit& hit) {
  const glm::dvec3& origin = scene.camera.from;
  switch (hit.kind) {
    case PrimitiveKind::sphere:
      return glm::length(scene.spheres[hit.index].center - origin) + scene.spheres[hit.index].radius;
    case PrimitiveKind::plane:
      return std::abs(glm::dot(scene.planes[hit.index].normal, scene.planes[hit.index].point - origin));
    case PrimitiveKind::triangle: {
      if (hit.instance == no_object) return triangle_reach[hit.index];
      const Instance& instance = scene.instances[hit.instance];
      const ObjectPrimitive source = reference.source(hit);
      const Mesh& mesh = scene.meshes[source.object];
      double farthest = 0.0;
      for (const uint32_t corner : mesh.triangles[source.primitive]) {
        farthest = std::max(farthest, glm::length(placed(instance, mesh.positions[corner]) - origin));
      }
      return placement_condition(scene, hit) * (glm::length(origin - instance.translation) + 2.0 * farthest);
    }
    default:
      return 0.0;
  }
}

std::vector<double> triangle_reaches(const Scene& scene) {
  std::vector<double> reach;
  for (const auto& mesh : scene.meshes) {
    for (const auto& corners : mesh.triangles) {
      double farthest = 0.0;
      for (uint32_t corner : corners) farthest = std::max(farthest, glm::length(mesh.positions[corner] - scene.camera.from));
      reach.push_back(farthest);  // an instanced mesh's are unused: its instances' are found per hit
    }
  }
  return reach;
}

// Bound on the distance from the GPU anchor of everything the rays can meet or start from.
double reach_radius(const Scene& scene, const glm::dvec3& anchor) {
  double radius = glm::length(scene.camera.from - anchor);
  for (const auto& sphere : scene.spheres) radius = std::max(radius, glm::length(sphere.center - anchor) + sphere.radius);
  for (const auto& plane : scene.planes) radius = std::max(radius, std::abs(glm::dot(plane.normal, plane.point - anchor)));
  for (const auto& mesh : scene.meshes) {
    if (mesh.instanced) continue;
    for (const auto& p : mesh.positions) radius = std::max(radius, glm::length(p - anchor));
  }
  for (const auto& instance : scene.instances) {
    for (const auto& p : scene.meshes[instance.mesh].positions) radius = std::max(radius, glm::length(placed(instance, p) - anchor));
  }
  return radius;
}

// Orthographic and equirectangular cameras: the host computes each pixel's unit direction in double
// and rounds each component to float once (cast as given rays), within eps of it: twice that.
constexpr double given_direction_uncertainty = 2 * eps + eps * eps;

struct PixelSamples {
  ReferenceHit hits[5];
  glm::dvec3 origin;
  glm::dvec3 dir;
  double eta = 0.0;  // the angle the samples are turned by
};

}  // namespace

double placement_condition(const Scene& scene, const ReferenceHit& hit) {
  if (hit.kind != PrimitiveKind::triangle || hit.instance == no_object) return 1.0;
  const glm::dmat3& linear = scene.instances[hit.instance].linear;
  return row_sum_norm(linear) * row_sum_norm(glm::inverse(linear));
}

std::string EnvelopeReport::describe() const {
  std::string text = std::to_string(failures) + " of " + std::to_string(pixels) + " pixels outside the error envelope (" +
                     std::to_string(boundary_pixels) + " boundary pixels); " + stats.summary();
  for (const auto& failure : first_failures) text += "\n  " + failure;
  return text;
}

EnvelopeReport check_against_reference(const Scene& scene, const Frame& frame, uint32_t row_step,
                                       const std::vector<ObjectPrimitive>* hit_ids, Mask ray_mask) {
  const uint32_t width = frame.width, height = frame.height;
  const ReferenceScene reference(scene, ray_mask);
  const CameraBasis camera = make_camera_basis(scene.camera, width, height);
  const bool pinhole = scene.camera.projection == Projection::perspective;
  const double radius = reach_radius(scene, scene_anchor(scene));
  const double split_error = 0x1p-44 * radius;  // the hi/lo split's 2^-46 R, times 4
  const std::vector<double> triangle_reach = triangle_reaches(scene);

  // The checked rows' pixels alone (every row_step-th): sample q is pixel pixel_of(q) of the frame.
  // (A 7680x4320 frame checked every 64th row held samples for every pixel: 10.5 GB.)
  const uint32_t checked_rows = (height + row_step - 1) / row_step;
  const auto pixel_of = [&](size_t q) { return (q / width) * row_step * width + q % width; };
  std::vector<PixelSamples> samples(size_t{checked_rows} * width);
  auto in_parallel = [&](const auto& per_sample) {
    parallel_for_strided(samples.size(), [&](size_t q, size_t) { per_sample(q); });
  };
  // The centre rays first: each pixel's position error subtends 2 eps (t + E) / t of its hit.
  std::vector<double> position_angle(samples.size(), 0.0);
  in_parallel([&](size_t p) {
    const size_t pixel = pixel_of(p);
    const auto i = static_cast<uint32_t>(pixel % width), j = static_cast<uint32_t>(pixel / width);
    const PixelRay ray = pixel_ray(scene.camera, camera, i, j, width, height);
    samples[p].origin = ray.origin;
    samples[p].dir = ray.direction;
    samples[p].hits[0] = reference.trace(ray.origin, samples[p].dir);
    const ReferenceHit& hit = samples[p].hits[0];
    if (hit.kind != PrimitiveKind::none) {
      // E from the camera, and as far again as an orthographic pixel's origin lies from it.
      const double reach = primitive_reach(scene, triangle_reach, reference, hit) + glm::length(ray.origin - camera.origin);
      position_angle[p] = 2 * eps * (hit.t + reach) / hit.t;
    }
    samples[p].eta = pinhole ? direction_uncertainty(camera, pixel_uv(i, j, width, height)) : given_direction_uncertainty;
  });
  // A miss takes the largest angle of any hit: next to a silhouette it may legitimately hit.
  const double miss_angle = *std::max_element(position_angle.begin(), position_angle.end());
  in_parallel([&](size_t p) {
    const double angle = samples[p].hits[0].kind == PrimitiveKind::none ? miss_angle : position_angle[p];
    const double eta = samples[p].eta + angle;
    samples[p].eta = eta;
    const glm::dvec3& dir = samples[p].dir;
    // Turned across the ray: the camera's right and up for a pinhole; any two axes across it
    // otherwise (an equirectangular ray near a pole runs along up).
    glm::dvec3 across_1 = camera.right, across_2 = camera.up;
    if (!pinhole) {
      const glm::dvec3 helper = std::abs(glm::dot(dir, camera.up)) < 0.9 ? camera.up : camera.right;
      across_1 = glm::normalize(glm::cross(dir, helper));
      across_2 = glm::cross(dir, across_1);
    }
    const glm::dvec3 turns[4] = {dir + eta * across_1, dir - eta * across_1, dir + eta * across_2, dir - eta * across_2};
    for (int k = 0; k < 4; ++k) samples[p].hits[k + 1] = reference.trace(samples[p].origin, glm::normalize(turns[k]));
  });

  // The checked rows alone, for the summary figures.
  Frame checked(width, checked_rows, frame.aovs);
  checked.allocate();
  std::vector<ReferenceHit> centre;
  for (uint32_t row = 0; row < checked_rows; ++row) {
    for (uint32_t i = 0; i < width; ++i) {
      const size_t from = size_t{row} * row_step * width + i, to = size_t{row} * width + i;
      centre.push_back(samples[to].hits[0]);
      if (frame.aovs.has(Aov::depth)) checked.depth[to] = frame.depth[from];
      for (size_t c = 0; c < 3 && frame.aovs.has(Aov::normal); ++c) {
        checked.normal[c * checked.pixel_count() + to] = frame.normal[c * frame.pixel_count() + from];
      }
    }
  }

  EnvelopeReport report;
  report.pixels = checked.pixel_count();
  report.stats = measure_error(checked, centre);
  const bool has_depth = frame.aovs.has(Aov::depth), has_normal = frame.aovs.has(Aov::normal);

  for (size_t q = 0; q < samples.size(); ++q) {
    const size_t p = pixel_of(q);
    const PixelSamples& s = samples[q];
    const bool stable = std::all_of(std::begin(s.hits), std::end(s.hits),
                                    [&](const ReferenceHit& h) { return same_primitive(h, s.hits[0]); });
    if (!stable) ++report.boundary_pixels;
    const bool gpu_hit = frame.hit(p);
    const float gpu_depth = has_depth ? frame.depth[p] : 0.0f;
    const glm::dvec3 gpu_normal = has_normal ? glm::dvec3(frame.normal_at(p)) : glm::dvec3(0.0);

    std::string failure;
    const bool any_miss = std::any_of(std::begin(s.hits), std::end(s.hits), [](const ReferenceHit& h) { return h.kind == PrimitiveKind::none; });
    const bool any_hit = std::any_of(std::begin(s.hits), std::end(s.hits), [](const ReferenceHit& h) { return h.kind != PrimitiveKind::none; });
    if (!gpu_hit && ((has_depth && gpu_depth != INFINITY) || gpu_normal != glm::dvec3(0.0))) {
      failure = "a miss must have depth +inf and normal 0";
    } else if (gpu_hit && has_normal && std::abs(glm::length(gpu_normal) - 1.0) > 8 * eps) {
      failure = "normal length " + std::to_string(glm::length(gpu_normal));
    } else if (gpu_hit ? !any_hit : !any_miss) {
      failure = gpu_hit ? "GPU hits, reference misses" : "GPU misses, reference hits at t=" + std::to_string(s.hits[0].t);
    } else if (gpu_hit) {
      double lo = INFINITY, hi = 0.0, spread = 0.0, curvature_radius = INFINITY;
      for (const auto& h : s.hits) {
        if (h.kind == PrimitiveKind::none) continue;
        lo = std::min(lo, h.t), hi = std::max(hi, h.t);
        for (const auto& other : s.hits) {
          if (other.kind != PrimitiveKind::none) spread = std::max(spread, angle_between(h.normal, other.normal));
        }
        if (!stable && h.kind == PrimitiveKind::sphere) spread = std::max(spread, std::asin(std::min(1.0, std::abs(glm::dot(h.normal, s.dir)))));
      }
      const ReferenceHit& main = s.hits[0].kind != PrimitiveKind::none ? s.hits[0] : *std::find_if(std::begin(s.hits), std::end(s.hits), [](const ReferenceHit& h) { return h.kind != PrimitiveKind::none; });
      if (main.kind == PrimitiveKind::sphere) curvature_radius = scene.spheres[main.index].radius;
      const double cos_theta = std::max(std::abs(glm::dot(main.normal, s.dir)), 1e-12);
      const double reach = primitive_reach(scene, triangle_reach, reference, main);
      const double position_slack = (16 * eps * (main.t + reach) + split_error) / cos_theta;
      const double grazing = stable ? 0.0 : std::sqrt(2 * s.eta);
      const double depth_lo = lo * (1 - grazing) - position_slack, depth_hi = hi * (1 + grazing) + position_slack;
      if (has_depth && !(gpu_depth >= depth_lo && gpu_depth <= depth_hi)) {
        char text[200];
        std::snprintf(text, sizeof text, "depth %.9g outside [%.9g, %.9g] (reference %.9g)", double(gpu_depth), depth_lo,
                      depth_hi, main.t);
        failure = text;
      }
      // A surface shifted by d moves the hit along it by d / cos(theta): the normal turns by that over rho.
      // An instance's triangle normal is A^T n in float32: its error grows by kappa as positions' do.
      const double normal_slack = 16 * eps * placement_condition(scene, main) * (1 + reach / (curvature_radius * cos_theta)) +
                                  split_error / (curvature_radius * cos_theta);
      double best = INFINITY;
      for (const auto& h : s.hits) {
        if (h.kind != PrimitiveKind::none) best = std::min(best, angle_between(gpu_normal, h.normal));
      }
      if (has_normal && failure.empty() && !(best <= spread + normal_slack)) {
        char text[200];
        std::snprintf(text, sizeof text, "normal (%.7f, %.7f, %.7f) is %.3g rad from the reference (allowed %.3g)",
                      gpu_normal.x, gpu_normal.y, gpu_normal.z, best, spread + normal_slack);
        failure = text;
      }
    }
    if (failure.empty() && hit_ids) {
      const ObjectPrimitive id = (*hit_ids)[p];
      const bool among_samples = std::any_of(std::begin(s.hits), std::end(s.hits),
                                             [&](const ReferenceHit& h) { return reference.source(h) == id; });
      if (stable ? !(id == reference.source(s.hits[0])) : !among_samples) {
        const ObjectPrimitive expected = reference.source(s.hits[0]);
        failure = "hit object " + std::to_string(id.object) + " primitive " + std::to_string(id.primitive) +
                  ", the reference's " + std::to_string(expected.object) + " " + std::to_string(expected.primitive);
      }
    }
    if (!failure.empty()) {
      ++report.failures;
      if (report.first_failures.size() < 10) {
        report.first_failures.push_back("pixel (" + std::to_string(p % width) + ", " + std::to_string(p / width) + ")" +
                                        (stable ? "" : " [boundary]") + ": " + failure);
      }
    }
  }
  return report;
}

}  // namespace vkray
