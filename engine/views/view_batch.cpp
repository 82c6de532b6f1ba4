#include "engine/views/view_batch.hpp"

#include "engine/io/image_io.hpp"
#include "engine/stopwatch.hpp"
#include "engine/views/manifest.hpp"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <algorithm>
#include <map>
#include <set>
#include <thread>

#include <unistd.h>

namespace vkray {
namespace {

uint64_t host_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGESIZE);
  return pages > 0 && page_size > 0 ? uint64_t(pages) * uint64_t(page_size) : 0;
}

double seconds_since(Clock::time_point start) { return elapsed_ms(start) / 1e3; }

struct WriteJob {
  uint32_t index;
  Frame frame;
};

// Frames from the device to the writers: at most `capacity` wait, so the device blocks rather than
// memory growing when writing is the slower part. The first writer failure stops everything.
class WriteQueue {
 public:
  explicit WriteQueue(size_t capacity) : capacity_(capacity) {}

  // Waits for room; false once a writer has failed. Returns the seconds it waited.
  bool push(WriteJob job, double& waited_s) {
    const auto start = Clock::now();
    std::unique_lock lock(mutex_);
    room_.wait(lock, [&] { return jobs_.size() < capacity_ || failure_; });
    waited_s += seconds_since(start);
    if (failure_) return false;
    jobs_.push_back(std::move(job));
    work_.notify_one();
    return true;
  }

  // The next job, or nothing once closed and empty (or failed).
  std::optional<WriteJob> pop() {
    std::unique_lock lock(mutex_);
    work_.wait(lock, [&] { return !jobs_.empty() || closed_ || failure_; });
    if (failure_ || jobs_.empty()) return std::nullopt;
    WriteJob job = std::move(jobs_.front());
    jobs_.pop_front();
    room_.notify_one();
    return job;
  }

  void close() {
    const std::lock_guard lock(mutex_);
    closed_ = true;
    work_.notify_all();
  }

  void fail(std::exception_ptr failure) {
    const std::lock_guard lock(mutex_);
    if (!failure_) failure_ = failure;
    room_.notify_all();
    work_.notify_all();
  }

  std::exception_ptr failure() {
    const std::lock_guard lock(mutex_);
    return failure_;
  }

 private:
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable room_, work_;
  std::deque<WriteJob> jobs_;
  bool closed_ = false;
  std::exception_ptr failure_;
};

// The files of view `index`, each named for messages: its outputs' (one EXR, or one an output) and
// its preview.
std::vector<NamedFile> view_outputs(const ViewBatch& batch, uint32_t index) {
  std::vector<NamedFile> files;
  const std::string view = "view " + std::to_string(index) + "'s ";
  for (const OutputFile& file : output_files(batch.exr.path(index), batch.aovs, batch.output_settings.format)) {
    files.push_back({file.path, view + (batch.output_settings.format == FileFormat::exr ? "EXR" : output_info(file.aov).name)});
  }
  if (batch.png) files.push_back({batch.png->path(index), view + "preview"});
  return files;
}

std::vector<std::filesystem::path> view_files(const ViewBatch& batch, uint32_t index) {
  std::vector<std::filesystem::path> files;
  for (NamedFile& file : view_outputs(batch, index)) files.push_back(std::move(file.path));
  return files;
}

// A view is complete once the manifest records it and its files are in place. Files alone are not
// enough: a stray file at a view's name, or one whose record a kill kept from being written, would
// stand for a view this run never wrote.
bool complete(const ViewBatch& batch, uint32_t index, const std::map<uint32_t, std::string>& records) {
  std::error_code error;
  return records.contains(index) &&
         std::ranges::all_of(view_files(batch, index), [&](const auto& file) { return std::filesystem::is_regular_file(file, error); });
}

// The views this run renders: its shard's, less those complete unless it overwrites.
bool to_be_rendered(const ViewBatch& batch, uint32_t index, const std::map<uint32_t, std::string>& records) {
  return batch.shard.holds(index) && (batch.overwrite || !complete(batch, index, records));
}

ViewRecord record_of(const ViewBatch& batch, uint32_t index) {
  ViewRecord record;
  record.index = index;
  record.views = static_cast<uint32_t>(batch.views.size());
  record.exr = batch.exr.path(index);
  if (batch.output_settings.format != FileFormat::exr) record.files = output_files(record.exr, batch.aovs, batch.output_settings.format);
  if (batch.png) record.png = batch.png->path(index);
  record.camera = batch.views[index].camera;
  record.poses = batch.views[index].poses;
  record.width = batch.width;
  record.height = batch.height;
  record.outputs = batch.aovs.names();
  record.scene = batch.scene;
  record.objects = batch.objects;
  if (batch.mask != every_mask_bit) record.mask = batch.mask;
  const OutputSettings& stored = batch.output_settings;
  record.half = stored.half.names();
  if (!(std::isinf(stored.miss) && stored.miss > 0)) record.miss = stored.miss;
  if (stored.format == FileFormat::png16) record.depth_step = stored.depth_step;
  return record;
}

