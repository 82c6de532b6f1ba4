// The SPIR-V modules the build embeds, as cmake/EmbedShaders.cmake lists them in the table it
// generates (embedded_shaders.cpp in the build tree, from shaders/CMakeLists.txt): no Vulkan type
// here, so that generated file needs nothing but this. engine/vulkan/shader_modules.hpp reads it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace vkray {

struct EmbeddedShader {
  const char* source;   // "raycast.comp"
  const char* defines;  // "VKRAY_STORAGE_GEOMETRY+VKRAY_DOUBLE_EDGES"; "" for none
  const uint32_t* words;
  size_t word_count;
  std::span<const uint32_t> spirv() const { return {words, word_count}; }
};

// The table cmake/EmbedShaders.cmake generates (embedded_shaders.cpp in the build tree).
extern const EmbeddedShader embedded_shader_table[];
extern const size_t embedded_shader_count;

}  // namespace vkray
