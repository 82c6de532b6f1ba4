// `vkray bench`: renders scenes with several configurations (variants) of the shader and reports,
// for each, its time beside its error against the double-precision reference, measured in the same
// run; Embree on the CPU is timed on the same rays as a baseline.
#pragma once

#include "engine/bench/bench_suites.hpp"
#include "engine/bench/embree_baseline.hpp"
#include "engine/reference/compare.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/io/array_files.hpp"
#include "engine/render/renderer.hpp"
#include "engine/statistics.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vkray {

// A row that is not vkray: Embree 3 on all CPU threads, same rays, as the baseline.
enum class CpuBaseline { none, embree_single, embree_packet };

struct BenchVariant {
  std::string name;
  std::string description;  // what it changes against the default
  RendererOptions options;
  CpuBaseline cpu = CpuBaseline::none;
  // Whether the variant means anything for a scene (a sphere formula for a scene without spheres
  // does not, brute force over a million triangles would only take minutes to say so).
  std::function<bool(const Scene&)> applies;
  // > 0: a many-views row: this many views orbiting the scene's camera rendered and written to
  // OpenEXR files in one run (engine/views), writing overlapped with rendering; its time is the
  // whole run's wall time a view, its error the first view's. Run only where named (--variants).
  uint32_t orbit_views = 0;
  FileFormat views_format = FileFormat::exr;  // how a many-views row stores its views
  // Outputs beside depth and normal (the camera, id and surface outputs): what each costs beside
  // the default, and its error against the reference's. Run only where named (--variants).
  AovSet extra_outputs = AovSet{};
};

// Every variant, by name: the default (what `vkray render` does) first, then one change each, then
// Embree's rows.
const std::vector<BenchVariant>& bench_variants();

// Brute force over more triangles and spheres than this is left out of the bench: its time grows
// with their count and says nothing new (10k spheres took 6.4 s a frame at 640x480 on lavapipe).
inline constexpr size_t bench_brute_force_max_primitives = 1024;

// One row of the bench: a variant of vkray, or a CPU baseline, on one scene.
struct BenchRow {
  std::string variant;
  bool on_gpu = true;               // false: a CPU baseline (Embree)
  SceneStats stats;                 // what the variant put on the device (GPU rows)
  double upload_ms = 0.0;           // scene conversion and upload, BVH build included; never in frame times
  double bvh_build_ms = 0.0;        // of which the BVH build (ray queries: the device's structures; CPU rows: Embree's scene build)
  double pipeline_ms = 0.0;         // pipeline creation, never in frame times
  TimeStats gpu;                    // GPU time per frame, from timestamps (CPU rows: wall time of the trace)
  uint64_t gpu_frames = 0;          // the timed frames behind `gpu`, over every round
  double frame_median_ms = 0.0;     // host wall time per frame, readback included (GPU rows)
  // GPU time a frame in passes back to back (Renderer::sustained_dispatch_ms), the fastest of three
  // bursts; 0 where not measured (BenchSettings::sustained_ms).
  double sustained_ms = 0.0;
  double mrays_per_s = 0.0;         // pixels / median GPU time
  uint64_t unfinished_rays = 0;     // finished on the CPU (loop budget), last frame
  FrameError error;                 // last frame against the reference
  OutputErrors outputs;             // its extra outputs against the reference's (BenchVariant::extra_outputs)
  bool pareto = false;              // on the Pareto front of its scene (see mark_pareto_front)
};

struct BenchSceneResult {
  std::string name;
  std::string hash;  // scene_hash: the same geometry, camera and size give the same hash
  uint32_t width = 0, height = 0;
  size_t triangles = 0, spheres = 0, planes = 0;
  double reference_ms = 0.0;  // the double-precision reference, once per scene and size
  // The reference traced along the float32 shader's rays (float32_ray_direction) against the exact
  // one: the error that rounding the ray alone brings, whatever the arithmetic after it. Measured
  // when BenchSettings::float32_ray_error asks; not in the JSON; docs/accuracy.md shows it.
  FrameError float32_ray;
  std::vector<BenchRow> rows;
  std::vector<std::string> skipped;  // variants asked for that do not apply to this scene
};

