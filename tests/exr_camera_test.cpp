// The camera in the EXR header, read back with OpenImageIO as a user's script would: OpenEXR's
// worldToCamera and worldToNDC take every reference hit point to its planar depth and to its pixel's
// centre, within the rounding of the matrices to float32 (the standard's type); vkray:camera holds
// the camera exactly and the pinhole intrinsics.
#include "engine/io/image_io.hpp"
#include "engine/reference/reference.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/temp_dir_test.hpp"
#include "tests/test_scenes.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>

namespace vkray {
namespace {

using ExrCameraTest = test::TempDirTest;

// An EXR attribute as 16 floats, Imath's order (row by row, for row vectors: p' = p M).
std::array<float, 16> read_matrix(const OIIO::ImageSpec& spec, const char* name) {
  std::array<float, 16> matrix{};
  const OIIO::ParamValue* value = spec.find_attribute(name, OIIO::TypeMatrix44);
  EXPECT_NE(value, nullptr) << name << " is not in the header";
  if (value) std::memcpy(matrix.data(), value->data(), sizeof matrix);
  return matrix;
}

// (p, 1) M as a user computes it, in double from the float32 entries, and the bound on how far each
// component is from the exact matrix's: every entry is within 2^-24 of its value relatively (round
// to nearest), so component c is off by at most 2^-24 sum_k |M_kc p_k| (the double evaluation adds
// some 1e-16 of that).
struct Transformed {
  glm::dvec4 value, bound;
};
Transformed transform(const std::array<float, 16>& m, const glm::dvec3& p) {
  const double point[4] = {p.x, p.y, p.z, 1.0};
  Transformed result{};
  for (int c = 0; c < 4; ++c) {
    for (int k = 0; k < 4; ++k) {
      const double term = point[k] * static_cast<double>(m[4 * k + c]);
      result.value[c] += term;
      result.bound[c] += std::abs(term) * 0x1p-24 * (1.0 + 1e-12);
    }
  }
  return result;
}

// The bound on x / w from bounds on x and w (first order; w is a planar depth well away from 0 here).
double quotient_bound(double x, double w, double x_bound, double w_bound) {
  return (x_bound + std::abs(x / w) * w_bound) / (std::abs(w) - w_bound);
}

TEST_F(ExrCameraTest, HeaderMatricesTakeEveryHitToItsPixelAndPlanarDepth) {
  const Scene scene = test::sized(default_scene(), 64, 48);
  const CameraBasis basis = make_camera_basis(scene.camera, scene.width, scene.height);
  const ReferenceScene reference(scene);
  const std::vector<ReferenceHit> hits = render_reference_hits(reference, scene.camera, scene.width, scene.height);
  const Frame frame = reference_frame(reference, scene, hits, scene.camera, scene.width, scene.height, {Aov::depth});
  const std::filesystem::path path = dir_ / "camera.exr";
  write_exr(path, frame);

  auto input = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(input) << OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  const std::array<float, 16> to_camera = read_matrix(spec, "worldtocamera");
  const std::array<float, 16> to_ndc = read_matrix(spec, "worldtoNDC");

  size_t checked = 0;
  for (uint32_t j = 0; j < scene.height; ++j) {
    for (uint32_t i = 0; i < scene.width; ++i) {
      const ReferenceHit& hit = hits[size_t{j} * scene.width + i];
      if (!std::isfinite(hit.t)) continue;
      const glm::dvec3 direction = basis.direction(pixel_uv(i, j, scene.width, scene.height));
      const glm::dvec3 point = basis.origin + hit.t * direction;
      // Camera space: x right, y up, z the planar depth (along the view direction, -forward).
      const Transformed camera = transform(to_camera, point);
      const glm::dvec3 expected_camera(glm::dot(point - basis.origin, basis.right), glm::dot(point - basis.origin, basis.up),
                                       hit.t * glm::dot(direction, -basis.forward));
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(camera.value[c], expected_camera[c], camera.bound[c] + 1e-12) << "pixel " << i << "," << j << " axis " << c;
      }
      // NDC: the pixel's centre, (0, 0) the image's top-left corner and (1, 1) its bottom-right.
      const Transformed ndc = transform(to_ndc, point);
      const double x = ndc.value.x / ndc.value.w, y = ndc.value.y / ndc.value.w;
      EXPECT_NEAR(x, (i + 0.5) / scene.width, quotient_bound(ndc.value.x, ndc.value.w, ndc.bound.x, ndc.bound.w) + 1e-12)
          << "pixel " << i << "," << j;
      EXPECT_NEAR(y, (j + 0.5) / scene.height, quotient_bound(ndc.value.y, ndc.value.w, ndc.bound.y, ndc.bound.w) + 1e-12)
          << "pixel " << i << "," << j;
      EXPECT_NEAR(ndc.value.w, expected_camera.z, ndc.bound.w + 1e-12) << "pixel " << i << "," << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, size_t{scene.width} * scene.height / 2) << "the scene should fill most of the image";

  // vkray:camera: the camera exactly (JSON numbers read back as the same doubles), and the intrinsics.
  const nlohmann::json description = nlohmann::json::parse(spec.get_string_attribute("vkray:camera"));
  const Camera& camera = scene.camera;
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(description["camera"]["from"][c].get<double>(), camera.from[c]);
    EXPECT_EQ(description["camera"]["to"][c].get<double>(), camera.to[c]);
    EXPECT_EQ(description["camera"]["up"][c].get<double>(), camera.up[c]);
  }
  EXPECT_EQ(description["camera"]["fovy"].get<double>(), camera.fovy_degrees);
  const PinholeIntrinsics k = pinhole_intrinsics(camera, scene.width, scene.height);
  EXPECT_EQ(description["intrinsics"]["fx"].get<double>(), k.fx);
  EXPECT_EQ(description["intrinsics"]["cy"].get<double>(), k.cy);
  EXPECT_EQ(description["world_to_camera"][2][3].get<double>(), world_to_camera(camera, scene.width, scene.height)[2][3]);
}

// What a user of vision code does with the file: reads planar.Z and the intrinsics and
// world_to_camera of vkray:camera, lifts every hit pixel to the world and lands on its P within
// the rounding of the two float32 channels: planar depth within 2^-24 relatively moves the point
// along its ray by 2^-24 t at most, P's components are within 2^-24 of theirs.
TEST_F(ExrCameraTest, PlanarDepthReprojectsToPositionWithTheHeaderCamera) {
  const Scene scene = test::sized(default_scene(), 64, 48);
  const ReferenceScene reference(scene);
  const std::vector<ReferenceHit> hits = render_reference_hits(reference, scene.camera, scene.width, scene.height);
  const Frame frame = reference_frame(reference, scene, hits, scene.camera, scene.width, scene.height,
                                      {Aov::planar_depth, Aov::position, Aov::camera_position});
  const std::filesystem::path path = dir_ / "camera-outputs.exr";
  write_exr(path, frame);

  auto input = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(input) << OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  std::vector<float> pixels(size_t{scene.width} * scene.height * spec.nchannels);
  ASSERT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, pixels.data())) << input->geterror();
  auto channel = [&](const char* name) {
    const int index = spec.channelindex(name);
    EXPECT_GE(index, 0) << name << " is not in the file";
    return [&, index](size_t p) { return index < 0 ? NAN : double{pixels[p * spec.nchannels + index]}; };
  };
  EXPECT_LT(spec.channelindex("Z"), 0) << "depth was not asked for";
  const auto planar = channel("planar.Z"), alpha = channel("A");
  const std::array<std::function<double(size_t)>, 3> position = {channel("P.X"), channel("P.Y"), channel("P.Z")};
  const std::array<std::function<double(size_t)>, 3> in_camera = {channel("camera.P.X"), channel("camera.P.Y"),
                                                                  channel("camera.P.Z")};

  const nlohmann::json description = nlohmann::json::parse(spec.get_string_attribute("vkray:camera"));
  const auto& k = description["intrinsics"];
  const double fx = k["fx"], fy = k["fy"], cx = k["cx"], cy = k["cy"];
  const auto rigid = description["world_to_camera"].get<std::array<std::array<double, 4>, 4>>();
  size_t hit_pixels = 0;
  for (uint32_t j = 0; j < scene.height; ++j) {
    for (uint32_t i = 0; i < scene.width; ++i) {
      const size_t p = size_t{j} * scene.width + i;
      const ReferenceHit& hit = hits[p];
      ASSERT_EQ(alpha(p), std::isfinite(hit.t) ? 1.0 : 0.0) << "pixel " << i << "," << j;
      if (!std::isfinite(hit.t)) {
        EXPECT_EQ(planar(p), INFINITY);
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(position[c](p), 0.0);
          EXPECT_EQ(in_camera[c](p), 0.0);
        }
        continue;
      }
      ++hit_pixels;
      // OpenCV's camera coordinates of the pixel at planar depth z, then p = R^T (c - t).
      const double z = planar(p);
      const glm::dvec3 c((i - cx) * z / fx, (j - cy) * z / fy, z);
      glm::dvec3 world(0.0);
      for (int row = 0; row < 3; ++row) {
        for (int axis = 0; axis < 3; ++axis) world[axis] += rigid[row][axis] * (c[row] - rigid[row][3]);
      }
      for (int axis = 0; axis < 3; ++axis) {
        const double bound = 0x1p-24 * (std::abs(position[axis](p)) + hit.t) + 1e-12 * (1.0 + std::abs(world[axis]));
        EXPECT_NEAR(world[axis], position[axis](p), bound) << "pixel " << i << "," << j << " axis " << axis;
      }
      // camera.P is OpenEXR's camera space: OpenCV's with y up; its z is the planar depth itself.
      EXPECT_EQ(in_camera[2](p), z);
      EXPECT_NEAR(in_camera[0](p), c.x, 0x1p-24 * (std::abs(c.x) + hit.t) + 1e-12) << "pixel " << i << "," << j;
      EXPECT_NEAR(in_camera[1](p), -c.y, 0x1p-24 * (std::abs(c.y) + hit.t) + 1e-12) << "pixel " << i << "," << j;
    }
  }
  EXPECT_GT(hit_pixels, size_t{scene.width} * scene.height / 2);
}

TEST_F(ExrCameraTest, FramesWithoutACameraHaveNone) {
  Frame frame(4, 3, {Aov::depth});  // given rays: no camera made them
  frame.allocate();
  const std::filesystem::path path = dir_ / "rays.exr";
  write_exr(path, frame);
  auto input = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(input) << OIIO::geterror();
  EXPECT_EQ(input->spec().find_attribute("worldtocamera"), nullptr);
  EXPECT_EQ(input->spec().find_attribute("worldtoNDC"), nullptr);
  EXPECT_EQ(input->spec().find_attribute("vkray:camera"), nullptr);
}

}  // namespace
}  // namespace vkray
