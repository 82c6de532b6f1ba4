// CPU reference ray caster in double precision: the ground truth the GPU output is measured
// against. Triangles are found through a BVH built by the same builder as the GPU's, traversed in
// double with box tests that never cull a hit; brute force over every triangle stays available so
// tests can check the tree against it. Parallel over image rows.
#pragma once

#include "engine/scene/bvh.hpp"
#include "engine/scene/camera.hpp"
#include "engine/frame.hpp"
#include "engine/point_outputs.hpp"
#include "engine/scene/scene.hpp"

#include <glm/vec3.hpp>

#include <functional>
#include <memory>
#include <mutex>
#include <limits>
#include <utility>
#include <vector>

namespace vkray {

inline constexpr double no_hit = std::numeric_limits<double>::infinity();

// The individual intersectors, in the same form as shaders/intersect.glsl. Each returns the ray
// parameter of the nearest hit in (0, t_max), else t_max.
// `near`, when given, receives whether the hit is the near root (the ray enters the sphere there);
// `far_root` the far root where the near one is taken (the ray enters ahead and leaves there; a
// tangent's double root twice), else t_max.
double intersect_sphere(const glm::dvec3& origin_minus_center, double radius, const glm::dvec3& dir, double t_max,
                        bool* near = nullptr, double* far_root = nullptr);
double intersect_plane(const glm::dvec3& normal, const glm::dvec3& point, const glm::dvec3& origin,
                       const glm::dvec3& dir, double t_max);
double intersect_triangle(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, const glm::dvec3& origin,
                          const glm::dvec3& dir, double t_max, bool claim_edges = false);

// `instance` marks a tree entry alone: a hit on an instance is a triangle with ReferenceHit::instance.
enum class PrimitiveKind : uint8_t { none, sphere, plane, triangle, instance };

// What a point query finds: the nearest point of what the scene's rays can meet (its mask's), and
// the primitive it lies on.
struct PointHit {
  double distance = no_hit;  // +inf where nothing lies within the query's distance
  glm::dvec3 point{0.0};
  // The primitive's outward normal there: a triangle's by its winding, through its instance's
  // placement (an instance places its mesh's solid: a mirrored one's normals point out of the
  // mirrored solid), a sphere's away from its centre, a plane's own; 0 where nothing was found.
  glm::dvec3 normal{0.0};
  PrimitiveKind kind = PrimitiveKind::none;
  uint32_t index = 0;             // as ReferenceHit's
  uint32_t instance = no_object;  // as ReferenceHit's
};

struct ReferenceHit {
  double t = no_hit;
  glm::dvec3 normal{0.0};  // unit, facing the ray; 0 on a miss
  PrimitiveKind kind = PrimitiveKind::none;
  uint32_t index = 0;  // within its kind; triangles are numbered across meshes in scene order
  uint32_t instance = no_object;  // the instance whose mesh's triangle this is (Scene::instances)
};

class ReferenceScene {
 public:
  // The scene as rays with `ray_mask` see it: what shares no bit of it is left out (see Mask),
  // numbered as in the whole scene.
  explicit ReferenceScene(const Scene& scene, Mask ray_mask = every_mask_bit);
  // The nearest hit before `t_max` (a miss where there is none). Among triangles at exactly the same
  // distance the lowest index wins (then the lowest instance), so the tree and brute force agree on
  // the triangle, not only on the distance. An instance's triangles are tested with the ray taken
  // into its mesh's coordinates (the inverse transform, in double): the ray's t is the same in both,
  // and an instance far from the origin keeps the precision of its own size.
  ReferenceHit trace(const glm::dvec3& origin, const glm::dvec3& dir, double t_max = no_hit) const;
  // The same with every triangle tested: the check on the tree.
  ReferenceHit trace_brute_force(const glm::dvec3& origin, const glm::dvec3& dir) const;
  // How many times the ray crosses a surface in (0, t_max): each triangle hit (an edge or vertex it
  // passes exactly through counts for one of the triangles that share it), each sphere root, each
  // plane. A closed surface's count is odd where the origin lies inside it.
  uint32_t count_crossings(const glm::dvec3& origin, const glm::dvec3& dir, double t_max = no_hit) const;
  // The first `count` of those crossings in order of distance, each as a nearest hit would be (a
  // sphere's far root with its inward normal, facing the ray), misses past the last.
  std::vector<ReferenceHit> first_hits(const glm::dvec3& origin, const glm::dvec3& dir, double t_max, uint32_t count) const;
  // The hit's object and primitive as the outputs number them (see ObjectPrimitive).
  ObjectPrimitive source(const ReferenceHit& hit) const;
  ObjectPrimitive source(const PointHit& hit) const;

