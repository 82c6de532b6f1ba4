/* vkray's C API, version 6 (VKRAY_API_VERSION): the engine's one outward boundary, libvkray.so. Python's `vkray`
 * package is written over it (ctypes, any CPython 3.9 or later, any numpy 1.22 to 2.x); C, Rust and
 * Julia callers use it as it is.
 *
 * Conventions:
 * - Every call that can fail returns a vkray_status; on failure vkray_last_error() gives the one
 *   line saying why (naming the file, key or ray at fault), kept per thread until its next failure.
 * - Arrays are the caller's, C order: vkray reads rays and writes results in place, each output one
 *   value a pixel or ray and its components last (H x W x C for an image). Nothing the caller passes
 *   is kept after a call returns.
 * - A scene is built (vkray_scene_new, then meshes, spheres, planes, instances, masks and a camera,
 *   then vkray_scene_finish, which checks it) or loaded (checked as it loads), and read-only from then
 *   on: the calls that add or change refuse a finished scene with VKRAY_INPUT_ERROR. A renderer copies
 *   what it needs of its scene.
 * - Threads: a finished scene may be read (described, given to vkray_renderer_new) from several
 *   threads at once; one being built belongs to one thread. A renderer may be shared: its calls from
 *   several threads wait their turn, each seeing the renderer as the one before left it. The caller's
 *   arrays must stay allocated for the call; another thread rewriting rays during a call gets each ray
 *   read as it stood at some moment (a ray refused is named with what was found wrong then).
 * - Distances along a ray are along its unit direction unless the call's flags say
 *   VKRAY_T_ALONG_DIRECTION (then in units of the direction as given: Embree's and Open3D's t).
 * - Strings returned (vkray_last_error, vkray_scene_describe, vkray_renderer_timings) are the calling
 *   thread's own, valid until that thread's next call of the same function; those of the version, the
 *   outputs, the traversals and a renderer's device name for the library's or the renderer's life.
 */
#ifndef VKRAY_H
#define VKRAY_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define VKRAY_API_VERSION 6  /* 4: instances (vkray_scene_add_instance, vkray_renderer_set_transforms); 5: point queries;
                                6: pipelines made at first use (vkray_renderer_prepare), a mesh's arrays (vkray_scene_mesh) */
#define VKRAY_API __attribute__((visibility("default")))

/* mesh_id and primitive_id of a ray that hit nothing. */
#define VKRAY_NO_HIT 0xffffffffu

typedef enum vkray_status {
  VKRAY_OK = 0,
  VKRAY_INPUT_ERROR = 1,     /* bad input: a file, an array, an argument (Python's ValueError) */
  VKRAY_DEVICE_ERROR = 2,    /* no device, a device lost or out of its memory (Python's vkray.Error) */
  VKRAY_OUT_OF_MEMORY = 3,   /* the host's memory */
  VKRAY_INTERNAL_ERROR = 4,  /* a fault of vkray's own */
} vkray_status;

typedef struct vkray_scene vkray_scene;
typedef struct vkray_renderer vkray_renderer;

VKRAY_API uint32_t vkray_api_version(void);
VKRAY_API const char* vkray_version(void);
VKRAY_API const char* vkray_last_error(void);

/* The outputs a render gives, by index from 0: returns 0 past the last. An output's values are
 * float32, or uint32 where is_integer (ids, flags); depth and normal are float64 from a renderer
 * whose vkray_renderer_doubles() is 1. */
typedef struct vkray_output_info {
  const char* name;         /* as `vkray render --aov` takes it: "depth", "mesh-id", ... */
  const char* description;
  uint32_t components;
  uint32_t is_integer;
  const char* channels[3];  /* the EXR channel `vkray render` writes each component to */
} vkray_output_info;
VKRAY_API int vkray_output(uint32_t index, vkray_output_info* info);

/* The traversals vkray_renderer_new takes besides "auto", by index from 0; NULL past the last. */
VKRAY_API const char* vkray_traversal(uint32_t index);

/* --- Scenes --- */

