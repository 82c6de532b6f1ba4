// Real, published OBJ meshes from the shared models folder (VKRAY_MODELS_DIR, described in its
// MODELS.md): each loads with the triangle count of fan triangulation and one position per `v `
// line, and the truncated Crytek Sponza is reported with its line. When the folder is absent (it is
// never part of the repository), the tests skip.
#include "engine/render/gpu_scene.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/obj_loader.hpp"

#include <glm/common.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::filesystem::path models_dir = VKRAY_MODELS_DIR;

struct Model {
  const char* file;
  size_t vertices;   // `v ` lines (MODELS.md, first table)
  size_t triangles;  // "Tris after fan-triangulation" (MODELS.md, "Extra checks per file")
};

// Copied from MODELS.md; ModelsDoc.TableMatchesHardCodedCounts checks that they still agree.
const Model models[] = {
    {"stanford-bunny.obj", 35947, 69451},
    {"stanford-dragon-100k.obj", 50000, 100000},
    {"armadillo-50k.obj", 25002, 50000},
    {"teapot.obj", 3644, 6320},
    {"spot.obj", 2930, 5856},
    {"suzanne.obj", 507, 968},
    {"beetle.obj", 1148, 2053},
    {"f-16.obj", 2344, 4592},
    {"cruiser.obj", 1364, 2875},
    {"obj-spec-cube-negative-indices.obj", 24, 12},
    {"alligator.obj", 3208, 5981},
    {"teapot-vn.obj", 1292, 2464},
    {"blub.obj", 7106, 14208},
    {"cow.obj", 2903, 5804},
    {"beetle-alt.obj", 19887, 38656},
    {"beast.obj", 32311, 64618},
    {"fandisk.obj", 6475, 12946},
    {"rocker-arm.obj", 10044, 20088},
    {"cheburashka.obj", 6669, 13334},
    {"homer.obj", 6002, 12000},
    {"ogre.obj", 62194, 124008},
    {"nefertiti.obj", 49971, 99938},
    {"woody.obj", 694, 1267},
};

const char* const truncated_file = "crytek-sponza-truncated.obj";
constexpr size_t truncated_last_line = 100066;  // 100,065 newlines, then the unfinished face line

#define SKIP_WITHOUT_MODELS()                                                                                 \
  if (!std::filesystem::is_directory(models_dir)) {                                                           \
    GTEST_SKIP() << "shared models folder " << models_dir << " is absent (set VKRAY_MODELS_DIR to use it)"; \
  }

std::vector<std::string> split_row(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  std::string cell;
  std::getline(stream, cell, '|');  // before the first '|'
  while (std::getline(stream, cell, '|')) {
    const size_t begin = cell.find_first_not_of(' ');
    const size_t end = cell.find_last_not_of(' ');
    cells.push_back(begin == std::string::npos ? "" : cell.substr(begin, end - begin + 1));
  }
  return cells;
}

size_t parse_count(std::string text) {
  text.erase(std::remove(text.begin(), text.end(), ','), text.end());
  return std::stoul(text);
}

struct DocRow {
  size_t vertices = 0;
  size_t triangles = 0;
  std::vector<double> bbox;  // min x, y, z, max x, y, z
};

// The rows of MODELS.md by file name: `v ` lines and bounding box from the first table, the
// triangle count from "Extra checks per file".
std::map<std::string, DocRow> read_models_doc() {
  std::ifstream file(models_dir / "MODELS.md");
  EXPECT_TRUE(file) << "cannot open " << models_dir / "MODELS.md";
  std::map<std::string, DocRow> rows;
  std::string line;
  while (std::getline(file, line)) {
    if (line.rfind("| `", 0) != 0) continue;
    const auto cells = split_row(line);
    const std::string name = cells[0].substr(1, cells[0].size() - 2);  // without the backquotes
    if (cells.size() >= 14) {
      rows[name].vertices = parse_count(cells[6]);
      for (const size_t column : {11, 12}) {
        std::stringstream numbers(cells[column]);
        std::string number;
        while (std::getline(numbers, number, ',')) rows[name].bbox.push_back(std::stod(number));
      }
    } else if (cells.size() >= 3) {
      rows[name].triangles = parse_count(cells[2]);
    }
  }
  return rows;
}

class RealModel : public testing::TestWithParam<Model> {};

