#include "engine/vulkan/shader_modules.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>

namespace vkray {
namespace {

// The SPIR-V instructions and operands the bindings are read from (SPIR-V 1.6 specification, 3.32;
// https://registry.khronos.org/SPIR-V/specs/unified1/SPIRV.html).
enum Op : uint32_t {
  op_type_image = 25,
  op_type_sampled_image = 27,
  op_type_pointer = 32,
  op_variable = 59,
  op_decorate = 71,
  op_type_acceleration_structure = 5341,
};
enum Decoration : uint32_t { decoration_block = 2, decoration_buffer_block = 3, decoration_binding = 33, decoration_set = 34 };
enum StorageClass : uint32_t { uniform_constant = 0, uniform = 2, storage_buffer = 12 };
constexpr uint32_t dim_buffer = 5;         // an image's Dim: a texel buffer
constexpr uint32_t sampled_storage = 2;    // an image's Sampled: read and written without a sampler
constexpr size_t header_words = 5;

std::string defines_key(std::initializer_list<std::string_view> defines) {
  std::vector<std::string> sorted(defines.begin(), defines.end());
  std::sort(sorted.begin(), sorted.end());
  std::string key;
  for (const auto& define : sorted) key += (key.empty() ? "" : "+") + define;
  return key;
}

std::string defines_key(std::string_view listed) {
  std::vector<std::string> sorted;
  for (size_t start = 0; start < listed.size();) {
    const size_t plus = std::min(listed.find('+', start), listed.size());
    sorted.emplace_back(listed.substr(start, plus - start));
    start = plus + 1;
  }
  std::sort(sorted.begin(), sorted.end());
  std::string key;
  for (const auto& define : sorted) key += (key.empty() ? "" : "+") + define;
  return key;
}

}  // namespace

std::span<const EmbeddedShader> embedded_shaders() { return {embedded_shader_table, embedded_shader_count}; }

const EmbeddedShader& embedded_shader(std::string_view source, std::initializer_list<std::string_view> defines) {
  const std::string wanted = defines_key(defines);
  for (const EmbeddedShader& shader : embedded_shaders()) {
    if (shader.source == source && defines_key(shader.defines) == wanted) return shader;
  }
  throw std::logic_error("no module " + std::string(source) + " with defines '" + wanted + "' (shaders/CMakeLists.txt)");
}

std::vector<vk::DescriptorType> binding_types(std::span<const uint32_t> spirv) {
  if (spirv.size() < header_words || spirv[0] != 0x07230203u) throw std::logic_error("binding_types: not a SPIR-V module");
  struct Pointer {
    uint32_t storage_class, pointee;
  };
  struct Image {
    uint32_t dim, sampled;
  };
  std::map<uint32_t, uint32_t> binding_of, set_of;  // by variable
  std::map<uint32_t, uint32_t> struct_decoration;   // Block or BufferBlock, by struct type
  std::map<uint32_t, Pointer> pointers;
  std::map<uint32_t, Image> images;
  std::map<uint32_t, uint32_t> sampled_images;  // by type: its image type
  std::map<uint32_t, uint32_t> variables;       // by variable: its pointer type
  std::vector<uint32_t> structures;  // acceleration-structure types
  for (size_t word = header_words; word < spirv.size();) {
    const uint32_t length = spirv[word] >> 16, opcode = spirv[word] & 0xffffu;
    if (length == 0 || word + length > spirv.size()) throw std::logic_error("binding_types: a malformed instruction");
    const uint32_t* operand = &spirv[word + 1];
    switch (opcode) {
      case op_decorate:
        if (operand[1] == decoration_binding) binding_of[operand[0]] = operand[2];
        if (operand[1] == decoration_set) set_of[operand[0]] = operand[2];
        if (operand[1] == decoration_block || operand[1] == decoration_buffer_block) struct_decoration[operand[0]] = operand[1];
        break;
      case op_type_image: images[operand[0]] = {operand[2], operand[6]}; break;
      case op_type_sampled_image: sampled_images[operand[0]] = operand[1]; break;
      case op_type_acceleration_structure: structures.push_back(operand[0]); break;
      case op_type_pointer: pointers[operand[0]] = {operand[1], operand[2]}; break;
      case op_variable: variables[operand[1]] = operand[0]; break;
      default: break;
    }
    word += length;
  }
  std::map<uint32_t, vk::DescriptorType> by_binding;
  for (const auto& [variable, binding] : binding_of) {
    if (set_of.count(variable) && set_of[variable] != 0) continue;
    const Pointer pointer = pointers.at(variables.at(variable));
    const uint32_t type = pointer.pointee;
    vk::DescriptorType kind;
    if (pointer.storage_class == storage_buffer ||
        (pointer.storage_class == uniform && struct_decoration[type] == decoration_buffer_block)) {
      kind = vk::DescriptorType::eStorageBuffer;
    } else if (pointer.storage_class == uniform && struct_decoration[type] == decoration_block) {
      kind = vk::DescriptorType::eUniformBuffer;
    } else if (pointer.storage_class == uniform_constant && sampled_images.count(type) &&
               images.at(sampled_images.at(type)).dim == dim_buffer) {
      kind = vk::DescriptorType::eUniformTexelBuffer;
    } else if (pointer.storage_class == uniform_constant && images.count(type) && images.at(type).sampled == sampled_storage) {
      kind = images.at(type).dim == dim_buffer ? vk::DescriptorType::eStorageTexelBuffer : vk::DescriptorType::eStorageImage;
    } else if (pointer.storage_class == uniform_constant && std::count(structures.begin(), structures.end(), type)) {
      kind = vk::DescriptorType::eAccelerationStructureKHR;
    } else {
      throw std::logic_error("binding_types: binding " + std::to_string(binding) + " is of a kind vkray's shaders never declare");
    }
    by_binding[binding] = kind;
  }
  std::vector<vk::DescriptorType> types;
  for (const auto& [binding, kind] : by_binding) {
    if (binding != types.size()) throw std::logic_error("binding_types: binding " + std::to_string(types.size()) + " is missing");
    types.push_back(kind);
  }
  return types;
}

ShaderBindings::ShaderBindings(const vk::raii::Device& device, const EmbeddedShader& shader) : types(binding_types(shader.spirv())) {
  std::vector<vk::DescriptorSetLayoutBinding> bindings;
  std::map<vk::DescriptorType, uint32_t> descriptors;  // of each type
  for (uint32_t i = 0; i < types.size(); ++i) {
    bindings.emplace_back(i, types[i], 1, vk::ShaderStageFlagBits::eCompute);
    ++descriptors[types[i]];
  }
  layout = vk::raii::DescriptorSetLayout(device, vk::DescriptorSetLayoutCreateInfo({}, bindings));
  std::vector<vk::DescriptorPoolSize> pool_sizes;
  for (const auto& [type, count] : descriptors) pool_sizes.emplace_back(type, count);
  pool = vk::raii::DescriptorPool(device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 1, pool_sizes));
  const vk::DescriptorSetLayout layouts[] = {*layout};
  set = std::move(vk::raii::DescriptorSets(device, vk::DescriptorSetAllocateInfo(*pool, layouts))[0]);
  module = vk::raii::ShaderModule(device, vk::ShaderModuleCreateInfo({}, shader.word_count * sizeof(uint32_t), shader.words));
}

}  // namespace vkray
