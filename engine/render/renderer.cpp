#include "engine/render/renderer_impl.hpp"

#include "engine/parallel.hpp"
#include "engine/render/specialization.hpp"
#include "engine/stopwatch.hpp"
#include "engine/surface_outputs.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <future>
#include <string>

namespace vkray {

Renderer::Renderer(GpuDevice& device, const Scene& scene, RendererOptions options)
    : impl_(std::make_unique<Impl>(device.vulkan(), options)) {
  with_vulkan_errors("uploading the scene", [&] {
    const auto start = Clock::now();
    Impl& r = *impl_;
    r.context.check_usable();
    r.check_workgroup();
    // A search asked for by name is refused before anything is built or uploaded (a ray-query
    // upload asks for device features a device without them never enabled).
    if (const std::string obstacle = search_obstacle(options.scene.search, r.context.info, options.shader); !obstacle.empty()) {
      throw GpuError("traversal '" + std::string(traversal_name(options.scene.search)) + "' cannot run on " +
                     r.context.info.name + ": " + obstacle);
    }
    const std::string packet_obstacle = search_obstacle(PrimitiveSearch::bvh_packet, r.context.info, options.shader);
    GpuSceneOptions scene_options = options.scene;
    scene_options.packet_walk = r.context.info.favours_packet_walk && packet_obstacle.empty();
    // The packet walk's pipeline does not depend on the tree: the first one is made on a second
    // thread while the tree builds and the scene uploads, and kept if the built scene is as planned.
    const GpuSceneShape planned = plan_gpu_scene(scene, scene_options);
    const SceneExtent extent = scene_extent(scene);
    std::optional<RaycastPipeline> early_pipeline;
    std::future<double> early_creation;
    if (!options.first_aovs.empty() && planned.search == PrimitiveSearch::bvh_packet && packet_obstacle.empty()) {
      early_pipeline.emplace(r.context, specialization_for(planned, 0, tree_loop_budget(planned, r.context.info, options.loop_budget),
                                                           options.shader));
      const bool lo_parts = needs_lo_parts(extent.anchor, extent.radius, scene.camera.from);
      early_creation = std::async(std::launch::async, [&early_pipeline, &options, lo_parts] {
        double created_ms = 0.0;
        early_pipeline->pipeline(options.first_aovs.on_device(), lo_parts, RaycastMode::image_buffers, created_ms);
        return created_ms;
      });
    }
    // Joins the second thread however the constructor ends: it uses the pipeline above.
    const auto join_early = [&] {
      return early_creation.valid() ? early_creation.get() : 0.0;
    };
    struct Joiner {
      std::future<double>& creation;
      ~Joiner() {
        if (creation.valid()) creation.wait();
      }
    } joiner{early_creation};
    r.scene_options = scene_options;
    GpuScene gpu_scene = make_gpu_scene(scene, scene_options, options.shader, extent);
    r.upload_scene(gpu_scene, scene);
    r.make_placeholders();
    r.placeholder_image = std::make_unique<ImageTarget>(device, 1, 1);
    const double early_ms = join_early();
    r.choose_pipeline(gpu_scene, early_pipeline);
    if (!early_pipeline) r.timings.pipeline_beside_upload_ms = early_ms;  // taken
    if (gpu_scene.instance_level) r.keep_for_placing(std::move(gpu_scene));
    r.timings.upload_ms = elapsed_ms(start);
  });
}

void Renderer::Impl::choose_pipeline(const GpuScene& gpu_scene, std::optional<RaycastPipeline>& early) {
  if (gpu_scene.search == PrimitiveSearch::bvh_packet && !packet_walk_fits(gpu_scene.bvh_depth)) {
    throw GpuError("the packet walk keeps its stack in registers, for trees up to " +
                   std::to_string(VKRAY_STACK_REGISTERS_MAX) + " deep; this one is " + std::to_string(gpu_scene.bvh_depth));
  }
  const PipelineSpecialization specialization =
      specialization_for(gpu_scene.shape(), gpu_scene.bvh_depth, stats.loop_budget, options.shader);
  if (early && early->specialization() == specialization) {
    pipeline.emplace(std::move(*early));
    early.reset();
  } else if (!pipeline || pipeline->specialization() != specialization) {
    pipeline.emplace(context, specialization);
  }
}

void Renderer::set_ray_mask(Mask mask) {
  if (mask == 0) throw InputError("mask: 0 shares no bit with any object's, so its rays would hit nothing; give 1..255");
  Impl& r = *impl_;
  if (mask == r.ray_mask) return;
  r.ray_mask = mask;
  r.counts.w = (r.counts.w & VKRAY_SEARCH_MODE_BITS) | uint32_t{mask} << VKRAY_RAY_MASK_SHIFT;
  r.reference.reset();  // made again for this mask where a ray needs it
}

void Renderer::set_vertices(uint32_t mesh, std::span<const glm::dvec3> positions) {
  Impl& r = *impl_;
  const auto start = Clock::now();
  move_vertices(r.host_scene, mesh, positions);
  r.reference.reset();  // made again from the moved scene where a ray needs it
  with_vulkan_errors("moving the vertices", [&] {
    r.context.check_usable();
    // The scene as a Renderer made from it would hold it (its anchor and radius too), the tree's
    // shape kept where it can be: in place from the second call on, else converted anew.
    const SceneExtent extent = scene_extent(r.host_scene);
    const auto refit_start = Clock::now();
    if (r.moving && refit_in_place(*r.moving, r.host_scene, r.options.shader, extent, mesh)) {
      r.write_refitted(*r.moving);
      r.reset_timings();
      r.timings.bvh_build_ms = elapsed_ms(refit_start);
      r.timings.tree_refitted = true;
      r.timings.refit_mesh_alone = r.moving->rewritten.mesh_alone;
      return;
    }
    r.moving.reset();  // a refit that could not finish left its arrays half rewritten
    GpuScene gpu_scene = make_gpu_scene(r.host_scene, r.scene_options, r.options.shader, extent,
                                        r.tree ? std::optional<RefitSource>({*r.tree, r.hit_sources}) : std::nullopt);
    r.upload_scene(gpu_scene, r.host_scene);
    std::optional<RaycastPipeline> none;
    r.choose_pipeline(gpu_scene, none);
    r.reset_timings();  // keeps the tree's time (and the structures'), which upload_scene set anew
    r.timings.tree_refitted = gpu_scene.refitted;
    // What a later call moves: the instances of the scene as it now is, or its tree.
    r.placing.reset();
    if (gpu_scene.instance_level) {
      r.keep_for_placing(std::move(gpu_scene));
    } else if (gpu_scene.tree) {
      r.moving = std::move(gpu_scene);
    }
  });
  r.timings.scene_update_ms = elapsed_ms(start);
}

void Renderer::Impl::keep_for_placing(GpuScene&& gpu_scene) {
  mesh_boxes = instanced_mesh_boxes(host_scene);
  placing = std::move(gpu_scene);
}

void Renderer::set_transforms(std::span<const uint32_t> instances, std::span<const glm::dmat4> transforms) {
  Impl& r = *impl_;
  const auto start = Clock::now();
  set_instance_transforms(r.host_scene, instances, transforms, r.mesh_boxes.empty() ? nullptr : &r.mesh_boxes);
  r.reference.reset();  // made again from the moved scene where a ray needs it
  if (!r.placing) {  // no instanced mesh has a triangle to place: nothing on the device moves
    r.timings.scene_update_ms = elapsed_ms(start);
    return;
  }
  with_vulkan_errors("moving the instances", [&] {
    r.context.check_usable();
    const auto build_start = Clock::now();
    place_instances(*r.placing, r.host_scene);
    if (r.placing->search == PrimitiveSearch::bvh_packet && !packet_walk_fits(r.placing->bvh_depth)) {
      // The world's new tree outgrew the packet walk's stack: the per-ray walk traces the scene as
      // it now stands, whose stack grows with the tree.
      r.placing->search = PrimitiveSearch::bvh_per_ray;
      r.stats.search = r.placing->search;
      r.stats.loop_budget = tree_loop_budget(r.placing->shape(), r.context.info, r.options.loop_budget);
      r.counts = run_time_counts(*r.placing, r.ray_mask);
    }
    r.write_refitted(*r.placing);
    if (r.structures) {  // ray queries: the device's top level placed anew, which the tiles bind
      r.structures->place(r.context, structure_placements(*r.placing, r.host_scene));
      r.tile = TileOutputs{};
      r.parked_tile = TileOutputs{};
    }
    r.hit_sources = r.placing->hit_sources;  // the world's slots in their new order (none moved without its tree)
    const GpuScene::ItemRange& slots = r.placing->rewritten.slots;
    if (r.hit_source_table && !slots.empty()) {  // rewritten in place: bound descriptor sets name this buffer
      write_buffer(r.context, *r.hit_source_table, r.hit_sources.slots.data() + slots.first,
                   (slots.end - slots.first) * sizeof(ObjectPrimitive), slots.first * sizeof(ObjectPrimitive));
    }
    std::optional<RaycastPipeline> none;
    r.choose_pipeline(*r.placing, none);  // the same unless the world's tree outgrew its stack
    r.reset_timings();
    r.timings.bvh_build_ms = elapsed_ms(build_start);
  });
  r.timings.scene_update_ms = elapsed_ms(start);
}

const Scene& Renderer::scene() const { return impl_->host_scene; }

Renderer::~Renderer() = default;

void Renderer::prepare_pipelines(const Camera& camera, uint32_t width, uint32_t height) {
  Impl& r = *impl_;
  const auto start = Clock::now();
  const RenderTimings constructor = r.timings;
  with_vulkan_errors("making the pipelines", [&] {
    struct Wanted {
      AovSet aovs;
      bool lo_parts;
      RaycastMode mode;
      HitQuery query;
    };
    // What render() asks for of a perspective camera (begin_render), and what cast_rays and
    // occluded ask for (Impl::cast_rays, cast_given).
    std::vector<Wanted> wanted{{AovSet{Aov::depth, Aov::normal}.on_device(), needs_lo_parts(r.anchor, r.scene_radius, camera.from),
                                RaycastMode::image_buffers, HitQuery::nearest}};
    std::vector<RaycastMode> given_modes{RaycastMode::given_rays};
    if (r.stats.search == PrimitiveSearch::bvh_packet && r.precision() == Precision::float32) {
      given_modes.push_back(RaycastMode::given_directions);
    }
    for (const RaycastMode mode : given_modes) {
      for (const bool lo_parts : {false, true}) {
        for (const HitQuery query : {HitQuery::nearest, HitQuery::any}) wanted.push_back({AovSet{Aov::depth, Aov::normal}, lo_parts, mode, query});
      }
    }
    if (r.casts_in_place()) {
      for (const bool lo_parts : {false, true}) {
        wanted.push_back({AovSet{Aov::depth, Aov::normal}, lo_parts, RaycastMode::caller_arrays, HitQuery::nearest});
      }
    }
    std::vector<std::future<void>> made;
    for (const Wanted& pipeline : wanted) {
      made.push_back(std::async(std::launch::async, [&r, pipeline] {
        double created_ms = 0.0;
        r.pipeline->pipeline(pipeline.aovs, pipeline.lo_parts, pipeline.mode, created_ms, pipeline.query);
      }));
    }
    for (std::future<void>& pipeline : made) pipeline.get();
  });
  // lavapipe compiles a pipeline's code at its first dispatch, not when it is made: a small call of
  // each kind runs each pipeline once (a first occlusion query took 5 times its tenth's time). The
  // lo parts of positions follow the rays' origins: near the scene (its anchor) and 4 radii away.
  render(camera, width, height, AovSet{Aov::depth, Aov::normal});  // its buffers made at the size too
  const glm::dvec3 near = r.anchor, far = r.anchor + glm::dvec3(0.0, 0.0, 4.0 * r.scene_radius);
  for (const glm::dvec3& origin : {near, far}) {
    std::vector<GivenRay> one_origin, two_origins;
    for (int k = 0; k < 64; ++k) {
      const double angle = 0.1 * k;
      const GivenRay ray{origin.x, origin.y, origin.z, std::cos(angle), std::sin(angle), 0.5};
      one_origin.push_back(ray);
      two_origins.push_back(ray);
      two_origins.back()[2] += k % 2 == 0 ? 0.0 : 1e-3 * r.scene_radius + 1e-9;  // two origins: one by one
    }
    cast_rays(one_origin);
    occluded(one_origin);
    cast_rays(two_origins);
    occluded(two_origins);
    // In place: an arc of rays long enough to walk in packets as listed, and the same arc in a
    // scrambled order, which the device orders by direction.
    std::vector<GivenRay> arc, scrambled;
    for (int k = 0; k < 1024; ++k) arc.push_back({origin.x, origin.y, origin.z, std::cos(1e-3 * k), std::sin(1e-3 * k), 0.5});
    for (size_t k = 0; k < arc.size(); ++k) scrambled.push_back(arc[k * 389 % arc.size()]);
    std::vector<float> t(arc.size()), normal(3 * arc.size());
    std::vector<uint32_t> object(arc.size()), primitive(arc.size());
    cast_rays_in_place(arc, {t.data(), normal.data(), object.data(), primitive.data()});
    cast_rays_in_place(scrambled, {t.data(), normal.data(), object.data(), primitive.data()});
  }
  // The calls above are a few rays each, their time mostly a submission's: no measure of what a pixel
  // or a ray costs (the first dispatch of the next call would be sized by it, and every one after it).
  r.camera_ms_per_pixel = 0.0;
  r.given_ms_per_ray.clear();
  r.timings = constructor;
  r.reset_timings();
  r.timings.pipeline_ms = elapsed_ms(start);
}

const RenderTimings& Renderer::timings() const { return impl_->timings; }

const SceneStats& Renderer::scene_stats() const { return impl_->stats; }

Frame Renderer::render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs) {
  check_image_size(width, height);
  Impl& r = *impl_;
  if (r.options.shader.generic) {  // it writes them all
    for (const Aov written : {Aov::depth, Aov::normal, Aov::uv}) aovs.add(written);
  }
  Frame frame(width, height, aovs);
  frame.camera = camera;
  if (aovs.has(Aov::mesh_id)) frame.object_names = object_names(r.host_scene);
  frame.allocate(r.precision() == Precision::float64);
  r.reset_timings();
  if (aovs.empty()) return frame;
  const AovSet device_aovs = aovs.on_device();
  if (camera.projection != Projection::perspective) {
    // Rays that do not leave one point through an image plane's pixels: the pixels' rays in double
    // (pixel_ray), cast as given rays. cast_rays picks their walk: an equirectangular image's from
    // its one origin in packets of its rows, an orthographic image's one by one.
    if (device_aovs.needs_rays() || device_aovs.has(Aov::hit)) r.render_by_given_rays(camera, frame);
    if (!frame.uv.empty()) fill_pixel_uv(frame);
  } else {
    r.render_camera_rows(camera, device_aovs, frame);
  }
  frame.round_doubles();
  add_camera_outputs(frame);
  add_surface_outputs(frame, r.host_scene);
  return frame;
}

