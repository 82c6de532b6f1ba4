#include "engine/views/manifest_export.hpp"

#include "engine/scene/scene.hpp"
#include "engine/views/manifest.hpp"

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

namespace vkray {
namespace {

using Json = nlohmann::json;

// vkray's pixel centres are at integer coordinates, COLMAP's and NeRF's half a pixel further.
constexpr double pixel_centre_shift = 0.5;

struct PinholeView {
  uint32_t index = 0;
  std::string image;  // the EXR, relative to the export's folder
  uint32_t width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;  // vkray's (OpenCV's) convention
  glm::dmat4 world_to_camera{1.0};        // OpenCV's axes
};

// The camera of one record (JSON errors are the caller's to name).
void read_pinhole(const Json& record, const std::filesystem::path& manifest, PinholeView& view) {
  if (!record.contains("intrinsics")) {
    throw InputError(manifest.string() + ": view " + std::to_string(view.index) +
                     " has no pinhole camera (orthographic and panoramic views cannot be exported)");
  }
  // The view's image: its EXR, or its first file of one output (--format npy, png16).
  view.image = record.contains("exr") ? record.at("exr").get<std::string>() : record.at("files").begin()->get<std::string>();
  const std::string where = manifest.string() + ": view " + std::to_string(view.index) + ": ";
  for (const char* side : {"width", "height"}) {
    const Json& pixels = record.at(side);
    if (!pixels.is_number_unsigned() || pixels.get<uint64_t>() == 0 || pixels.get<uint64_t>() > max_image_side) {
      throw InputError(where + side + " is " + pixels.dump() + ", not a side of 1 to " + std::to_string(max_image_side) + " pixels");
    }
  }
  view.width = record.at("width").get<uint32_t>();
  view.height = record.at("height").get<uint32_t>();
  const Json& intrinsics = record.at("intrinsics");
  view.fx = intrinsics.at("fx").get<double>(), view.fy = intrinsics.at("fy").get<double>();
  view.cx = intrinsics.at("cx").get<double>(), view.cy = intrinsics.at("cy").get<double>();
  if (!(view.fx > 0.0 && view.fy > 0.0 && std::isfinite(view.fx) && std::isfinite(view.fy) && std::isfinite(view.cx) &&
        std::isfinite(view.cy))) {
    throw InputError(where + "intrinsics " + intrinsics.dump() + " are not a pinhole's (fx and fy positive, all finite)");
  }
  const Json& rows = record.at("world_to_camera");
  for (int row = 0; row < 4; ++row) {
    for (int column = 0; column < 4; ++column) view.world_to_camera[column][row] = rows.at(row).at(column).get<double>();
  }
  // A camera's pose: a rotation and a translation, which is what NeRF's and COLMAP's readers take
  // (a singular matrix would be written as null and nan). vkray writes rotations orthonormal to
  // double's rounding; 1e-6 still takes a record rounded to 7 digits by another program.
  const glm::dmat3 rotation(view.world_to_camera);
  const glm::dmat3 drift = glm::transpose(rotation) * rotation - glm::dmat3(1.0);
  bool pose = glm::determinant(rotation) > 0.0 && view.world_to_camera[0][3] == 0.0 && view.world_to_camera[1][3] == 0.0 &&
              view.world_to_camera[2][3] == 0.0 && view.world_to_camera[3][3] == 1.0 &&
              std::isfinite(view.world_to_camera[3].x) && std::isfinite(view.world_to_camera[3].y) && std::isfinite(view.world_to_camera[3].z);
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) pose = pose && std::abs(drift[c][r]) <= 1e-6;
  }
  if (!pose) throw InputError(where + "world_to_camera is no camera pose (a rotation and a translation, last row 0 0 0 1)");
}

std::vector<PinholeView> pinhole_views(const std::filesystem::path& manifest, const std::filesystem::path& folder) {
  // The merge's reading: a complete set in index order, file names relative to `folder`.
  const std::string records = merge_manifests({manifest}, folder / "transforms.json");
  std::vector<PinholeView> views;
  for (size_t start = 0; start < records.size();) {
    const size_t end = records.find('\n', start);
    const Json record = Json::parse(records.substr(start, end - start));
    start = end + 1;
    PinholeView view;
    view.index = record.at("index").get<uint32_t>();
    try {
      read_pinhole(record, manifest, view);
    } catch (const Json::exception& error) {  // a record some other program wrote or changed
      throw InputError(manifest.string() + ": view " + std::to_string(view.index) + ": " + error.what());
    }
    views.push_back(std::move(view));
  }
  return views;
}


std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// The unit quaternion (w, x, y, z) of a rotation matrix, w >= 0: from the largest of the four
// squared components, which keeps the division well away from 0 (Shepperd, "Quaternion from
// Rotation Matrix", J. Guidance and Control 1(3), 1978).
glm::dvec4 quaternion_of(const glm::dmat3& r) {
  const double trace = r[0][0] + r[1][1] + r[2][2];
  glm::dvec4 q;  // w, x, y, z; r[column][row]
  if (trace >= r[0][0] && trace >= r[1][1] && trace >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    q = {0.25 * s, (r[1][2] - r[2][1]) / s, (r[2][0] - r[0][2]) / s, (r[0][1] - r[1][0]) / s};
  } else if (r[0][0] >= r[1][1] && r[0][0] >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]);
    q = {(r[1][2] - r[2][1]) / s, 0.25 * s, (r[1][0] + r[0][1]) / s, (r[2][0] + r[0][2]) / s};
  } else if (r[1][1] >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]);
    q = {(r[2][0] - r[0][2]) / s, (r[1][0] + r[0][1]) / s, 0.25 * s, (r[2][1] + r[1][2]) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]);
    q = {(r[0][1] - r[1][0]) / s, (r[2][0] + r[0][2]) / s, (r[2][1] + r[1][2]) / s, 0.25 * s};
  }
  q /= glm::length(q);
  return q.x < 0.0 ? -q : q;
}

