#include "engine/views/manifest.hpp"

#include "engine/io/image_io.hpp"
#include "engine/scene/camera_description.hpp"
#include "engine/scene/scene.hpp"
#include "engine/views/manifest_record.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace vkray {
namespace {

std::string relative_name(const std::filesystem::path& file, const std::filesystem::path& folder) {
  // A manifest named without a folder ("manifest.jsonl", the default) has the parent "", which
  // std::filesystem::absolute refuses: it is the working folder.
  const std::filesystem::path base = folder.empty() ? std::filesystem::path(".") : folder;
  const std::filesystem::path relative = std::filesystem::absolute(file).lexically_normal().lexically_relative(
      std::filesystem::absolute(base).lexically_normal());
  return relative.empty() ? file.string() : relative.string();
}

// A miss value as --miss takes it: "nan", "-inf", or the number.
std::string miss_text(float miss) {
  if (std::isnan(miss)) return "nan";
  if (std::isinf(miss)) return miss > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", miss);
  return text;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

// The records of a manifest's text, and whether anything else was there (a line cut off, or one
// that is no record).
struct ManifestText {
  std::map<uint32_t, std::string> records;
  bool dropped = false;
};

ManifestText read_manifest_text(const std::string& text) {
  ManifestText read;
  for (size_t start = 0; start < text.size();) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      read.dropped = true;
      break;
    }
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    if (const auto index = manifest_line_index(line)) {
      read.records[*index] = line;
    } else {
      read.dropped = read.dropped || !line.empty();
    }
  }
  return read;
}

}  // namespace

std::map<uint32_t, std::string> read_manifest_records(const std::filesystem::path& path) {
  check_is_a_manifest(path);
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return {};
  return read_manifest_text(read_file(path)).records;
}

std::string manifest_line(const ViewRecord& record, const std::filesystem::path& folder) {
  nlohmann::ordered_json line;  // keys in this order, the index first
  line["index"] = record.index;
  line["views"] = record.views;
  if (record.files.empty()) {
    line["exr"] = relative_name(record.exr, folder);
  } else {
    nlohmann::ordered_json& files = line["files"];
    for (const OutputFile& file : record.files) files[output_info(file.aov).name] = relative_name(file.path, folder);
  }
  if (record.png) line["png"] = relative_name(*record.png, folder);
  line["width"] = record.width;
  line["height"] = record.height;
  line["outputs"] = record.outputs;
  line["scene"] = record.scene;
  if (!record.objects.empty()) line["objects"] = record.objects;
  if (!record.half.empty()) line["half"] = record.half;
  if (record.miss) line["miss"] = miss_text(*record.miss);
  if (record.depth_step) line["depth_step"] = *record.depth_step;
  if (record.mask) line["mask"] = *record.mask;
  const nlohmann::ordered_json camera = camera_description(record.camera, record.width, record.height);
  for (auto key = camera.begin(); key != camera.end(); ++key) line[key.key()] = key.value();
  for (size_t k = 0; k < record.poses.instances.size(); ++k) {
    const glm::dmat4& m = record.poses.transforms[k];  // columns; written as rows, as world_to_camera
    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    for (int row = 0; row < 4; ++row) rows.push_back({m[0][row], m[1][row], m[2][row], m[3][row]});
    line["instances"].push_back({{"instance", record.poses.instances[k]}, {"transform", std::move(rows)}});
  }
  return line.dump();
}

void check_is_a_manifest(const std::filesystem::path& path) {
  // A record is under 10 KB (two paths and a camera): the first 64 KiB hold a manifest's first line.
  constexpr size_t first_line_room = 64 * 1024;
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) return;
  const std::string refused = path.string() + ": is not a manifest (";
  const std::string remedy = "): --manifest names a manifest to continue or a new file";
  if (!std::filesystem::is_regular_file(status)) throw InputError(refused + "not a regular file" + remedy);
  std::ifstream file(path, std::ios::binary);
  std::string start(first_line_room, '\0');
  file.read(start.data(), static_cast<std::streamsize>(start.size()));
  start.resize(static_cast<size_t>(file.gcount()));
  if (start.empty()) return;
  const size_t end = start.find('\n');
  const bool first_line_is_record = end == std::string::npos
                                        ? start.size() < first_line_room && start.starts_with("{\"index\":")
                                        : manifest_line_index(start.substr(0, end)).has_value();
  if (!first_line_is_record) throw InputError(refused + "its first line is no view record" + remedy);
}

