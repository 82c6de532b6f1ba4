// The manifest of a many-view render: JSON Lines, one record a view, appended as each view's files
// are in place, so that it is valid after any interruption. Every record is one line:
//
//   {"index": 42, "views": 100, "exr": "view-00042.exr", "png": "view-00042.png", "width": 1920, "height": 1080,
//    "outputs": "depth,normal", "scene": "3f2a...", "camera": {"from": [...], "to": [...], "up": [...], "fovy": 40},
//    "intrinsics": {"fx": ..., "fy": ..., "cx": ..., "cy": ...},
//    "world_to_camera": [[...], [...], [...], [0, 0, 0, 1]]}
//
// "exr" where the outputs are one EXR, else "files": {"depth": "view-00042.depth.npy", ...}, one
// file an output; "png" only where previews are written; "objects" (what each mesh_id stands for: a mesh's file or
// glTF node, "spheres[i]", "planes[i]") only with the mesh-id output; "mask" (the rays') where not 255; file names relative to the manifest's folder; "scene" the
// geometry's hash (geometry_hash); the camera's keys as engine/scene/camera_description.hpp
// describes them (docs/many-views.md).
#pragma once

#include "engine/io/array_files.hpp"
#include "engine/scene/camera.hpp"
#include "engine/scene/scene.hpp"
#include "engine/views/manifest_record.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <map>
#include <string>
#include <vector>

namespace vkray {

struct ViewRecord {
  uint32_t index = 0;
  uint32_t views = 0;  // in the whole run, every shard's: what a merge checks its parts against
  std::filesystem::path exr;       // the EXR, or the -o name the files below are named after
  std::vector<OutputFile> files;   // one file an output (--format npy, png16): the record's "files"
  std::optional<std::filesystem::path> png;
  Camera camera;
  uint32_t width = 0, height = 0;
  std::string outputs;  // AovSet::names(): "depth,normal"
  std::string scene;    // geometry_hash of the scene: a resumed run on another scene is refused
  std::vector<std::string> objects;  // what each mesh_id stands for (object_names), with that output
  // How the values are stored, each only where it is not the default: a resumed run that stored
  // them otherwise would mix two encodings in one dataset.
  std::string half;                  // AovSet::names() of --half
  std::optional<float> miss;         // --miss, where not +inf
  std::optional<double> depth_step;  // --depth-step, with png16 files
  // The rays' mask (--mask), where not every bit: a resumed run with another would mix two scenes.
  std::optional<uint32_t> mask;
  // The instances the view placed anew (a views file's "instances"), where it placed any: the
  // record's "instances", [{"instance": k, "transform": 4 rows of 4}], the dataset's object poses.
  InstancePoses poses;
};

// One line, without its newline; file names relative to `folder`.
std::string manifest_line(const ViewRecord& record, const std::filesystem::path& folder);

// Throws InputError unless `path` is what a manifest writer may continue or start afresh: nothing
// yet, or a regular file whose first line is a record (or the start of one, cut off). Any other file
// named by mistake (the views file, a model, a device node, a FIFO) is refused before a byte of it
// is read past its first line or written.
void check_is_a_manifest(const std::filesystem::path& path);

// The whole records of the manifest at `path`, by index (none where there is no file yet); a line cut
// off by an interruption is left out. Throws InputError as check_is_a_manifest does.
std::map<uint32_t, std::string> read_manifest_records(const std::filesystem::path& path);

// A manifest being written: opened, it keeps the complete records already there (a line cut off by
// an interruption is dropped) unless `fresh`, which starts it empty. It is held under an exclusive
// flock while open: a second writer of the same file (two shards given one --manifest) gets
// InputError. Each append writes one whole
// line with a single write(). Throws InputError as check_is_a_manifest does, std::runtime_error
// naming the file where it cannot be read or written.
class ManifestWriter {
 public:
  ManifestWriter(const std::filesystem::path& path, bool fresh);
  ~ManifestWriter();
  ManifestWriter(const ManifestWriter&) = delete;
  ManifestWriter& operator=(const ManifestWriter&) = delete;

  // The record of view `index` as the manifest holds it, or null.
  const std::string* recorded(uint32_t index) const {
    const auto found = recorded_.find(index);
    return found == recorded_.end() ? nullptr : &found->second;
  }
  const std::map<uint32_t, std::string>& records() const { return recorded_; }
  void append(const ViewRecord& record);
  const std::filesystem::path& path() const { return path_; }

 private:
  void rewrite(const std::string& text);  // the whole manifest, in place

  std::filesystem::path path_;
  int descriptor_ = -1;
  std::map<uint32_t, std::string> recorded_;  // index -> its line
};

// What differs between a view's record from an earlier run and the record this run would write:
// "" where they agree, else each change ("the size: 64x48 then, 128x96 now"). The size, the outputs,
// the scene, the camera, the instances placed and how values are stored (half, miss, depth_step)
// count; the file names do not (the same pattern gives the same ones). A size, outputs, scene or
// camera key an older vkray did not write is not compared.
std::string record_changes(const std::string& recorded, const std::string& now);

// The parts' records in index order, each index once (identical copies of a record merge; two
// different records of one index are an error), as the text of the manifest `output`: file names
// relative to its folder, rewritten where a part lies in another. Throws InputError naming the
// file and line of a line that is no record, and of a conflicting one.
std::string merge_manifests(const std::vector<std::filesystem::path>& parts, const std::filesystem::path& output);

}  // namespace vkray
