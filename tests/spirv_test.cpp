// What the compiled shaders promise about their arithmetic. The error-free transformations of
// shaders/intersect.glsl are exact only if no compiler fuses a * b + c into an fma or reassociates
// them; GLSL's `precise` becomes SPIR-V's NoContraction decoration, which forbids both on every
// device. lavapipe never fuses, so no image on it could show a missing decoration: the SPIR-V can.
#include <cstdint>
#include <span>

#include "raycast.comp.VKRAY_DOUBLE_EDGES.spv.h"
#include "raycast.comp.VKRAY_FLOAT64.spv.h"
#include "raycast.comp.spv.h"

#include <gtest/gtest.h>

namespace {

// OpDecorate (opcode 71) with decoration NoContraction (42), in a SPIR-V module.
size_t no_contraction_decorations(std::span<const uint32_t> spirv) {
  constexpr uint32_t op_decorate = 71, no_contraction = 42;
  size_t count = 0;
  for (size_t word = 5; word < spirv.size();) {  // 5 header words, then instructions
    const uint32_t length = spirv[word] >> 16, opcode = spirv[word] & 0xffffu;
    if (length == 0) break;
    if (opcode == op_decorate && length >= 3 && spirv[word + 2] == no_contraction) ++count;
    word += length;
  }
  return count;
}

// Two-sum and two-product (intersect.glsl) for float and vec3 alone mark 4 + 10 operations each;
// the camera-relative differences and the sphere terms more.
constexpr size_t least_precise_operations = 2 * (4 + 10);

TEST(Spirv, ErrorFreeTransformationsAreNeverContracted) {
  EXPECT_GE(no_contraction_decorations(raycast_comp), least_precise_operations);
  EXPECT_GE(no_contraction_decorations(raycast_comp_VKRAY_DOUBLE_EDGES), least_precise_operations);
}

// The float64 module computes in double, where rounding is far below float32's: it needs none.
TEST(Spirv, TheDecorationCountIsReadFromTheModules) {
  EXPECT_EQ(raycast_comp[0], 0x07230203u);  // the SPIR-V magic number: these are modules
  EXPECT_LT(no_contraction_decorations(raycast_comp_VKRAY_FLOAT64), no_contraction_decorations(raycast_comp));
}

}  // namespace