ManifestWriter::ManifestWriter(const std::filesystem::path& path, bool fresh) : path_(path) {
  check_is_a_manifest(path);
  descriptor_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (descriptor_ < 0) throw std::runtime_error(path.string() + ": cannot open the manifest: " + std::strerror(errno));
  // One writer a manifest, held for the run: shards given one --manifest would otherwise write over
  // each other's records. Changes below are made in place, under the lock (a rename would hand the
  // next writer a new, unlocked file while this one appends to the old).
  if (::flock(descriptor_, LOCK_EX | LOCK_NB) != 0) {
    ::close(descriptor_);
    descriptor_ = -1;
    throw InputError(path.string() + ": another vkray is writing this manifest (each shard writes its own: leave out "
                     "--manifest, or give each shard one)");
  }
  if (fresh) {
    rewrite("");
  } else {
    // Keep the whole records; a line an interruption cut off (no newline, or no record) goes. A
    // crash while rewriting loses records, not views: they are rendered and recorded again.
    const ManifestText text = read_manifest_text(read_file(path));
    recorded_ = text.records;
    if (text.dropped) {
      std::string kept;
      for (const auto& [index, line] : recorded_) kept += line + '\n';
      rewrite(kept);
    }
  }
}

void ManifestWriter::rewrite(const std::string& text) {
  if (::ftruncate(descriptor_, 0) != 0) {
    throw std::runtime_error(path_.string() + ": cannot write the manifest: " + std::strerror(errno));
  }
  const ssize_t written = ::write(descriptor_, text.data(), text.size());
  if (written != static_cast<ssize_t>(text.size())) {
    throw std::runtime_error(path_.string() + ": cannot write the manifest: " + (written < 0 ? std::strerror(errno) : "short write"));
  }
}

ManifestWriter::~ManifestWriter() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

void ManifestWriter::append(const ViewRecord& record) {
  const std::string line = manifest_line(record, path_.parent_path()) + '\n';
  // A view rendered again after its files vanished has its record already: one record an index.
  if (const std::string* recorded = this->recorded(record.index); recorded && *recorded + '\n' == line) return;
  const ssize_t written = ::write(descriptor_, line.data(), line.size());
  if (written != static_cast<ssize_t>(line.size())) {
    throw std::runtime_error(path_.string() + ": cannot append to the manifest: " +
                             (written < 0 ? std::strerror(errno) : "short write"));
  }
  recorded_[record.index] = line.substr(0, line.size() - 1);
}

std::string record_changes(const std::string& recorded, const std::string& now) {
  const nlohmann::json before = nlohmann::json::parse(recorded), after = nlohmann::json::parse(now);
  using Keys = std::vector<const char*>;
  const auto shown = [](const nlohmann::json& record, const Keys& keys) {
    std::string text;
    for (const char* key : keys) {
      if (record.contains(key)) text += (text.empty() ? "" : "x") + (record[key].is_string() ? record[key].get<std::string>() : record[key].dump());
    }
    return text;
  };
  std::string changes;
  const std::pair<const char*, Keys> parts[] = {
      {"the size", {"width", "height"}}, {"the outputs", {"outputs"}}, {"the scene", {"scene"}},
      {"the camera", {"camera", "world_to_camera"}}};  // intrinsics follow from the camera and the size
  for (const auto& [what, keys] : parts) {
    bool compared = true;
    for (const char* key : keys) compared = compared && before.contains(key);
    if (!compared || shown(before, keys) == shown(after, keys)) continue;
    changes += (changes.empty() ? "" : "; ") + std::string(what);
    if (std::string(what) != "the camera") changes += ": " + shown(before, keys) + " then, " + shown(after, keys) + " now";
  }
  // How values are stored, and what the rays see: a key left out holds its default.
  const std::pair<const char*, const char*> storage[] = {{"half", "none"}, {"miss", "inf"}, {"depth_step", "none"}, {"mask", "255"}};
  for (const auto& [key, default_value] : storage) {
    const std::string then = before.contains(key) ? shown(before, {key}) : default_value;
    const std::string now_value = after.contains(key) ? shown(after, {key}) : default_value;
    if (then != now_value) changes += (changes.empty() ? "" : "; ") + std::string(key) + ": " + then + " then, " + now_value + " now";
  }
  // The instances the view placed: none where the key is left out.
  const auto poses = [](const nlohmann::json& record) { return record.contains("instances") ? record["instances"].dump() : ""; };
  if (poses(before) != poses(after)) changes += (changes.empty() ? "" : "; ") + std::string("the instances placed");
  // The kind of files: one EXR, or one file an output (--format), by the extension of the first.
  const auto format = [](const nlohmann::json& record) {
    const bool files = record.contains("files") && record["files"].is_object() && !record["files"].empty() &&
                       record["files"].begin()->is_string();
    return files ? std::filesystem::path(record["files"].begin()->get<std::string>()).extension().string().substr(1) : std::string("exr");
  };
  if (format(before) != format(after)) {
    changes += (changes.empty() ? "" : "; ") + std::string("the format: ") + format(before) + " then, " + format(after) + " now";
  }
  return changes;
}

