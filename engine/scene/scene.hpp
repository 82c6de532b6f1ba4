// The scene model. The host keeps everything in double precision; conversion to the GPU's float32
// layout happens once, relative to an anchor point, in gpu_scene.cpp.
#pragma once

#include "engine/scene/camera.hpp"
#include "shaders/gpu_layout.h"

#include <glm/common.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace vkray {

// `text` as one line a person can read: its control characters but tab as \xNN (a NUL from the input
// would end a printed line there, a line break would make two of one message), and beyond
// max_message_bytes its middle left out (a message quoting a whole data: uri ran to 4 MB).
std::string one_line_message(const std::string& text);
inline constexpr size_t max_message_bytes = 1000;

// Bad input from the user (scene file, OBJ file, option value). The message names the file and the
// place (a JSON path or a line number), on one line whatever bytes it quotes from the input. The CLI
// maps it to exit code 2.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(one_line_message(message)) {}
};

// Ray masks: every mesh, sphere and plane has a mask of 8 bits, and a ray hits only what shares a
// bit with its own (the rays of one call share one: Renderer::set_ray_mask). Eight bits, as Vulkan's
// instance masks and a ray query's cull mask have them (and Embree's low byte), so that the device's
// own masks can take them. By default every bit: a scene that sets none is traced without them.
using Mask = uint8_t;
inline constexpr Mask every_mask_bit = 0xff;

struct Sphere {
  glm::dvec3 center;
  double radius;
  Mask mask = every_mask_bit;
};

struct Plane {
  glm::dvec3 point;
  glm::dvec3 normal;  // unit length
  Mask mask = every_mask_bit;
};

// A triangle corner's vn or vt that its face does not give (Mesh::normal_corners, texcoord_corners).
inline constexpr uint32_t no_attribute = 0xffffffffu;

struct Mesh {
  std::vector<glm::dvec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;  // 0-based, checked against positions
  // The OBJ's shading normals (vn, as given, through the mesh's transform's inverse transpose)
  // and texture coordinates (vt: u, v), and each triangle's corners' indices into them
  // (no_attribute where its face gives none). The corner lists are empty, or one a triangle.
  std::vector<glm::dvec3> normals;
  std::vector<glm::dvec2> texcoords;
  std::vector<std::array<uint32_t, 3>> normal_corners;
  std::vector<std::array<uint32_t, 3>> texcoord_corners;
  // Where the mesh comes from, naming its mesh_id in the outputs: the model file ("bunny.ply"), a
  // glTF's node ("scene.glb#Wheel"), or a scene file's entry ("scene.json: meshes[2]").
  std::string source;
  Mask mask = every_mask_bit;
  // Drawn only where instances place it (Scene::instances), not where its positions stand.
  bool instanced = false;
};

// A placement of an instanced mesh: each of its positions p drawn at linear * p + translation (an
// affine map, invertible), with the instance's own mask in place of the mesh's. The mesh is stored
// once however many instances place it; each keeps its own transform, so a ray is taken into the
// mesh's own coordinates (transformed back, in double on the host) rather than the mesh into the
// world's: an instance 1e-6 across placed 1e5 away keeps the precision of its own size.
struct Instance {
  uint32_t mesh = 0;  // into Scene::meshes, a mesh with `instanced`
  glm::dmat3 linear{1.0};
  glm::dvec3 translation{0.0};
  Mask mask = every_mask_bit;
};

// The least factor by which `linear` shrinks a length: its smallest singular value (the square root
// of the least eigenvalue of linear^T linear), a little below it. A distance in a mesh's coordinates
// times this bounds the placed distance from below: what prunes an instance's boxes in a point query.
double smallest_scale(const glm::dmat3& linear);

