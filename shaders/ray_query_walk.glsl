// The ray-query traversal (VKRAY_SEARCH_RAY_QUERY): the device walks its own acceleration
// structures (GL_EXT_ray_query; ray-tracing hardware where the GPU has it) and hands every
// candidate it finds to this shader, which tests the candidate itself with vkray's watertight
// triangle test or its sphere test on the camera-relative positions. The device's float32
// arithmetic on anchor-relative positions only proposes; depth and normal are vkray's, with the
// default's error contract, except at edges, where the device's own tests decide what is
// proposed (see below). A triangle the device's test misses is never proposed: docs/accuracy.md
// measures how often that changes a pixel.
// Instances (INSTANCES) are the device's own: the top level places an instanced mesh's structure by
// the instance's transform (rounded to float32), and vkray tests a candidate in the mesh's
// coordinates (ray_in_mesh), as its tree walks do.
// Compiled into the modules with VKRAY_RAY_QUERY (SPIR-V 1.4 and up, Vulkan 1.2).
#ifndef VKRAY_RAY_QUERY_WALK_GLSL
#define VKRAY_RAY_QUERY_WALK_GLSL

#extension GL_EXT_ray_query : require

#include "gpu_layout.h"
#include "primitives.glsl"  // test_primitive, primitive_normal

layout(binding = VKRAY_BINDING_TOP_STRUCTURE) uniform accelerationStructureEXT top_structure;

// Whether the query has another candidate, within the walk's LOOP_BUDGET (over both queries).
bool next_candidate(rayQueryEXT query, inout uint iterations, inout bool unfinished) {
  if (!rayQueryProceedEXT(query)) return false;
  if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
    unfinished = true;
    rayQueryTerminateEXT(query);
    return false;
  }
  ++iterations;
  return true;
}

// The candidate's slot: the instance carries its structure's first slot
// (engine/vulkan/acceleration_structures.hpp).
uint candidate_slot(rayQueryEXT query) {
  return uint(rayQueryGetIntersectionInstanceCustomIndexEXT(query, false)) +
         uint(rayQueryGetIntersectionPrimitiveIndexEXT(query, false));
}

// The scene's instance placing the candidate, or VKRAY_NO_INSTANCE: the device instance's shader
// binding table record offset carries it plus one (StructureInput::Placement).
uint candidate_instance(rayQueryEXT query) {
  if (!INSTANCES) return VKRAY_NO_INSTANCE;
  uint offset = rayQueryGetIntersectionInstanceShaderBindingTableRecordOffsetEXT(query, false);
  return offset == 0u ? VKRAY_NO_INSTANCE : offset - 1u;
}

// vkray's own test of the candidate in `slot`, placed by `instance`, against the world's ray (its
// frame, origin and direction): in the instance's mesh's coordinates where it is one. The hit it
// takes carries the instance, and so does each hit it lists (listing_instance).
void test_candidate(RayFrame frame, Origin origin, vec3 dir, uint slot, uint instance, inout SlotHit hit) {
  if (!INSTANCES || instance == VKRAY_NO_INSTANCE) {
    listing_instance = VKRAY_NO_INSTANCE;
    test_primitive(frame, origin, dir, slot, hit);
    return;
  }
  Origin mesh_origin;
  vec3 mesh_dir;
  ray_in_mesh(fetch_placement(instance), origin, dir, mesh_origin, mesh_dir);
  listing_instance = instance;
  float before = hit.t;
  test_primitive(make_ray_frame(mesh_dir), mesh_origin, mesh_dir, slot, hit);
  if (hit.t != before) hit.instance = instance;
}

