// Rendering many views of one scene in one run: the scene uploaded and the pipeline made once, each
// view only a new camera. The device renders the next view while writer threads write the last
// ones, through a queue that blocks rather than grows; every file is written whole or not at all,
// and the manifest gets a view's record once its files are in place, so that a run stopped at any
// moment and started again ends with the same files.
#pragma once

#include "engine/io/image_io.hpp"
#include "engine/render/renderer.hpp"
#include "engine/views/output_pattern.hpp"
#include "engine/views/view_list.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vkray {

// Which views this process renders: every view whose index is `index` modulo `count` (a Slurm array
// task or a Kubernetes Indexed Job's pod each take one shard).
struct Shard {
  uint32_t index = 0;
  uint32_t count = 1;
  bool holds(uint32_t view) const { return view % count == index; }
};

struct ViewBatch {
  std::vector<View> views;  // view k is views[k]: its camera, and instances placed for it alone
  uint32_t width = 0, height = 0;
  AovSet aovs;
  OutputPattern exr{"view-{index}.exr", "-o"};
  std::optional<OutputPattern> png;  // a preview per view, where given
  OutputSettings output_settings;
  std::filesystem::path manifest;
  Shard shard;
  std::string scene;       // geometry_hash of the scene, recorded with each view
  std::vector<std::string> objects;  // object_names of the scene, recorded with each view's mesh_id
  Mask mask = every_mask_bit;  // the rays' (Renderer::set_ray_mask), recorded with each view where not every bit
  bool overwrite = false;  // render views whose files exist too (and start the manifest afresh)
  unsigned writers = 0;    // threads writing files, a view each (0: writer_threads's choice); the queue holds one frame more
  // Called with each view's index before it renders; what it throws stops the batch as a failed
  // render does. The tests inject faults here (a device lost at view k).
  std::function<void(uint32_t)> before_render;
};

struct ViewBatchProgress {
  uint32_t done = 0;      // views rendered and written in this run
  uint32_t to_do = 0;     // views this run renders (its shard's, less those already complete)
  double seconds = 0.0;   // since the first render
};

struct ViewBatchSummary {
  uint32_t rendered = 0;
  uint32_t skipped = 0;   // complete already (recorded in the manifest, files in place): left alone
  double seconds = 0.0;   // from the first render to the last file in place
  double render_seconds = 0.0;      // the device's part: renders and readbacks
  double queue_wait_seconds = 0.0;  // the device waiting for a writer (the writing took longer)
  size_t beyond_png16_samples = 0;  // png16 depths past 65535 steps (stored as 0), and their views
  uint32_t beyond_png16_views = 0;
  unsigned writers = 0;             // threads that wrote the files
};

// How many views are written at once where the batch does not say: one a host thread (each file is
// encoded on its writer's thread alone), as long as the frames held stay within a quarter of the
// host's memory: each writer's, about as much again for its encoder, the queue's one more than the
// writers and the one rendering (3 w + 2 frames of Frame::bytes). At least one.
unsigned writer_threads(unsigned host_threads, uint64_t frame_bytes, uint64_t host_memory_bytes);

// Throws InputError where the batch's names would have two views, two files of one view, or a view
// and the manifest write one file ("d{index}/../v.exr", a png16 depth named as the preview, a
// manifest named like a view's file: views overwritten, or a view counted complete that never
// rendered), or where its manifest is a file that is no manifest (check_is_a_manifest), or a name
// over 255 bytes, or where a view this run would render has a link, a device, a FIFO or a read-only
// file at one of its names (refuse_to_replace). Every view of every shard is checked. render_views
// checks this first; a front end calls it before it opens a device.
void check_view_names(const ViewBatch& batch);

// Creates the output folders, checks that they take files, then renders and writes the shard's
// views that are not complete, each with the instances it places moved there (set_transforms; the
// others where the renderer's scene had them when called). `progress` is called after each view is
// written, on a writer thread. Throws std::runtime_error for a file that cannot be written (after
// the views before it are written and recorded), InputError for a batch without an index in its
// output pattern or whose names give two views, or a view and the manifest, one file, or whose
// views place instances wrongly (check_view_poses).
ViewBatchSummary render_views(Renderer& renderer, const ViewBatch& batch,
                              const std::function<void(const ViewBatchProgress&)>& progress = {});

}  // namespace vkray