TEST_P(RealModel, LoadsWithDocumentedCounts) {
  SKIP_WITHOUT_MODELS();
  const Model& model = GetParam();
  const auto path = models_dir / model.file;
  vkray::Mesh mesh;
  try {
    mesh = vkray::load_obj_file(path);
  } catch (const vkray::InputError& error) {
    FAIL() << "InputError: " << error.what();
  }
  EXPECT_EQ(mesh.positions.size(), model.vertices) << path;
  EXPECT_EQ(mesh.triangles.size(), model.triangles) << path;
  ASSERT_FALSE(mesh.positions.empty());
  for (const auto& triangle : mesh.triangles) {
    for (const uint32_t index : triangle) ASSERT_LT(index, mesh.positions.size()) << path;
  }

  // The bounding box over all positions, against MODELS.md (which prints about six significant
  // digits): the coordinates themselves are read right, not only counted.
  const auto doc = read_models_doc();
  const auto row = doc.find(model.file);
  ASSERT_NE(row, doc.end()) << model.file << " is not in MODELS.md";
  ASSERT_EQ(row->second.bbox.size(), 6u) << model.file;
  glm::dvec3 low = mesh.positions[0], high = mesh.positions[0];
  for (const auto& position : mesh.positions) {
    ASSERT_TRUE(std::isfinite(position.x) && std::isfinite(position.y) && std::isfinite(position.z)) << path;
    low = glm::min(low, position);
    high = glm::max(high, position);
  }
  const double actual[6] = {low.x, low.y, low.z, high.x, high.y, high.z};
  for (size_t k = 0; k < 6; ++k) {
    const double expected = row->second.bbox[k];
    EXPECT_NEAR(actual[k], expected, 1e-5 * std::max(1.0, std::abs(expected))) << model.file << " bbox value " << k;
  }
}

std::string model_name(const testing::TestParamInfo<Model>& info) {
  std::string name = info.param.file;
  name = name.substr(0, name.rfind(".obj"));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

INSTANTIATE_TEST_SUITE_P(SharedModels, RealModel, testing::ValuesIn(models), model_name);

// A mesh above 10k triangles takes at most 64 bytes a triangle on the device, everything counted
// (records, distinct vertices with their lo parts, normals, tree nodes), as the default float32
// shader reads it: every shared model that size, and a generated closed sphere.
double device_bytes_a_triangle(vkray::Mesh mesh) {
  vkray::Scene scene;
  scene.meshes.push_back(std::move(mesh));
  const vkray::GpuScene gpu = vkray::make_gpu_scene(scene);
  EXPECT_TRUE(gpu.has_tree());
  return static_cast<double>(gpu.geometry_bytes()) / gpu.triangle_count;
}

TEST(DeviceLayout, MeshesAboveTenThousandTrianglesTakeAtMost64BytesATriangle) {
  EXPECT_LE(device_bytes_a_triangle(vkray::make_sphere_mesh(20000)), 64.0) << "generated sphere";
  SKIP_WITHOUT_MODELS();
  size_t checked = 0;
  for (const Model& model : models) {
    if (model.triangles <= 10000) continue;
    EXPECT_LE(device_bytes_a_triangle(vkray::load_obj_file(models_dir / model.file)), 64.0) << model.file;
    ++checked;
  }
  EXPECT_GE(checked, 10u);
}

TEST(TruncatedModel, ReportsTheCutOffLine) {
  SKIP_WITHOUT_MODELS();
  const auto path = models_dir / truncated_file;
  std::string message;
  try {
    vkray::load_obj_file(path);
  } catch (const vkray::InputError& error) {
    message = error.what();
  }
  ASSERT_FALSE(message.empty()) << path << " loaded without an InputError";
  const std::string location = path.string() + ":" + std::to_string(truncated_last_line) + ": ";
  EXPECT_EQ(message.rfind(location, 0), 0u) << message;
  EXPECT_NE(message.find(truncated_file), std::string::npos) << message;
  EXPECT_NE(message.find("cut off"), std::string::npos) << message;
  EXPECT_NE(message.find("28866/19"), std::string::npos) << message;  // the unfinished face vertex
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

TEST(ModelsDoc, TableMatchesHardCodedCounts) {
  SKIP_WITHOUT_MODELS();
  const auto doc = read_models_doc();
  std::map<std::string, DocRow> expected_rows(doc);
  ASSERT_EQ(expected_rows.erase(truncated_file), 1u) << "MODELS.md no longer lists " << truncated_file;
  EXPECT_EQ(expected_rows.size(), std::size(models));
  for (const Model& model : models) {
    const auto row = expected_rows.find(model.file);
    ASSERT_NE(row, expected_rows.end()) << model.file << " is not in MODELS.md";
    EXPECT_EQ(row->second.vertices, model.vertices) << model.file;
    EXPECT_EQ(row->second.triangles, model.triangles) << model.file;
  }
}

}  // namespace
