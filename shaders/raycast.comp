#version 460
// One primary ray per pixel through the pixel centre; the nearest hit over every primitive wins.
// Writes the requested outputs (depth, normal, uv, and what each ray hit: WRITE_HIT) for one tile
// of rows of the image into buffers, or one output into a storage image (IMAGE_TARGET, the
// viewer's frame); or traces rays the caller gave (RAY_INPUT), writing depth, normal and what each
// hit (or how many surfaces each crosses: COUNT_CROSSINGS), or directions the caller gave from one
// origin. Compiled seven times (shaders/CMakeLists.txt):
// float32; float32 with VKRAY_DOUBLE_EDGES defined (triangle edge functions from exact double
// products, for devices whose doubles are fast: see intersect.glsl); each of those two with VKRAY_STORAGE_GEOMETRY
// (geometry in storage buffers, not texel buffers: see primitives.glsl) and with VKRAY_RAY_QUERY
// (the device's acceleration structures: ray_query_walk.glsl); and float64 with VKRAY_FLOAT64
// defined (`--precision double`), which writes depth and normals as doubles.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "gpu_layout.h"
#include "intersect.glsl"
#include "primitives.glsl"

layout(local_size_x_id = VKRAY_SPEC_WORKGROUP_X, local_size_y_id = VKRAY_SPEC_WORKGROUP_Y) in;

// A count of 0 removes that primitive loop entirely once the pipeline is specialized.
layout(constant_id = VKRAY_SPEC_PLANE_COUNT) const uint PLANE_COUNT = 0;
layout(constant_id = VKRAY_SPEC_WRITE_DEPTH) const bool WRITE_DEPTH = true;
layout(constant_id = VKRAY_SPEC_WRITE_NORMAL) const bool WRITE_NORMAL = true;
layout(constant_id = VKRAY_SPEC_WRITE_UV) const bool WRITE_UV = false;
layout(constant_id = VKRAY_SPEC_WRITE_HIT) const bool WRITE_HIT = false;
layout(constant_id = VKRAY_SPEC_MORTON_ORDER) const bool MORTON_ORDER = true;
layout(constant_id = VKRAY_SPEC_IMAGE_TARGET) const bool IMAGE_TARGET = false;
layout(constant_id = VKRAY_SPEC_RAY_INPUT) const uint RAY_INPUT_KIND = VKRAY_RAY_INPUT_NONE;
const bool RAY_INPUT = RAY_INPUT_KIND != VKRAY_RAY_INPUT_NONE;
// Each ray from its own origin; otherwise every ray starts at the camera's (RayGenParams.camera).
// The float64 shader is given rays alone (the host gives directions to the packet walk alone).
const bool GIVEN_ORIGINS = RAY_INPUT_KIND == VKRAY_RAY_INPUT_RAYS;
// The caller's rays and arrays, in place (VKRAY_RAY_INPUT_CALLER_DIRECTIONS).
const bool CALLER_ARRAYS = RAY_INPUT_KIND == VKRAY_RAY_INPUT_CALLER_DIRECTIONS;
// Whether rays are cast at all: a camera's for depth or normal (uv alone needs none), given rays
// always (an occlusion query or a count of crossings writes its hits alone).
const bool CASTS_RAYS = WRITE_DEPTH || WRITE_NORMAL || RAY_INPUT;
// Whether each ray's hit is written (VKRAY_BINDING_HITS), and beside it the instance placing it
// (VKRAY_BINDING_INSTANCE_HITS). The || has a name of its own: inside the && chain glslang made the
// whole expression code at its first use, not a specialization constant, and spirv-val refused its
// second use (not dominated).
const bool HIT_IDS_WRITTEN = WRITE_HIT || RAY_INPUT;
const bool WRITE_INSTANCE_HITS = INSTANCES && !COUNT_CROSSINGS && HIT_IDS_WRITTEN;

layout(push_constant) uniform PushConstants { RayGenParams params; };