void Renderer::Impl::render_camera_rows(const Camera& camera, AovSet device_aovs, Frame& frame) {
  const uint32_t width = frame.width, height = frame.height;
  with_vulkan_errors("rendering", [&] {
    const CameraBasis basis = make_camera_basis(camera, width, height);
    uint32_t tile_rows = 0;
    const vk::raii::Pipeline& camera_pipeline = begin_render(camera, width, height, device_aovs, nullptr, tile_rows);
    const FrameLanding landing = land_in_frame(frame);
    dispatch_camera_rows(camera_pipeline, basis, width, height, tile_rows, RaycastMode::image_buffers,
                         [&](uint32_t first_row, uint32_t rows) {
      read_tile(frame, first_row, rows);
      if (tile.overflow) {
        finish_unfinished_rays(basis, width, height, first_row, [&](uint32_t i, uint32_t j, const ReferenceHit& hit) {
          store_reference_hit(frame, size_t{j} * width + i, hit);
          store_ids(frame, size_t{j} * width + i, reference->source(hit), hit.instance);
        });
      }
    });
  });
}

double Renderer::sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs,
                                       uint32_t repeats) {
  check_image_size(width, height);
  if (camera.projection != Projection::perspective) {
    throw InputError("sustained dispatches are timed for perspective cameras, whose rays the device makes");
  }
  Impl& r = *impl_;
  r.reset_timings();
  double ms = 0.0;
  with_vulkan_errors("rendering", [&] { ms = r.sustained_dispatch_ms(camera, width, height, aovs.on_device(), std::max(repeats, 1u)); });
  return ms;
}

