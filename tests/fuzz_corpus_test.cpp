// Every input in the fuzzers' corpus (tests/fuzz/corpus: seeds, and each finding of a fuzz run,
// added there as a regression test) goes through the loaders in the ordinary suite too: it must be
// accepted or rejected with InputError, nothing else.
#include "engine/scene/gltf_loader.hpp"
#include "engine/scene/model_loader.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/views/manifest_record.hpp"
#include "engine/views/view_list.hpp"
#include "tests/fuzz/ply_header_input.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>

#ifndef VKRAY_FUZZ_CORPUS_DIR
#error "VKRAY_FUZZ_CORPUS_DIR comes from CMake"
#endif

namespace vkray {
namespace {

const std::filesystem::path corpus = VKRAY_FUZZ_CORPUS_DIR;

std::string read(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

size_t for_each_input(const char* kind, const std::function<void(const std::string&, const std::string&)>& parse) {
  size_t inputs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(corpus / kind)) {
    SCOPED_TRACE(entry.path().string());
    ++inputs;
    try {
      parse(read(entry.path()), entry.path().filename().string());
    } catch (const InputError&) {
    }
  }
  return inputs;
}

TEST(FuzzCorpus, SceneInputsAreAcceptedOrRejectedCleanly) {
  const Mesh cube = load_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "cube.obj");
  const size_t inputs = for_each_input("scene", [&](const std::string& text, const std::string& name) {
    parse_scene(text, name, "/nonexistent", [&](const std::filesystem::path&) { return std::vector<Mesh>{cube}; });
  });
  EXPECT_GE(inputs, 4u);
}

TEST(FuzzCorpus, ObjInputsAreAcceptedOrRejectedCleanly) {
  const size_t inputs = for_each_input("obj", [](const std::string& text, const std::string& name) {
    const Mesh mesh = load_obj_text(text, name);
    for (const auto& triangle : mesh.triangles) {
      for (uint32_t index : triangle) EXPECT_LT(index, mesh.positions.size());
    }
  });
  EXPECT_GE(inputs, 3u);
}

TEST(FuzzCorpus, ModelInputsAreAcceptedOrRejectedCleanly) {
  size_t accepted = 0;
  const size_t inputs = for_each_input("model", [&](const std::string& bytes, const std::string& name) {
    const Model model = read_model_bytes(bytes, lower_extension(name), name);
    for (const Mesh& mesh : model.meshes) {
      for (const auto& triangle : mesh.triangles) {
        for (uint32_t index : triangle) EXPECT_LT(index, mesh.positions.size());
      }
    }
    ++accepted;
  });
  EXPECT_GE(inputs, 5u);
  EXPECT_GE(accepted, 4u);  // one seed a kind is a good file: each kind's reader reached
}

TEST(FuzzCorpus, GltfInputsAreAcceptedOrRejectedCleanly) {
  size_t accepted = 0;
  const size_t inputs = for_each_input("gltf", [&](const std::string& text, const std::string& name) {
    const Model model = read_gltf(text, false, "/nonexistent", name);
    for (const Mesh& mesh : model.meshes) {
      for (const auto& triangle : mesh.triangles) {
        for (uint32_t index : triangle) EXPECT_LT(index, mesh.positions.size());
      }
    }
    ++accepted;
  });
  EXPECT_GE(inputs, 12u);
  EXPECT_GE(accepted, 3u);  // the triangle, the cycle-free shared accessors, the flattened node
}

TEST(FuzzCorpus, PlyHeaderInputsAreAcceptedOrRejectedCleanly) {
  size_t accepted = 0;
  const size_t inputs = for_each_input("ply_header", [&](const std::string& header, const std::string& name) {
    const Model model = read_model_bytes(test::ply_from_header(header), ".ply", name);
    for (const auto& triangle : model.meshes.at(0).triangles) {
      for (uint32_t index : triangle) EXPECT_LT(index, model.meshes[0].positions.size());
    }
    ++accepted;
  });
  EXPECT_GE(inputs, 7u);
  EXPECT_GE(accepted, 3u);  // ASCII and binary triangles, MeshLab's texcoords
}

TEST(FuzzCorpus, ViewsInputsAreAcceptedOrRejectedCleanly) {
  const size_t inputs = for_each_input("views", [](const std::string& text, const std::string& name) { parse_views(text, name); });
  EXPECT_GE(inputs, 2u);
}

// Manifest lines give an index or nothing, never an exception; the seeds' complete records give one.
TEST(FuzzCorpus, ManifestLinesGiveAnIndexOrNothing) {
  size_t records = 0;
  const size_t inputs = for_each_input("manifest", [&](const std::string& text, const std::string&) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) records += manifest_line_index(line).has_value();
  });
  EXPECT_GE(inputs, 2u);
  EXPECT_GE(records, 3u);
}

}  // namespace
}  // namespace vkray