GEOMETRY_BUFFER(VKRAY_BINDING_PLANES, GeometryTexel, GeometrySampler, planes);  // GpuPlane
layout(std430, binding = VKRAY_BINDING_DEPTH) writeonly buffer DepthOut { real depth_out[]; };
layout(std430, binding = VKRAY_BINDING_NORMAL) writeonly buffer NormalOut { real normal_out[]; };
layout(std430, binding = VKRAY_BINDING_UV) writeonly buffer UvOut { float uv_out[]; };
// Rays that ran out of LOOP_BUDGET: their count, then their pixels' indices within the tile (the
// caller's rays' own indices, with CALLER_ARRAYS).
layout(std430, binding = VKRAY_BINDING_OVERFLOW) buffer Overflow { uint overflow_count; uint overflow_pixels[]; };
// The storage-image target: the output at its pixel (depth in x, normal in xyz, uv in xy), and the
// range of finite depths.
layout(binding = VKRAY_BINDING_IMAGE, rgba32f) uniform writeonly image2D image_out;
layout(std430, binding = VKRAY_BINDING_DEPTH_RANGE) buffer DepthRange { DepthRangeBits depth_range; };
GEOMETRY_BUFFER(VKRAY_BINDING_RAYS, GeometryTexel, GeometrySampler, rays_in);  // GpuRay
layout(std430, binding = VKRAY_BINDING_HITS) writeonly buffer HitsOut { uint hit_out[]; };
GEOMETRY_BUFFER(VKRAY_BINDING_CALLER_RAYS, uvec4, usamplerBuffer, caller_rays);  // six doubles a ray
layout(std430, binding = VKRAY_BINDING_HIT_SOURCES) readonly buffer HitSourcesIn { uvec2 hit_sources[]; };
layout(std430, binding = VKRAY_BINDING_MESH_IDS) writeonly buffer MeshIdsOut { uint mesh_id_out[]; };
layout(std430, binding = VKRAY_BINDING_PRIMITIVE_IDS) writeonly buffer PrimitiveIdsOut { uint primitive_id_out[]; };
layout(std430, binding = VKRAY_BINDING_RAY_ORDER) readonly buffer RayOrder { uint ray_order[]; };
layout(std430, binding = VKRAY_BINDING_INSTANCE_HITS) writeonly buffer InstanceHitsOut { uint instance_hit_out[]; };

// The mesh id and primitive id of what a ray hit (VKRAY_HIT_*), as HitSources gives them on the host.
uvec2 hit_source(uint hit) {
  if (hit == VKRAY_HIT_NONE) return uvec2(VKRAY_HIT_NONE);
  uint index = hit & VKRAY_HIT_INDEX_MASK;
  if ((hit & VKRAY_HIT_PLANE) != 0u) return uvec2(params.camera[5].w + index, index);
  if ((hit & VKRAY_HIT_SPHERE_APART) != 0u) return uvec2(params.camera[5].z + index, index);
  return hit_sources[index];
}

// Folds a range of depths into depth_range (near = +infinity and far = 0 where the invocation has
// none): reduced across the subgroup first, then one atomic pair per subgroup (per-invocation
// atomics cost llvmpipe ~20 ms a 1280x720 frame; a workgroup barrier costs it more than that).
// Positive floats order as their bits do.
void record_depth_range(float near, float far) {
  uint near_bits = subgroupMin(floatBitsToUint(near));
  uint far_bits = subgroupMax(floatBitsToUint(far));
  if (subgroupElect() && far_bits != 0u) {
    atomicMin(depth_range.near_far.x, near_bits);
    atomicMax(depth_range.near_far.y, far_bits);
  }
}

// Every other bit of `bits` (bits 0, 2, 4, 6), packed: one coordinate of a Morton index below 256.
uint compact_even_bits(uint bits) {
  bits &= 0x55u;
  bits = (bits | (bits >> 1)) & 0x33u;
  return (bits | (bits >> 2)) & 0x0fu;
}