PrimitiveHit nearest_primitive_ray_query(RayFrame frame, Origin origin, vec3 dir, float t_max) {
  SlotHit hit = SlotHit(t_max, no_primitive, VKRAY_NO_INSTANCE);
  bool unfinished = false;
  rayQueryEXT query;
  // The structures hold the hi parts of positions relative to the anchor, as float32: the query's
  // ray starts at the origin rounded to them. Its far end stays finite (3.4e38 for no hit yet).
  // The device's instance masks are the meshes' (engine/vulkan/acceleration_structures.hpp): it
  // proposes no triangle the call's mask hides; a sphere's own mask is tested with it.
  rayQueryInitializeEXT(query, top_structure, gl_RayFlagsNoneEXT, ray_mask, origin.hi + origin.lo, 0.0, dir,
                        min(t_max, 3.4e38));
  uint iterations = 0;
  while (next_candidate(query, iterations, unfinished)) {
    const uint slot = candidate_slot(query);
    const uint instance = candidate_instance(query);
    const float before = hit.t;
    // vkray's own test of the candidate, against the whole ray: "it misses" and "it hits, but not
    // nearer" must not look alike, or with crossing or coplanar triangles the device's float32
    // ordering would bring its distance and another triangle's normal.
    SlotHit own = SlotHit(t_max, no_primitive, VKRAY_NO_INSTANCE);
    test_candidate(frame, origin, dir, slot, instance, own);
    // Counting crossings or listing the first hits commits nothing, so the device proposes every
    // candidate along the range; test_primitive counted or listed this one where vkray's test takes
    // it. What the device never proposes (a triangle its own test misses at an edge) is not: a ray
    // within rounding of an edge may cross one surface fewer here than with vkray's walks.
    if (COUNT_CROSSINGS || FIRST_HITS) continue;
    if (own.slot != no_primitive && own.t < hit.t) hit = own;
    const bool triangle = rayQueryGetIntersectionTypeEXT(query, false) == gl_RayQueryCandidateIntersectionTriangleEXT;
    if (triangle && own.slot == no_primitive && slot_visible(slot)) {
      // The device's triangle test hit what vkray's rejects: the ray passes within rounding of an
      // edge. At an edge shared with a triangle vkray's test would take, the device may never
      // propose that one (its own tie-break, or none: lavapipe's is not watertight), so the
      // proposal is taken at the device's distance, one rounding away from the shared edge's
      // point; a pixel there lies on the boundary the error envelope allows either side of.
      const float device_t = rayQueryGetIntersectionTEXT(query, false);
      if (device_t < hit.t) hit = SlotHit(device_t, slot, instance);
    }
    if (hit.t < before) {
      // Committing it lets the device cull what lies beyond: at its own distance for a triangle,
      // at vkray's for a sphere's box.
      if (triangle) {
        rayQueryConfirmIntersectionEXT(query);
      } else {
        rayQueryGenerateIntersectionEXT(query, hit.t);
      }
    }
  }
  if (hit.slot != no_primitive && !unfinished && !FIRST_HITS) {
    // Once a triangle is committed, the device culls every other at its own float32 distance, so a
    // triangle that vkray's test finds nearer by less than the two distances' disagreement (two
    // overlapping coplanar triangles, or one crossing the winner at the hit) may never have been
    // proposed. A second query over a short window around the winner commits nothing, so the
    // device culls nothing inside it, and vkray's test picks among all it proposes.
    // The window: the device sees each point rounded to float32 relative to the anchor (an error
    // of 2^-24 of the hit point's distance from it, P), and a plane moved by e moves a ray's hit
    // by e / cos of the ray's angle to its normal; a half-width of 2^-12 P holds the disagreement
    // of a few such roundings for every ray meeting the planes at more than about 2^-10 rad
    // (0.06 degrees). The query starts at the window, not at the origin with t_min there: a device
    // that culls boxes by the far end alone (lavapipe) would walk every node up to the hit again.
    const float window = exp2(-12.0) * (length(origin.hi) / length(dir) + hit.t);
    const float start = max(hit.t - window, 0.0);
    rayQueryInitializeEXT(query, top_structure, gl_RayFlagsNoneEXT, ray_mask, origin.hi + origin.lo + start * dir,
                          0.0, dir, min(hit.t + window, 3.4e38) - start);
    while (next_candidate(query, iterations, unfinished)) {
      test_candidate(frame, origin, dir, candidate_slot(query), candidate_instance(query), hit);
    }
  }
  listing_instance = VKRAY_NO_INSTANCE;
  PrimitiveHit result = PrimitiveHit(hit.t, vec3(0.0), unfinished, hit.slot, hit.instance);
  if (hit.slot != no_primitive && !FIRST_HITS) {
    result.normal = INSTANCES && hit.instance != VKRAY_NO_INSTANCE ? instance_normal(hit.slot, hit.instance, dir)
                                                                   : primitive_normal(hit.slot, origin, dir);
  }
  return result;
}

#endif  // VKRAY_RAY_QUERY_WALK_GLSL
