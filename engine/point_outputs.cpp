#include "engine/point_outputs.hpp"

#include "engine/parallel.hpp"
#include "engine/surface_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace vkray {

namespace {

// In the order files and dicts list them. The sign of a signed distance and occupancy are the
// winding number's: inside where it is at least 1/2 (a closed mesh's 1 inside and 0 outside; an
// open one's in between, where half is the natural threshold: Jacobson et al. 2013, section 3).
const PointOutputInfo point_output_table[] = {
    {PointOutput::distance, "distance", "distance to the nearest point of the scene; +inf past the largest distance", 1, false, true, false},
    {PointOutput::signed_distance, "signed-distance", "the distance, negative inside (where the winding number is 1/2 or more)", 1, false, true, true},
    {PointOutput::winding_number, "winding-number", "generalized winding number: 1 inside a closed surface, 0 outside", 1, false, false, true},
    {PointOutput::occupancy, "occupancy", "1 inside (winding number 1/2 or more), 0 outside", 1, true, false, true},
    {PointOutput::position, "position", "the nearest point, world", 3, false, true, false},
    {PointOutput::normal, "normal", "the primitive's outward unit normal there (a triangle's by its winding)", 3, false, true, false},
    {PointOutput::barycentric, "barycentric", "weights of the triangle's second and third vertices there", 2, false, true, false},
    {PointOutput::mesh_id, "mesh-id", "mesh, sphere or plane it lies on", 1, true, true, false},
    {PointOutput::primitive_id, "primitive-id", "triangle it lies on, in its file", 1, true, true, false},
    {PointOutput::instance_id, "instance-id", "instance placing the mesh it lies on", 1, true, true, false},
};

}  // namespace

void PointHits::allocate(size_t point_count, bool doubles, bool nearest) {
  count = point_count;
  distance.resize(count);
  distance64.resize(doubles ? count : 0);
  const size_t found = nearest ? count : 0;  // a winding number names no primitive
  offset.resize(3 * found);
  offset64.resize(doubles ? 3 * found : 0);
  object.resize(found);
  primitive.resize(found);
  instance.resize(found);
}

void PointHits::store(size_t point, double found_distance, const glm::dvec3& found_offset, ObjectPrimitive source,
                      uint32_t placing_instance) {
  distance[point] = static_cast<float>(found_distance);
  if (!distance64.empty()) distance64[point] = found_distance;
  if (object.empty()) return;  // a winding number
  for (int c = 0; c < 3; ++c) offset[c * count + point] = static_cast<float>(found_offset[c]);
  if (!offset64.empty()) {
    for (int c = 0; c < 3; ++c) offset64[c * count + point] = found_offset[c];
  }
  object[point] = source.object;
  primitive[point] = source.primitive;
  instance[point] = placing_instance;
}

glm::dvec3 PointHits::offset_at(size_t k) const {
  if (!offset64.empty()) return {offset64[k], offset64[count + k], offset64[2 * count + k]};
  return {offset[k], offset[count + k], offset[2 * count + k]};
}

namespace {

// Point k's value of `output`, component by component into `out`.
template <typename T>
void point_output_at(PointOutput output, const Scene& scene, const PointAnswers& answers, size_t k, T* out) {
  const PointHits* nearest = answers.nearest;
  const auto surface = [&] {
    if (nearest->object[k] == no_object) return PointSurface{};
    return point_surface(scene, {nearest->object[k], nearest->primitive[k]}, nearest->instance[k], answers.points[k] + nearest->offset_at(k));
  };
  const auto components = [&](const auto& value, int count) {
    for (int c = 0; c < count; ++c) out[c] = static_cast<T>(value[c]);
  };
  switch (output) {
    case PointOutput::distance: out[0] = static_cast<T>(nearest->distance_at(k)); break;
    case PointOutput::signed_distance:
      out[0] = static_cast<T>((inside_by_winding(answers.winding->distance_at(k)) ? -1.0 : 1.0) * nearest->distance_at(k));
      break;
    case PointOutput::winding_number: out[0] = static_cast<T>(answers.winding->distance_at(k)); break;
    case PointOutput::occupancy: out[0] = static_cast<T>(inside_by_winding(answers.winding->distance_at(k)) ? 1 : 0); break;
    // Where nothing lies within the largest distance, no point: not a number.
    case PointOutput::position:
      components(nearest->object[k] == no_object ? glm::dvec3(NAN) : answers.points[k] + nearest->offset_at(k), 3);
      break;
    case PointOutput::normal: components(surface().normal, 3); break;
    case PointOutput::barycentric: components(surface().barycentric, 2); break;
    case PointOutput::mesh_id: out[0] = static_cast<T>(nearest->object[k]); break;
    case PointOutput::primitive_id: out[0] = static_cast<T>(nearest->primitive[k]); break;
    case PointOutput::instance_id: out[0] = static_cast<T>(nearest->instance[k]); break;
  }
}

}  // namespace

void write_point_output(const PointOutputInfo& info, const Scene& scene, const PointAnswers& answers, bool doubles, void* result) {
  const auto write = [&]<typename T>(T* out) {
    parallel_for_chunks(answers.points.size(), [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) point_output_at(info.output, scene, answers, k, out + k * info.components);
    });
  };
  if (info.integer) {
    write(static_cast<uint32_t*>(result));
  } else if (doubles) {
    write(static_cast<double*>(result));
  } else {
    write(static_cast<float*>(result));
  }
}

std::span<const PointOutputInfo> point_outputs() { return point_output_table; }

const PointOutputInfo* find_point_output(std::string_view name) {
  std::string dashed(name);
  std::replace(dashed.begin(), dashed.end(), '_', '-');
  for (const PointOutputInfo& info : point_output_table) {
    if (dashed == info.name) return &info;
  }
  return nullptr;
}

const char* point_output_names() {
  static const std::string names = [] {
    std::string all;
    for (const PointOutputInfo& info : point_output_table) all += (all.empty() ? "" : ", ") + std::string(info.name);
    return all;
  }();
  return names.c_str();
}

}  // namespace vkray
