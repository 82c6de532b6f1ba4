#include "engine/bench/bench_report.hpp"

#include "engine/fnv1a.hpp"

#include <nlohmann/json.hpp>

#include <functional>

#include <algorithm>
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

// Every figure of a row, by its name in JSON and CSV: one table per kind of row, so both formats and
// the reader always hold the same fields.
using FieldRef = std::variant<double*, uint64_t*, uint32_t*, bool*, std::string*>;
template <typename Row>
struct Field {
  std::string name;
  std::function<FieldRef(Row&)> ref;
};
using RowField = Field<BenchRow>;

const RowField fixed_row_fields[] = {
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
    {"gpu_max_ms", [](BenchRow& r) -> FieldRef { return &r.gpu.max_ms; }},
    {"gpu_frames", [](BenchRow& r) -> FieldRef { return &r.gpu_frames; }},
    {"frame_median_ms", [](BenchRow& r) -> FieldRef { return &r.frame_median_ms; }},
    {"gpu_sustained_ms", [](BenchRow& r) -> FieldRef { return &r.sustained_ms; }},
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
    // The extra outputs of a "+..." row (zeros elsewhere, and for the outputs it lacks), then a
    // field for each of their figures (row_fields()).
    {"outputs_compared", [](BenchRow& r) -> FieldRef { return &r.outputs.compared; }},
};

// Every figure of a row: the fields above, then the outputs' error fields (output_error_fields).
const std::vector<RowField>& row_fields() {
  static const std::vector<RowField> fields = [] {
    std::vector<RowField> all(std::begin(fixed_row_fields), std::end(fixed_row_fields));
    for (const OutputErrorField& field : output_error_fields()) {
      const std::string name = field.name;
      if (field.count) {
        all.push_back({field.name, [name](BenchRow& r) -> FieldRef { return &r.outputs.counts[name]; }});
      } else {
        all.push_back({field.name, [name](BenchRow& r) -> FieldRef { return &r.outputs.measures[name]; }});
      }
    }
    return all;
  }();
  return fields;
}

// A row of `vkray bench --suite rays`: Embree's figures are those of its row for the same rays,
// embree-1m (rtcIntersect1M) or embree-occluded (rtcOccluded1M).
const std::vector<Field<GivenRaysRow>>& given_rays_fields() {
  using R = GivenRaysRow;
  static const std::vector<Field<R>> fields = {
      {"rays", [](R& r) -> FieldRef { return &r.kind; }},
      {"count", [](R& r) -> FieldRef { return &r.rays; }},
      {"walk", [](R& r) -> FieldRef { return &r.walk; }},
      {"median_ms", [](R& r) -> FieldRef { return &r.vkray.median_ms; }},
      {"min_ms", [](R& r) -> FieldRef { return &r.vkray.min_ms; }},
      {"max_ms", [](R& r) -> FieldRef { return &r.vkray.max_ms; }},
      {"hit_mismatches", [](R& r) -> FieldRef { return &r.hit_mismatches; }},
      {"both_hit", [](R& r) -> FieldRef { return &r.both_hit; }},
      {"t_rel_p99", [](R& r) -> FieldRef { return &r.t_rel_p99; }},
      {"t_rel_max", [](R& r) -> FieldRef { return &r.t_rel_max; }},
      {"embree_variant", [](R& r) -> FieldRef { return &r.embree_variant; }},
      {"embree_threads", [](R& r) -> FieldRef { return &r.embree_threads; }},
      {"embree_median_ms", [](R& r) -> FieldRef { return &r.embree.median_ms; }},
      {"embree_min_ms", [](R& r) -> FieldRef { return &r.embree.min_ms; }},
      {"embree_max_ms", [](R& r) -> FieldRef { return &r.embree.max_ms; }},
      {"embree_hit_mismatches", [](R& r) -> FieldRef { return &r.embree_hit_mismatches; }},
      {"embree_t_rel_p99", [](R& r) -> FieldRef { return &r.embree_t_rel_p99; }},
  };
  return fields;
}

template <typename Row>
Json row_json(Row row, const std::vector<Field<Row>>& fields) {
  Json json = Json::object();
  for (const auto& field : fields) {
    std::visit([&](auto* value) { json[field.name] = *value; }, field.ref(row));
  }
  return json;
}