RayHits Renderer::cast_rays(std::span<const GivenRay> rays, const RayRanges& ranges, uint32_t hits) {
  return impl_->cast_rays({rays, ranges, HitQuery::nearest, hits});
}

void RenderTimings::add(const RenderTimings& later) {
  pipeline_ms += later.pipeline_ms;
  dispatch_gpu_ms += later.dispatch_gpu_ms;
  order_gpu_ms += later.order_gpu_ms;
  readback_ms += later.readback_ms;
  readback_bytes += later.readback_bytes;
  readback_in_place_bytes += later.readback_in_place_bytes;
  rays_ms += later.rays_ms;
  tiles += later.tiles;
  longest_dispatch_ms = std::max(longest_dispatch_ms, later.longest_dispatch_ms);
  unfinished_rays += later.unfinished_rays;
  cpu_finish_ms += later.cpu_finish_ms;
}

bool Renderer::casts_in_place() const { return impl_->casts_in_place(); }

bool Renderer::cast_rays_in_place(std::span<const GivenRay> rays, const HitArrays& into) {
  return impl_->cast_rays_in_place(rays, into);
}

std::vector<uint8_t> Renderer::occluded(std::span<const GivenRay> rays, const RayRanges& ranges) {
  const RayHits hits = impl_->cast_rays({rays, ranges, HitQuery::any});
  std::vector<uint8_t> blocked(hits.count);
  parallel_for_chunks(hits.count, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) blocked[k] = hits.object[k] != no_object ? 1 : 0;
  });
  return blocked;
}