/* A scene file (.json) or a model (.obj, .ply, .gltf, .glb). width, height: 0 for the file's.
 * view: NULL, or a side ("front", "back", "left", "right", "top", "bottom") to frame it from;
 * view_direction: NULL, or 3 numbers, the direction from the scene's centre to the eye. */
VKRAY_API vkray_status vkray_scene_load(const char* path, uint32_t width, uint32_t height, const char* view,
                                        const double* view_direction, vkray_scene** scene);
/* An empty scene of width x height pixels, to which meshes, spheres, planes and a camera are added. */
VKRAY_API vkray_status vkray_scene_new(uint32_t width, uint32_t height, vkray_scene** scene);
/* A mesh: vertices vertex_count x 3; triangles triangle_count x 3 vertex indices, int64 (or uint64
 * where triangles_unsigned); transform NULL or a 4 x 4 affine matrix, row-major (last row 0 0 0 1). */
VKRAY_API vkray_status vkray_scene_add_mesh(vkray_scene* scene, const double* vertices, uint64_t vertex_count,
                                            const void* triangles, int triangles_unsigned, uint64_t triangle_count,
                                            const double* transform);
/* Places mesh `mesh` (its mesh_id among the meshes added so far), which from then on is drawn only
 * where instances place it, stored once however many do: by transform, NULL or a 4 x 4 affine
 * matrix, row-major (last row 0 0 0 1, invertible), with ray mask `mask` (0..255) of its own in
 * place of the mesh's. Instances are numbered in the order added: the instance_id output's numbers. */
VKRAY_API vkray_status vkray_scene_add_instance(vkray_scene* scene, uint32_t mesh, const double* transform, uint32_t mask);
/* count x 4: centre, radius. */
VKRAY_API vkray_status vkray_scene_add_spheres(vkray_scene* scene, const double* spheres, uint64_t count);
/* count x 6: a point, the normal. */
VKRAY_API vkray_status vkray_scene_add_planes(vkray_scene* scene, const double* planes, uint64_t count);
/* The ray mask (0..255) of object `object`, numbered as mesh_id numbers the objects added so far (the
 * meshes, then the spheres, then the planes; so set it once all are added): a call's rays (its
 * `mask`) hit it only where their mask shares a bit with it. Every bit (255) by default. A mesh that
 * instances place takes theirs instead: vkray_scene_finish refuses a mask of its own. */
VKRAY_API vkray_status vkray_scene_set_mask(vkray_scene* scene, uint32_t object, uint32_t mask);
/* The camera in the scene file's form, as JSON: {"from": [0, 1, 5], "to": [0, 0, 0], "fovy": 40}. */
VKRAY_API vkray_status vkray_scene_set_camera(vkray_scene* scene, const char* camera_json);
/* Checks the scene as a scene file is checked (every coordinate finite and within 1e15, radii > 0,
 * plane normals non-zero, each instance's transform invertible, its mesh's box placed within 1e15 and
 * walkable in float32 as the reference walks it); frames the geometry where no camera was set (planes
 * alone: the first seen from one unit above it, the horizon in view). */
VKRAY_API vkray_status vkray_scene_finish(vkray_scene* scene);
/* The finished scene as JSON: {"width", "height", "meshes", "triangles", "spheres", "planes",
 * "camera" (the scene file's form), "object_names" (what each mesh_id stands for), "masks" (each
 * one's mask)}. */
VKRAY_API const char* vkray_scene_describe(vkray_scene* scene);
/* Mesh `mesh`'s vertex positions (vertex_count x 3 doubles, in the order vkray_renderer_set_vertices
 * takes them: a model's every vertex in its file's order, used or not) and its triangles (triangle_count x
 * 3 indices into them), each copied into its array where that is not NULL; the counts into
 * vertex_count and triangle_count where those are not NULL (version 6). A finished scene. */
VKRAY_API vkray_status vkray_scene_mesh(const vkray_scene* scene, uint32_t mesh, double* positions, uint32_t* triangles,
                                        uint64_t* vertex_count, uint64_t* triangle_count);
VKRAY_API void vkray_scene_free(vkray_scene* scene);

/* --- Renderers --- */