// The affine 4x4 of a placement (columns; the last row 0 0 0 1), and the placement a 4x4's upper
// three rows give: the form set_transforms, views files and the manifest hold transforms in.
inline glm::dmat4 affine_matrix(const glm::dmat3& linear, const glm::dvec3& translation) {
  glm::dmat4 matrix(linear);
  matrix[3] = glm::dvec4(translation, 1.0);
  return matrix;
}
inline void place_by(Instance& instance, const glm::dmat4& matrix) {
  instance.linear = glm::dmat3(matrix);
  instance.translation = glm::dvec3(matrix[3]);
}

// Where `instance` places the mesh position `position`.
inline glm::dvec3 placed(const Instance& instance, const glm::dvec3& position) {
  return instance.linear * position + instance.translation;
}

// The ray (origin, dir) taken into an instance's mesh coordinates, given its translation and
// `to_mesh`, the inverse of its linear map: its origin and direction there. The origin's difference
// first: near the instance it is exact or nearly (Sterbenz), however far both lie from the world's
// origin. Affine maps keep a ray's t.
inline std::pair<glm::dvec3, glm::dvec3> ray_in_mesh(const glm::dvec3& translation, const glm::dmat3& to_mesh,
                                                     const glm::dvec3& origin, const glm::dvec3& dir) {
  return {to_mesh * (origin - translation), to_mesh * dir};
}

// Largest coordinate or radius magnitude accepted. The shader squares distances in float32 (max
// ~3.4e38) and splits them with a factor of 4097 for the exact sphere term, so magnitudes must stay
// well below 1e19; 1e15 leaves room and is far beyond any real scene.
inline constexpr double max_coordinate = 1e15;

inline constexpr uint32_t default_image_width = 800;
inline constexpr uint32_t default_image_height = 600;
// Largest image side and pixel count accepted: beyond these, host memory for the outputs
// (28 bytes per pixel with every output) passes several GiB and the request is almost surely a typo.
inline constexpr uint32_t max_image_side = 65536;
inline constexpr uint64_t max_image_pixels = uint64_t{1} << 27;

struct Scene {
  Camera camera;
  uint32_t width = default_image_width;
  uint32_t height = default_image_height;
  std::vector<Sphere> spheres;
  std::vector<Plane> planes;
  std::vector<Mesh> meshes;
  std::vector<Instance> instances;

  size_t triangle_count() const;
  // The triangles of the drawn meshes, each mesh's once however many instances place it: an
  // ordinary mesh's, and an instanced one's where some instance places it (a named mesh no instance
  // places is drawn nowhere, as the reference has it).
  size_t drawn_triangle_count() const;
  // Triangles of zero area (coincident or collinear vertices: their edge vectors' cross product is
  // exactly 0 in double). No ray can hit them; the renderer and the reference leave them out, and
  // the command line says how many.
  size_t zero_area_triangle_count() const;
  // The objects the outputs' mesh_id numbers: the meshes, then the spheres, then the planes.
  size_t object_count() const { return meshes.size() + spheres.size() + planes.size(); }
  // Whether any mesh, instance, sphere or plane has a mask other than every bit: only then do the
  // shaders test masks (VKRAY_SPEC_MASKS).
  bool has_masks() const;
};

// The mask of the object `object` (ObjectPrimitive's numbering: meshes, spheres, planes); setting
// it throws InputError for an object out of range.
Mask object_mask(const Scene& scene, uint32_t object);
void set_object_mask(Scene& scene, uint32_t object, Mask mask);

// Whether a ray with `ray_mask` hits an object with `mask`.
inline bool mask_hits(Mask mask, Mask ray_mask) { return (mask & ray_mask) != 0; }

struct Fnv1a;

// Adds the scene's geometry (spheres, planes, meshes' positions and triangles; not the camera or the
// size) to `fnv`: the bench's scene_hash and a many-view run's record of its scene.
void add_geometry(Fnv1a& fnv, const Scene& scene);

// The geometry's FNV-1a hash in 16 hex digits: a manifest's "scene", so a run resumed on a changed
// scene is caught.
std::string geometry_hash(const Scene& scene);