#ifdef VKRAY_RAY_QUERY
#include "ray_query_walk.glsl"
#endif
#include "point_walk.glsl"
// Points instead of rays: each invocation one point (see VKRAY_RAY_INPUT_POINTS).
const bool POINT_QUERY = RAY_INPUT_KIND == VKRAY_RAY_INPUT_POINTS;

// A point query's invocation: its point from the points' texels (rows of `width`), its answer into the
// outputs at the same place; a point past the loop budget listed for the host.
void answer_point() {
  uint width = params.image.x;
  uint local = gl_LocalInvocationIndex;
  uvec2 place = gl_WorkGroupID.xy * gl_WorkGroupSize.xy + uvec2(local % gl_WorkGroupSize.x, local / gl_WorkGroupSize.x);
  uint index = (params.image.z + place.y) * width + place.x;
  if (place.x >= width || place.y >= params.image.w || index >= params.image.y) return;
  Point point = fetch_point(rays_in, int(index));  // a GpuPoint a query point
#ifdef VKRAY_FLOAT64
  Origin query = Origin(point.value.xyz);
  real max_distance = point.value.w;
#else
  Origin query = Origin(point.hi.xyz, point.lo.xyz);
  real max_distance = point.hi.w;
#endif
  uint out_index = place.y * width + place.x;
  uint plane_size = params.image.x * params.image.w;
  if (WINDING) {
    depth_out[out_index] = winding_number(query);
  } else {
    Nearest best = nearest_point(query, max_distance);
    bool found = best.id != VKRAY_HIT_NONE;
    depth_out[out_index] = found ? best.distance : uintBitsToFloat(0x7f800000u);
    for (uint c = 0; c < 3; ++c) normal_out[c * plane_size + out_index] = found ? best.offset[c] : 0.0;
    hit_out[out_index] = best.id;
    if (WRITE_INSTANCE_HITS) instance_hit_out[out_index] = best.instance;
  }
  if (point_unfinished) overflow_pixels[atomicAdd(overflow_count, 1u)] = out_index;
}
#if defined(VKRAY_DOUBLE_EDGES)
#define CALLER_RAY_TEXEL(index) FETCH(caller_rays, index)
#include "caller_rays.glsl"
#endif
#if defined(VKRAY_DOUBLE_EDGES) && !defined(VKRAY_RAY_QUERY)
#include "packet_walk.glsl"
const bool PACKET_WALK = SEARCH_MODE == VKRAY_SEARCH_BVH_PACKET && !GIVEN_ORIGINS;
#else
const bool PACKET_WALK = false;
#endif

// `counts`: RayGenParams.counts, read only by the generic variant.
// With the tree, a handful of spheres beside many triangles are tested one by one first (see
// make_gpu_scene): the tree's loop then holds the triangle test alone, and their nearest hit
// bounds the walk.
PrimitiveHit nearest_primitive(Origin origin, real3 dir, real t_max, uvec4 counts) {
  RayFrame frame = make_ray_frame(dir);
  uint search_mode = GENERIC ? counts.w & VKRAY_SEARCH_MODE_BITS : SEARCH_MODE;
  uint sphere_count = GENERIC ? counts.x : SPHERE_COUNT;
  if (search_mode == VKRAY_SEARCH_BRUTE_FORCE) {
    return nearest_primitive_brute_force(frame, origin, dir, t_max, sphere_count, GENERIC ? counts.z : TRIANGLE_SLOTS, true);
  }
  PrimitiveHit sphere_hit = nearest_primitive_brute_force(frame, origin, dir, t_max, sphere_count, 0u, false);
#ifdef VKRAY_RAY_QUERY
  PrimitiveHit tree_hit = nearest_primitive_ray_query(frame, origin, dir, sphere_hit.t);
#else
  PrimitiveHit tree_hit = nearest_primitive_in_tree(frame, origin, dir, sphere_hit.t);
#endif
  if (tree_hit.t < sphere_hit.t) return tree_hit;
  sphere_hit.unfinished = tree_hit.unfinished;
  return sphere_hit;
}