/* Opens the device and uploads the scene (its tree built); each call makes the pipeline it takes at
 * its first use of it (vkray_renderer_timings: "pipeline_ms"). device: NULL or part of a device name
 * (`vkray info`); precision: "float" or "double"; traversal: "auto" or one of vkray_traversal(). */
VKRAY_API vkray_status vkray_renderer_new(const vkray_scene* scene, const char* device, const char* precision,
                                          const char* traversal, vkray_renderer** renderer);
/* Makes and first runs every pipeline that render (of the scene's camera), cast_rays and occluded
 * take, several at once, so that no later call of theirs pays for a first use; its time is added to
 * the setup's "pipeline_ms" (version 6). For a process that answers calls as they come (a service, a
 * robot's loop), not for a script that makes one call of each kind. */
VKRAY_API vkray_status vkray_renderer_prepare(vkray_renderer* renderer);
/* The double-precision CPU reference, with the renderer's calls (every float output in float64). */
VKRAY_API vkray_status vkray_reference_new(const vkray_scene* scene, vkray_renderer** renderer);
/* Whether depth, normal and t come in float64 (the float64 shader, the reference). */
VKRAY_API int vkray_renderer_doubles(const vkray_renderer* renderer);
VKRAY_API const char* vkray_renderer_device_name(const vkray_renderer* renderer);
/* Moves the vertices of mesh `mesh` (its mesh_id) to `positions`, `count` x 3 doubles in the mesh's
 * vertex order: the next call renders the moved scene, as a renderer made from it would. The GPU's
 * tree keeps its shape, its boxes recomputed, while the same triangles keep a non-zero area; else it
 * is built anew. Where the centre of the scene's box stays and the mesh shares no vertex position
 * with another, only this mesh's part is redone (vkray_renderer_timings: "scene_update_ms",
 * "tree_refitted", "refit_mesh_alone"). A bad mesh, count or coordinate: VKRAY_INPUT_ERROR, the scene
 * unchanged. */
VKRAY_API vkray_status vkray_renderer_set_vertices(vkray_renderer* renderer, uint32_t mesh, const double* positions,
                                                   uint64_t count);
/* Instance instances[k] takes transforms[k] (count x 16, each as vkray_scene_add_instance's): the
 * GPU's top level (its tree over the instances) is built anew where they now stand, the meshes'
 * trees kept, and the next call renders the moved scene ("scene_update_ms"). A bad instance or
 * transform: VKRAY_INPUT_ERROR, the scene unchanged. */
VKRAY_API vkray_status vkray_renderer_set_transforms(vkray_renderer* renderer, const uint32_t* instances,
                                                     const double* transforms, uint64_t count);
/* What the last call's time went to, as JSON ({"dispatch_gpu_ms": ..., ...}, milliseconds); the
 * constructor's own (upload, BVH build, pipelines) under "setup". */
VKRAY_API const char* vkray_renderer_timings(vkray_renderer* renderer);
VKRAY_API void vkray_renderer_free(vkray_renderer* renderer);

/* Renders the scene's camera, or camera_json (its keys over the scene's camera), at width x height
 * (0: the scene's): the outputs named in aovs, aovs[k] into results[k], H x W x components of its type.
 * mask: the rays' ray mask, 1..255 (255 for every object): they hit only the objects whose mask
 * (vkray_scene_set_mask, a scene file's "mask") shares a bit with it. */
VKRAY_API vkray_status vkray_render(vkray_renderer* renderer, const char* camera_json, uint32_t width, uint32_t height,
                                    uint32_t mask, uint32_t aov_count, const char* const* aovs, void* const* results);

/* What a given ray is traced for. */
typedef enum vkray_ray_flags {
  VKRAY_T_ALONG_DIRECTION = 1,  /* t, t_min and t_max in units of the direction as given */
  VKRAY_BAD_RAYS_FAIL = 2,      /* a ray with a zero or non-finite direction, or a bad range, fails the call
                                   (by default it is a miss) */
} vkray_ray_flags;  /* other bits: VKRAY_INPUT_ERROR */