// What a ray hit, as the outputs number it. `object` counts the meshes, then the spheres, then the
// planes, each in scene order; `primitive` is a triangle's index within its mesh (the order of the
// file after triangulation, zero-area triangles counted though never hit), or a sphere's or a
// plane's index among the spheres or planes. Both are no_object on a miss.
inline constexpr uint32_t no_object = 0xffffffffu;
struct ObjectPrimitive {
  uint32_t object = no_object;
  uint32_t primitive = no_object;
  bool operator==(const ObjectPrimitive&) const = default;
};

// A box grown point by point; lower > upper while it holds none.
struct Bounds {
  glm::dvec3 lower{std::numeric_limits<double>::infinity()};
  glm::dvec3 upper{-std::numeric_limits<double>::infinity()};
  void add(const glm::dvec3& p) {
    lower = glm::min(lower, p);
    upper = glm::max(upper, p);
  }
  bool empty() const { return !(lower.x <= upper.x); }
  // Corner `k` (0..7) of a box that holds some point: bit 0 takes x from upper, bit 1 y, bit 2 z.
  glm::dvec3 corner(int k) const {
    return {(k & 1) ? upper.x : lower.x, (k & 2) ? upper.y : lower.y, (k & 4) ? upper.z : lower.z};
  }
};

// The world box of `mesh_box` placed by `instance`: its eight corners placed, and 1e-12 of their
// magnitude more on each side. A triangle a ray meets in the mesh's coordinates lies where the
// placed ray is, to the rounding of taking the ray there (in double, a few units in the last
// place): the margin, ten thousand times more, keeps a walk of the world's boxes from culling it.
Bounds placed_box(const Bounds& mesh_box, const Instance& instance);

// Throws InputError naming `path` where `instance`'s transform is not finite or cannot be inverted,
// places a corner of `mesh_box` (its mesh's box; none where empty) beyond max_coordinate (the placed
// corners bound every placed position), or cannot be walked in float32 as the reference walks it
// (float32_placement_fault): what is accepted is drawn as the fp64 reference draws it.
void check_transform(const Instance& instance, const Bounds& mesh_box, const std::string& path);

// Why float32 shaders cannot take a ray into the mesh of a placement by `linear` as the reference
// does; empty where they can. They store its inverse A rounded to float32 and take a ray (o, d) to
// (A (o - T), A d) in float32, which moves the mesh coordinate i by a rounding of |A row i| |v| at
// most (v: the ray's point relative to T), and so the world point by
// mu = sum_i |linear column i| |A row i| roundings of |v|: 3 for a rotation and scale in any order of
// its own axes (each column's length times its row's is 1), more for a scale or shear across
// rotated axes. Refused where:
// - mu > max_placement_spread: more than about twice a rotation's and scale's spread, beyond the
//   depth contract's few float32 roundings (bake such a placement into a mesh of its own);
// - the condition number, |linear|_F |A|_F, exceeds max_placement_condition: the mesh flattened by
//   more than 2^32 along some axis, whose mesh coordinates a ray resolving it (within 2^24 of its
//   size) reaches past float32's squares;
// - A's entries leave [2^-100, 2^100] in some row (rounded to float32: a row lost to underflow,
//   or overflowing the coordinates it makes).
std::string float32_placement_fault(const glm::dmat3& linear);
inline constexpr double max_placement_spread = 8.0;
inline constexpr double max_placement_condition = 4294967296.0;  // 2^32

// Instances placed anew: instances[k] of a scene by transforms[k], an affine map of its mesh's
// positions (last row 0 0 0 1). A view of many may carry its own (a views file's "instances").
struct InstancePoses {
  std::vector<uint32_t> instances;
  std::vector<glm::dmat4> transforms;
  bool empty() const { return instances.empty(); }
};

// The box of each mesh's positions, by mesh, where it is instanced (an empty box elsewhere): what
// check_transform holds an instance's placement to.
std::vector<Bounds> instanced_mesh_boxes(const Scene& scene);