// How long a row runs: a GPU idling between rows (a BVH build, a reference) drops its clocks, and
// timed frames of a fraction of a millisecond each never bring them back up (seen on an H100:
// identical pipelines timed 0.68 and 3.05 ms at 3840x2160 one after the other).
struct BenchTiming {
  uint32_t frames = 5;        // timed frames at least, after the warm-up
  double warm_up_ms = 0.0;    // frames not timed, after the caller's first, until this much wall time
  double min_timed_ms = 0.0;  // and timed frames until this much wall time
  double sustained_burst_ms = 0.0;  // BenchRow::sustained_ms from bursts this long; 0: not measured
};

// Calls `frame` (which returns its own time, ms) until `timing.warm_up_ms` have passed, then
// `timing.frames` times and on until `timing.min_timed_ms` have passed: the times of the timed calls.
std::vector<double> timed_runs(const BenchTiming& timing, const std::function<double()>& frame);

struct BenchSettings {
  uint32_t frames = 5;                       // timed frames per variant and round, after one warm-up
  // Rounds over the scene's variants, in order and then in reverse, each row's frames pooled over
  // them: a machine busy for a while slows every variant a little rather than one a lot (on two
  // shared cores one variant moved 1.5x between runs, more than variants differ).
  uint32_t rounds = 2;
  // The report's rows: warm-up and timing by wall time (BenchTiming) on top of `frames`, and
  // BenchRow::sustained_ms from bursts of about this many ms each (0: not measured).
  double warm_up_ms = 0.0, min_timed_ms = 0.0, sustained_burst_ms = 0.0;
  std::vector<std::string> variants;         // names; empty: every variant that applies
  bool float32_ray_error = false;            // also BenchSceneResult::float32_ray (docs/accuracy.md)
  std::function<void(double)> reference_progress;  // fraction done of the reference, from any thread
};

// A many-views row by name (bench_variants() has views-100): "views-100" writes OpenEXR files,
// "views-100-npy" .npy arrays. None for another name.
std::optional<BenchVariant> views_variant(const std::string& name);

// Throws InputError naming the known variants when `name` is not one.
const BenchVariant& find_bench_variant(const std::string& name);

// One scene's rows, one at a time (the GPU report runs each in a process that may die): the
// reference is traced once, when made; Embree's trace, which gives both its rows, on first use.
class BenchSceneRun {
 public:
  BenchSceneRun(const BenchScene& scene, const BenchSettings& settings);
  // The row of `variant` (which must apply to the scene), measured against the reference. Throws
  // GpuError where the device cannot run it.
  BenchRow row(GpuDevice& device, const BenchVariant& variant);
  // The scene's figures, without rows: the caller collects those.
  BenchSceneResult& result() { return result_; }
  // Embree is traced again for the next round's rows, so its rows too are timed in every round.
  void next_round() { embree_.reset(); }

 private:
  const Scene& scene_;
  BenchTiming timing_;
  ReferenceScene reference_scene_;
  std::vector<ReferenceHit> reference_;
  std::optional<EmbreeResult> embree_;
  BenchSceneResult result_;
};

// Renders the scene with each variant and Embree in BenchSettings::rounds rounds, measures each
// against the reference, and marks the Pareto front.
BenchSceneResult bench_scene(GpuDevice& device, const BenchScene& scene, const BenchSettings& settings);

// A row is on the Pareto front of its scene when no other row is at least as good in time and in
// every error figure (hit/miss flips, depth p99, normal p99) and better in one. Time compares the
// spreads of the frames' GPU times: one row is faster only where its slowest frame beat the other's
// fastest; overlapping spreads are as good as each other.
void mark_pareto_front(std::vector<BenchRow>& rows);

}  // namespace vkray