// The normal, facing the ray, of a hit in the list of first hits (FIRST_HITS; not yet unit length),
// placed by `instance` where that is one.
real3 first_hit_normal(uint id, uint instance, Origin origin, real3 dir) {
  if (id == VKRAY_HIT_NONE) return real3(0.0);
  bool far = (id & VKRAY_HIT_FAR_ROOT) != 0u;
  uint index = id & VKRAY_HIT_INDEX_MASK & ~VKRAY_HIT_FAR_ROOT;
  if ((id & VKRAY_HIT_PLANE) != 0u) {
#ifdef VKRAY_FLOAT64
    real3 plane_normal = fetch_point(planes, 2 * int(index)).value.xyz;
#else
    real3 plane_normal = fetch_point_hi(planes, 2 * int(index)).hi.xyz;
#endif
    return facing_the_ray(plane_normal, dir);
  }
  if ((id & VKRAY_HIT_SPHERE_APART) != 0u) {
    real3 normal, far_normal;
    real far_root;
    intersect_sphere_point(fetch_point(spheres, int(index)), origin, dir, uintBitsToFloat(0x7f800000u), normal, far_root,
                           far_normal);
    return far ? far_normal : normal;
  }
  if (INSTANCES && instance != VKRAY_NO_INSTANCE) return instance_normal(id, instance, dir);
  return primitive_normal(id, origin, dir);
}

// The rays this invocation traces: one, or a column of a packet (see VKRAY_PACKET_ROWS).
const uint RAYS = PACKET_WALK ? VKRAY_PACKET_ROWS : 1u;