// Instance instances[k] of `scene` placed by transforms[k], an affine map of its mesh's positions
// (last row 0 0 0 1). Every one is checked first (check_transform, against its mesh's box, from
// `mesh_boxes` (instanced_mesh_boxes) where given, else found here), so a refused call changes nothing: an
// InputError names the entry, or the second entry of an instance listed twice.
void set_instance_transforms(Scene& scene, std::span<const uint32_t> instances, std::span<const glm::dmat4> transforms,
                             const std::vector<Bounds>* mesh_boxes = nullptr);

// A box of the finite primitives: every sphere and ordinary mesh's vertex, and the corners of each
// instanced mesh's box where an instance places it (planes are infinite). An instance costs its
// eight corners, not its vertices: 1e5 placements of a 35k-vertex model are 8e5 points, not 3.5e9.
// The box holds every placed vertex, a little more than they need where a placement rotates.
Bounds finite_bounds(const Scene& scene);

// The centre of finite_bounds, where the framed camera looks; the camera for a scene of planes alone.
glm::dvec3 scene_centre(const Scene& scene);

// Where the GPU's positions are stored from: scene_centre rounded to a grid of spacing s = 2^(k - 4),
// 2^k <= h < 2^(k+1) for h the box's largest half-size, so within s / 2 <= h / 32 of the centre on
// each axis (the radius about it at most sqrt(3) / 32 of h longer). An object moving inside the box
// moves its centre, if at all, seldom out of its grid cell: set_vertices then finds every other
// object's stored positions as they were and redoes the moved one's part alone.
glm::dvec3 scene_anchor(const Scene& scene);

// The largest distance from `anchor` of a sphere's surface, an ordinary mesh's vertex or a corner of
// an instanced mesh's box where an instance places it (0 without any): at least that of every
// vertex where it is drawn, in the time of finite_bounds.
double scene_radius(const Scene& scene, const glm::dvec3& anchor);

// Moves the vertices of scene.meshes[mesh] to `positions`, one a vertex in its order. Throws
// InputError, the scene unchanged, for a mesh out of range, another count of positions, a
// coordinate not finite or beyond max_coordinate, or (an instanced mesh) a placement of the moved
// mesh that check_transform refuses (its box placed beyond max_coordinate).
void move_vertices(Scene& scene, uint32_t mesh, std::span<const glm::dvec3> positions);

// The anchor and the radius about it, found once for all who need them (two passes over the vertices).
struct SceneExtent {
  glm::dvec3 anchor;
  double radius = 0.0;
};
SceneExtent scene_extent(const Scene& scene);

// The masks of what a ray can meet: each drawn ordinary mesh's, sphere's and plane's, and each
// instance's in place of its mesh's (the CLI's note that a --mask sees nothing).
std::vector<Mask> drawn_masks(const Scene& scene);

// What each mesh_id of the outputs stands for, by id: the meshes' sources (Mesh::source; "meshes[i]"
// for one built in memory), then "spheres[i]", then "planes[i]", as ObjectPrimitive numbers them.
std::vector<std::string> object_names(const Scene& scene);

// Whether every coordinate of `point` is finite and within max_coordinate. False for NaN too: each
// comparison with NaN is false (a std::max over the three would keep a number over a NaN after it).
inline bool within_coordinate_bound(const glm::dvec3& point) {
  return std::abs(point.x) <= max_coordinate && std::abs(point.y) <= max_coordinate && std::abs(point.z) <= max_coordinate;
}

// Throws InputError naming `path` unless every coordinate of `point` is finite and within
// max_coordinate.
void check_coordinates(const glm::dvec3& point, const std::string& path);

// Throws InputError, its message after `what` (where the camera comes from), where `camera` cannot
// render at width x height: an orthographic image plane reaching beyond max_coordinate.
void check_camera_reach(const Camera& camera, uint32_t width, uint32_t height, const std::string& what);