// Every instance some view places, each with the scene's own transform: what a view that does not
// place one of them puts back, so that a view's image never depends on the views before it (a shard,
// a resumed run).
InstancePoses every_placed_instance(const ViewBatch& batch, const Scene& scene) {
  std::set<uint32_t> placed;
  for (const View& view : batch.views) placed.insert(view.poses.instances.begin(), view.poses.instances.end());
  InstancePoses poses;
  for (uint32_t id : placed) {
    poses.instances.push_back(id);
    poses.transforms.push_back(affine_matrix(scene.instances[id].linear, scene.instances[id].translation));
  }
  return poses;
}

// The transforms of `placing.instances` for `view`: its own where it places one, else the scene's.
std::vector<glm::dmat4> poses_of(const View& view, const InstancePoses& placing) {
  std::vector<glm::dmat4> transforms = placing.transforms;
  for (size_t k = 0; k < view.poses.instances.size(); ++k) {
    const auto slot = std::lower_bound(placing.instances.begin(), placing.instances.end(), view.poses.instances[k]);
    transforms[static_cast<size_t>(slot - placing.instances.begin())] = view.poses.transforms[k];
  }
  return transforms;
}

// Every folder the batch writes into exists and takes new files, before any view is rendered.
void prepare_folders(const ViewBatch& batch, const std::vector<uint32_t>& views) {
  std::set<std::filesystem::path> checked;
  auto prepare = [&](const std::filesystem::path& file) {
    const std::filesystem::path folder = file.parent_path();
    if (!checked.insert(folder).second) return;
    std::error_code error;
    if (!folder.empty()) std::filesystem::create_directories(folder, error);
    if (error) throw std::runtime_error(folder.string() + ": cannot create the output folder: " + error.message());
    check_output_path(file);
  };
  prepare(batch.manifest);
  for (uint32_t index : views) {
    for (const std::filesystem::path& file : view_files(batch, index)) prepare(file);
  }
}

}  // namespace

void check_view_names(const ViewBatch& batch) {
  const std::map<uint32_t, std::string> records = read_manifest_records(batch.manifest);
  // Checked without a list of every name (a run may have millions): from the patterns' structure.
  const std::filesystem::path working = std::filesystem::current_path();
  auto normal = [&](const std::filesystem::path& file) { return (working / file).lexically_normal(); };
  auto refuse = [](const std::filesystem::path& file, const std::string& one, const std::string& other) {
    throw InputError(file.string() + ": " + one + " and " + other +
                     " would write this one file: give each view names of its own (-o, --preview, --manifest)");
  };
  const uint32_t views = static_cast<uint32_t>(batch.views.size());
  if (views == 0) return;
  std::vector<std::pair<const OutputPattern*, std::string>> patterns = {{&batch.exr, "EXR"}};
  if (batch.png) patterns.emplace_back(&*batch.png, "preview");
  for (const auto& [pattern, kind] : patterns) {
    // The longest name is the last view's (its index has the most digits). A name too long would
    // fail only when its view is written, after the views before it.
    const std::filesystem::path last = pattern->path(views - 1);
    if (last.filename().string().size() > max_file_name_bytes) {
      throw InputError(last.string() + ": the name of view " + std::to_string(views - 1) + "'s " + kind + " is longer than the " +
                       std::to_string(max_file_name_bytes) + " bytes a file name may have");
    }
    // Different indices give different names unless ".." takes every {index} out of the path
    // ("d{index}/../v.exr"): then views 0 and 1 already meet.
    if (views > 1 && normal(pattern->path(0)) == normal(pattern->path(1))) {
      refuse(pattern->path(1), "view 0's " + kind, "view 1's " + kind);
    }
  }
  // Within each view, its files and the manifest must be apart: a manifest named as a view's file
  // would count that view complete before it rendered; a png16 depth and a preview of one name
  // would replace each other. A link, a device or a read-only file at a view's name is refused now,
  // not when that view comes to be written after the ones before it.
  for (uint32_t index = 0; index < views; ++index) {
    std::vector<NamedFile> files = view_outputs(batch, index);
    files.push_back({batch.manifest, "the manifest"});
    refuse_one_file_twice(files);
    if (!to_be_rendered(batch, index, records)) continue;
    for (size_t k = 0; k + 1 < files.size(); ++k) {
      try {
        refuse_to_replace(files[k].path);
      } catch (const std::runtime_error& error) {
        throw InputError(error.what());
      }
    }
  }
}

