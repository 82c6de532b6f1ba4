// Choices compiled into the ray-casting shader that trade accuracy, generality or memory order for
// time. The defaults are what vkray renders with; the others exist so that `vkray bench` can show,
// measured, what each choice buys (engine/bench/bench.cpp).
#pragma once

#include "shaders/gpu_layout.h"

#include <cstdint>

namespace vkray {

// float32: the default. float64 (`--precision double`): the same shader compiled with doubles,
// geometry and camera in world coordinates as doubles, depth and normals written as doubles; it
// needs a device with shaderFloat64.
enum class Precision : uint32_t { float32, float64 };

// How float32 shaders evaluate the watertight triangle test's edge functions exactly in sign
// (shaders/intersect.glsl): in float with an error-free fallback where they are small, or as
// differences of products of floats taken in double (exact products). automatic: double where the
// device runs doubles fast (GpuDeviceInfo::fast_float64: lavapipe, which runs the fallback masked on
// every test; the data-centre GPUs measured), float elsewhere (most GPUs run doubles at a small
// fraction of float speed, and skip the fallback).
enum class EdgeArithmetic : uint32_t { automatic, float_error_free, double_products };

struct ShaderVariant {
  Precision precision = Precision::float32;
  // How float32 shaders hold positions (VKRAY_COORDINATES_*): camera-relative by default; the
  // others exist to measure what that buys.
  uint32_t coordinates = VKRAY_COORDINATES_CAMERA_RELATIVE;
  uint32_t sphere_formula = VKRAY_SPHERE_STABLE;         // VKRAY_SPHERE_*
  uint32_t triangle_test = VKRAY_TRIANGLE_WATERTIGHT;    // VKRAY_TRIANGLE_*
  uint32_t workgroup_width = VKRAY_WORKGROUP_X;
  uint32_t workgroup_height = VKRAY_WORKGROUP_Y;
  // Invocations in Morton order within the workgroup; needs a square power-of-two workgroup of at
  // most 16x16 (raycast.comp decodes 8 bits). Otherwise row by row.
  bool morton_order = true;
  // Every primitive type's code compiled in, counts and search mode read at run time (see
  // VKRAY_SPEC_GENERIC); renders must then request every output, since the shader writes them all.
  bool generic = false;
  // The tree walk's stack in registers where the tree is shallow enough (VKRAY_SPEC_STACK_REGISTERS),
  // else in a private array, as the generic variant always has it.
  bool stack_in_registers = true;
  EdgeArithmetic edges = EdgeArithmetic::automatic;
  // Geometry (and given rays) read from storage buffers rather than uniform texel buffers (float32
  // shaders): what NVIDIA and AMD drivers are usually tuned for; llvmpipe gathers texels faster.
  bool storage_geometry = false;
  bool operator==(const ShaderVariant&) const = default;
};

// The default variant with another workgroup shape and order.
inline ShaderVariant with_workgroup(uint32_t width, uint32_t height, bool morton_order) {
  ShaderVariant shader;
  shader.workgroup_width = width;
  shader.workgroup_height = height;
  shader.morton_order = morton_order;
  return shader;
}

}  // namespace vkray