void main() {
  if (MASKS) ray_mask = params.counts.w >> VKRAY_RAY_MASK_SHIFT;
  if (POINT_QUERY) {
    answer_point();
    return;
  }
  uint width = params.image.x;
  uint height = params.image.y;
  // Where this invocation's first ray goes, relative to the tile, and the step to its next one.
  // One ray each: invocations cover their square workgroup in Morton order, so any 8 consecutive
  // ones (a lavapipe subgroup) form a 4x2 block and any 32 (an NVIDIA warp) an 8x4 block: rays
  // that run together are as close together as they can be, which is what tree walks in lockstep
  // want. Given rays come in rows one workgroup wide (see Renderer::cast_rays): in row-major order
  // the invocations take consecutive rays, which callers usually order as they lie in space.
  uint local = gl_LocalInvocationIndex;
  uvec2 first_pixel;
  if (PACKET_WALK) {
    first_pixel = gl_WorkGroupID.xy * uvec2(VKRAY_PACKET_GROUP_WIDTH, VKRAY_PACKET_GROUP_HEIGHT) +
                  uvec2(local % VKRAY_PACKET_GROUP_WIDTH, (local / VKRAY_PACKET_GROUP_WIDTH) * VKRAY_PACKET_ROWS);
  } else {
    uvec2 in_group = RAY_INPUT      ? uvec2(local % gl_WorkGroupSize.x, local / gl_WorkGroupSize.x)
                     : MORTON_ORDER ? uvec2(compact_even_bits(local), compact_even_bits(local >> 1))
                                    : gl_LocalInvocationID.xy;
    first_pixel = gl_WorkGroupID.xy * gl_WorkGroupSize.xy + in_group;
  }
  // Outputs are planar (all x, then all y, ...) with one plane per buffer tile, so neighbouring
  // invocations store to neighbouring addresses.
  uint plane_size = params.image.x * params.image.w;
  float shorter = float(min(width, height));

  // Per ray: its pixel, whether it lies in the image (rays past the image's edge stay alive with
  // t_max = 0: they can hit nothing, and subgroup operations always see whole subgroups), the
  // nearest plane hit, and the search's bound. (Arrays of RAYS entries used; the rest is removed.)
  uvec2 tile_pixel[VKRAY_PACKET_ROWS];
  bool inside[VKRAY_PACKET_ROWS];
  real3 dirs[VKRAY_PACKET_ROWS];
  real t_best[VKRAY_PACKET_ROWS];
  real primitive_t_max[VKRAY_PACKET_ROWS];
  real3 normal[VKRAY_PACKET_ROWS];
  uint hit_id[VKRAY_PACKET_ROWS];
  uint hit_instance[VKRAY_PACKET_ROWS];  // INSTANCES
  bool unfinished[VKRAY_PACKET_ROWS];
  // CALLER_ARRAYS: each ray's index in the caller's arrays, and whether it can be traced here (from
  // the shared origin, with a direction that has one).
  uint caller_index[VKRAY_PACKET_ROWS];
  bool traceable[VKRAY_PACKET_ROWS];
  Origin origin;
  for (uint r = 0; r < RAYS; ++r) {
    tile_pixel[r] = first_pixel + uvec2(0, r);
    uint row = params.image.z + tile_pixel[r].y;
    uint ray_index = row * width + tile_pixel[r].x;  // RAY_INPUT: rows of `width` rays, `height` in all
    // (camera[5] holds these bits only with CALLER_ARRAYS; the float64 shader's camera fills it.)
    bool by_direction = CALLER_ARRAYS && (params.camera[5].x & VKRAY_CALLER_BY_DIRECTION) != 0u;
    bool in_order = CALLER_ARRAYS && ((params.camera[5].x & VKRAY_CALLER_IN_ORDER) != 0u || by_direction);
    if (in_order) ray_index = packet_order_index(ray_index);  // the place in the order
    inside[r] = tile_pixel[r].x < width && tile_pixel[r].y < params.image.w && (!RAY_INPUT || ray_index < height);
    caller_index[r] = by_direction && inside[r] ? ray_order[ray_index] : ray_index;
    traceable[r] = true;
    uint out_index = tile_pixel[r].y * width + tile_pixel[r].x;

    // UV of the pixel centre: origin at the image centre, the shorter side spans [-1, 1]. The
    // numerators are small integers, exact in float; the division is the only rounding (within
    // 2.5 ulp by Vulkan's precision rules).
    vec2 uv_numerator = vec2(float(2 * tile_pixel[r].x + 1) - float(width), float(height) - float(2 * row + 1));
    vec2 uv = uv_numerator / shorter;
    if (WRITE_UV && !RAY_INPUT && inside[r]) {
      if (IMAGE_TARGET) {
        imageStore(image_out, ivec2(tile_pixel[r].x, row), vec4(uv, 0.0, 0.0));
      } else {
        uv_out[out_index] = uv.x;
        uv_out[plane_size + out_index] = uv.y;
      }
    }
    if (!CASTS_RAYS) continue;

    // A GpuRay is two points; lanes past the last ray read the first (their t_max is 0). float32
    // shaders take the direction rounded to float, as a camera's. A given ray's range ends at its
    // direction's w (+infinity where the caller set none); a camera's never does. The rays' buffer is read only
    // where rays are given: for a camera it is a 16-byte placeholder, which a driver that keeps a
    // dead read (of a storage buffer, in the storage-geometry variant) would read past.
    const real no_hit = uintBitsToFloat(0x7f800000u);  // +infinity
    real range_end = no_hit;
#ifdef VKRAY_FLOAT64
    if (RAY_INPUT) {
      origin = Origin(fetch_point(rays_in, inside[r] ? 2 * int(ray_index) : 0).value.xyz);
      dvec4 direction_end = fetch_point(rays_in, inside[r] ? 2 * int(ray_index) + 1 : 1).value;
      dirs[r] = direction_end.xyz;
      range_end = direction_end.w;
    } else {
      dvec3 camera[4];  // origin, right, up, forward_scaled
      for (int k = 0; k < 4; ++k) {
        uvec4 first = params.camera[(3 * k) / 2];
        uvec4 second = params.camera[(3 * k + 2) / 2];
        uvec2 x = k % 2 == 0 ? first.xy : first.zw;
        uvec2 y = k % 2 == 0 ? first.zw : second.xy;
        uvec2 z = k % 2 == 0 ? second.xy : second.zw;
        camera[k] = dvec3(packDouble2x32(x), packDouble2x32(y), packDouble2x32(z));
      }
      origin = Origin(camera[0]);
      precise dvec3 toward = double(uv_numerator.x) / shorter * camera[1] + double(uv_numerator.y) / shorter * camera[2] +
                             camera[3];
      dirs[r] = normalize(toward);
    }
#else
    if (GIVEN_ORIGINS) {
      Point ray_origin = fetch_point(rays_in, inside[r] ? 2 * int(ray_index) : 0);
      origin = Origin(ray_origin.hi.xyz, ray_origin.lo.xyz);
      vec4 direction_end = fetch_point_hi(rays_in, inside[r] ? 2 * int(ray_index) + 1 : 1).hi;
      dirs[r] = direction_end.xyz;
      range_end = direction_end.w;
    } else {
      origin = Origin(uintBitsToFloat(params.camera[0].xyz), use_lo_parts ? uintBitsToFloat(params.camera[1].xyz) : vec3(0.0));
#if defined(VKRAY_DOUBLE_EDGES)
      if (CALLER_ARRAYS) {
        traceable[r] = caller_unit_direction(int(inside[r] ? caller_index[r] : 0u), dirs[r]);
        if (!traceable[r]) range_end = 0.0;  // hits nothing; listed for the host below
      } else
#endif
      if (RAY_INPUT) {
        vec4 direction_end = FETCH(rays_in, inside[r] ? int(ray_index) : 0);
        dirs[r] = direction_end.xyz;
        range_end = direction_end.w;
      } else {
        // `precise`: the ray must be the same bits in every pipeline that renders this pixel (the
        // workgroup shapes, the generic variant), so no compiler may fuse these products differently.
        precise vec3 toward = uv.x * uintBitsToFloat(params.camera[2].xyz) + uv.y * uintBitsToFloat(params.camera[3].xyz) +
                              uintBitsToFloat(params.camera[4].xyz);
        dirs[r] = normalize(toward);
      }
    }
#endif
    real3 dir = dirs[r];

    t_best[r] = inside[r] ? range_end : 0.0;
    normal[r] = real3(0.0);
    hit_id[r] = VKRAY_HIT_NONE;
    hit_instance[r] = VKRAY_NO_INSTANCE;
    if (FIRST_HITS) clear_first_hits(t_best[r]);

    // Planes first; spheres and triangles then search up to VKRAY_PRIMITIVE_T_MAX (coincident
    // surfaces: the plane wins; see gpu_layout.h).
    primitive_t_max[r] = t_best[r];
    uint plane_count = GENERIC ? params.counts.y : PLANE_COUNT;
    uint spheres_apart = GENERIC ? params.counts.x : SPHERE_COUNT;  // whose masks come before the planes'
    for (uint i = 0; i < plane_count; ++i) {
      // The height above the camera, set by the host per render (see GpuPlane). Plain float
      // coordinates subtract the camera from the anchored offset instead, and so does each given
      // ray (its own origin), hi and lo parts apart: the height is then within a few float32
      // roundings of the larger of the offset and the origin's distance from the anchor.
#ifdef VKRAY_FLOAT64
      Point plane = fetch_point(planes, RAY_INPUT ? 2 * int(i) + 1 : 2 * int(i));
      real3 plane_normal = plane.value.xyz;
      real height = RAY_INPUT ? plane.value.w - dot(plane_normal, origin.position) : plane.value.w;
#else
      bool anchored = GIVEN_ORIGINS || COORDINATES != VKRAY_COORDINATES_CAMERA_RELATIVE;
      Point plane = GIVEN_ORIGINS ? fetch_point(planes, 2 * int(i) + 1)
                                  : fetch_point_hi(planes, anchored ? 2 * int(i) + 1 : 2 * int(i));
      vec3 plane_normal = plane.hi.xyz;
      float height = anchored ? plane.hi.w - dot(plane_normal, origin.hi) : plane.hi.w;
      if (GIVEN_ORIGINS) height += plane.lo.w - dot(plane_normal, origin.lo);
#endif
      real t = intersect_plane(plane_normal, height, dir, t_best[r]);
      if (COUNT_CROSSINGS) {
        if (t < t_best[r] && apart_visible(spheres_apart + i)) ++crossings;
      } else if (FIRST_HITS) {
        if (apart_visible(spheres_apart + i)) primitive_t_max[r] = list_first_hit(t, VKRAY_HIT_PLANE | i);
      } else if (t < t_best[r] && apart_visible(spheres_apart + i)) {
        t_best[r] = t;
        normal[r] = facing_the_ray(plane_normal, dir);
        primitive_t_max[r] = VKRAY_PRIMITIVE_T_MAX(t, abs(dot(plane_normal, dir)));
        hit_id[r] = VKRAY_HIT_PLANE | i;
      }
    }
    // An occlusion query hit by a plane is answered: its walk finds nothing below 0.
    if (ANY_HIT && hit_id[r] != VKRAY_HIT_NONE) primitive_t_max[r] = 0.0;
  }
  if (!CASTS_RAYS) return;

  // Spheres and triangles: each ray on its own, or the packet's rays together.
  PrimitiveHit hits[VKRAY_PACKET_ROWS];
#if defined(VKRAY_DOUBLE_EDGES) && !defined(VKRAY_RAY_QUERY)
  if (PACKET_WALK) {
    // Spheres tested one by one (a handful beside the tree's triangles) bound each ray's walk.
    float t_max[VKRAY_PACKET_ROWS];
    for (uint r = 0; r < RAYS; ++r) {
      hits[r] = nearest_primitive_brute_force(make_ray_frame(dirs[r]), origin, dirs[r], primitive_t_max[r], SPHERE_COUNT, 0u, false);
      t_max[r] = hits[r].t;
    }
    uint slots[VKRAY_PACKET_ROWS];
    uint instances[VKRAY_PACKET_ROWS];
    bool packet_unfinished;
    nearest_primitives_packet(origin, dirs, t_max, slots, instances, packet_unfinished);
    for (uint r = 0; r < RAYS; ++r) {
      // The normal is read for the winner alone.
      if (slots[r] != no_primitive) {
        real3 winner_normal = INSTANCES && instances[r] != VKRAY_NO_INSTANCE ? instance_normal(slots[r], instances[r], dirs[r])
                                                                            : primitive_normal(slots[r], origin, dirs[r]);
        hits[r] = PrimitiveHit(t_max[r], winner_normal, false, slots[r], instances[r]);
      }
      hits[r].unfinished = packet_unfinished;
    }
  }
#endif
  if (!PACKET_WALK) hits[0] = nearest_primitive(origin, dirs[0], primitive_t_max[0], params.counts);

  float near = uintBitsToFloat(0x7f800000u), far = 0.0;
  for (uint r = 0; r < RAYS; ++r) {
    if (!FIRST_HITS && hits[r].t < primitive_t_max[r]) {
      t_best[r] = hits[r].t;
      normal[r] = hits[r].normal;
      hit_id[r] = hits[r].id;
      hit_instance[r] = hits[r].instance;
    }
    uint out_index = tile_pixel[r].y * width + tile_pixel[r].x;
    if ((hits[r].unfinished || !traceable[r]) && inside[r]) {
      overflow_pixels[atomicAdd(overflow_count, 1u)] = CALLER_ARRAYS ? caller_index[r] : out_index;
    }
    // Unfinished rays stay out of the depth range: the host finishes them and folds their depth in.
    // A ray that hit nothing keeps the end of its range as t_best; its depth is written +infinity.
    if (hit_id[r] == VKRAY_HIT_NONE) t_best[r] = uintBitsToFloat(0x7f800000u);
    if (inside[r] && !hits[r].unfinished && t_best[r] < uintBitsToFloat(0x7f800000u)) {
      near = min(near, float(t_best[r]));
      far = max(far, float(t_best[r]));
    }
  }
  if (IMAGE_TARGET && WRITE_DEPTH) record_depth_range(near, far);

  for (uint r = 0; r < RAYS; ++r) {
    if (!inside[r]) continue;
    uint out_index = tile_pixel[r].y * width + tile_pixel[r].x;
    // Unit length again (the sphere normal carries rounding); every kind turned it to face the ray.
    if (WRITE_NORMAL && t_best[r] < uintBitsToFloat(0x7f800000u)) normal[r] = normalize(normal[r]);
    if (IMAGE_TARGET) {
      imageStore(image_out, ivec2(tile_pixel[r].x, params.image.z + tile_pixel[r].y),
                 WRITE_DEPTH ? vec4(t_best[r], 0.0, 0.0, 0.0) : vec4(normal[r], 0.0));
      continue;
    }
    if (FIRST_HITS) {  // hit k in the k-th run of each output's planes
      [[unroll]] for (uint k = 0; k < VKRAY_HITS_MAX; ++k) {
        if (k >= HITS) continue;
        uint id = first_id[k];
        bool listed = id != VKRAY_HIT_NONE;
        hit_out[k * plane_size + out_index] = listed ? id & ~VKRAY_HIT_FAR_ROOT : VKRAY_HIT_NONE;
        depth_out[k * plane_size + out_index] = listed ? first_t[k] : uintBitsToFloat(0x7f800000u);
        uint instance = INSTANCES ? first_instance[k] : VKRAY_NO_INSTANCE;
        real3 unit_normal = listed ? normalize(first_hit_normal(id, instance, origin, dirs[r])) : real3(0.0);
        for (uint c = 0; c < 3; ++c) normal_out[(3 * k + c) * plane_size + out_index] = unit_normal[c];
        if (WRITE_INSTANCE_HITS) instance_hit_out[k * plane_size + out_index] = instance;
      }
      continue;
    }
    if (CALLER_ARRAYS) {  // by ray, as the caller holds them: t, x y z of the normal, the ids
      uint k = caller_index[r];
      uint written = params.camera[5].x;
      if ((written & VKRAY_CALLER_WRITE_T) != 0u) depth_out[k] = t_best[r];
      if ((written & VKRAY_CALLER_WRITE_NORMAL) != 0u) {
        normal_out[3 * k] = normal[r].x;
        normal_out[3 * k + 1] = normal[r].y;
        normal_out[3 * k + 2] = normal[r].z;
      }
      uvec2 ids = hit_source(hit_id[r]);
      if ((written & VKRAY_CALLER_WRITE_MESH_ID) != 0u) mesh_id_out[k] = ids.x;
      if ((written & VKRAY_CALLER_WRITE_PRIMITIVE_ID) != 0u) primitive_id_out[k] = ids.y;
      continue;
    }
    if (HIT_IDS_WRITTEN) hit_out[out_index] = COUNT_CROSSINGS ? crossings : hit_id[r];
    if (WRITE_INSTANCE_HITS) instance_hit_out[out_index] = hit_instance[r];
    if (WRITE_DEPTH) depth_out[out_index] = t_best[r];
    if (WRITE_NORMAL) {
      normal_out[out_index] = normal[r].x;
      normal_out[plane_size + out_index] = normal[r].y;
      normal_out[2 * plane_size + out_index] = normal[r].z;
    }
  }
}