/* Traces rays (count x 6: origin, direction) to their nearest hits at t_min < t < t_max (each NULL,
 * for 0 and +inf, or count values). outputs[k] into results[k], count x components: "t" (float32 or
 * float64, +inf on a miss), "normal" (3, the geometric normal facing the ray; 0 on a miss),
 * "primitive-id" and "mesh-id" (uint32, VKRAY_NO_HIT on a miss), and the surface outputs render
 * gives: "position" (3), "barycentric" (2), "front-facing" (uint32), "shading-normal" (3),
 * "texcoord" (2). mask: the rays' ray mask, as vkray_render's. hits: 1 for the nearest hit, or up to
 * VKRAY_HITS_MAX for each ray's first hits in order of distance (every surface it crosses, a
 * sphere's far root too, an edge passed exactly through once; misses past the last), results then
 * count x hits x components. */
#define VKRAY_HITS_MAX 16 /* as shaders/gpu_layout.h defines it: a different value is a redefinition warning */
VKRAY_API vkray_status vkray_cast_rays(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min,
                                       const double* t_max, uint32_t flags, uint32_t mask, uint32_t hits,
                                       uint32_t output_count, const char* const* outputs, void* const* results);
/* Occlusion queries: whether each ray hits anything at t_min < t < t_max (1) or not (0), into
 * occluded (count bytes). The same rays, ranges, flags and mask as vkray_cast_rays. */
VKRAY_API vkray_status vkray_occluded(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min,
                                      const double* t_max, uint32_t flags, uint32_t mask, uint8_t* occluded);
/* How many times each ray crosses a surface at t_min < t < t_max, into crossings (count uint32s;
 * a bad ray: 0): every triangle, sphere root and plane it meets; an edge or vertex it passes exactly
 * through counts once, so the count is odd where a ray starts inside a closed mesh (Open3D's
 * count_intersections). The same rays, ranges, flags and mask as vkray_cast_rays. */
VKRAY_API vkray_status vkray_count_intersections(vkray_renderer* renderer, const double* rays, uint64_t count,
                                                 const double* t_min, const double* t_max, uint32_t flags, uint32_t mask,
                                                 uint32_t* crossings);

/* --- Point queries (version 5) --- */

/* The outputs of point queries, index 0 up (0 past the last): name, description, components and
 * whether uint32 (channels: none). */
VKRAY_API int vkray_point_output(uint32_t index, vkray_output_info* info);
/* For each of `count` points (count x 3 doubles, world coordinates), what the scene's surfaces that
 * rays of `mask` can meet (as vkray_render's) say there: outputs[k] into results[k], count x
 * components, each named as vkray_point_output() lists them:
 * - "distance": to the nearest point of the scene, within max_distance (NULL: no bound; else count
 *   values >= 0, +inf for none; a point at exactly its bound is found); +inf where nothing lies
 *   within it. float32, or float64 where vkray_renderer_doubles.
 * - "winding-number": the generalized winding number (Jacobson et al. 2013): 1 inside a closed mesh
 *   and 0 outside (a mirrored instance's too), between for an open one; 1 inside a sphere and behind
 *   a plane (the side its normal leaves). "signed-distance": the distance, negative where the winding
 *   number is 1/2 or more; "occupancy" (uint32): 1 there, else 0.
 * - "position" (3): the nearest point (NaN where none); "normal" (3): the outward unit normal there (a
 *   triangle's by its winding, (b - a) x (c - a); an instance's through its inverse transpose, turned
 *   where it mirrors; a sphere's away from its centre; a plane's own); "barycentric" (2): the
 *   triangle's weights of its second and third vertices there.
 * - "mesh-id", "primitive-id", "instance-id" (uint32, VKRAY_NO_HIT where none): what it lies on.
 * A point with a coordinate not finite or beyond 1e15, or a bad max_distance: VKRAY_INPUT_ERROR naming
 * it. Renderers of traversal "ray-query" walk no tree of vkray's: VKRAY_INPUT_ERROR. The error bound of
 * each output in float32 is docs/points.md's. */
VKRAY_API vkray_status vkray_query_points(vkray_renderer* renderer, const double* points, uint64_t count, const double* max_distance,
                                          uint32_t mask, uint32_t output_count, const char* const* outputs, void* const* results);

#ifdef __cplusplus
}
#endif

#endif /* VKRAY_H */