// Checks a scene built in memory (Python's vkray.Scene) as a scene file is checked, naming the item
// by its path ("meshes[2].triangles[7]: ..."): every coordinate finite and within max_coordinate,
// radii > 0, plane normals non-zero (made unit length here), vertex indices within their mesh, at
// least one triangle a mesh, the camera's from and to apart, its up non-zero and its fovy in
// (0, 180) degrees, the image size within limits; each instance placing an instanced mesh by a
// finite transform that can be inverted and walked in float32 (check_transform), its mesh's box placed
// within max_coordinate, and no mask of the mesh's own (its instances' masks stand for it). Throws
// InputError. Every way a scene comes in (a scene file, a model, Python and the C API) ends here.
void check_scene(Scene& scene);

// A ray the caller gives (Python's cast_rays): its origin, then its direction (any length but 0), in
// world coordinates.
using GivenRay = std::array<double, 6>;

// What is wrong with a given ray: its origin or direction is not finite, its origin is beyond
// max_coordinate, or its direction is 0; null for nothing.
const char* given_ray_fault(const GivenRay& ray);

// Throws InputError naming the first ray (by its index) given_ray_fault finds fault with. The rays
// are read once: a caller's thread rewriting them meanwhile changes which one is named, never the
// message's making (the ray is not read again for it).
void check_given_rays(std::span<const GivenRay> rays);

// Where along each given ray a hit counts: t_min < t < t_max, t the distance from the ray's origin
// along its unit direction. An empty span means 0 (t_min) or +infinity (t_max) for every ray. A range
// that starts past the origin is traced as the ray from origin + t_min * unit direction, that point
// computed in double (by vkray's shaders and the reference alike), and its distances count from the
// origin again: the start is exact to double's rounding of that point, far below float32's.
struct RayRanges {
  std::span<const double> t_min, t_max;
  double start(size_t ray) const { return t_min.empty() ? 0.0 : t_min[ray]; }
  double end(size_t ray) const { return t_max.empty() ? std::numeric_limits<double>::infinity() : t_max[ray]; }
};

// What a given ray looks for: its nearest hit, any hit at all (an occlusion query), or how many
// times it crosses a surface (VKRAY_SPEC_HIT_QUERY); what a point looks for: its nearest point
// (nearest), or the winding number there.
enum class HitQuery : uint32_t {
  nearest = VKRAY_HIT_QUERY_NEAREST,
  any = VKRAY_HIT_QUERY_ANY,
  count = VKRAY_HIT_QUERY_COUNT,
  winding = VKRAY_HIT_QUERY_WINDING
};

// The ray traced for `ray`'s range from `t_min` on: its origin moved to the range's start, its
// direction unit length.
GivenRay range_start_ray(const GivenRay& ray, double t_min);

// Throws InputError naming the first ray (by its index) whose t_min is negative or not finite, whose
// t_max is NaN or below its t_min, or whose range starts beyond max_coordinate; or naming the span
// whose length is not `rays`'.
void check_ray_ranges(std::span<const GivenRay> rays, const RayRanges& ranges);

// Throws InputError naming the first query point (by its index) with a coordinate that is not finite
// or beyond max_coordinate, the first largest distance that is negative or NaN, or a count of
// largest distances that is neither none, one for all nor one a point.
void check_query_points(std::span<const glm::dvec3> points, std::span<const double> max_distances);
// Point k's largest distance among those check_query_points takes: +inf where none is given.
inline double max_distance_of(std::span<const double> max_distances, size_t k) {
  return max_distances.empty() ? std::numeric_limits<double>::infinity() : max_distances[max_distances.size() == 1 ? 0 : k];
}

// Which of `rays` check_given_rays or check_ray_ranges would refuse (1), in one pass: the rays a
// caller that takes bad rays as misses leaves out (the C API's default). Throws InputError where a
// range's length is not `rays`'.
std::vector<uint8_t> refused_rays(std::span<const GivenRay> rays, const RayRanges& ranges);

// Throws InputError unless 1 <= side <= max_image_side and the pixel count is within the limit.
void check_image_size(uint32_t width, uint32_t height);

}  // namespace vkray