std::string nerf_transforms(const std::vector<PinholeView>& views) {
  // NeRF's camera axes from OpenCV's: y and z negated.
  const glm::dmat4 opencv_to_opengl(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
  auto camera_of = [](const PinholeView& view) { return std::tuple{view.fx, view.fy, view.cx, view.cy, view.width, view.height}; };
  auto put_intrinsics = [](const PinholeView& view, nlohmann::ordered_json& into) {
    into["fl_x"] = view.fx;
    into["fl_y"] = view.fy;
    into["cx"] = view.cx + pixel_centre_shift;
    into["cy"] = view.cy + pixel_centre_shift;
    into["w"] = view.width;
    into["h"] = view.height;
  };
  // Shared intrinsics at the top, as the format's readers expect; per frame where views differ.
  bool shared = true;
  for (const PinholeView& view : views) shared = shared && camera_of(view) == camera_of(views.front());
  nlohmann::ordered_json transforms;
  transforms["camera_model"] = "OPENCV";  // with no distortion: a pinhole
  if (shared) put_intrinsics(views.front(), transforms);
  transforms["frames"] = nlohmann::ordered_json::array();
  for (const PinholeView& view : views) {
    const glm::dmat4 camera_to_world = glm::inverse(view.world_to_camera) * opencv_to_opengl;
    nlohmann::ordered_json frame;
    frame["file_path"] = view.image;
    std::vector<std::array<double, 4>> rows(4);
    for (int row = 0; row < 4; ++row) {
      for (int column = 0; column < 4; ++column) rows[row][column] = camera_to_world[column][row];
    }
    frame["transform_matrix"] = rows;
    if (!shared) put_intrinsics(view, frame);
    transforms["frames"].push_back(frame);
  }
  return transforms.dump(2) + "\n";
}

std::vector<std::pair<std::string, std::string>> colmap_model(const std::vector<PinholeView>& views) {
  std::map<std::tuple<uint32_t, uint32_t, double, double, double, double>, uint32_t> camera_ids;
  std::string cameras = "# Camera list with one line of data per camera:\n"
                        "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
  std::string images = "# Image list with two lines of data per image:\n"
                       "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                       "#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
  for (const PinholeView& view : views) {
    const auto key = std::tuple{view.width, view.height, view.fx, view.fy, view.cx, view.cy};
    auto [found, added] = camera_ids.emplace(key, static_cast<uint32_t>(camera_ids.size() + 1));
    if (added) {
      cameras += std::to_string(found->second) + " PINHOLE " + std::to_string(view.width) + " " +
                 std::to_string(view.height) + " " + number(view.fx) + " " + number(view.fy) + " " +
                 number(view.cx + pixel_centre_shift) + " " + number(view.cy + pixel_centre_shift) + "\n";
    }
    const glm::dvec4 q = quaternion_of(glm::dmat3(view.world_to_camera));
    const glm::dvec3 t(view.world_to_camera[3]);
    images += std::to_string(view.index + 1) + " " + number(q.x) + " " + number(q.y) + " " + number(q.z) + " " +
              number(q.w) + " " + number(t.x) + " " + number(t.y) + " " + number(t.z) + " " +
              std::to_string(found->second) + " " + view.image + "\n\n";
  }
  return {{"cameras.txt", cameras},
          {"images.txt", images},
          {"points3D.txt", "# 3D point list (none: vkray knows the geometry, not tracked points)\n"}};
}

}  // namespace

ManifestFormat manifest_format_from_name(const std::string& name) {
  if (name == "nerf") return ManifestFormat::nerf;
  if (name == "colmap") return ManifestFormat::colmap;
  throw InputError("--format: unknown format '" + name + "' (choose from nerf, colmap)");
}

std::vector<std::pair<std::string, std::string>> export_manifest(const std::filesystem::path& manifest,
                                                                 ManifestFormat format,
                                                                 const std::filesystem::path& folder) {
  const std::vector<PinholeView> views = pinhole_views(manifest, folder);
  if (format == ManifestFormat::nerf) return {{"transforms.json", nerf_transforms(views)}};
  // COLMAP's images.txt ends an image's NAME at the next space (its ReadImagesText reads the line
  // field by field): a name holding whitespace would be cut short, naming another file or none.
  for (const PinholeView& view : views) {
    if (view.image.find_first_of(" \t\n\r") != std::string::npos) {
      throw InputError(manifest.string() + ": view " + std::to_string(view.index) + ": COLMAP reads a file name up to its first space, and '" +
                       view.image + "' holds one: render to names without spaces, or export --format nerf");
    }
  }
  return colmap_model(views);
}

}  // namespace vkray
