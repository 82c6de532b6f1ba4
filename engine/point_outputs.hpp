// What a point query answers (docs/points.md): one table, which the C API's vkray_query_points,
// Python's Renderer.query_points and its shorthands, and `vkray points` read. Each output is one of
// two device queries (the nearest point, the winding number) or computed on the host from one.
#pragma once

#include "engine/host_memory.hpp"
#include "engine/scene/scene.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <string_view>

namespace vkray {

// What each of a batch of points found (Renderer::closest_points, winding_numbers; the reference's
// reference_point_hits), in the points' order.
struct PointHits {
  size_t count = 0;
  // The distance to the nearest point (+inf where none lies within the query's distance), or the
  // winding number; in float64 shaders also in double.
  UninitializedVector<float> distance;
  UninitializedVector<double> distance64;
  // The nearest point's offset from the point, 3 planes (all x, then y, then z); 0 where none. In
  // float64 shaders also in double.
  UninitializedVector<float> offset;
  UninitializedVector<double> offset64;
  UninitializedVector<uint32_t> object, primitive, instance;  // what it lies on, as RayHits names it
  void allocate(size_t point_count, bool doubles, bool nearest);
  void store(size_t point, double distance, const glm::dvec3& offset, ObjectPrimitive source, uint32_t placing_instance);
  // Point k's, in double where held so.
  double distance_at(size_t k) const { return distance64.empty() ? double{distance[k]} : distance64[k]; }
  glm::dvec3 offset_at(size_t k) const;
};

enum class PointOutput { distance, signed_distance, winding_number, occupancy, position, normal, barycentric, mesh_id, primitive_id, instance_id };

struct PointOutputInfo {
  PointOutput output;
  const char* name;  // as vkray_query_points, Python (with '_' for '-') and `vkray points --output` take it
  const char* description;
  uint32_t components;
  bool integer;              // uint32 (ids, occupancy); float32, or float64 in doubles, otherwise
  bool nearest, winding;     // the device queries it is computed from
};

std::span<const PointOutputInfo> point_outputs();
// The output of that name ('_' read as '-'), or nullptr.
const PointOutputInfo* find_point_output(std::string_view name);
// The names, comma separated, for messages.
const char* point_output_names();

// Whether a winding number says inside: 1/2 or more (see point_outputs.cpp).
inline bool inside_by_winding(double winding) { return winding >= 0.5; }

// A point query's answers, from the device or the reference: the queries the outputs asked need.
struct PointAnswers {
  std::span<const glm::dvec3> points;
  const PointHits* nearest = nullptr;
  const PointHits* winding = nullptr;
};
// Writes output `info` of every point into `result`, count x components in C order: uint32 for the
// integer outputs, else float64 where `doubles` and float32 otherwise. What the device does not
// give (position, normal, barycentric, the sign, occupancy) is computed here in double from `scene`,
// the scene queried.
void write_point_output(const PointOutputInfo& info, const Scene& scene, const PointAnswers& answers, bool doubles, void* result);

}  // namespace vkray