std::vector<uint32_t> Renderer::count_intersections(std::span<const GivenRay> rays, const RayRanges& ranges) {
  RayHits hits = impl_->cast_rays({rays, ranges, HitQuery::count});
  return {hits.crossings.begin(), hits.crossings.end()};
}

DepthRange Renderer::render(const Camera& camera, Aov aov, ImageTarget& target) {
  const uint32_t width = target.width(), height = target.height();
  check_image_size(width, height);
  if (camera.projection != Projection::perspective) {
    throw InputError(std::string("the viewer draws perspective cameras; `vkray render` writes ") +
                     projection_name(camera.projection) + " ones");
  }
  Impl& r = *impl_;
  if (r.options.shader.generic || r.precision() != Precision::float32) {
    throw std::logic_error("the storage-image target takes a float32 shader specialized on its output");
  }
  r.reset_timings();
  DepthRange depths;
  with_vulkan_errors("rendering", [&] {
    const CameraBasis basis = make_camera_basis(camera, width, height);
    if (!r.depth_range) r.depth_range = r.make_output(0, 0, sizeof(gpu::DepthRangeBits));
    uint32_t tile_rows = 0;
    const vk::raii::Pipeline& pipeline = r.begin_render(camera, width, height, AovSet{aov}, &target, tile_rows);
    std::vector<PixelPatch> patches;
    r.dispatch_camera_rows(pipeline, basis, width, height, tile_rows, RaycastMode::image_target, [&](uint32_t first_row, uint32_t) {
      if (aov == Aov::depth) {
        const auto& bits = static_cast<const gpu::DepthRangeBits*>(r.depth_range->host())->near_far;
        if (bits.y != 0) depths.add(std::bit_cast<float>(bits.x)), depths.add(std::bit_cast<float>(bits.y));
      }
      if (r.tile.overflow) {
        // The values store_reference_hit puts in a Frame, as the shader stores them.
        r.finish_unfinished_rays(basis, width, height, first_row, [&](uint32_t i, uint32_t j, const ReferenceHit& hit) {
          const float depth = static_cast<float>(hit.t);
          patches.push_back({i, j, aov == Aov::depth ? glm::vec4(depth, 0.0f, 0.0f, 0.0f) : glm::vec4(glm::vec3(hit.normal), 0.0f)});
          if (aov == Aov::depth && std::isfinite(depth)) depths.add(depth);
        });
      }
    });
    if (!patches.empty()) r.write_patches(patches, target);
  });
  return depths;
}

}  // namespace vkray
