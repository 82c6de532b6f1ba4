// What the compiled shaders promise about their arithmetic. The error-free transformations of
// shaders/intersect.glsl are exact only if no compiler fuses a * b + c into an fma or reassociates
// them; GLSL's `precise` becomes SPIR-V's NoContraction decoration, which forbids both on every
// device. lavapipe never fuses, so no image on it could show a missing decoration: the SPIR-V can.
#include "engine/vulkan/shader_modules.hpp"
#include "shaders/gpu_layout.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <span>
#include <string>

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

using vkray::embedded_shader;

TEST(Spirv, ErrorFreeTransformationsAreNeverContracted) {
  EXPECT_GE(no_contraction_decorations(embedded_shader("raycast.comp", {}).spirv()), least_precise_operations);
  EXPECT_GE(no_contraction_decorations(embedded_shader("raycast.comp", {"VKRAY_DOUBLE_EDGES"}).spirv()),
            least_precise_operations);
}

// The float64 module computes in double, where rounding is far below float32's: it needs fewer.
TEST(Spirv, TheDecorationCountIsReadFromTheModules) {
  EXPECT_EQ(embedded_shader("raycast.comp", {}).words[0], 0x07230203u);  // the SPIR-V magic number: these are modules
  EXPECT_LT(no_contraction_decorations(embedded_shader("raycast.comp", {"VKRAY_FLOAT64"}).spirv()),
            no_contraction_decorations(embedded_shader("raycast.comp", {}).spirv()));
}

// Every module the build embeds is there once, and its bindings, read from its SPIR-V, are what
// gpu_layout.h numbers them: geometry as texel buffers, or storage buffers in the storage-geometry
// modules; the ray-query modules with their top-level structure last; the preview's ramps a uniform
// buffer; the ray order's caller rays texels beside storage buffers.
TEST(Spirv, TheBindingsAreReadFromEachModule) {
  EXPECT_EQ(vkray::embedded_shaders().size(), 9u);
  for (const vkray::EmbeddedShader& shader : vkray::embedded_shaders()) {
    SCOPED_TRACE(std::string(shader.source) + " " + shader.defines);
    EXPECT_EQ(&embedded_shader(shader.source, {}) == &shader, std::string(shader.defines).empty());
    const auto types = vkray::binding_types(shader.spirv());
    if (std::string(shader.source) == "preview.comp") {
      ASSERT_EQ(types.size(), 3u);
      EXPECT_EQ(types[VKRAY_PREVIEW_BINDING_RAMPS], vk::DescriptorType::eUniformBuffer);
      EXPECT_EQ(types[VKRAY_PREVIEW_BINDING_VALUES], vk::DescriptorType::eStorageImage);
      continue;
    }
    if (std::string(shader.source) == "direction_order.comp") {
      ASSERT_EQ(types.size(), 4u);
      EXPECT_EQ(types[VKRAY_ORDER_BINDING_RAYS], vk::DescriptorType::eUniformTexelBuffer);
      for (const uint32_t binding : {VKRAY_ORDER_BINDING_CELLS, VKRAY_ORDER_BINDING_RANKS, VKRAY_ORDER_BINDING_ORDER}) {
        EXPECT_EQ(types[binding], vk::DescriptorType::eStorageBuffer);
      }
      continue;
    }
    const std::string defines = shader.defines;
    const bool ray_query = defines.find("VKRAY_RAY_QUERY") != std::string::npos;
    ASSERT_EQ(types.size(), ray_query ? VKRAY_BINDING_COUNT : VKRAY_BINDING_TOP_STRUCTURE);
    const bool storage = defines.find("VKRAY_STORAGE_GEOMETRY") != std::string::npos;
    EXPECT_EQ(types[VKRAY_BINDING_VERTICES], storage ? vk::DescriptorType::eStorageBuffer : vk::DescriptorType::eUniformTexelBuffer);
    EXPECT_EQ(types[VKRAY_BINDING_DEPTH], vk::DescriptorType::eStorageBuffer);
    EXPECT_EQ(types[VKRAY_BINDING_IMAGE], vk::DescriptorType::eStorageImage);
    EXPECT_EQ(types[VKRAY_BINDING_CALLER_RAYS], storage ? vk::DescriptorType::eStorageBuffer : vk::DescriptorType::eUniformTexelBuffer);
    EXPECT_EQ(types[VKRAY_BINDING_RAY_ORDER], vk::DescriptorType::eStorageBuffer);
    if (ray_query) {
      EXPECT_EQ(types[VKRAY_BINDING_TOP_STRUCTURE], vk::DescriptorType::eAccelerationStructureKHR);
    }
  }
  EXPECT_THROW(embedded_shader("raycast.comp", {"VKRAY_FLOAT64", "VKRAY_DOUBLE_EDGES"}), std::logic_error);
}

}  // namespace
