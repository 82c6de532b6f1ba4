// The SPIR-V modules the build compiled and embedded (shaders/CMakeLists.txt, the one list of them:
// cmake/EmbedShaders.cmake generates the table), and what each one's bindings are, read from its
// SPIR-V as niagara does rather than written down a second time.
#pragma once

#include "engine/vulkan/embedded_shaders.hpp"

#include <vulkan/vulkan_raii.hpp>

#include <initializer_list>
#include <span>
#include <string_view>
#include <vector>

namespace vkray {

// Every embedded module, in the build's order.
std::span<const EmbeddedShader> embedded_shaders();

// The module of `source` compiled with exactly `defines` (in any order); throws std::logic_error
// for a module the build does not make.
const EmbeddedShader& embedded_shader(std::string_view source, std::initializer_list<std::string_view> defines);

// The descriptor type of each binding of descriptor set 0 that `spirv` declares, by binding number
// 0 to N - 1: storage and uniform buffers, uniform texel buffers (samplerBuffer), storage images
// and acceleration structures, the kinds vkray's shaders declare. Throws std::logic_error for a
// module whose bindings leave a number out or take another kind.
std::vector<vk::DescriptorType> binding_types(std::span<const uint32_t> spirv);

// A compute module made on a device, with a descriptor set laid out as the module declares it
// (binding_types), from a pool of its own: the one set a pipeline of vkray's binds.
struct ShaderBindings {
  ShaderBindings(const vk::raii::Device& device, const EmbeddedShader& shader);
  std::vector<vk::DescriptorType> types;  // by binding
  vk::raii::DescriptorSetLayout layout{nullptr};
  vk::raii::DescriptorPool pool{nullptr};
  vk::raii::DescriptorSet set{nullptr};
  vk::raii::ShaderModule module{nullptr};
};

}  // namespace vkray