  // Point queries (reference_points.cpp), exact in double. The nearest point to `point` within
  // `max_distance`, inclusive (beyond it a miss, its distance +inf): among points at exactly the same distance the lowest
  // triangle index wins, then the lowest instance, so the tree and brute force agree on the
  // primitive. An instance's triangles are measured in the world's coordinates, so a placement that
  // scales unevenly still gives the world's nearest point.
  PointHit closest_point(const glm::dvec3& point, double max_distance = no_hit) const;
  // The same with every primitive measured: the check on the tree.
  PointHit closest_point_brute_force(const glm::dvec3& point, double max_distance = no_hit) const;
  // The generalized winding number at `point` (Jacobson et al. 2013): each triangle's solid angle over
  // 4 pi, signed by its winding; an instance's mesh's at the point taken into its coordinates (so a
  // mirrored placement of a closed mesh is 1 inside, as the mesh is); 1 inside a sphere, 1 behind a
  // plane (the side its normal leaves). A closed mesh's is 1 inside and 0 outside; an open one's
  // between. Walked with caps (engine/scene/winding_caps.hpp): exact, not an approximation.
  double winding_number(const glm::dvec3& point) const;
  // The same summed over every triangle: the check on the caps.
  double winding_number_brute_force(const glm::dvec3& point) const;
  // The caps of its trees' subtrees (reference_points.cpp), made at the first winding number asked.
  struct Caps;
  const Caps& caps() const;

 private:
  struct Triangle {
    glm::dvec3 v0, v1, v2, normal;
    uint32_t index;
    // Its vertices' ids, in its winding order (winding_caps.hpp): a world triangle's numbered across
    // the meshes, an instanced mesh's within it.
    std::array<uint32_t, 3> corners;
  };
  // What a tree leaf holds: a triangle (into triangles_, or an instanced mesh's), a sphere (into
  // spheres_) or an instance (into instances_).
  struct TreeEntry {
    PrimitiveKind kind;
    uint32_t index;
  };
  // A BVH (planes are infinite: always tested one by one) and what its leaves hold, in leaf order.
  struct Tree {
    std::vector<TreeEntry> entries;
    std::vector<std::array<uint32_t, 2>> nodes;   // child references (engine/scene/bvh.hpp)
    std::vector<std::array<Box, 2>> child_boxes;  // their boxes, exact in double
    bool empty() const { return nodes.empty(); }
  };
  // An instanced mesh's triangles in its own coordinates, and their tree.
  struct MeshTree {
    std::vector<Triangle> triangles;
    Tree tree;
  };
  // An instance as the walk needs it: what takes a ray into its mesh's coordinates, and a mesh
  // normal back into the world's.
  struct Placement {
    uint32_t mesh;
    glm::dmat3 to_mesh;  // the inverse of Instance::linear
    glm::dvec3 translation;
    // The inverse transpose, times the sign of the determinant: a placed triangle's normal by its
    // winding (a mirrored instance turns its winding over with its triangles).
    glm::dmat3 normal_to_world;
    glm::dmat3 linear;      // Instance::linear: a mesh point's offset into the world's
    double smallest_scale;  // the least factor it shrinks a length by (smallest_scale)
  };
  // Point queries' pieces (reference_points.cpp): the nearest so far within a bound, each kind's
  // nearest point, and an instanced mesh's triangles that may hold a nearer one.
  class NearestSoFar;
  PointHit plane_hit(uint32_t index, const glm::dvec3& point) const;
  PointHit sphere_hit(uint32_t index, const glm::dvec3& point) const;
  PointHit triangle_hit(const Triangle& triangle, uint32_t instance, const glm::dvec3& point) const;
  template <typename Visit>
  void nearest_in_mesh(uint32_t instance, const glm::dvec3& point, const NearestSoFar& nearest, Visit visit) const;
  static Tree build_tree(std::vector<TreeEntry> entries, const std::vector<Box>& boxes);
  void test_sphere(uint32_t index, const glm::dvec3& origin, const glm::dvec3& dir, ReferenceHit& hit) const;
  // `instance`: the instance placing the triangle (the ray already in its mesh's coordinates), or
  // no_object.
  void test_triangle(const Triangle& triangle, const glm::dvec3& origin, const glm::dvec3& dir, ReferenceHit& hit,
                     uint32_t instance = no_object) const;
  // Calls visit(entry) for each entry of `tree` in a box the ray enters before t_max, nearer child
  // first; t_max is read again at every box (a nearest-hit search lowers it as it goes).
  template <typename Visit>
  static void walk_tree(const Tree& tree, const glm::dvec3& origin, const glm::dvec3& dir, const double& t_max, Visit visit);
  // Calls visit(triangle, mesh_origin, mesh_dir) for each triangle of instance `instance` in a box of
  // its mesh's tree the ray enters before t_max, the ray taken into the mesh's coordinates.
  template <typename Visit>
  void walk_instance(uint32_t instance, const glm::dvec3& origin, const glm::dvec3& dir, const double& t_max,
                     Visit visit) const;
  // The ray taken into instance `instance`'s mesh's coordinates: its origin and direction there.
  std::pair<glm::dvec3, glm::dvec3> ray_in_mesh(uint32_t instance, const glm::dvec3& origin, const glm::dvec3& dir) const;
  // A mesh normal of instance `instance` (or of no instance) in world coordinates, unit length.
  glm::dvec3 world_normal(const glm::dvec3& normal, uint32_t instance) const;
  void nearest_in_tree(const glm::dvec3& origin, const glm::dvec3& dir, ReferenceHit& hit) const;
  ReferenceHit trace_with(const glm::dvec3& origin, const glm::dvec3& dir, double t_max, bool brute_force) const;

