// Pixel-by-pixel check of a GPU frame against the double-precision reference, with tolerances
// derived from float32 error bounds (see envelope.cpp for the derivation): what the tests and the
// GPU report's checks hold every float32 frame to.
#pragma once

#include "engine/reference/compare.hpp"
#include "engine/reference/reference.hpp"
#include "engine/frame.hpp"
#include "engine/scene/scene.hpp"

#include <string>
#include <vector>

namespace vkray {

struct EnvelopeReport {
  size_t pixels = 0;
  size_t boundary_pixels = 0;  // the reference's hit primitive changes within the error cone
  size_t failures = 0;
  std::vector<std::string> first_failures;  // up to 10, "pixel (i, j): ..."
  FrameError stats;                         // plain GPU-vs-reference figures (centre ray only)
  std::string describe() const;
};

// kappa = |L| |A| (row-sum norms) of the instance placing `hit`'s triangle, 1 for none: what an
// instance's transform multiplies float32's errors by, in distance and in normal (envelope.cpp,
// primitive_reach).
double placement_condition(const Scene& scene, const ReferenceHit& hit);

// Renders the reference for `scene` at the frame's size and checks every pixel of `frame`, or
// those of every row_step-th row (for images too large to trace five times on the CPU).
// `hit_ids`, when given, holds what each pixel's ray hit (ObjectPrimitive): it must be the
// reference's where all five samples hit the same primitive, one of theirs elsewhere. `ray_mask`:
// the frame's rays' (Renderer::set_ray_mask); the envelope's error scale stays the whole scene's,
// whose anchor the GPU stores every position from.
EnvelopeReport check_against_reference(const Scene& scene, const Frame& frame, uint32_t row_step = 1,
                                       const std::vector<ObjectPrimitive>* hit_ids = nullptr,
                                       Mask ray_mask = every_mask_bit);

}  // namespace vkray
