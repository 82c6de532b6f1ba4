/* vkray.h from C (a C compiler, no C++): the built-in scene loaded and rendered, rays cast from its
 * camera through the image's centre, masks, first hits and counts, instances moved and a mesh's
 * vertices moved, a bad call answered with a status and a message, a finished scene left as checked.
 * Exits 0 when
 * every check holds, else prints the first that failed. */
#include "engine/api/vkray.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK(condition)                                                        \
  do {                                                                          \
    if (!(condition)) {                                                         \
      fprintf(stderr, "c_api_test: %s failed (%s)\n", #condition, vkray_last_error()); \
      return 1;                                                                 \
    }                                                                           \
  } while (0)

int main(void) {
  CHECK(vkray_api_version() == VKRAY_API_VERSION);
  vkray_output_info output;
  CHECK(vkray_output(0, &output) == 1 && strcmp(output.name, "depth") == 0 && output.components == 1);

  vkray_scene* scene = NULL;
  CHECK(vkray_scene_load("", 32, 24, NULL, NULL, &scene) == VKRAY_OK);
  CHECK(strstr(vkray_scene_describe(scene), "\"width\":32") != NULL);
  /* A mesh's arrays: the counts first, then the copies (the built-in scene's first mesh). */
  uint64_t vertex_count = 0, triangle_count = 0;
  CHECK(vkray_scene_mesh(scene, 0, NULL, NULL, &vertex_count, &triangle_count) == VKRAY_OK && vertex_count >= 3 && triangle_count >= 1);
  double* positions = malloc(vertex_count * 3 * sizeof(double));
  uint32_t* indices = malloc(triangle_count * 3 * sizeof(uint32_t));
  CHECK(vkray_scene_mesh(scene, 0, positions, indices, NULL, NULL) == VKRAY_OK);
  for (uint64_t k = 0; k < triangle_count * 3; ++k) CHECK(indices[k] < vertex_count);
  CHECK(isfinite(positions[3 * vertex_count - 1]));
  free(positions);
  free(indices);
  CHECK(vkray_scene_mesh(scene, 1000, NULL, NULL, NULL, NULL) == VKRAY_INPUT_ERROR);
  vkray_renderer* renderer = NULL;
  CHECK(vkray_renderer_new(scene, NULL, "float", "auto", &renderer) == VKRAY_OK);
  CHECK(vkray_renderer_prepare(renderer) == VKRAY_OK);
  /* Its time joins the setup's, the one "pipeline_ms" there is (no call has run). */
  const char* made = strstr(vkray_renderer_timings(renderer), "\"pipeline_ms\":");
  CHECK(made != NULL && strtod(made + strlen("\"pipeline_ms\":"), NULL) > 0.0);
  CHECK(vkray_renderer_prepare(NULL) == VKRAY_INPUT_ERROR);

  static float depth[24][32], normal[24][32][3];
  const char* aovs[] = {"depth", "normal"};
  void* results[] = {depth, normal};
  CHECK(vkray_render(renderer, NULL, 0, 0, 255, 2, aovs, results) == VKRAY_OK);
  CHECK(isfinite(depth[12][16]) && depth[12][16] > 0.0f);

  /* The scene's camera is at (0, 1.8, 6) looking at (0, 0.7, 0): a ray there, and a dead one. */
  const double rays[2][6] = {{0.0, 1.8, 6.0, 0.0, -1.1, -6.0}, {0.0, 1.8, 6.0, 0.0, 0.0, 0.0}};
  float t[2];
  uint32_t mesh[2];
  const char* outputs[] = {"t", "mesh-id"};
  void* hits[] = {t, mesh};
  CHECK(vkray_cast_rays(renderer, &rays[0][0], 2, NULL, NULL, 0, 255, 1, 2, outputs, hits) == VKRAY_OK);
  CHECK(isfinite(t[0]) && isinf(t[1]) && mesh[1] == VKRAY_NO_HIT);
  CHECK(vkray_cast_rays(renderer, &rays[0][0], 2, NULL, NULL, VKRAY_BAD_RAYS_FAIL, 255, 1, 2, outputs, hits) == VKRAY_INPUT_ERROR);
  CHECK(strstr(vkray_last_error(), "ray 1: the direction is 0") != NULL);
  uint8_t blocked[2];
  CHECK(vkray_occluded(renderer, &rays[0][0], 2, NULL, NULL, 0, 255, blocked) == VKRAY_OK && blocked[0] == 1 && blocked[1] == 0);

  /* Masks: a triangle in front of another; rays of mask 1 pass the near one (mask 2). */
  vkray_scene* layered = NULL;
  const double near_far[2][9] = {{-1, -1, 0, 1, -1, 0, 0, 1, 0}, {-1, -1, -1, 1, -1, -1, 0, 1, -1}};
  const int64_t corners[3] = {0, 1, 2};
  CHECK(vkray_scene_new(8, 8, &layered) == VKRAY_OK);
  for (int k = 0; k < 2; ++k) CHECK(vkray_scene_add_mesh(layered, near_far[k], 3, corners, 0, 1, NULL) == VKRAY_OK);
  CHECK(vkray_scene_set_mask(layered, 0, 2) == VKRAY_OK && vkray_scene_set_mask(layered, 2, 1) == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_finish(layered) == VKRAY_OK && strstr(vkray_scene_describe(layered), "\"masks\":[2,255]") != NULL);
  vkray_renderer* masked = NULL;
  CHECK(vkray_renderer_new(layered, NULL, "float", "auto", &masked) == VKRAY_OK);
  const double down_z[6] = {0, 0, 5, 0, 0, -1};
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 1, 1, 2, outputs, hits) == VKRAY_OK && mesh[0] == 1 && fabsf(t[0] - 6.0f) < 1e-5f);
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 0, 1, 2, outputs, hits) == VKRAY_INPUT_ERROR);
  CHECK(vkray_occluded(masked, down_z, 1, NULL, NULL, 0, 256, blocked) == VKRAY_INPUT_ERROR);
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 255, 1, 2, outputs, hits) == VKRAY_OK && mesh[0] == 0);
  /* First hits: the near triangle (mesh 0) at 5, the far one at 6, then a miss; 0 or too many refused. */
  float first_t[3];
  uint32_t first_mesh[3];
  void* first_hits[2] = {first_t, first_mesh};
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 255, 3, 2, outputs, first_hits) == VKRAY_OK);
  CHECK(first_mesh[0] == 0 && first_mesh[1] == 1 && first_mesh[2] == VKRAY_NO_HIT);
  CHECK(fabsf(first_t[0] - 5.0f) < 1e-5f && fabsf(first_t[1] - 6.0f) < 1e-5f && isinf(first_t[2]));
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 255, 0, 2, outputs, first_hits) == VKRAY_INPUT_ERROR);
  CHECK(vkray_cast_rays(masked, down_z, 1, NULL, NULL, 0, 255, VKRAY_HITS_MAX + 1, 2, outputs, first_hits) == VKRAY_INPUT_ERROR);
  /* Counting: both triangles with every bit, the far one alone with mask 1, the near one in a range ending between. */
  uint32_t crossings[1];
  const double ends_between[1] = {5.5};
  CHECK(vkray_count_intersections(masked, down_z, 1, NULL, NULL, 0, 255, crossings) == VKRAY_OK && crossings[0] == 2);
  CHECK(vkray_count_intersections(masked, down_z, 1, NULL, NULL, 0, 1, crossings) == VKRAY_OK && crossings[0] == 1);
  CHECK(vkray_count_intersections(masked, down_z, 1, NULL, ends_between, 0, 255, crossings) == VKRAY_OK && crossings[0] == 1);
  vkray_renderer_free(masked);
  vkray_scene_free(layered);

  /* Instances: the near triangle stored once, placed at z = 0 and at z = -1; the first moved to
   * z = -2 (the second, 6 away, is then the nearest), then the mesh's vertices raised by 0.5, which
   * moves both. A mesh or instance that does not exist is refused. */
  vkray_scene* placed = NULL;
  const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const double lowered[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 1};
  const double sunk[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -2, 0, 0, 0, 1};
  CHECK(vkray_scene_new(8, 8, &placed) == VKRAY_OK);
  CHECK(vkray_scene_add_mesh(placed, near_far[0], 3, corners, 0, 1, NULL) == VKRAY_OK);
  CHECK(vkray_scene_add_instance(placed, 0, identity, 255) == VKRAY_OK && vkray_scene_add_instance(placed, 0, lowered, 255) == VKRAY_OK);
  CHECK(vkray_scene_add_instance(placed, 1, identity, 255) == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_finish(placed) == VKRAY_OK);
  vkray_renderer* moving = NULL;
  CHECK(vkray_renderer_new(placed, NULL, "float", "auto", &moving) == VKRAY_OK);
  uint32_t instance[1];
  const char* placed_outputs[] = {"t", "instance-id"};
  void* placed_hits[] = {t, instance};
  CHECK(vkray_cast_rays(moving, down_z, 1, NULL, NULL, 0, 255, 1, 2, placed_outputs, placed_hits) == VKRAY_OK);
  CHECK(instance[0] == 0 && fabsf(t[0] - 5.0f) < 1e-5f);
  const uint32_t first_instance = 0, no_instance = 2;
  CHECK(vkray_renderer_set_transforms(moving, &first_instance, sunk, 1) == VKRAY_OK);
  CHECK(strstr(vkray_renderer_timings(moving), "\"scene_update_ms\"") != NULL && vkray_renderer_device_name(moving)[0] != '\0');
  CHECK(vkray_renderer_set_transforms(moving, &no_instance, sunk, 1) == VKRAY_INPUT_ERROR);
  CHECK(vkray_cast_rays(moving, down_z, 1, NULL, NULL, 0, 255, 1, 2, placed_outputs, placed_hits) == VKRAY_OK);
  CHECK(instance[0] == 1 && fabsf(t[0] - 6.0f) < 1e-5f);
  double raised[9];
  for (int k = 0; k < 9; ++k) raised[k] = near_far[0][k] + (k % 3 == 2 ? 0.5 : 0.0);
  CHECK(vkray_renderer_set_vertices(moving, 0, raised, 3) == VKRAY_OK);
  CHECK(vkray_renderer_set_vertices(moving, 1, raised, 3) == VKRAY_INPUT_ERROR);
  CHECK(vkray_cast_rays(moving, down_z, 1, NULL, NULL, 0, 255, 1, 2, placed_outputs, placed_hits) == VKRAY_OK);
  CHECK(instance[0] == 1 && fabsf(t[0] - 5.5f) < 1e-5f);
  vkray_renderer_free(moving);
  vkray_scene_free(placed);

  /* A finished or loaded scene is read-only: every call that adds or changes is refused (a NaN radius
   * added after the check would reach the renderer unchecked), and a loaded one too. */
  const double sphere[4] = {0, 0, 0, 1}, plane[6] = {0, -1, 0, 0, 1, 0};
  CHECK(vkray_scene_add_spheres(scene, sphere, 1) == VKRAY_INPUT_ERROR && strstr(vkray_last_error(), "finished") != NULL);
  CHECK(vkray_scene_add_planes(scene, plane, 1) == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_add_instance(scene, 0, NULL, 255) == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_set_mask(scene, 0, 3) == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_set_camera(scene, "{\"from\": [0, 0, 5], \"to\": [0, 0, 0]}") == VKRAY_INPUT_ERROR);
  CHECK(vkray_scene_add_mesh(scene, near_far[0], 3, corners, 0, 1, NULL) == VKRAY_INPUT_ERROR);
  /* Before the check, what it refuses: a NaN radius, a negative one, a zero plane normal, a singular
   * placement, a mask on a mesh its instances draw. */
  const double nan_sphere[4] = {0, 0, 0, NAN}, negative_sphere[4] = {0, 0, 0, -1}, flat_plane[6] = {0, 0, 0, 0, 0, 0};
  const double singular[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  const double* bad_spheres[2] = {nan_sphere, negative_sphere};
  for (int k = 0; k < 2; ++k) {
    vkray_scene* unchecked = NULL;
    CHECK(vkray_scene_new(8, 8, &unchecked) == VKRAY_OK && vkray_scene_add_spheres(unchecked, bad_spheres[k], 1) == VKRAY_OK);
    CHECK(vkray_scene_finish(unchecked) == VKRAY_INPUT_ERROR && strstr(vkray_last_error(), "spheres[0].radius") != NULL);
    vkray_scene_free(unchecked);
  }
  vkray_scene* unchecked = NULL;
  CHECK(vkray_scene_new(8, 8, &unchecked) == VKRAY_OK && vkray_scene_add_planes(unchecked, flat_plane, 1) == VKRAY_OK);
  CHECK(vkray_scene_finish(unchecked) == VKRAY_INPUT_ERROR && strstr(vkray_last_error(), "planes[0].normal") != NULL);
  vkray_scene_free(unchecked);
  CHECK(vkray_scene_new(8, 8, &unchecked) == VKRAY_OK && vkray_scene_add_mesh(unchecked, near_far[0], 3, corners, 0, 1, NULL) == VKRAY_OK);
  CHECK(vkray_scene_add_instance(unchecked, 0, singular, 255) == VKRAY_OK);
  CHECK(vkray_scene_finish(unchecked) == VKRAY_INPUT_ERROR && strstr(vkray_last_error(), "instances[0].transform") != NULL);
  vkray_scene_free(unchecked);
  CHECK(vkray_scene_new(8, 8, &unchecked) == VKRAY_OK && vkray_scene_add_mesh(unchecked, near_far[0], 3, corners, 0, 1, NULL) == VKRAY_OK);
  CHECK(vkray_scene_add_instance(unchecked, 0, identity, 255) == VKRAY_OK && vkray_scene_set_mask(unchecked, 0, 2) == VKRAY_OK);
  CHECK(vkray_scene_finish(unchecked) == VKRAY_INPUT_ERROR && strstr(vkray_last_error(), "meshes[0].mask") != NULL);
  vkray_scene_free(unchecked);
  /* A flag vkray does not know is refused, not ignored. */
  CHECK(vkray_cast_rays(renderer, &rays[0][0], 1, NULL, NULL, 4, 255, 1, 2, outputs, hits) == VKRAY_INPUT_ERROR);
  CHECK(strstr(vkray_last_error(), "flags") != NULL);

  vkray_scene* missing = NULL;
  CHECK(vkray_scene_load("/nonexistent/scene.json", 0, 0, NULL, NULL, &missing) == VKRAY_INPUT_ERROR && missing == NULL);
  CHECK(strstr(vkray_last_error(), "/nonexistent/scene.json") != NULL);
  vkray_renderer_free(renderer);
  vkray_scene_free(scene);
  printf("c_api_test: vkray %s through its C API on %s\n", vkray_version(), "the default device");
  return 0;
}
