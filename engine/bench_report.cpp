#include "engine/bench_report.hpp"

#include <nlohmann/json.hpp>

#include <bit>
#include <cinttypes>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <variant>

namespace vkray {
namespace {

using Json = nlohmann::ordered_json;  // fields in the order written here

static_assert(std::is_same_v<size_t, uint64_t>, "row fields store counts as uint64_t");

// Every figure of a row, by its name in JSON and CSV: one table, so both formats and the reader
// always hold the same fields.
using FieldRef = std::variant<double*, uint64_t*, uint32_t*, bool*, std::string*>;
struct RowField {
  const char* name;
  FieldRef (*ref)(BenchRow&);
};

const RowField row_fields[] = {
    {"variant", [](BenchRow& r) -> FieldRef { return &r.variant; }},
    {"on_gpu", [](BenchRow& r) -> FieldRef { return &r.on_gpu; }},
    {"device_triangles", [](BenchRow& r) -> FieldRef { return &r.stats.triangles; }},
    {"device_geometry_bytes", [](BenchRow& r) -> FieldRef { return &r.stats.geometry_bytes; }},
    {"bvh_nodes", [](BenchRow& r) -> FieldRef { return &r.stats.bvh_nodes; }},
    {"bvh_depth", [](BenchRow& r) -> FieldRef { return &r.stats.bvh_depth; }},
    {"loop_budget", [](BenchRow& r) -> FieldRef { return &r.stats.loop_budget; }},
    {"upload_ms", [](BenchRow& r) -> FieldRef { return &r.upload_ms; }},
    {"bvh_build_ms", [](BenchRow& r) -> FieldRef { return &r.bvh_build_ms; }},
    {"pipeline_ms", [](BenchRow& r) -> FieldRef { return &r.pipeline_ms; }},
    {"gpu_median_ms", [](BenchRow& r) -> FieldRef { return &r.gpu.median_ms; }},
    {"gpu_min_ms", [](BenchRow& r) -> FieldRef { return &r.gpu.min_ms; }},
    {"frame_median_ms", [](BenchRow& r) -> FieldRef { return &r.frame_median_ms; }},
    {"mrays_per_s", [](BenchRow& r) -> FieldRef { return &r.mrays_per_s; }},
    {"unfinished_rays", [](BenchRow& r) -> FieldRef { return &r.unfinished_rays; }},
    {"pixels", [](BenchRow& r) -> FieldRef { return &r.error.pixels; }},
    {"hit_mismatches", [](BenchRow& r) -> FieldRef { return &r.error.hit_mismatches; }},
    {"both_hit", [](BenchRow& r) -> FieldRef { return &r.error.both_hit; }},
    {"nan_pixels", [](BenchRow& r) -> FieldRef { return &r.error.nan_pixels; }},
    {"depth_rel_p50", [](BenchRow& r) -> FieldRef { return &r.error.depth_p50; }},
    {"depth_rel_p99", [](BenchRow& r) -> FieldRef { return &r.error.depth_p99; }},
    {"depth_rel_max", [](BenchRow& r) -> FieldRef { return &r.error.depth_max; }},
    {"depth_ulp_p50", [](BenchRow& r) -> FieldRef { return &r.error.depth_ulp_p50; }},
    {"depth_ulp_p99", [](BenchRow& r) -> FieldRef { return &r.error.depth_ulp_p99; }},
    {"depth_ulp_max", [](BenchRow& r) -> FieldRef { return &r.error.depth_ulp_max; }},
    {"normal_deg_p50", [](BenchRow& r) -> FieldRef { return &r.error.normal_deg_p50; }},
    {"normal_deg_p99", [](BenchRow& r) -> FieldRef { return &r.error.normal_deg_p99; }},
    {"normal_deg_max", [](BenchRow& r) -> FieldRef { return &r.error.normal_deg_max; }},
    {"pareto", [](BenchRow& r) -> FieldRef { return &r.pareto; }},
};

Json row_json(BenchRow row) {
  Json json = Json::object();
  for (const auto& field : row_fields) {
    std::visit([&](auto* value) { json[field.name] = *value; }, field.ref(row));
  }
  return json;
}

std::string csv_cell(BenchRow row, const RowField& field) {
  return std::visit(
      [](auto* value) -> std::string {
        using T = std::remove_pointer_t<decltype(value)>;
        if constexpr (std::is_same_v<T, std::string>) return *value;
        if constexpr (std::is_same_v<T, bool>) return *value ? "true" : "false";
        if constexpr (std::is_same_v<T, double>) {
          char text[32];
          std::snprintf(text, sizeof text, "%.9g", *value);
          return text;
        }
        if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) return std::to_string(*value);
      },
      field.ref(row));
}

// Scene names are ours or file names; quote them for CSV anyway.
std::string csv_quoted(const std::string& text) {
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

struct Fnv1a {
  uint64_t hash = 0xcbf29ce484222325ull;
  void add_bytes(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  }
  void add(double value) { add_bytes(&value, sizeof value); }
  void add(const glm::dvec3& v) { add(v.x), add(v.y), add(v.z); }
  void add(uint64_t value) { add_bytes(&value, sizeof value); }
};

const BenchRow* fastest_gpu_row(const BenchSceneResult& scene) {
  const BenchRow* fastest = nullptr;
  for (const auto& row : scene.rows) {
    if (row.on_gpu && (!fastest || row.gpu.median_ms < fastest->gpu.median_ms)) fastest = &row;
  }
  return fastest;
}

std::string format(const char* pattern, auto... values) {
  char line[512];
  std::snprintf(line, sizeof line, pattern, values...);
  return line;
}

}  // namespace

BenchReport new_bench_report(const GpuDeviceInfo& device, std::string suite, uint32_t frames) {
  BenchReport report;
  report.vkray_version = VKRAY_VERSION;
  report.git_commit = VKRAY_GIT_COMMIT;
  report.device = device.name;
  report.device_type = device.type;
  report.driver = device.driver;
  report.api_version = device.api_version;
  report.suite = std::move(suite);
  report.frames = frames;
  return report;
}

std::string scene_hash(const Scene& scene) {
  Fnv1a fnv;
  fnv.add(scene.camera.from), fnv.add(scene.camera.to), fnv.add(scene.camera.up), fnv.add(scene.camera.fovy_degrees);
  fnv.add(uint64_t{scene.width}), fnv.add(uint64_t{scene.height});
  fnv.add(uint64_t{scene.spheres.size()});
  for (const auto& sphere : scene.spheres) fnv.add(sphere.center), fnv.add(sphere.radius);
  fnv.add(uint64_t{scene.planes.size()});
  for (const auto& plane : scene.planes) fnv.add(plane.point), fnv.add(plane.normal);
  fnv.add(uint64_t{scene.meshes.size()});
  for (const auto& mesh : scene.meshes) {
    fnv.add(uint64_t{mesh.positions.size()});
    for (const auto& position : mesh.positions) fnv.add(position);
    fnv.add(uint64_t{mesh.triangles.size()});
    fnv.add_bytes(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
  }
  return format("%016" PRIx64, fnv.hash);
}

std::string bench_table_header() {
  return format("%-24s %-18s %9s %6s %8s %8s %8s %8s %8s %7s %6s %9s %9s %9s %9s\n", "scene", "variant", "triangles",
                "B/tri", "build ms", "gpu med", "gpu min", "frame ms", "Mrays/s", "flips", "unfin", "depth p99",
                "depth max", "norm p99", "norm max") +
         "(gpu med/min: GPU ms per frame, or the CPU's wall time for Embree; frame ms: host wall time with readback;\n"
         " flips: hit/miss differences from the double-precision reference; depth: relative error; norm: degrees;\n"
         " *: on the Pareto front of time and error)\n";
}

std::string bench_table_rows(const BenchSceneResult& scene) {
  std::string text;
  for (const auto& row : scene.rows) {
    const double bytes_per_triangle =
        row.stats.triangles ? static_cast<double>(row.stats.geometry_bytes) / row.stats.triangles : 0.0;
    const std::string variant = row.variant + (row.pareto ? " *" : "");
    if (row.on_gpu) {
      text += format("%-24s %-18s %9u %6.1f %8.1f %8.2f %8.2f %8.2f %8.2f %7zu %6" PRIu64 " %9.2e %9.2e %9.2e %9.2e\n",
                     scene.name.c_str(), variant.c_str(), row.stats.triangles, bytes_per_triangle, row.bvh_build_ms,
                     row.gpu.median_ms, row.gpu.min_ms, row.frame_median_ms, row.mrays_per_s,
                     row.error.hit_mismatches, row.unfinished_rays, row.error.depth_p99, row.error.depth_max,
                     row.error.normal_deg_p99, row.error.normal_deg_max);
    } else {
      text += format("%-24s %-18s %9s %6s %8.1f %8.2f %8.2f %8s %8.2f %7zu %6s %9.2e %9.2e %9.2e %9.2e\n",
                     scene.name.c_str(), variant.c_str(), "", "", row.bvh_build_ms, row.gpu.median_ms, row.gpu.min_ms,
                     "", row.mrays_per_s, row.error.hit_mismatches, "", row.error.depth_p99, row.error.depth_max,
                     row.error.normal_deg_p99, row.error.normal_deg_max);
    }
  }
  const BenchRow* fastest = fastest_gpu_row(scene);
  for (const auto& row : scene.rows) {
    if (fastest && row.variant == "embree-8") {
      text += format("%-24s fastest GPU variant (%s) against Embree's 8-wide packets on the CPU: %.2fx the time\n",
                     scene.name.c_str(), fastest->variant.c_str(), fastest->gpu.median_ms / row.gpu.median_ms);
    }
  }
  for (const auto& skipped : scene.skipped) text += scene.name + ": skipped " + skipped + "\n";
  return text;
}

std::string bench_json(const BenchReport& report) {
  Json scenes = Json::array();
  for (const auto& scene : report.scenes) {
    Json rows = Json::array();
    for (const auto& row : scene.rows) rows.push_back(row_json(row));
    scenes.push_back({{"name", scene.name},
                      {"hash", scene.hash},
                      {"width", scene.width},
                      {"height", scene.height},
                      {"triangles", scene.triangles},
                      {"spheres", scene.spheres},
                      {"planes", scene.planes},
                      {"reference_ms", scene.reference_ms},
                      {"skipped", scene.skipped},
                      {"rows", rows}});
  }
  const Json json = {{"schema", bench_schema},
                     {"vkray_version", report.vkray_version},
                     {"git_commit", report.git_commit},
                     {"device",
                      {{"name", report.device},
                       {"type", report.device_type},
                       {"driver", report.driver},
                       {"api_version", report.api_version}}},
                     {"suite", report.suite},
                     {"frames", report.frames},
                     {"scenes", scenes}};
  return json.dump(2) + "\n";
}

std::string bench_csv(const BenchReport& report) {
  std::string text = "vkray_version,git_commit,device,driver,suite,frames,scene,scene_hash,width,height";
  for (const auto& field : row_fields) text += std::string(",") + field.name;
  text += "\n";
  for (const auto& scene : report.scenes) {
    for (const auto& row : scene.rows) {
      text += csv_quoted(report.vkray_version) + "," + report.git_commit + "," + csv_quoted(report.device) + "," +
              csv_quoted(report.driver) + "," + report.suite + "," + std::to_string(report.frames) + "," +
              csv_quoted(scene.name) + "," + scene.hash + "," + std::to_string(scene.width) + "," +
              std::to_string(scene.height);
      for (const auto& field : row_fields) text += "," + csv_cell(row, field);
      text += "\n";
    }
  }
  return text;
}

BenchReport read_bench_json(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) throw InputError(path.string() + ": cannot open");
  std::string where = "the top level";
  try {
    const Json json = Json::parse(file);
    if (json.value("schema", "") != bench_schema) {
      throw InputError(path.string() + ": not a vkray bench file (\"schema\" is not \"" + bench_schema + "\")");
    }
    BenchReport report;
    report.vkray_version = json.at("vkray_version").get<std::string>();
    report.git_commit = json.at("git_commit").get<std::string>();
    report.device = json.at("device").at("name").get<std::string>();
    report.device_type = json.at("device").at("type").get<std::string>();
    report.driver = json.at("device").at("driver").get<std::string>();
    report.api_version = json.at("device").at("api_version").get<std::string>();
    report.suite = json.at("suite").get<std::string>();
    report.frames = json.at("frames").get<uint32_t>();
    for (size_t s = 0; s < json.at("scenes").size(); ++s) {
      const Json& scene_json = json.at("scenes").at(s);
      where = "scenes[" + std::to_string(s) + "]";
      BenchSceneResult scene;
      scene.name = scene_json.at("name").get<std::string>();
      scene.hash = scene_json.at("hash").get<std::string>();
      scene.width = scene_json.at("width").get<uint32_t>();
      scene.height = scene_json.at("height").get<uint32_t>();
      scene.triangles = scene_json.at("triangles").get<size_t>();
      scene.spheres = scene_json.at("spheres").get<size_t>();
      scene.planes = scene_json.at("planes").get<size_t>();
      scene.reference_ms = scene_json.at("reference_ms").get<double>();
      scene.skipped = scene_json.at("skipped").get<std::vector<std::string>>();
      for (size_t r = 0; r < scene_json.at("rows").size(); ++r) {
        where = "scenes[" + std::to_string(s) + "].rows[" + std::to_string(r) + "]";
        const Json& row_json = scene_json.at("rows").at(r);
        BenchRow row;
        for (const auto& field : row_fields) {
          where = "scenes[" + std::to_string(s) + "].rows[" + std::to_string(r) + "]." + field.name;
          std::visit([&](auto* value) { row_json.at(field.name).get_to(*value); }, field.ref(row));
        }
        scene.rows.push_back(row);
      }
      report.scenes.push_back(std::move(scene));
    }
    return report;
  } catch (const Json::exception& error) {
    throw InputError(path.string() + ": " + where + ": " + error.what());
  }
}

std::string compare_bench(const BenchReport& before, const BenchReport& after) {
  std::string text = format("A: vkray %s (%s) on %s (%s)\nB: vkray %s (%s) on %s (%s)\n", before.vkray_version.c_str(),
                            before.git_commit.c_str(), before.device.c_str(), before.driver.c_str(),
                            after.vkray_version.c_str(), after.git_commit.c_str(), after.device.c_str(),
                            after.driver.c_str());
  text += format("%-24s %-16s %10s %10s %8s %7s %7s %9s %9s %8s %9s %9s %8s\n", "scene", "variant", "A gpu ms",
                 "B gpu ms", "B/A", "A flips", "B flips", "A depth99", "B depth99", "B/A", "A norm99", "B norm99", "B/A");
  auto ratio = [](double b, double a) { return a > 0.0 ? format("%8.3f", b / a) : format("%8s", b > 0.0 ? "inf" : "-"); };
  size_t matched = 0;
  for (const auto& scene_b : after.scenes) {
    for (const auto& scene_a : before.scenes) {
      if (scene_a.name != scene_b.name || scene_a.width != scene_b.width || scene_a.height != scene_b.height) continue;
      if (scene_a.hash != scene_b.hash) {
        text += scene_b.name + ": the scene hashes differ (" + scene_a.hash + ", " + scene_b.hash +
                "): not the same geometry or camera; compared anyway\n";
      }
      for (const auto& row_b : scene_b.rows) {
        for (const auto& row_a : scene_a.rows) {
          if (row_a.variant != row_b.variant) continue;
          ++matched;
          text += format("%-24s %-16s %10.3f %10.3f %s %7zu %7zu %9.2e %9.2e %s %9.2e %9.2e %s\n", scene_b.name.c_str(),
                         row_b.variant.c_str(), row_a.gpu.median_ms, row_b.gpu.median_ms,
                         ratio(row_b.gpu.median_ms, row_a.gpu.median_ms).c_str(), row_a.error.hit_mismatches,
                         row_b.error.hit_mismatches, row_a.error.depth_p99, row_b.error.depth_p99,
                         ratio(row_b.error.depth_p99, row_a.error.depth_p99).c_str(), row_a.error.normal_deg_p99,
                         row_b.error.normal_deg_p99,
                         ratio(row_b.error.normal_deg_p99, row_a.error.normal_deg_p99).c_str());
        }
      }
    }
  }
  if (matched == 0) text += "no row in common (rows match by scene name, image size and variant)\n";
  return text;
}

}  // namespace vkray