template <typename Row>
std::string csv_cell(Row row, const Field<Row>& field) {
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


std::string format(const char* pattern, auto... values) {
  char line[512];
  std::snprintf(line, sizeof line, pattern, values...);
  return line;
}

// A scene name cut to fit its column, keeping its end (a file name's end tells models apart).
std::string short_name(const std::string& name, size_t width) {
  return name.size() <= width ? name : "..." + name.substr(name.size() - (width - 3));
}

// The rows on the Pareto front, fastest first, each with its time against the default's and its
// error: what the time it saves costs.
std::string pareto_summary(const BenchSceneResult& scene) {
  std::vector<const BenchRow*> front;
  const BenchRow* baseline = nullptr;
  for (const auto& row : scene.rows) {
    if (row.pareto) front.push_back(&row);
    if (row.variant == "default") baseline = &row;
  }
  if (front.size() < 2 && (front.empty() || front[0] == baseline)) return "";
  std::sort(front.begin(), front.end(), [](const BenchRow* a, const BenchRow* b) { return a->gpu.median_ms < b->gpu.median_ms; });
  if (!baseline) baseline = front.front();
  std::string text = format("%s: Pareto front, fastest first; time against %s, then the error it comes with:\n",
                            short_name(scene.name, 24).c_str(), baseline->variant.c_str());
  for (const BenchRow* row : front) {
    // A ratio whose spreads overlap the baseline's is noise: said ("alike"), not claimed. Within
    // 100 columns.
    const bool apart = row == baseline || row->gpu.clearly_faster_than(baseline->gpu) || baseline->gpu.clearly_faster_than(row->gpu);
    text += format("  %-16s %6.2fx time %-5s %7zu flips  depth p99 %8.2e  normal p99 %8.2e deg\n",
                   row->variant.c_str(), row->gpu.median_ms / baseline->gpu.median_ms, apart ? "" : "alike",
                   row->error.hit_mismatches, row->error.depth_p99, row->error.normal_deg_p99);
  }
  return text;
}

// The "+..." rows: each extra output's cost beside the default (whole frames on the host, readback
// and the host's derivation included) and its error against the reference's.
std::string outputs_summary(const BenchSceneResult& scene) {
  const BenchRow* baseline = nullptr;
  std::string lines;
  for (const auto& row : scene.rows) {
    if (row.variant == "default") baseline = &row;
    if (!row.outputs.compared) continue;
    lines += format("  %-16s %8.2f ms %+8.2f ms", row.variant.c_str(), row.frame_median_ms,
                    baseline ? row.frame_median_ms - baseline->frame_median_ms : 0.0);
    for (const OutputErrorField& field : output_error_fields()) {
      lines += field.count ? format("  %s %6llu off", field.label.c_str(),
                                    static_cast<unsigned long long>(row.outputs.counts.at(field.name)))
                           : format("  %s %8.2e%s", field.label.c_str(), row.outputs.measures.at(field.name),
                                    field.degrees ? " deg" : "");
    }
    lines += "\n";
  }
  if (lines.empty()) return "";
  return format("%s: outputs beside depth and normal: frame time (host%s), then the error of each against the reference's "
                "(relative p99s, max for weights and texture coordinates):\n",
                short_name(scene.name, 24).c_str(), baseline ? ", and its difference from default's" : "") +
         lines;
}

}  // namespace

std::string build_version() { return VKRAY_VERSION; }
std::string build_commit() { return VKRAY_GIT_COMMIT; }

BenchReport new_bench_report(const GpuDeviceInfo& device, std::string suite, uint32_t frames) {
  BenchReport report;
  report.vkray_version = build_version();
  report.git_commit = build_commit();
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
  add_geometry(fnv, scene);
  return format("%016" PRIx64, fnv.hash);
}

std::string bench_table_legend(bool wide) {
  return wide ? "gpu med/min/max: GPU ms per frame (Embree: the CPU's wall time); frame ms: host wall time with readback;\n"
                "flips: hit/miss differences from the double-precision reference; depth: relative error; norm: degrees;\n"
                "B/tri: device bytes a triangle; unfin: rays finished on the CPU; *: on the Pareto front of time and error\n"
              : "ms: GPU time per frame, median; min-max: its spread over the frames (Embree: the CPU's wall time);\n"
                "flips: hit/miss differences from the double-precision reference; depth: relative error;\n"
                "normal: degrees; B/tri: device bytes a triangle; *: on the Pareto front of time and error, where a\n"
                "row is faster only if its spread lies below the other's (--wide, --json or --csv: every figure)\n";
}