ViewBatchSummary render_views(Renderer& renderer, const ViewBatch& batch,
                              const std::function<void(const ViewBatchProgress&)>& progress) {
  if (batch.views.size() > 1 && (!batch.exr.has_index() || (batch.png && !batch.png->has_index()))) {
    throw InputError("many views need the view's index in every output name, as in out/view-{index:05}.exr; '" +
                     (batch.exr.has_index() ? batch.png->text() : batch.exr.text()) + "' would write them all to one file");
  }
  ViewBatchSummary summary;
  std::vector<uint32_t> shard_views;
  for (uint32_t index = 0; index < batch.views.size(); ++index) {
    if (batch.shard.holds(index)) shard_views.push_back(index);
  }
  check_view_names(batch);
  check_view_poses(batch.views, renderer.scene());
  renderer.set_ray_mask(batch.mask);
  prepare_folders(batch, shard_views);
  ManifestWriter manifest(batch.manifest, batch.overwrite);
  std::vector<uint32_t> to_render;
  std::vector<std::filesystem::path> to_write;
  for (uint32_t index : shard_views) {
    // A view an earlier run recorded counts only if that run asked what this one asks; else its
    // files, or its record beside this run's, would stand for views they are not.
    const std::string* recorded = manifest.recorded(index);
    if (recorded) {
      const std::string changes = record_changes(*recorded, manifest_line(record_of(batch, index), batch.manifest.parent_path()));
      if (!changes.empty()) {
        throw InputError(batch.manifest.string() + ": view " + std::to_string(index) + " was rendered with other settings (" +
                         changes + "): --overwrite renders every view again, or write to another folder");
      }
    }
    if (!to_be_rendered(batch, index, manifest.records())) {
      ++summary.skipped;
      continue;
    }
    for (std::filesystem::path& file : view_files(batch, index)) to_write.push_back(std::move(file));
    to_render.push_back(index);
  }
  remove_stale_partial_files(to_write);
  if (to_render.empty()) return summary;

  // Each writer compresses its own file on its own thread: with several views in flight, that keeps
  // the cores as busy as a file's encoding threads would, without their hand-offs.
  use_exr_threads(1);
  summary.writers = batch.writers > 0 ? batch.writers
                                      : writer_threads(std::thread::hardware_concurrency(),
                                                       Frame::bytes(batch.width, batch.height, batch.aovs, true), host_memory_bytes());
  const auto start = Clock::now();
  WriteQueue queue(summary.writers + 1);
  std::mutex progress_mutex;
  ViewBatchProgress done{0, static_cast<uint32_t>(to_render.size()), 0.0};
  std::vector<std::jthread> writers;
  for (unsigned w = 0; w < summary.writers; ++w) {
    writers.emplace_back([&] {
      while (std::optional<WriteJob> job = queue.pop()) {
        try {
          const std::filesystem::path exr = batch.exr.path(job->index);
          const std::optional<std::filesystem::path> png =
              batch.png ? std::optional(batch.png->path(job->index)) : std::nullopt;
          const size_t beyond_png16 = write_outputs(exr, png ? &*png : nullptr, job->frame, batch.output_settings);
          const std::lock_guard lock(progress_mutex);
          summary.beyond_png16_samples += beyond_png16;
          summary.beyond_png16_views += beyond_png16 > 0;
          manifest.append(record_of(batch, job->index));
          ++done.done;
          done.seconds = seconds_since(start);
          if (progress) progress(done);
        } catch (...) {
          queue.fail(std::current_exception());
          return;
        }
      }
    });
  }
  // A render that fails (the device lost, out of memory) ends the loop like the last view does: the
  // queue closes, the writers finish the views before it, and only then is the failure passed on.
  // (Left open, the writers would wait in pop() for ever, and joining them would hang the process.)
  std::optional<std::pair<uint32_t, std::string>> render_failure;  // the view, and why
  const InstancePoses placing = every_placed_instance(batch, renderer.scene());
  for (uint32_t index : to_render) {
    const auto render_start = Clock::now();
    Frame frame;
    try {
      if (batch.before_render) batch.before_render(index);
      if (!placing.empty()) renderer.set_transforms(placing.instances, poses_of(batch.views[index], placing));
      frame = renderer.render(batch.views[index].camera, batch.width, batch.height, batch.aovs);
    } catch (const std::exception& error) {
      render_failure.emplace(index, error.what());
      break;
    }
    summary.render_seconds += seconds_since(render_start);
    if (!queue.push({index, std::move(frame)}, summary.queue_wait_seconds)) break;
  }
  queue.close();
  writers.clear();  // joins
  if (const std::exception_ptr failure = queue.failure()) std::rethrow_exception(failure);
  if (render_failure) {
    throw std::runtime_error("view " + std::to_string(render_failure->first) + " could not be rendered: " + render_failure->second +
                             " (" + std::to_string(done.done) + " views of this run written and recorded before it; run again to go on)");
  }
  summary.rendered = done.done;
  summary.seconds = seconds_since(start);
  return summary;
}

unsigned writer_threads(unsigned host_threads, uint64_t frame_bytes, uint64_t host_memory_bytes) {
  const uint64_t frames_in_budget = frame_bytes > 0 ? host_memory_bytes / 4 / frame_bytes : UINT64_MAX;
  const uint64_t by_memory = frames_in_budget > 2 ? (frames_in_budget - 2) / 3 : 0;
  return static_cast<unsigned>(std::max<uint64_t>(1, std::min<uint64_t>(host_threads, by_memory)));
}

}  // namespace vkray