  std::vector<uint32_t> first_triangle_of_mesh_;  // in the numbering of ReferenceHit::index
  std::vector<Sphere> spheres_;  // all of them, those the mask leaves out too (their index is their place)
  std::vector<Plane> planes_;
  Mask ray_mask_;
  std::vector<Triangle> triangles_;  // zero-area triangles left out: no ray can hit them
  std::vector<MeshTree> mesh_trees_;    // by mesh: an instanced mesh's, empty for the others
  std::vector<Placement> instances_;    // all of them, those the mask leaves out too
  Tree tree_;  // triangles, spheres and instances in world coordinates
  mutable std::once_flag caps_made_;
  mutable std::shared_ptr<const Caps> caps_;
};

// Point queries answered by the reference on all cores, as the device's Renderer::closest_points
// (query nearest) and winding_numbers (winding) answer them, in double. The points and largest
// distances are checked (check_query_points).
PointHits reference_point_hits(const ReferenceScene& reference, std::span<const glm::dvec3> points, std::span<const double> max_distances,
                               HitQuery query);
// One point's answer into hits' entry k (a device's point past its loop budget is answered so).
void answer_point(const ReferenceScene& reference, const glm::dvec3& point, double max_distance, HitQuery query, PointHits& hits,
                  size_t k);

// Every pixel's hit for the scene's camera at width x height, on all cores. `progress`, when set,
// receives the fraction of rows done from time to time, from a worker thread.
std::vector<ReferenceHit> render_reference_hits(const ReferenceScene& scene, const Camera& camera,
                                                uint32_t width, uint32_t height,
                                                const std::function<void(double)>& progress = {});

// Depth and normal of the exact scene along the float32 shader's ray directions
// (float32_ray_direction), on all cores: against the reference it is the error of the float32 ray
// alone, the floor that no float32 arithmetic after the ray can go below.
// `aovs`: which of depth and normal to compute.
Frame float32_ray_frame(const ReferenceScene& scene, const Camera& camera, uint32_t width, uint32_t height,
                        AovSet aovs = AovSet{Aov::depth, Aov::normal});

// The nearest hit of each given ray within its range (both checked first: check_given_rays,
// check_ray_ranges), its direction normalized, on all cores; t counts from the ray's origin.
std::vector<ReferenceHit> trace_reference_rays(const ReferenceScene& scene, std::span<const GivenRay> rays,
                                               const RayRanges& ranges = {});

// The nearest hit of `ray` within (t_min, t_max) (see RayRanges), t counting from its origin.
ReferenceHit trace_reference_ray(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max);

// How many times `ray` crosses a surface within (t_min, t_max) (ReferenceScene::count_crossings).
uint32_t count_reference_crossings(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max);

// The first `count` hits of `ray` within (t_min, t_max) (ReferenceScene::first_hits), t counting
// from its origin.
std::vector<ReferenceHit> first_reference_hits(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max,
                                               uint32_t count);

// Pixel `pixel` of `frame`'s outputs (depth and normal; uv is the camera's) from a reference hit,
// rounded to float only here.
void store_reference_hit(Frame& frame, size_t pixel, const ReferenceHit& hit);

// The same outputs the GPU writes, from `scene`'s hits of `camera`'s rays (rounded to float only at
// the end); `source` is the scene `scene` was made from (the surface outputs read its meshes).
// `doubles`: depth64 and normal64 kept too (Python's Reference); they are anyway where camera
// outputs are asked for, which the exact depth makes.
Frame reference_frame(const ReferenceScene& scene, const Scene& source, const std::vector<ReferenceHit>& hits,
                      const Camera& camera, uint32_t width, uint32_t height, AovSet aovs, bool doubles = false);

}  // namespace vkray