std::string bench_table_header(bool wide) {
  if (wide) {
    return format("%-24s %-18s %9s %6s %8s %8s %8s %8s %8s %8s %7s %6s %9s %9s %9s %9s\n", "scene", "variant", "triangles",
                  "B/tri", "build ms", "gpu med", "gpu min", "gpu max", "frame ms", "Mrays/s", "flips", "unfin", "depth p99",
                  "depth max", "norm p99", "norm max");
  }
  return format("%-18s %-17s %9s %13s %6s %7s %9s %9s\n", "scene", "variant", "ms", "min-max", "B/tri", "flips",
                "depth p99", "normal p99");
}

std::string bench_table_rows(const BenchSceneResult& scene, bool wide) {
  std::string text;
  for (const auto& row : scene.rows) {
    const double bytes_per_triangle =
        row.stats.triangles ? static_cast<double>(row.stats.geometry_bytes) / row.stats.triangles : 0.0;
    const std::string variant = row.variant + (row.pareto ? " *" : "");
    const std::string bytes = row.on_gpu && row.stats.triangles ? format("%6.1f", bytes_per_triangle) : format("%6s", "");
    if (!wide) {
      const std::string spread = format("%.2f-%.2f", row.gpu.min_ms, row.gpu.max_ms);
      text += format("%-18s %-17s %9.2f %13s %s %7zu %9.2e %9.2e\n", short_name(scene.name, 18).c_str(),
                     variant.c_str(), row.gpu.median_ms, spread.c_str(), bytes.c_str(), row.error.hit_mismatches,
                     row.error.depth_p99, row.error.normal_deg_p99);
    } else if (row.on_gpu) {
      text += format("%-24s %-18s %9u %s %8.1f %8.2f %8.2f %8.2f %8.2f %8.2f %7zu %6" PRIu64 " %9.2e %9.2e %9.2e %9.2e\n",
                     scene.name.c_str(), variant.c_str(), row.stats.triangles, bytes.c_str(), row.bvh_build_ms,
                     row.gpu.median_ms, row.gpu.min_ms, row.gpu.max_ms, row.frame_median_ms, row.mrays_per_s,
                     row.error.hit_mismatches, row.unfinished_rays, row.error.depth_p99, row.error.depth_max,
                     row.error.normal_deg_p99, row.error.normal_deg_max);
    } else {
      text += format("%-24s %-18s %9s %6s %8.1f %8.2f %8.2f %8.2f %8s %8.2f %7zu %6s %9.2e %9.2e %9.2e %9.2e\n",
                     scene.name.c_str(), variant.c_str(), "", "", row.bvh_build_ms, row.gpu.median_ms, row.gpu.min_ms,
                     row.gpu.max_ms, "", row.mrays_per_s, row.error.hit_mismatches, "", row.error.depth_p99, row.error.depth_max,
                     row.error.normal_deg_p99, row.error.normal_deg_max);
    }
  }
  text += pareto_summary(scene);
  text += outputs_summary(scene);
  for (const auto& skipped : scene.skipped) text += scene.name + ": skipped " + skipped + "\n";
  return text;
}

namespace {

// What every report file starts with: the build, the device and what was run; `schema` tells the
// image suites' files from the rays suite's.
Json report_json(const BenchReport& report, const char* schema) {
  return {{"schema", schema},
          {"vkray_version", report.vkray_version},
          {"git_commit", report.git_commit},
          {"device",
           {{"name", report.device},
            {"type", report.device_type},
            {"driver", report.driver},
            {"api_version", report.api_version}}},
          {"suite", report.suite},
          {"frames", report.frames}};
}

// The same as the first columns of every CSV line.
const char* const report_csv_header = "vkray_version,git_commit,device,driver,suite,frames";
std::string report_csv_cells(const BenchReport& report) {
  return csv_quoted(report.vkray_version) + "," + report.git_commit + "," + csv_quoted(report.device) + "," +
         csv_quoted(report.driver) + "," + report.suite + "," + std::to_string(report.frames);
}

}  // namespace