namespace {

// `line` with its file names made relative to `to` instead of `from` (a merged manifest written to
// another folder than its part's); the line itself where the two folders are one.
std::string with_names_moved(const std::string& line, const std::filesystem::path& from, const std::filesystem::path& to) {
  const auto absolute = [](const std::filesystem::path& folder) {
    return std::filesystem::absolute(folder.empty() ? std::filesystem::path(".") : folder).lexically_normal();
  };
  if (absolute(from) == absolute(to)) return line;
  nlohmann::ordered_json record = nlohmann::ordered_json::parse(line);  // a record: manifest_line_index took it
  for (const char* key : {"exr", "png"}) {
    if (record.contains(key) && record[key].is_string()) {
      record[key] = relative_name(from / record[key].get<std::string>(), to);
    }
  }
  if (record.contains("files") && record["files"].is_object()) {
    for (auto& file : record["files"]) {
      if (file.is_string()) file = relative_name(from / file.get<std::string>(), to);
    }
  }
  return record.dump();
}

// Throws InputError where the records are not every view of one run: parts of runs with other view
// counts, or views missing (a shard that failed, a part not given, --shard-count unlike the Job's
// completions), named. Records of a vkray that wrote no "views" are not checked.
void refuse_a_short_set(const std::map<uint32_t, std::pair<std::string, std::string>>& records) {
  std::optional<std::pair<uint64_t, std::string>> views;  // the run's count, and where it was read
  for (const auto& [index, record] : records) {
    const nlohmann::json parsed = nlohmann::json::parse(record.first);
    if (!parsed.contains("views") || !parsed["views"].is_number_unsigned()) continue;
    const uint64_t count = parsed["views"].get<uint64_t>();
    // Indices are 32-bit: a run has at most 2^32 views, and each record's index lies within its run.
    if (count <= index || count > uint64_t{UINT32_MAX} + 1) {
      throw InputError(record.second + ": view " + std::to_string(index) + " of a run of " + std::to_string(count) +
                       " views: no run of vkray has such a view (the record was changed?)");
    }
    if (!views) views.emplace(count, record.second);
    if (count != views->first) {
      throw InputError(record.second + ": a record of a run of " + std::to_string(count) + " views, where " + views->second +
                       " is of a run of " + std::to_string(views->first) + ": parts of different runs (an older part left in the folder?)");
    }
  }
  if (!views) return;
  // The gaps between the records' indices, in order: as many steps as records, however large the run.
  const uint64_t missing_count = views->first - records.size();
  if (missing_count == 0) return;
  std::string missing;
  size_t listed = 0;
  uint64_t next = 0;
  const auto list_up_to = [&](uint64_t end) {
    for (; next < end && listed < 10; ++next, ++listed) missing += (missing.empty() ? "" : ", ") + std::to_string(next);
    next = end + 1;
  };
  for (const auto& [index, record] : records) list_up_to(index);
  list_up_to(views->first);
  if (missing_count > 10) missing += ", ...";
  throw InputError("the parts hold " + std::to_string(records.size()) + " of the run's " + std::to_string(views->first) +
                   " views; missing: " + missing + " (a shard that failed or was not given: render it, then merge again)");
}

}  // namespace

std::string merge_manifests(const std::vector<std::filesystem::path>& parts, const std::filesystem::path& output) {
  std::map<uint32_t, std::pair<std::string, std::string>> records;  // index -> line, where it came from
  for (const auto& part : parts) {
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(part, error);
    if (std::filesystem::is_directory(status)) throw InputError(part.string() + ": is a folder, not a manifest");
    if (!std::filesystem::exists(status)) throw InputError(part.string() + ": no such manifest");
    if (!std::filesystem::is_regular_file(status)) throw InputError(part.string() + ": is not a regular file, so no manifest");
    const std::string text = read_file(part);
    size_t line_number = 0;
    for (size_t start = 0; start < text.size();) {
      const size_t end = std::min(text.find('\n', start), text.size());
      const std::string line = text.substr(start, end - start);
      start = end + 1;
      ++line_number;
      if (line.empty()) continue;
      const std::string where = part.string() + ":" + std::to_string(line_number);
      const auto index = manifest_line_index(line);
      // A last line without its newline is one an interruption cut off, as resuming takes it: its
      // view counts as missing.
      if (!index && end == text.size()) continue;
      if (!index) throw InputError(where + ": not a view record");
      const std::string moved = with_names_moved(line, part.parent_path(), output.parent_path());
      const auto [found, inserted] = records.emplace(*index, std::pair{moved, where});
      if (!inserted && found->second.first != moved) {
        throw InputError(where + ": view " + std::to_string(*index) + " differs from its record at " + found->second.second);
      }
    }
  }
  // Parts without a record (a shard that wrote nothing yet) are fine beside others, whose run's view
  // count names every view missing; alone they would merge into an empty manifest.
  if (records.empty()) {
    throw InputError(parts.front().string() + (parts.size() > 1 ? " and the other parts hold" : " holds") +
                     " no view record (empty, or the only line cut off): no view to merge");
  }
  refuse_a_short_set(records);
  std::string merged;
  for (const auto& [index, record] : records) merged += record.first + '\n';
  return merged;
}

}  // namespace vkray
