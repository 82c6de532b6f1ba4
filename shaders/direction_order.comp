#version 460
// Orders a caller's rays from one origin by direction on the device (engine/vulkan/direction_order_pass.hpp),
// for the packet walk of rays listed in no usable order: a counting sort by direction_key
// (gpu_layout.h). Three passes, one pipeline each (VKRAY_ORDER_PASS):
// - count: each ray's key, and its rank among the rays of that key (an atomic count per key);
// - scan: the counts turned into each key's first place (an exclusive prefix sum, one workgroup);
// - place: each ray's index written at its key's first place plus its rank.
// Rays of one key keep no particular order among themselves: a key's cell is small enough that any
// of its rays walk well together. A ray the walk cannot take (from another origin, a zero or
// non-finite direction) takes key 0 (raycast.comp lists it for the host).
#extension GL_GOOGLE_include_directive : require

#include "gpu_layout.h"

layout(local_size_x = VKRAY_ORDER_GROUP_SIZE) in;
layout(constant_id = 0) const uint PASS = VKRAY_ORDER_PASS_COUNT;

layout(push_constant) uniform Push { DirectionOrderParams params; };

layout(binding = VKRAY_ORDER_BINDING_RAYS) uniform usamplerBuffer rays;  // six doubles a ray, three texels
layout(std430, binding = VKRAY_ORDER_BINDING_CELLS) buffer Cells { uint cells[]; };  // counts, then first places
layout(std430, binding = VKRAY_ORDER_BINDING_RANKS) buffer Ranks { uvec2 key_rank[]; };
layout(std430, binding = VKRAY_ORDER_BINDING_ORDER) writeonly buffer Order { uint order[]; };

#define CALLER_RAY_TEXEL(index) texelFetch(rays, index)
#include "caller_rays.glsl"

shared uint chunk_sums[VKRAY_ORDER_GROUP_SIZE];

void main() {
  uint count = params.sizes.x, bits = params.sizes.y, keys = params.sizes.z;
  if (PASS == VKRAY_ORDER_PASS_SCAN) {
    // One workgroup: each invocation sums a chunk of the counts, the chunks' sums are scanned, then
    // each chunk is scanned from its sum's place.
    uint chunk = (keys + VKRAY_ORDER_GROUP_SIZE - 1u) / VKRAY_ORDER_GROUP_SIZE;
    uint first = gl_LocalInvocationIndex * chunk, end = min(first + chunk, keys);
    uint sum = 0u;
    for (uint key = first; key < end; ++key) sum += cells[key];
    chunk_sums[gl_LocalInvocationIndex] = sum;
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
      uint place = 0u;
      for (uint c = 0u; c < VKRAY_ORDER_GROUP_SIZE; ++c) {
        uint next = place + chunk_sums[c];
        chunk_sums[c] = place;
        place = next;
      }
    }
    barrier();
    uint place = chunk_sums[gl_LocalInvocationIndex];
    for (uint key = first; key < end; ++key) {
      uint next = place + cells[key];
      cells[key] = place;
      place = next;
    }
    return;
  }
  uint ray = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * VKRAY_ORDER_GROUP_SIZE) + gl_GlobalInvocationID.x;
  if (ray >= count) return;
  if (PASS == VKRAY_ORDER_PASS_COUNT) {
    vec3 direction;
    uint key = caller_unit_direction(int(ray), direction) ? direction_key(direction.x, direction.y, direction.z, bits) : 0u;
    key_rank[ray] = uvec2(key, atomicAdd(cells[key], 1u));
  } else {
    uvec2 ranked = key_rank[ray];
    order[cells[ranked.x] + ranked.y] = ray;
  }
}