std::string bench_json(const BenchReport& report) {
  Json scenes = Json::array();
  for (const auto& scene : report.scenes) {
    Json rows = Json::array();
    for (const auto& row : scene.rows) rows.push_back(row_json(row, row_fields()));
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
  Json json = report_json(report, bench_schema);
  json["scenes"] = scenes;
  return json.dump(2) + "\n";
}

std::string bench_csv(const BenchReport& report) {
  std::string text = std::string(report_csv_header) + ",scene,scene_hash,width,height";
  for (const auto& field : row_fields()) text += std::string(",") + field.name;
  text += "\n";
  for (const auto& scene : report.scenes) {
    for (const auto& row : scene.rows) {
      text += report_csv_cells(report) + "," + csv_quoted(scene.name) + "," + scene.hash + "," +
              std::to_string(scene.width) + "," + std::to_string(scene.height);
      for (const auto& field : row_fields()) text += "," + csv_cell(row, field);
      text += "\n";
    }
  }
  return text;
}

std::string given_rays_json(const BenchReport& report) {
  Json rows = Json::array();
  for (const auto& result : report.given_rays) {
    Json row = {{"scene", result.scene}, {"scene_hash", result.scene_hash}};
    row.update(row_json(result.row, given_rays_fields()));
    rows.push_back(row);
  }
  Json json = report_json(report, given_rays_schema);
  json["rows"] = rows;
  return json.dump(2) + "\n";
}

std::string given_rays_csv(const BenchReport& report) {
  std::string text = std::string(report_csv_header) + ",scene,scene_hash";
  for (const auto& field : given_rays_fields()) text += std::string(",") + field.name;
  text += "\n";
  for (const auto& result : report.given_rays) {
    text += report_csv_cells(report) + "," + csv_quoted(result.scene) + "," + result.scene_hash;
    for (const auto& field : given_rays_fields()) text += "," + csv_cell(result.row, field);
    text += "\n";
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
        for (const auto& field : row_fields()) {
          where = "scenes[" + std::to_string(s) + "].rows[" + std::to_string(r) + "]." + field.name;
          // A file from before an output existed lacks its error field: it stays 0 there.
          const bool output_field = std::any_of(output_error_fields().begin(), output_error_fields().end(),
                                                [&](const OutputErrorField& f) { return f.name == field.name; });
          if (output_field && !row_json.contains(field.name)) continue;
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
  // Scenes pair by name, image size and hash: two different meshes both called mesh.obj, or one
  // mesh seen from another camera, are not the same measurement.
  auto same_scene = [](const BenchSceneResult& a, const BenchSceneResult& b) {
    return a.name == b.name && a.width == b.width && a.height == b.height && a.hash == b.hash;
  };
  auto label = [](const BenchSceneResult& scene) {
    return scene.name + " (" + std::to_string(scene.width) + "x" + std::to_string(scene.height) + ", hash " + scene.hash + ")";
  };
  std::vector<std::string> unpaired;
  for (const auto& scene_a : before.scenes) {
    if (std::none_of(after.scenes.begin(), after.scenes.end(), [&](const auto& b) { return same_scene(scene_a, b); })) {
      unpaired.push_back("only in A: " + label(scene_a));
    }
  }
  size_t matched = 0;
  for (const auto& scene_b : after.scenes) {
    const auto scene_a = std::find_if(before.scenes.begin(), before.scenes.end(),
                                      [&](const auto& a) { return same_scene(a, scene_b); });
    if (scene_a == before.scenes.end()) {
      unpaired.push_back("only in B: " + label(scene_b));
      continue;
    }
    for (const auto& row_b : scene_b.rows) {
      const auto row_a = std::find_if(scene_a->rows.begin(), scene_a->rows.end(),
                                      [&](const BenchRow& row) { return row.variant == row_b.variant; });
      if (row_a == scene_a->rows.end()) {
        unpaired.push_back("only in B: " + scene_b.name + " " + row_b.variant);
        continue;
      }
      ++matched;
      text += format("%-24s %-16s %10.3f %10.3f %s %7zu %7zu %9.2e %9.2e %s %9.2e %9.2e %s\n", scene_b.name.c_str(),
                     row_b.variant.c_str(), row_a->gpu.median_ms, row_b.gpu.median_ms,
                     ratio(row_b.gpu.median_ms, row_a->gpu.median_ms).c_str(), row_a->error.hit_mismatches,
                     row_b.error.hit_mismatches, row_a->error.depth_p99, row_b.error.depth_p99,
                     ratio(row_b.error.depth_p99, row_a->error.depth_p99).c_str(), row_a->error.normal_deg_p99,
                     row_b.error.normal_deg_p99, ratio(row_b.error.normal_deg_p99, row_a->error.normal_deg_p99).c_str());
    }
    for (const auto& row_a : scene_a->rows) {
      if (std::none_of(scene_b.rows.begin(), scene_b.rows.end(), [&](const BenchRow& row) { return row.variant == row_a.variant; })) {
        unpaired.push_back("only in A: " + scene_a->name + " " + row_a.variant);
      }
    }
  }
  if (matched == 0) text += "no row in common (rows pair by scene name, image size, scene hash and variant)\n";
  for (const auto& line : unpaired) text += "not compared, " + line + "\n";
  return text;
}

}  // namespace vkray
