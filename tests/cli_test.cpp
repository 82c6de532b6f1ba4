// End-to-end tests of the `vkray` command: each test runs the built binary (VKRAY_BINARY) in a
// temporary folder of its own through the shell, with stdout and stderr redirected into files, and
// reads the OpenEXR and PNG files it writes back with OpenImageIO. Expected values come from the
// output contract (channel names, UV formula, camera model) and closed-form scenes, never from the
// engine's own code.
#include "engine/frame.hpp"
#include "engine/reference/compare.hpp"
#include "engine/render/search.hpp"
#include "tests/temp_dir_test.hpp"
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <string_view>
#include <vector>

#ifndef VKRAY_BINARY
#error "VKRAY_BINARY comes from CMake"
#endif

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Running vkray

struct RunResult {
  std::string args;    // for messages
  int exit_code = -1;  // the process's exit status; 128 + signal when it was killed
  std::string out;
  std::string err;
};

std::string shell_quote(std::string_view text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string read_text(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

size_t count_lines(const std::string& text) { return static_cast<size_t>(std::count(text.begin(), text.end(), '\n')); }

bool starts_with(const std::string& text, std::string_view prefix) { return text.rfind(prefix, 0) == 0; }

bool has_line_starting_with(const std::string& text, std::string_view prefix) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (starts_with(line, prefix)) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Reading images back

struct Image {
  std::string format;  // OpenImageIO's format name: "openexr", "png"
  int width = 0;
  int height = 0;
  std::set<std::string> channel_names;
  std::map<std::string, std::vector<float>> channels;  // by name, row-major from the top row

  float at(const std::string& channel, int i, int j) const {
    return channels.at(channel)[static_cast<size_t>(j) * static_cast<size_t>(width) + static_cast<size_t>(i)];
  }
};

// Reads every channel as float; with `require_contract_types`, fails unless each is stored as the
// contract says: float32, but A as half.
void read_image(const fs::path& path, Image& image, bool require_contract_types = false) {
  ASSERT_TRUE(fs::is_regular_file(path)) << path << " was not written";
  auto input = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(input) << path << ": " << OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  image.format = input->format_name();
  image.width = spec.width;
  image.height = spec.height;
  EXPECT_EQ(spec.x, 0);
  EXPECT_EQ(spec.y, 0);
  if (require_contract_types) {
    for (int c = 0; c < spec.nchannels; ++c) {
      const OIIO::TypeDesc contract = spec.channelnames[c] == "A" ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
      EXPECT_EQ(spec.channelformat(c), contract) << path << ": " << spec.channelnames[c] << " is " << spec.channelformat(c).c_str();
    }
  }
  const size_t pixel_count = static_cast<size_t>(spec.width) * static_cast<size_t>(spec.height);
  const size_t channel_count = static_cast<size_t>(spec.nchannels);
  std::vector<float> pixels(pixel_count * channel_count);
  ASSERT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
      << path << ": " << input->geterror();
  for (size_t c = 0; c < channel_count; ++c) {
    const std::string& name = spec.channelnames[c];
    image.channel_names.insert(name);
    std::vector<float>& values = image.channels[name];
    values.resize(pixel_count);
    for (size_t p = 0; p < pixel_count; ++p) values[p] = pixels[p * channel_count + c];
  }
}

// ---------------------------------------------------------------------------------------------
// The contract's image plane and camera model, written out independently of the engine

using Vec3 = std::array<double, 3>;

Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 operator*(double s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 normalize(const Vec3& a) { return (1.0 / std::sqrt(dot(a, a))) * a; }

// Pixel (i, j), j from the top row: x = (2(i+0.5) - W)/min(W,H), y = (H - 2(j+0.5))/min(W,H).
std::array<double, 2> pixel_uv(int i, int j, int width, int height) {
  const double shorter = std::min(width, height);
  return {(2.0 * (i + 0.5) - width) / shorter, (height - 2.0 * (j + 0.5)) / shorter};
}

struct PinholeCamera {
  Vec3 from, to, up;
  double fovy_degrees;

  // The course camera: forward = normalize(from - to), right = normalize(up x forward),
  // up' = forward x right, image plane at d = sy / tan(fovy/2) with sy = H / min(W, H).
  Vec3 direction(int i, int j, int width, int height) const {
    const Vec3 forward = normalize(from - to);
    const Vec3 right = normalize(cross(up, forward));
    const Vec3 true_up = cross(forward, right);
    const double sy = static_cast<double>(height) / std::min(width, height);
    const double d = sy / std::tan(fovy_degrees * std::numbers::pi / 360.0);
    const auto uv = pixel_uv(i, j, width, height);
    return normalize(uv[0] * right + uv[1] * true_up - d * forward);
  }
};

double relative_error(double value, double expected) { return std::abs(value - expected) / std::abs(expected); }

constexpr float infinity = std::numeric_limits<float>::infinity();

// The per-pixel invariants of the depth and normal outputs and A that hold for any scene: A is 0 or
// 1; a hit has finite Z > 0 and a unit normal, a miss Z = +inf and N = 0. Reports the first few
// offending pixels.
void expect_hit_invariants(const Image& exr) {
  const bool has_depth = exr.channel_names.count("Z") != 0, has_normal = exr.channel_names.count("N.X") != 0;
  ASSERT_TRUE(exr.channel_names.count("A")) << "depth or normal come with A";
  int failures = 0;
  for (int j = 0; j < exr.height; ++j) {
    for (int i = 0; i < exr.width; ++i) {
      std::ostringstream problem;
      const float a = exr.at("A", i, j);
      if (a != 0.0f && a != 1.0f) problem << " A = " << a << " is neither 0 nor 1;";
      const bool hit = a == 1.0f;
      if (has_depth) {
        const float z = exr.at("Z", i, j);
        if (hit && !(std::isfinite(z) && z > 0.0f)) problem << " a hit with Z = " << z << ";";
        if (!hit && z != infinity) problem << " a miss with Z = " << z << " (expected +inf);";
      }
      if (has_normal) {
        const Vec3 n{exr.at("N.X", i, j), exr.at("N.Y", i, j), exr.at("N.Z", i, j)};
        const double length = std::sqrt(dot(n, n));
        if (hit && !(std::abs(length - 1.0) <= 1e-5)) problem << " a hit with |N| = " << length << ";";
        if (!hit && length != 0.0) problem << " a miss with N = " << n[0] << ", " << n[1] << ", " << n[2] << ";";
      }
      if (!problem.str().empty() && ++failures <= 10) {
        ADD_FAILURE() << "pixel (" << i << ", " << j << "):" << problem.str();
      }
    }
  }
  EXPECT_EQ(failures, 0) << "pixels breaking the hit/miss invariants";
}

std::set<std::string> names(std::initializer_list<const char*> list) { return {list.begin(), list.end()}; }

// ---------------------------------------------------------------------------------------------
// Fixture: a temporary folder per test, where vkray runs

class CliTest : public vkray::test::TempDirTest {
 protected:
  // Runs vkray with `args` in the test's folder; a hung run is killed after 300 s (exit 124): the
  // basic suite's bench under AddressSanitizer on lavapipe ran past 120 s on a slow day, and ctest's
  // 600 s a test still stands behind this.
  // `environment`: extra NAME=value settings for the run, e.g. to hide every Vulkan driver.
  RunResult vkray(const std::vector<std::string>& args, const std::string& environment = "") const {
    std::string command = "cd " + shell_quote(dir_.string()) + " && exec env " + environment + " timeout 300 " +
                          shell_quote(VKRAY_BINARY);
    for (const auto& arg : args) command += " " + shell_quote(arg);
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    command += " >" + shell_quote(out.string()) + " 2>" + shell_quote(err.string()) + " </dev/null";
    const int status = std::system(command.c_str());
    RunResult result;
    for (const auto& arg : args) result.args += (result.args.empty() ? "" : " ") + shell_quote(arg);
    if (status != -1 && WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
    if (status != -1 && WIFSIGNALED(status)) result.exit_code = 128 + WTERMSIG(status);
    result.out = read_text(out);
    result.err = read_text(err);
    fs::remove(out);
    fs::remove(err);
    return result;
  }

  fs::path path(const std::string& name) const { return dir_ / name; }

  // A usage, input or runtime error: the exit code, one line on stderr that starts with "vkray: ",
  // nothing on stdout and no image written.
  void expect_error(const RunResult& run, int exit_code, std::initializer_list<std::string> mentions) const {
    SCOPED_TRACE("vkray " + run.args);
    EXPECT_EQ(run.exit_code, exit_code) << "stderr: " << run.err;
    EXPECT_EQ(count_lines(run.err), 1u) << "stderr must be one line, got: " << run.err;
    EXPECT_TRUE(!run.err.empty() && run.err.back() == '\n') << run.err;
    EXPECT_TRUE(starts_with(run.err, "vkray: ")) << run.err;
    for (const auto& text : mentions) EXPECT_NE(run.err.find(text), std::string::npos) << "'" << text << "' not in: " << run.err;
    EXPECT_EQ(run.out, "");
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const auto extension = entry.path().extension();
      EXPECT_TRUE(extension != ".exr" && extension != ".png") << entry.path() << " written despite the error";
    }
  }
};

// A camera on +z looking at a unit sphere at the origin; 33 is odd, so the centre pixel's ray is
// exactly the -z axis and hits at distance 4 with normal +z.
constexpr const char* sphere_scene = R"({
  "camera": {"from": [0, 0, 5], "to": [0, 0, 0], "up": [0, 1, 0], "fovy": 30},
  "image": {"width": 33, "height": 33},
  "spheres": [{"center": [0, 0, 0], "radius": 1}]
})";

// Checks every pixel of a render of sphere_scene against the closed-form ray/sphere intersection:
// from O = (0,0,5) along unit D, t = -b - sqrt(b^2 - 24) with b = O.D, normal (O + tD) / 1. Pixels
// whose rays graze the silhouette (|b^2 - 24| < 0.05) are left out: float32 cannot classify them.
void expect_sphere_closed_form(const Image& exr) {
  ASSERT_EQ(exr.width, 33);
  ASSERT_EQ(exr.height, 33);
  // The centre pixel, to float precision.
  EXPECT_NEAR(exr.at("Z", 16, 16), 4.0, 4.0 * 1e-6);
  EXPECT_NEAR(exr.at("N.X", 16, 16), 0.0, 1e-6);
  EXPECT_NEAR(exr.at("N.Y", 16, 16), 0.0, 1e-6);
  EXPECT_NEAR(exr.at("N.Z", 16, 16), 1.0, 1e-6);
  EXPECT_EQ(exr.at("A", 16, 16), 1.0f);

  const PinholeCamera camera{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30.0};
  const Vec3 origin{0, 0, 5};
  int hits = 0, misses = 0;
  for (int j = 0; j < 33; ++j) {
    for (int i = 0; i < 33; ++i) {
      SCOPED_TRACE("pixel (" + std::to_string(i) + ", " + std::to_string(j) + ")");
      const Vec3 d = camera.direction(i, j, 33, 33);
      const double b = dot(origin, d), discriminant = b * b - 24.0;
      if (std::abs(discriminant) < 0.05) continue;
      if (discriminant < 0.0) {
        ++misses;
        EXPECT_EQ(exr.at("A", i, j), 0.0f);
        EXPECT_EQ(exr.at("Z", i, j), infinity);
        continue;
      }
      ++hits;
      const double t = -b - std::sqrt(discriminant);
      const Vec3 n = origin + t * d;
      ASSERT_EQ(exr.at("A", i, j), 1.0f);
      EXPECT_LT(relative_error(exr.at("Z", i, j), t), 1e-5) << "Z = " << exr.at("Z", i, j) << ", expected " << t;
      EXPECT_NEAR(exr.at("N.X", i, j), n[0], 1e-4);
      EXPECT_NEAR(exr.at("N.Y", i, j), n[1], 1e-4);
      EXPECT_NEAR(exr.at("N.Z", i, j), n[2], 1e-4);
    }
  }
  // The sphere's silhouette has a radius of about 12.5 pixels: ~490 hit, ~560 miss.
  EXPECT_GT(hits, 400);
  EXPECT_GT(misses, 450);
}

// ---------------------------------------------------------------------------------------------
// 1. The default scene

TEST_F(CliTest, DefaultSceneWritesContractChannels) {
  const RunResult run = vkray({"render", "--width", "64", "--height", "48", "-o", "out.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray: wrote out.exr and out.png (64x48, depth,normal) on ")) << run.out;
  EXPECT_EQ(count_lines(run.out), 2u) << run.out;  // and the preview's depth legend
  EXPECT_TRUE(has_line_starting_with(run.out, "preview: depth ")) << run.out;

  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("out.exr"), exr, true));
  EXPECT_EQ(exr.format, "openexr");
  EXPECT_EQ(exr.channel_names, names({"Z", "N.X", "N.Y", "N.Z", "A"}));
  ASSERT_EQ(exr.width, 64);
  ASSERT_EQ(exr.height, 48);
  ASSERT_EQ(exr.channel_names.size(), 5u);
  expect_hit_invariants(exr);

  // Top row: the camera looks 10 degrees down with a 45 degree field of view, so the top row sees
  // sky above every object.
  for (int i = 0; i < 64; ++i) {
    EXPECT_EQ(exr.at("A", i, 0), 0.0f) << "top row, pixel " << i;
    EXPECT_EQ(exr.at("Z", i, 0), infinity) << "top row, pixel " << i;
  }
  // Bottom row: the ground plane y = 0 in front of every object, seen from y = 1.8, so the depth
  // is 1.8 / -dir.y along the contract's camera ray and the normal is +y.
  const PinholeCamera camera{{0.0, 1.8, 6.0}, {0.0, 0.7, 0.0}, {0, 1, 0}, 45.0};
  for (int i = 0; i < 64; ++i) {
    SCOPED_TRACE("bottom row, pixel " + std::to_string(i));
    ASSERT_EQ(exr.at("A", i, 47), 1.0f);
    const double expected = 1.8 / -camera.direction(i, 47, 64, 48)[1];
    EXPECT_LT(relative_error(exr.at("Z", i, 47), expected), 1e-5) << exr.at("Z", i, 47) << " vs " << expected;
    EXPECT_NEAR(exr.at("N.X", i, 47), 0.0, 1e-6);
    EXPECT_NEAR(exr.at("N.Y", i, 47), 1.0, 1e-6);
    EXPECT_NEAR(exr.at("N.Z", i, 47), 0.0, 1e-6);
  }

  Image png;
  ASSERT_NO_FATAL_FAILURE(read_image(path("out.png"), png));
  EXPECT_EQ(png.format, "png");
  EXPECT_EQ(png.width, 2 * 64) << "one panel per output";
  EXPECT_EQ(png.height, 48);
}

// The built-in scene has its own size (800x600) when no --width/--height is given, and the
// default output is render.exr in the working folder.
TEST_F(CliTest, DefaultOutputNameAndSceneSize) {
  const RunResult run = vkray({"render", "--no-preview"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray: wrote render.exr (800x600, depth,normal) on ")) << run.out;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("render.exr"), exr, true));
  EXPECT_EQ(exr.width, 800);
  EXPECT_EQ(exr.height, 600);
  EXPECT_FALSE(fs::exists(path("render.png"))) << "--no-preview wrote a preview";
}

// ---------------------------------------------------------------------------------------------
// 2. Scenes with closed-form answers

TEST_F(CliTest, SphereSceneMatchesClosedForm) {
  write("sphere.json", sphere_scene);
  const RunResult run = vkray({"render", "sphere.json", "-o", "sphere.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(33x33, depth,normal)"), std::string::npos) << "the scene's image size: " << run.out;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("sphere.exr"), exr, true));
  EXPECT_EQ(exr.channel_names, names({"Z", "N.X", "N.Y", "N.Z", "A"}));
  expect_hit_invariants(exr);
  expect_sphere_closed_form(exr);
}

// Zero-area triangles (a repeated vertex, collinear vertices) are dropped and counted; the
// proper triangle beside them still renders.
TEST_F(CliTest, ZeroAreaTrianglesAreCountedAndDropped) {
  write("degenerate.json", R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
    "image": {"width": 16, "height": 16},
    "meshes": [{"positions": [[-1, -1, 0], [1, -1, 0], [0, 1, 0], [2, 2, 0], [3, 3, 0]],
                "triangles": [[0, 1, 2], [0, 0, 1], [0, 3, 4], [2, 3, 3]]}]})");
  const RunResult run = vkray({"render", "degenerate.json", "-o", "degenerate.exr", "--check"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("vkray: note: degenerate.json: 3 zero-area triangles dropped (no ray can hit them)"),
            std::string::npos) << run.err;
  EXPECT_NE(run.out.find("hit/miss mismatches 0 of 256"), std::string::npos) << run.out;
}

// The double-precision CPU reference (--reference) writes the same contract.
TEST_F(CliTest, ReferenceRendererMatchesClosedForm) {
  write("sphere.json", sphere_scene);
  const RunResult run = vkray({"render", "sphere.json", "--reference", "--no-preview", "-o", "sphere.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out, "vkray: wrote sphere.exr (33x33, depth,normal) on CPU reference (double precision)\n");
  EXPECT_FALSE(fs::exists(path("sphere.png")));
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("sphere.exr"), exr, true));
  EXPECT_EQ(exr.channel_names, names({"Z", "N.X", "N.Y", "N.Z", "A"}));
  expect_hit_invariants(exr);
  expect_sphere_closed_form(exr);
}

// A camera at height h looking straight down at the plane y = 0: every ray hits, at distance
// h * sqrt(x^2 + y^2 + d^2) / d for image-plane point (x, y), d = sy / tan(fovy / 2). The image is
// portrait (sy = 1.5), and the plane's normal is given pointing away from the camera, unnormalised:
// the output normal must still be the unit normal facing the ray, +y.
TEST_F(CliTest, PlaneSceneDepthMatchesClosedFormEverywhere) {
  write("plane.json", R"({
    "camera": {"from": [0, 2.5, 0], "to": [0, 0, 0], "up": [0, 0, -1], "fovy": 60},
    "planes": [{"point": [0, 0, 0], "normal": [0, -3, 0]}]
  })");
  const int width = 24, height = 36;
  const RunResult run = vkray({"render", "plane.json", "--width", "24", "--height", "36", "-o", "plane.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("plane.exr"), exr, true));
  ASSERT_EQ(exr.width, width);
  ASSERT_EQ(exr.height, height);
  const double h = 2.5, sy = 36.0 / 24.0, d = sy / std::tan(30.0 * std::numbers::pi / 180.0);
  int failures = 0;
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const auto [x, y] = pixel_uv(i, j, width, height);
      const double expected = h * std::sqrt(x * x + y * y + d * d) / d;
      const float z = exr.at("Z", i, j);
      const bool ok = exr.at("A", i, j) == 1.0f && relative_error(z, expected) < 1e-5 &&
                      std::abs(exr.at("N.X", i, j)) < 1e-6f && std::abs(exr.at("N.Y", i, j) - 1.0f) < 1e-6f &&
                      std::abs(exr.at("N.Z", i, j)) < 1e-6f;
      if (!ok && ++failures <= 10) {
        ADD_FAILURE() << "pixel (" << i << ", " << j << "): A = " << exr.at("A", i, j) << ", Z = " << z << " (expected "
                      << expected << "), N = " << exr.at("N.X", i, j) << ", " << exr.at("N.Y", i, j) << ", "
                      << exr.at("N.Z", i, j) << " (expected 0, 1, 0)";
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

// The camera outputs alone (no depth asked for) on the same plane, seen straight down from height
// h: every hit is at planar depth h, at P = (h x / d, 0, -h y / d) in the world and (h x / d,
// h y / d, h) in OpenEXR's camera space (x right, y up, z the view direction). They come from the
// GPU's depth, within the relative error the test above holds it to, and from the camera in double.
TEST_F(CliTest, CameraOutputsOnAPlaneMatchClosedForm) {
  write("plane.json", R"({
    "camera": {"from": [0, 2.5, 0], "to": [0, 0, 0], "up": [0, 0, -1], "fovy": 60},
    "planes": [{"point": [0, 0, 0], "normal": [0, -3, 0]}]
  })");
  const int width = 24, height = 36;
  const RunResult run = vkray({"render", "plane.json", "--width", "24", "--height", "36", "--aov",
                               "planar-depth,position,camera-position", "-o", "plane.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("plane.exr"), exr, true));
  EXPECT_EQ(exr.channels.count("Z"), 0u) << "depth was not asked for";
  EXPECT_TRUE(fs::is_regular_file(path("plane.png"))) << "the preview shows the depth the outputs come from";
  const double h = 2.5, sy = 36.0 / 24.0, d = sy / std::tan(30.0 * std::numbers::pi / 180.0);
  const double tolerance = 1e-5;  // relative, of the distance to the hit (the depth test above)
  int failures = 0;
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const auto [x, y] = pixel_uv(i, j, width, height);
      const double distance = h * std::sqrt(x * x + y * y + d * d) / d;
      const std::array<double, 3> world = {h * x / d, 0.0, -h * y / d}, camera = {h * x / d, h * y / d, h};
      const char* world_channels[] = {"P.X", "P.Y", "P.Z"};
      const char* camera_channels[] = {"camera.P.X", "camera.P.Y", "camera.P.Z"};
      bool ok = exr.at("A", i, j) == 1.0f && std::abs(exr.at("planar.Z", i, j) - h) <= tolerance * distance;
      for (int c = 0; c < 3; ++c) {
        ok = ok && std::abs(exr.at(world_channels[c], i, j) - world[c]) <= tolerance * distance &&
             std::abs(exr.at(camera_channels[c], i, j) - camera[c]) <= tolerance * distance;
      }
      if (!ok && ++failures <= 10) {
        ADD_FAILURE() << "pixel (" << i << ", " << j << "): planar.Z = " << exr.at("planar.Z", i, j) << " (expected " << h
                      << "), P = " << exr.at("P.X", i, j) << ", " << exr.at("P.Y", i, j) << ", " << exr.at("P.Z", i, j)
                      << " (expected " << world[0] << ", 0, " << world[2] << "), camera.P = " << exr.at("camera.P.X", i, j)
                      << ", " << exr.at("camera.P.Y", i, j) << ", " << exr.at("camera.P.Z", i, j);
      }
    }
  }
  EXPECT_EQ(failures, 0);
}

// --miss changes the depth channels on missed pixels alone (A = 0 there) and says so in the header;
// a value that is not one is refused before any work.
TEST_F(CliTest, MissValueReplacesOnlyMissedDepths) {
  expect_error(vkray({"render", "missing.json", "--miss", "zero"}), 2, {"--miss", "'zero'", "inf, -inf, nan or a number"});
  expect_error(vkray({"render", "missing.json", "--miss", "1e99"}), 2, {"--miss", "'1e99'", "beyond float32's range"});
  expect_error(vkray({"render", "missing.json", "--miss", "1e39"}), 2, {"--miss", "'1e39'", "beyond float32's range"});
  write("sphere.json", sphere_scene);
  Image reference;
  ASSERT_EQ(vkray({"render", "sphere.json", "--aov", "depth,planar-depth", "--no-preview", "-o", "inf.exr"}).exit_code, 0);
  ASSERT_NO_FATAL_FAILURE(read_image(path("inf.exr"), reference, true));
  for (const auto& [given, expected] : {std::pair<std::string, float>{"0", 0.0f}, {"-1.5", -1.5f}, {"nan", NAN}}) {
    SCOPED_TRACE("--miss " + given);
    const RunResult run = vkray({"render", "sphere.json", "--aov", "depth,planar-depth", "--no-preview", "-o",
                                 "miss.exr", "--miss", given});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image exr;
    ASSERT_NO_FATAL_FAILURE(read_image(path("miss.exr"), exr, true));
    size_t misses = 0;
    for (const char* channel : {"Z", "planar.Z"}) {
      for (size_t p = 0; p < exr.channels.at(channel).size(); ++p) {
        const float value = exr.channels.at(channel)[p], before = reference.channels.at(channel)[p];
        if (reference.channels.at("A")[p] == 1.0f) {
          EXPECT_EQ(value, before) << channel << " pixel " << p;
        } else {
          ++misses;
          EXPECT_TRUE(std::isinf(before)) << channel << " pixel " << p;
          EXPECT_TRUE(std::isnan(expected) ? std::isnan(value) : value == expected) << channel << " pixel " << p << ": " << value;
        }
      }
    }
    EXPECT_GT(misses, 0u);
    EXPECT_EQ(exr.channels.at("A"), reference.channels.at("A"));
    auto input = OIIO::ImageInput::open(path("miss.exr").string());
    ASSERT_TRUE(input);
    const float recorded = input->spec().get_float_attribute("vkray:miss", 12345.0f);
    EXPECT_TRUE(std::isnan(expected) ? std::isnan(recorded) : recorded == expected) << recorded;
  }
}

// mesh-id and primitive-id are 32-bit unsigned channels, 0xffffffff exactly where A is 0, from the
// GPU and from the reference; both see the built-in scene's two meshes (0, 1), its sphere (2) and its
// plane (3). (tests/bvh_gpu_test.cpp holds the GPU's ids to the reference's pixel by pixel.)
TEST_F(CliTest, IdsAreUnsignedChannelsNumberedMeshesSpheresPlanes) {
  for (const char* renderer : {"gpu", "reference"}) {
    SCOPED_TRACE(renderer);
    std::vector<std::string> args = {"render", "--width", "64", "--height", "48", "--aov", "mesh-id,primitive-id",
                                     "--no-preview", "-o", std::string(renderer) + ".exr"};
    if (std::string(renderer) == "reference") args.push_back("--reference");
    const RunResult run = vkray(args);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    auto input = OIIO::ImageInput::open(path(std::string(renderer) + ".exr").string());
    ASSERT_TRUE(input) << OIIO::geterror();
    const OIIO::ImageSpec& spec = input->spec();
    const size_t pixels = size_t{64} * 48;
    std::vector<float> alpha(pixels);
    const int a = spec.channelindex("A");
    ASSERT_GE(a, 0);
    ASSERT_TRUE(input->read_image(0, 0, a, a + 1, OIIO::TypeFloat, alpha.data()));
    for (const char* name : {"mesh_id", "primitive_id"}) {
      const int channel = spec.channelindex(name);
      ASSERT_GE(channel, 0) << name;
      EXPECT_EQ(spec.channelformat(channel), OIIO::TypeUInt) << name;
      std::vector<uint32_t> ids(pixels);
      ASSERT_TRUE(input->read_image(0, 0, channel, channel + 1, OIIO::TypeUInt, ids.data()));
      std::set<uint32_t> seen;
      for (size_t p = 0; p < pixels; ++p) {
        EXPECT_EQ(ids[p] == 0xffffffffu, alpha[p] == 0.0f) << name << " pixel " << p;
        if (alpha[p] == 1.0f) seen.insert(ids[p]);
      }
      if (std::string(name) == "mesh_id") {
        EXPECT_EQ(seen, (std::set<uint32_t>{0, 1, 2, 3}));
      }
    }
  }
}

// --mask: a sphere in front of a plane, each with its own bit. The mask of the plane's bit alone
// shows the plane where the sphere stood, on the GPU, in many views and in the reference alike.
TEST_F(CliTest, MaskLeavesOutWhatSharesNoBitWithIt) {
  std::ofstream(path("masked.json")) << R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
    "spheres": [{"center": [0, 0, 0], "radius": 1, "mask": 2}],
    "planes": [{"point": [0, 0, -2], "normal": [0, 0, 1], "mask": 1}]})";
  const std::vector<std::vector<std::string>> runs = {
      {"--mask", "1", "-o", "plane.exr"}, {"--mask", "1", "--reference", "-o", "plane-ref.exr"},
      {"--mask", "1", "--orbit", "2", "-o", "plane-{index}.exr"}, {"--mask", "3", "-o", "both.exr"}};
  for (const std::vector<std::string>& extra : runs) {
    std::vector<std::string> args = {"render", path("masked.json").string(), "--width", "16", "--height", "12",
                                     "--aov", "mesh-id"};
    args.insert(args.end(), extra.begin(), extra.end());
    if (std::ranges::find(extra, "--orbit") == extra.end()) args.push_back("--no-preview");
    const RunResult run = vkray(args);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string output = extra.back().find("{index}") != std::string::npos ? "plane-0.exr" : extra.back();
    SCOPED_TRACE(output);
    auto input = OIIO::ImageInput::open(path(output).string());
    ASSERT_TRUE(input) << OIIO::geterror();
    const int channel = input->spec().channelindex("mesh_id");
    ASSERT_GE(channel, 0);
    std::vector<uint32_t> ids(16 * 12);
    ASSERT_TRUE(input->read_image(0, 0, channel, channel + 1, OIIO::TypeUInt, ids.data()));
    const uint32_t centre = ids[6 * 16 + 8];  // the sphere's, where the mask lets it through
    EXPECT_EQ(centre, extra[1] == "3" ? 0u : 1u);
  }
  const RunResult none = vkray({"render", path("masked.json").string(), "--mask", "4", "-o", "none.exr", "--no-preview"});
  EXPECT_EQ(none.exit_code, 0) << none.err;
  EXPECT_NE(none.err.find("--mask 4 shares no bit with the mask of any object of the scene (1, 2): every ray misses"),
            std::string::npos)
      << none.err;
  const RunResult zero = vkray({"render", path("masked.json").string(), "--mask", "0", "-o", "zero.exr"});
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_NE(zero.err.find("--mask"), std::string::npos) << zero.err;
}

// The note counts what a ray can meet: an instanced mesh's instances' masks, not the mesh's own (which
// stood for them before, so every instance masked out went without a note).
TEST_F(CliTest, MaskNoteCountsInstancesMasks) {
  std::ofstream(path("placed.json")) << R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
    "meshes": [{"name": "leaf", "positions": [[-1, -1, 0], [1, -1, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]}],
    "instances": [{"mesh": "leaf", "mask": 2}, {"mesh": "leaf", "transform": {"translate": [0, 0, -1]}, "mask": 6}]})";
  const RunResult none = vkray({"render", path("placed.json").string(), "--mask", "1", "-o", "none.exr", "--no-preview",
                                "--width", "8", "--height", "8"});
  EXPECT_EQ(none.exit_code, 0) << none.err;
  EXPECT_NE(none.err.find("--mask 1 shares no bit with the mask of any object of the scene (2, 6): every ray misses"),
            std::string::npos)
      << none.err;
  const RunResult some = vkray({"render", path("placed.json").string(), "--mask", "4", "-o", "some.exr", "--no-preview",
                                "--width", "8", "--height", "8"});
  EXPECT_EQ(some.exit_code, 0) << some.err;
  EXPECT_EQ(some.err.find("every ray misses"), std::string::npos) << some.err;
}

// An instance a scene file scales past what vkray holds is refused as the file is read, with --check
// too (hostile campaign 3: a scale of 1e39 aborted the process in Embree's builder, 1e38 rendered
// every ray a miss and exited 0).
TEST_F(CliTest, InstanceTransformsBeyondWhatVkrayHoldsAreRefused) {
  for (const std::string scale : {"1e39", "1e38", "[1, 1, 1e-39]"}) {
    std::ofstream(path("huge.json")) << R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
      "meshes": [{"name": "leaf", "positions": [[-1, -1, 0], [1, -1, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]}],
      "instances": [{"mesh": "leaf"}, {"mesh": "leaf", "transform": {"scale": )" << scale << "}}]}";
    expect_error(vkray({"render", path("huge.json").string(), "--check", "--width", "8", "--height", "8", "-o", "huge.exr"}), 2,
                 {"huge.json: instances[1].transform: "});
  }
}

// ---------------------------------------------------------------------------------------------
// 3. and 4. Choosing outputs with --aov

TEST_F(CliTest, UvOnlyMatchesImagePlaneFormula) {
  for (const auto& [width, height] : {std::pair{40, 20}, std::pair{20, 40}, std::pair{7, 7}}) {
    SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height));
    const std::string size = std::to_string(width) + "x" + std::to_string(height);
    const RunResult run = vkray({"render", "--aov", "uv", "--width", std::to_string(width), "--height",
                                 std::to_string(height), "-o", "uv" + size + ".exr"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("(" + size + ", uv)"), std::string::npos) << run.out;
    Image exr;
    ASSERT_NO_FATAL_FAILURE(read_image(path("uv" + size + ".exr"), exr, true));
    EXPECT_EQ(exr.channel_names, names({"U", "V"})) << "uv alone has no A";
    ASSERT_EQ(exr.width, width);
    ASSERT_EQ(exr.height, height);
    ASSERT_EQ(exr.channel_names.size(), 2u);
    int failures = 0;
    for (int j = 0; j < height; ++j) {
      for (int i = 0; i < width; ++i) {
        const auto [x, y] = pixel_uv(i, j, width, height);
        if ((std::abs(exr.at("U", i, j) - x) > 1e-6 || std::abs(exr.at("V", i, j) - y) > 1e-6) && ++failures <= 10) {
          ADD_FAILURE() << "pixel (" << i << ", " << j << "): UV = " << exr.at("U", i, j) << ", " << exr.at("V", i, j)
                        << ", expected " << x << ", " << y;
        }
      }
    }
    // The shorter side spans [-1, 1]: the outermost pixel centres sit half a pixel inside it.
    const int shorter = std::min(width, height);
    const std::string across = width <= height ? "U" : "V";
    const auto [lowest, highest] = std::minmax_element(exr.channels[across].begin(), exr.channels[across].end());
    EXPECT_NEAR(*highest, 1.0 - 1.0 / shorter, 1e-6);
    EXPECT_NEAR(*lowest, -(1.0 - 1.0 / shorter), 1e-6);

    Image png;
    ASSERT_NO_FATAL_FAILURE(read_image(path("uv" + size + ".png"), png));
    EXPECT_EQ(png.width, width);
    EXPECT_EQ(png.height, height);
  }
}

// --aov depth and --aov normal alone write only their channels (and A), with the same values as a
// render of both; all three outputs give three preview panels.
TEST_F(CliTest, AovSelectsChannels) {
  RunResult run = vkray({"render", "--width", "40", "--height", "30", "-o", "both.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image both;
  ASSERT_NO_FATAL_FAILURE(read_image(path("both.exr"), both, true));

  run = vkray({"render", "--aov", "depth", "--width", "40", "--height", "30", "-o", "depth.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(40x30, depth)"), std::string::npos) << run.out;
  Image depth;
  ASSERT_NO_FATAL_FAILURE(read_image(path("depth.exr"), depth, true));
  EXPECT_EQ(depth.channel_names, names({"Z", "A"}));
  expect_hit_invariants(depth);

  run = vkray({"render", "--aov", "normal", "--width", "40", "--height", "30", "-o", "normal.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(40x30, normal)"), std::string::npos) << run.out;
  Image normal;
  ASSERT_NO_FATAL_FAILURE(read_image(path("normal.exr"), normal, true));
  EXPECT_EQ(normal.channel_names, names({"N.X", "N.Y", "N.Z", "A"}));
  expect_hit_invariants(normal);

  ASSERT_EQ(depth.width, 40);
  ASSERT_EQ(normal.width, 40);
  ASSERT_EQ(depth.height, 30);
  ASSERT_EQ(normal.height, 30);
  int failures = 0;
  for (int j = 0; j < 30; ++j) {
    for (int i = 0; i < 40; ++i) {
      const float z = both.at("Z", i, j), z_alone = depth.at("Z", i, j);
      const bool same = both.at("A", i, j) == depth.at("A", i, j) && both.at("A", i, j) == normal.at("A", i, j) &&
                        (z == z_alone || relative_error(z_alone, z) < 1e-6) &&
                        std::abs(both.at("N.X", i, j) - normal.at("N.X", i, j)) < 1e-6f &&
                        std::abs(both.at("N.Y", i, j) - normal.at("N.Y", i, j)) < 1e-6f &&
                        std::abs(both.at("N.Z", i, j) - normal.at("N.Z", i, j)) < 1e-6f;
      if (!same && ++failures <= 10) ADD_FAILURE() << "pixel (" << i << ", " << j << ") differs between renders";
    }
  }
  for (const char* name : {"depth.png", "normal.png"}) {
    Image png;
    ASSERT_NO_FATAL_FAILURE(read_image(path(name), png));
    EXPECT_EQ(png.width, 40) << name;
  }

  run = vkray({"render", "--aov", "uv,normal,depth", "--width", "40", "--height", "30", "-o", "all.exr", "--preview",
               "panels.png"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray: wrote all.exr and panels.png (40x30, depth,normal,uv) on ")) << run.out;
  Image all;
  ASSERT_NO_FATAL_FAILURE(read_image(path("all.exr"), all, true));
  EXPECT_EQ(all.channel_names, names({"Z", "N.X", "N.Y", "N.Z", "U", "V", "A"}));
  expect_hit_invariants(all);
  EXPECT_FALSE(fs::exists(path("all.png"))) << "--preview names the preview";
  Image png;
  ASSERT_NO_FATAL_FAILURE(read_image(path("panels.png"), png));
  EXPECT_EQ(png.width, 3 * 40);
  EXPECT_EQ(png.height, 30);
}

// ---------------------------------------------------------------------------------------------
// 5. Errors: exit 2 for usage and input, 1 for runtime failures, always one line on stderr

TEST_F(CliTest, OutputInMissingFolderExitsOne) {
  const std::string output = (dir_ / "no-such-folder" / "out.exr").string();
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "-o", output});
  expect_error(run, 1, {output});
  EXPECT_FALSE(fs::exists(dir_ / "no-such-folder"));
}

TEST_F(CliTest, UnwritablePreviewExitsOne) {
  const std::string preview = (dir_ / "no-such-folder" / "out.png").string();
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "-o", "out.exr", "--preview", preview});
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_EQ(count_lines(run.err), 1u) << run.err;
  EXPECT_NE(run.err.find(preview), std::string::npos) << run.err;
}

TEST_F(CliTest, InvalidSceneValueExitsTwoNamingFileAndJsonPath) {
  write("bad.json", R"({
    "camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 30},
    "spheres": [{"center": [0, 0, 0], "radius": -1}]
  })");
  const RunResult run = vkray({"render", "bad.json", "-o", "out.exr"});
  expect_error(run, 2, {"bad.json: spheres[0].radius: "});

  write("typo.json", R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 30}, "sphere": []})");
  expect_error(vkray({"render", "typo.json", "-o", "out.exr"}), 2, {"typo.json: sphere: ", "spheres"});
}

TEST_F(CliTest, InvalidJsonExitsTwoNamingFileAndLine) {
  write("broken.json", "{\n  \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0], \"fovy\": 30},\n  \"spheres\": [,]\n}\n");
  expect_error(vkray({"render", "broken.json", "-o", "out.exr"}), 2, {"broken.json:3:", "invalid JSON"});
}

TEST_F(CliTest, MissingSceneFileExitsTwo) {
  expect_error(vkray({"render", "no-such-scene.json", "-o", "out.exr"}), 2, {"no-such-scene.json"});
}

TEST_F(CliTest, TruncatedObjExitsTwoNamingObjAndLine) {
  write("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2");  // the last face cut off mid-line
  write("cut.json", R"({
    "camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 30},
    "meshes": [{"obj": "cut.obj"}]
  })");
  expect_error(vkray({"render", "cut.json", "-o", "out.exr"}), 2, {"cut.json", "meshes[0].obj", "cut.obj:4:"});
}

// No Vulkan driver at all (the loader pointed at a driver manifest that does not exist): exit 1
// with one line that says how to get one.
TEST_F(CliTest, NoVulkanDriverExitsOneWithTheFix) {
  for (const char* command : {"render", "info"}) {
    const RunResult run = vkray({command}, "VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json");
    EXPECT_EQ(run.exit_code, 1) << command << ": " << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_NE(run.err.find("mesa-vulkan-drivers"), std::string::npos) << run.err;
    EXPECT_FALSE(fs::exists(path("render.exr")));
  }
}

TEST_F(CliTest, UnknownDeviceExitsOne) {
  expect_error(vkray({"render", "--width", "8", "--height", "8", "--device", "no-such-device", "-o", "out.exr"}), 1,
               {"no-such-device"});
  expect_error(vkray({"info", "--device", "no-such-device"}), 1, {"no-such-device"});
}

TEST_F(CliTest, BadImageSizeExitsTwo) {
  expect_error(vkray({"render", "--width", "0", "-o", "out.exr"}), 2, {"0x600"});
  expect_error(vkray({"render", "--height", "0", "-o", "out.exr"}), 2, {"800x0"});
  expect_error(vkray({"render", "--width", "65537", "--height", "1", "-o", "out.exr"}), 2, {"65537x1"});
  expect_error(vkray({"render", "--width", "-1", "-o", "out.exr"}), 2, {"--width"});
  expect_error(vkray({"render", "--width", "ten", "-o", "out.exr"}), 2, {"--width"});
}

TEST_F(CliTest, BadAovExitsTwo) {
  expect_error(vkray({"render", "--aov", "bogus", "-o", "out.exr"}), 2, {"bogus", "depth, normal, uv"});
  expect_error(vkray({"render", "--aov", "depth,", "-o", "out.exr"}), 2, {"--aov"});
  expect_error(vkray({"render", "--aov", "", "-o", "out.exr"}), 2, {"--aov"});
}

TEST_F(CliTest, UsageErrorsExitTwo) {
  expect_error(vkray({}), 2, {"subcommand"});
  expect_error(vkray({"bogus"}), 2, {});
  expect_error(vkray({"--bogus"}), 2, {});
  expect_error(vkray({"render", "--bogus"}), 2, {"--bogus"});
  expect_error(vkray({"render", "a.json", "b.json"}), 2, {"b.json"});
  expect_error(vkray({"info", "--bogus"}), 2, {"--bogus"});
}

// The output is OpenEXR whatever its name would make the image writer choose, and the preview never
// replaces it.
TEST_F(CliTest, NonExrOutputExitsTwo) {
  expect_error(vkray({"render", "--aov", "normal", "--width", "8", "--height", "8", "-o", "out.png"}), 2, {"out.png"});
  expect_error(vkray({"render", "--width", "8", "--height", "8", "-o", "out.tif"}), 2, {"out.tif"});
  expect_error(vkray({"render", "--width", "8", "--height", "8", "-o", "out"}), 2, {"out"});
  expect_error(vkray({"render", "--width", "8", "--height", "8", "-o", "out.exr", "--preview", "./out.exr"}), 2,
               {"--preview"});
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "-o", "upper.EXR", "--no-preview"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("upper.EXR"), exr, true));
  EXPECT_EQ(exr.format, "openexr");
}

// --check measures hits against the reference, which uv alone does not have.
TEST_F(CliTest, CheckWithUvOnlyExitsTwo) {
  expect_error(vkray({"render", "--aov", "uv", "--check", "--width", "8", "--height", "8", "-o", "out.exr"}), 2,
               {"--check"});
}

// ---------------------------------------------------------------------------------------------
// 6. and 7. Help, version and device information

std::string project_version() {
  const fs::path cmake_lists = fs::path(__FILE__).parent_path().parent_path() / "CMakeLists.txt";
  const std::string text = read_text(cmake_lists);
  std::smatch match;
  if (!std::regex_search(text, match, std::regex(R"(project\(\s*vkray\s+VERSION\s+([0-9.]+))"))) return {};
  return match[1];
}

// The synopses of docs/command-line.md (the page's first block) name every option each command's
// --help lists, by its long name or its short one: a student reads the synopsis first.
TEST_F(CliTest, ReadmeSynopsesNameEveryOption) {
  const std::string page = read_text(fs::path(__FILE__).parent_path().parent_path() / "docs" / "command-line.md");
  const size_t block = page.find("\n```");
  ASSERT_NE(block, std::string::npos);
  const std::string synopses = page.substr(block, page.find("```", block + 4) - block);
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"render"}, {"bench"}, {"view"}, {"info"}, {"report"}, {"manifest", "merge"}, {"manifest", "export"}}) {
    std::string name = "vkray";
    for (const auto& word : command) name += " " + word;
    SCOPED_TRACE(name);
    // The command's lines: from its first to the next command's.
    std::string lines;
    std::istringstream in(synopses);
    bool own = false;
    for (std::string line; std::getline(in, line);) {
      if (line.starts_with("vkray ")) own = line.starts_with(name + " ");
      if (own) lines += line + "\n";
    }
    ASSERT_FALSE(lines.empty());
    std::vector<std::string> arguments = command;
    arguments.push_back("--help");
    const RunResult help = vkray(arguments);
    ASSERT_EQ(help.exit_code, 0) << help.err;
    const std::regex option(R"(\n +(-[a-zA-Z],)?(--[a-z][a-z0-9-]*))");
    size_t options = 0;
    for (auto it = std::sregex_iterator(help.out.begin(), help.out.end(), option); it != std::sregex_iterator(); ++it) {
      const std::string long_name = (*it)[2], short_name = (*it)[1].str().substr(0, 2);
      if (long_name == "--help") continue;
      ++options;
      auto named = [&](const std::string& flag) {
        return !flag.empty() && std::regex_search(lines, std::regex("[\\[ |]" + flag + "[\\] ]"));
      };
      EXPECT_TRUE(named(long_name) || named(short_name)) << long_name << " is not in the synopsis of docs/command-line.md";
    }
    EXPECT_GT(options, 0u);
  }
}

TEST_F(CliTest, HelpAndVersionPrintToStdout) {
  RunResult run = vkray({"--help"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  EXPECT_NE(run.out.find("render"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("info"), std::string::npos) << run.out;

  run = vkray({"render", "--help"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  for (const char* option : {"--aov", "--width", "--height", "-o,--output", "--preview", "--no-preview", "--device",
                             "--timings", "--check", "--reference", "depth, normal, uv"}) {
    EXPECT_NE(run.out.find(option), std::string::npos) << option << " missing from: " << run.out;
  }

  const std::string version = project_version();
  ASSERT_FALSE(version.empty()) << "no project(vkray VERSION ...) in the top-level CMakeLists.txt";
  run = vkray({"--version"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  EXPECT_EQ(run.out, "vkray " + version + "\n");
}

TEST_F(CliTest, InfoMarksTheChosenDevice) {
  const RunResult run = vkray({"info"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(has_line_starting_with(run.out, "* [")) << run.out;
  EXPECT_TRUE(has_line_starting_with(run.out, "vkray uses [")) << run.out;
  // The device marked "* [k] NAME" is the one "vkray uses [k] NAME" names.
  std::smatch chosen, uses;
  ASSERT_TRUE(std::regex_search(run.out, chosen, std::regex(R"((^|\n)\* (\[[0-9]+\] [^\n(]*))")));
  ASSERT_TRUE(std::regex_search(run.out, uses, std::regex(R"(\nvkray uses (\[[0-9]+\] [^\n]*))")));
  EXPECT_TRUE(starts_with(uses[1].str(), chosen[2].str())) << run.out;
}

// ---------------------------------------------------------------------------------------------
// 8. Extremes and reports

TEST_F(CliTest, OnePixelImage) {
  const RunResult run = vkray({"render", "--width", "1", "--height", "1", "-o", "one.exr", "--timings"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray: wrote one.exr and one.png (1x1, depth,normal) on ")) << run.out;
  EXPECT_TRUE(has_line_starting_with(run.out, "timings ")) << run.out;
  EXPECT_TRUE(has_line_starting_with(run.out, "      dispatch (GPU time)")) << run.out;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("one.exr"), exr, true));
  EXPECT_EQ(exr.width, 1);
  EXPECT_EQ(exr.height, 1);
  EXPECT_EQ(exr.channel_names, names({"Z", "N.X", "N.Y", "N.Z", "A"}));
  expect_hit_invariants(exr);
  // The single ray is the view direction, from (0, 1.8, 6) towards (0, 0.7, 0). It meets the
  // built-in cube (the box [-0.7, 0.7] x [0, 1.4] x [-0.7, 0.7] turned 30 degrees about +y and moved
  // to (0.4, 0, -1.6)) before the ground: a slab test in the cube's frame gives the distance and face.
  const Vec3 from{0.0, 1.8, 6.0}, direction = normalize(Vec3{0.0, 0.7, 0.0} - from), centre{0.4, 0.0, -1.6};
  const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
  auto to_cube = [&](const Vec3& v) { return Vec3{c * v[0] - s * v[2], v[1], s * v[0] + c * v[2]}; };
  auto from_cube = [&](const Vec3& v) { return Vec3{c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]}; };
  const Vec3 origin = to_cube(from - centre), d = to_cube(direction);
  const Vec3 low{-0.7, 0.0, -0.7}, high{0.7, 1.4, 0.7};
  double t_enter = -INFINITY, t_exit = INFINITY;
  Vec3 face{0, 0, 0};
  for (size_t axis = 0; axis < 3; ++axis) {
    const double t1 = (low[axis] - origin[axis]) / d[axis], t2 = (high[axis] - origin[axis]) / d[axis];
    if (std::min(t1, t2) > t_enter) {
      t_enter = std::min(t1, t2);
      face = Vec3{0, 0, 0};
      face[axis] = d[axis] > 0 ? -1.0 : 1.0;
    }
    t_exit = std::min(t_exit, std::max(t1, t2));
  }
  ASSERT_LT(t_enter, t_exit) << "the test's own geometry: the view ray must meet the cube";
  ASSERT_LT(t_enter, 1.8 / -direction[1]) << "the test's own geometry: the cube must be in front of the ground";
  const Vec3 normal = from_cube(face);
  EXPECT_EQ(exr.at("A", 0, 0), 1.0f);
  EXPECT_LT(relative_error(exr.at("Z", 0, 0), t_enter), 1e-5) << exr.at("Z", 0, 0) << " vs " << t_enter;
  EXPECT_NEAR(exr.at("N.X", 0, 0), normal[0], 1e-5);
  EXPECT_NEAR(exr.at("N.Y", 0, 0), normal[1], 1e-5);
  EXPECT_NEAR(exr.at("N.Z", 0, 0), normal[2], 1e-5);
  Image png;
  ASSERT_NO_FATAL_FAILURE(read_image(path("one.png"), png));
  EXPECT_EQ(png.width, 2);
  EXPECT_EQ(png.height, 1);
}

TEST_F(CliTest, CheckPrintsErrorAgainstReference) {
  const RunResult run = vkray({"render", "--width", "32", "--height", "24", "--check", "-o", "out.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(has_line_starting_with(run.out, "error vs. double-precision reference: ")) << run.out;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(run.out, match, std::regex(R"(hit/miss mismatches ([0-9]+) of ([0-9]+) )"))) << run.out;
  EXPECT_EQ(match[2].str(), "768") << "every pixel compared";
  EXPECT_LE(std::stoi(match[1].str()), 2) << "GPU and reference disagree on hit or miss: " << run.out;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("out.exr"), exr, true));
  EXPECT_EQ(exr.width, 32);
}

// The preview's depth panel has a legend: the depth of its white and of its darkest grey, the
// nearest and farthest finite depth of the EXR, printed and stored as the PNG's Comment.
TEST_F(CliTest, ThePreviewsDepthLegendGivesTheNearestAndFarthestDepth) {
  const RunResult run = vkray({"render", "--width", "64", "--height", "48", "--aov", "depth,normal", "-o", "out.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("out.exr"), exr, true));
  float nearest = INFINITY, farthest = 0.0f;
  for (float z : exr.channels.at("Z")) {
    if (std::isfinite(z)) nearest = std::min(nearest, z), farthest = std::max(farthest, z);
  }
  char legend[120];
  std::snprintf(legend, sizeof legend, "depth %.5g white .. %.5g dark grey (grey ~ 1/depth)", nearest, farthest);
  EXPECT_TRUE(has_line_starting_with(run.out, std::string("preview: ") + legend)) << run.out << legend;
  auto png = OIIO::ImageInput::open(path("out.png").string());
  ASSERT_TRUE(png);
  EXPECT_EQ(png->spec().get_string_attribute("Comment"), legend);
  // No depth panel, no legend.
  const RunResult normals = vkray({"render", "--width", "64", "--height", "48", "--aov", "normal", "-o", "n.exr"});
  ASSERT_EQ(normals.exit_code, 0) << normals.err;
  EXPECT_EQ(normals.out.find("preview: depth"), std::string::npos) << normals.out;
}

// A sphere of radius 1e-6 seen obliquely through a 1e-4 degree field of view: the float32 rays
// alone are too coarse for its silhouette (adjacent pixels' directions differ by ~4e-8, a float32
// step of the direction). --check prints that floor beside the error, so flips there read as the
// ray's; the float64 shader has no such floor and no flips.
TEST_F(CliTest, CheckPrintsTheFloat32RaysOwnErrorBesideTheError) {
  write("tiny.json", R"({"image": {"width": 64, "height": 48},
    "camera": {"from": [0, 0, 0], "to": [1, 1, 1], "up": [0, 1, 0], "fovy": 1e-4},
    "spheres": [{"center": [1, 1, 1], "radius": 1e-6}]})");
  const std::regex mismatches(R"(hit/miss mismatches ([0-9]+) of 3072 )");
  const RunResult run = vkray({"render", "tiny.json", "--check", "-o", "out.exr", "--no-preview"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(run.out, match, std::regex(R"(\nfloat32 rays alone \([^)]*\): hit/miss mismatches ([0-9]+) of 3072 )")))
      << run.out;
  EXPECT_GT(std::stoi(match[1].str()), 0) << run.out;
  const RunResult exact = vkray({"render", "tiny.json", "--check", "--precision", "double", "-o", "out.exr", "--no-preview"});
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  EXPECT_EQ(exact.out.find("float32 rays alone"), std::string::npos) << exact.out;
  ASSERT_TRUE(std::regex_search(exact.out, match, mismatches)) << exact.out;
  EXPECT_EQ(match[1].str(), "0") << exact.out;
}

// A UV sphere of radius 1 around (2, 3, -1) as OBJ text: 64 segments around, 32 from pole to pole.
// Its silhouette from any direction lies between radius cos(pi / 32) > 0.995 and 1.
std::string uv_sphere_obj() {
  std::ostringstream obj;
  constexpr int rings = 32, segments = 64;
  obj << "v 2 4 -1\n";
  for (int r = 1; r < rings; ++r) {
    const double theta = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * std::numbers::pi * s / segments;
      obj << "v " << 2 + std::sin(theta) * std::cos(phi) << ' ' << 3 + std::cos(theta) << ' ' << -1 + std::sin(theta) * std::sin(phi) << '\n';
    }
  }
  obj << "v 2 2 -1\n";
  auto vertex = [](int r, int s) { return 2 + (r - 1) * segments + s % segments; };
  for (int s = 0; s < segments; ++s) obj << "f 1 " << vertex(1, s + 1) << ' ' << vertex(1, s) << '\n';
  for (int r = 1; r < rings - 1; ++r) {
    for (int s = 0; s < segments; ++s) {
      obj << "f " << vertex(r, s) << ' ' << vertex(r, s + 1) << ' ' << vertex(r + 1, s + 1) << '\n';
      obj << "f " << vertex(r, s) << ' ' << vertex(r + 1, s + 1) << ' ' << vertex(r + 1, s) << '\n';
    }
  }
  const int last = 2 + (rings - 1) * segments;
  for (int s = 0; s < segments; ++s) obj << "f " << last << ' ' << vertex(rings - 1, s) << ' ' << vertex(rings - 1, s + 1) << '\n';
  return obj.str();
}

// `vkray render MODEL.obj` frames the model: its bounding sphere (here the sphere itself) touches
// the shorter borders. A pixel centre at distance k + 0.5 pixels from the image centre along the
// shorter side lies inside the silhouette (radius between 0.995 and 1 of half that side) for the
// outermost rows or columns at these sizes, and the longer side keeps the same margins as the
// circle does.
TEST_F(CliTest, ModelIsFramedToItsBoundingSphere) {
  {
    std::ofstream(path("ball.obj")) << uv_sphere_obj();
  }
  for (const auto& [width, height] : {std::pair{64, 48}, std::pair{48, 64}, std::pair{40, 40}}) {
    SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height));
    const RunResult run = vkray({"render", "ball.obj", "--width", std::to_string(width), "--height",
                                 std::to_string(height), "--aov", "depth", "--no-preview", "-o", "ball.exr"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image exr;
    ASSERT_NO_FATAL_FAILURE(read_image(path("ball.exr"), exr, true));
    int min_i = width, max_i = -1, min_j = height, max_j = -1;
    for (int j = 0; j < height; ++j) {
      for (int i = 0; i < width; ++i) {
        if (exr.at("A", i, j) == 1.0f) min_i = std::min(min_i, i), max_i = std::max(max_i, i), min_j = std::min(min_j, j), max_j = std::max(max_j, j);
      }
    }
    const int shorter = std::min(width, height);
    // Centred: the hit pixels span the same number of pixels on both sides of the centre.
    EXPECT_EQ(min_i + max_i, width - 1);
    EXPECT_EQ(min_j + max_j, height - 1);
    // Touching the shorter borders, and a disk: as wide as it is high.
    EXPECT_EQ(max_i - min_i + 1, shorter);
    EXPECT_EQ(max_j - min_j + 1, shorter);
  }
}

// The camera that frames a model is printed as a --camera option; pasted back, it renders the same
// pixels (the numbers read back as the same doubles). A model off the origin, so that no coordinate
// is round.
TEST_F(CliTest, FramedCameraIsPrintedReadyToPaste) {
  write("tetra.obj", "v 0.1234567 -3.3 7.01\nv 1.9 -2.2 7.3\nv 0.7 -1.05 6.4\nv 0.8 -2.9 8.9\nf 1 2 3\nf 1 3 4\nf 2 4 3\nf 1 4 2\n");
  const RunResult framed = vkray({"render", "tetra.obj", "--width", "48", "--height", "40", "--no-preview", "-o", "framed.exr"});
  ASSERT_EQ(framed.exit_code, 0) << framed.err;
  const std::string prefix = "camera: --camera '";
  const size_t start = framed.out.find(prefix);
  ASSERT_NE(start, std::string::npos) << framed.out;
  const size_t end = framed.out.find("'\n", start + prefix.size());
  ASSERT_NE(end, std::string::npos) << framed.out;
  const std::string camera = framed.out.substr(start + prefix.size(), end - start - prefix.size());
  const RunResult pasted = vkray({"render", "tetra.obj", "--width", "48", "--height", "40", "--no-preview", "-o",
                                  "pasted.exr", "--camera", camera});
  ASSERT_EQ(pasted.exit_code, 0) << pasted.err;
  EXPECT_NE(pasted.out.find(prefix + camera + "'"), std::string::npos) << pasted.out;
  Image first, second;
  ASSERT_NO_FATAL_FAILURE(read_image(path("framed.exr"), first, true));
  ASSERT_NO_FATAL_FAILURE(read_image(path("pasted.exr"), second, true));
  for (const char* channel : {"Z", "N.X", "N.Y", "N.Z", "A"}) EXPECT_EQ(first.channels.at(channel), second.channels.at(channel)) << channel;
  size_t hits = 0;
  for (float a : first.channels.at("A")) hits += a == 1.0f;
  EXPECT_GT(hits, 100u) << "the model should fill much of the image";
}

// --view frames from another side: a tetrahedron whose faces all point away from one vertex is
// seen from behind and from above as the framing says (the eye on that side of the centre, at the
// framed distance), a scene file's camera replaced; a side that does not exist is refused.
TEST_F(CliTest, ViewFramesFromTheSideNamed) {
  write("tetra.obj", "v 0.1234567 -3.3 7.01\nv 1.9 -2.2 7.3\nv 0.7 -1.05 6.4\nv 0.8 -2.9 8.9\nf 1 2 3\nf 1 3 4\nf 2 4 3\nf 1 4 2\n");
  expect_error(vkray({"render", "tetra.obj", "--view", "behind"}), 2, {"--view: 'behind' is neither a side", "back"});
  expect_error(vkray({"render", "tetra.obj", "--view", "0,0,0"}), 2, {"--view: the direction must not be 0, 0, 0"});
  auto printed_camera = [&](const std::vector<std::string>& view) {
    std::vector<std::string> arguments = {"render", "tetra.obj", "--width", "48", "--height", "40", "--no-preview", "-o", "v.exr"};
    arguments.insert(arguments.end(), view.begin(), view.end());
    const RunResult run = vkray(arguments);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    const size_t start = run.out.find("camera: --camera '");
    EXPECT_NE(start, std::string::npos) << run.out;
    return start == std::string::npos ? std::string() : run.out.substr(start, run.out.find('\n', start) - start);
  };
  const std::string front = printed_camera({});
  EXPECT_EQ(printed_camera({"--view", "front"}), front);
  // The framed distance is the same from every side: from differs in its z from the front's only.
  const std::string back = printed_camera({"--view", "back"});
  EXPECT_NE(back, front);
  EXPECT_NE(back.find(" up=0,1,0 fovy=40'"), std::string::npos) << back;
  const std::string top = printed_camera({"--view", "top"});
  EXPECT_NE(top.find(" up=0,0,-1 fovy=40'"), std::string::npos) << top;
  EXPECT_EQ(printed_camera({"--view", "0, 0.25, 1"}), front);
}

TEST_F(CliTest, ModelBeyondTheCoordinateLimitExitsTwo) {
  {
    std::ofstream(path("huge.obj")) << "v 0 0 0\nv 1 0 0\nv 0 2e16 0\nf 1 2 3\n";
  }
  expect_error(vkray({"render", "huge.obj"}), 2, {"huge.obj", "vertex 3", "1e15"});
}

TEST_F(CliTest, UnknownSceneKindExitsTwo) {
  {
    std::ofstream(path("scene.stl")) << "solid\n";
  }
  expect_error(vkray({"render", "scene.stl"}), 2, {"scene.stl", ".json", ".obj, .ply, .gltf or .glb"});
}

TEST_F(CliTest, CameraOptionOverridesTheScene) {
  {
    std::ofstream(path("sphere.json")) << sphere_scene;
  }
  // Moved from z = 5 to z = 10: the centre pixel hits the unit sphere at distance 9, not 4.
  const RunResult run = vkray({"render", "sphere.json", "--camera", "from=0,0,10", "--aov", "depth", "-o", "far.exr"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Image exr;
  ASSERT_NO_FATAL_FAILURE(read_image(path("far.exr"), exr, true));
  EXPECT_EQ(exr.at("Z", 16, 16), 9.0f);
}

TEST_F(CliTest, BadCameraOptionsExitTwo) {
  expect_error(vkray({"render", "--camera", "from=1,2"}), 2, {"--camera", "from"});
  expect_error(vkray({"render", "--camera", "fovy=180"}), 2, {"--camera", "fovy"});
  expect_error(vkray({"render", "--camera", "to=0,1,x"}), 2, {"--camera", "'x'"});
  expect_error(vkray({"render", "--camera", "from=0,0,0 to=0,0,0"}), 2, {"--camera", "differ"});
  expect_error(vkray({"render", "--camera", "eye=0,0,1"}), 2, {"--camera", "'eye'"});
  expect_error(vkray({"render", "--camera", "up=0,0,0"}), 2, {"--camera", "up"});
}

// The bench prints a row per variant and the Embree baseline with its error; no speed is asserted.
TEST_F(CliTest, BenchPrintsTimesBesideErrors) {
  const RunResult run = vkray({"bench", "--size", "32x24", "--frames", "1"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* variant : {"default", "per-ray", "packet", "generic", "embree-1", "embree-8"}) {
    EXPECT_NE(run.out.find(variant), std::string::npos) << variant << " missing from:\n" << run.out;
  }
  expect_error(vkray({"bench", "--size", "32by24"}), 2, {"--size"});
  expect_error(vkray({"bench", "--variants", "fastest"}), 2, {"--variants", "'fastest'"});
  expect_error(vkray({"bench", "--suite", "fast"}), 2, {"--suite", "'fast'"});
  expect_error(vkray({"bench", "--suite", "models", "--models", "/nonexistent/vkray-models"}), 2,
               {"--suite models", "/nonexistent/vkray-models"});
  // Output paths are checked before any rendering.
  expect_error(vkray({"bench", "--json", "/nonexistent/vkray/bench.json"}), 1, {"/nonexistent/vkray/bench.json"});
  expect_error(vkray({"bench", "--csv", "missing/bench.csv"}), 1, {"missing/bench.csv", "does not exist"});
}

// The rays suite on the one of its models a folder holds (the teapot, linked): a row per kind of
// rays, each with no flips against the reference, in the table and in the JSON and CSV files; the
// two models it lacks are named. Options that only make sense for variants are refused.
// The host's stages alone, on a frame the host makes: a row each, the EXR with one thread and with
// every core, and what more threads did for it; no device opened, so no lavapipe note.
TEST_F(CliTest, BenchHostSuiteTimesTheHostsStagesAlone) {
  const RunResult run = vkray({"bench", "--suite", "host", "--size", "320x240", "--frames", "1"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("host stages on a 320x240 frame of depth and normal"), std::string::npos) << run.out;
  for (const char* stage : {"EXR (zip:1), depth and normal                  1", "PNG preview, depth and normal panels",
                            "npy files, depth and normal", "host copy of the frame's planes", "disk: 256 MiB written and flushed"}) {
    EXPECT_NE(run.out.find(stage), std::string::npos) << stage << "\n" << run.out;
  }
  if (std::thread::hardware_concurrency() > 1) {
    EXPECT_NE(run.out.find("of one thread's time"), std::string::npos) << run.out;
  }
  EXPECT_EQ(run.err.find("lavapipe"), std::string::npos) << run.err;
  const RunResult refused = vkray({"bench", "--suite", "host", "--json", "host.json"});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--json: not for --suite host"), std::string::npos) << refused.err;
}

TEST_F(CliTest, BenchRaysSuitePrintsARowPerKindOfRays) {
  const fs::path teapot = fs::path(VKRAY_MODELS_DIR) / "teapot.obj";
  if (!fs::exists(teapot)) GTEST_SKIP() << teapot << " is absent: the shared models folder is not beside the project";
  fs::create_directory(path("models"));
  fs::create_symlink(teapot, path("models/teapot.obj"));
  const RunResult run = vkray({"bench", "--suite", "rays", "--models", path("models").string(), "--rays", "4096", "--frames",
                               "1", "--json", "rays.json", "--csv", "rays.csv"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  for (const char* missing : {"stanford-bunny.obj", "stanford-dragon-100k.obj"}) {
    EXPECT_NE(run.err.find(std::string("skipped ") + missing), std::string::npos) << run.err;
  }
  for (const char* kind : {"camera-rows", "sensor", "incoherent", "occlusion", "first-4-hits"}) {
    const size_t row = run.out.find(std::string("teapot.obj                   ") + kind);
    ASSERT_NE(row, std::string::npos) << kind << " missing from:\n" << run.out;
    std::istringstream fields(run.out.substr(row, run.out.find('\n', row) - row));
    std::string scene, name, count, walk_or_number;
    fields >> scene >> name >> count;
    EXPECT_EQ(count, "4096");
    std::vector<std::string> rest;
    while (fields >> walk_or_number) rest.push_back(walk_or_number);
    ASSERT_GE(rest.size(), 6u);
    EXPECT_EQ(rest[rest.size() - 3], "0") << "flips against the reference in: " << run.out.substr(row, 120);
  }
  const auto json = nlohmann::json::parse(read_text(path("rays.json")));
  EXPECT_EQ(json.at("schema"), "vkray-bench-rays-1");
  EXPECT_EQ(json.at("suite"), "rays");
  const std::vector<std::string> kinds = {"camera-rows", "sensor", "incoherent", "occlusion", "first-4-hits"};
  ASSERT_EQ(json.at("rows").size(), kinds.size());
  for (size_t k = 0; k < kinds.size(); ++k) {
    const auto& row = json.at("rows").at(k);
    EXPECT_EQ(row.at("scene"), "teapot.obj");
    EXPECT_EQ(row.at("rays"), kinds[k]);
    EXPECT_EQ(row.at("count"), 4096);
    EXPECT_EQ(row.at("hit_mismatches"), 0) << kinds[k];
    // Embree has no call for first hits: that row has no Embree figures.
    const bool first_hits = kinds[k] == "first-4-hits";
    EXPECT_EQ(row.at("embree_variant"), kinds[k] == "occlusion" ? "embree-occluded" : first_hits ? "" : "embree-1m");
    EXPECT_GT(row.at("median_ms").get<double>(), 0.0);
    EXPECT_LE(row.at("min_ms").get<double>(), row.at("median_ms").get<double>());
    EXPECT_EQ(row.at("embree_median_ms").get<double>() > 0.0, !first_hits);
    // Rays that hit are compared by distance (occlusion answers only whether, so none are).
    EXPECT_EQ(row.at("both_hit").get<size_t>() > 0, kinds[k] != "occlusion") << kinds[k];
  }
  const std::string csv = read_text(path("rays.csv"));
  EXPECT_EQ(count_lines(csv), kinds.size() + 1);
  const std::string header = csv.substr(0, csv.find('\n'));
  EXPECT_EQ(header.rfind("vkray_version,git_commit,device,driver,suite,frames,scene,scene_hash,rays,count,walk,", 0), 0u)
      << header;
  expect_error(vkray({"bench", "--suite", "rays", "--models", path("models").string(), "--variants", "default"}), 2,
               {"--variants", "--suite rays"});
  expect_error(vkray({"bench", "--suite", "rays", "--models", "/nonexistent/vkray-models"}), 2,
               {"--suite rays", "/nonexistent/vkray-models"});
}

// --suite moving: a row for the bunny (the dragon absent from the folder is named as skipped) with
// refit and rebuild times, the renders after, and each frame's error against the reference; the
// files and variants of the other suites are refused.
TEST_F(CliTest, BenchMovingSuitePrintsARowPerModel) {
  const fs::path bunny = fs::path(VKRAY_MODELS_DIR) / "stanford-bunny.obj";
  if (!fs::exists(bunny)) GTEST_SKIP() << bunny << " is absent: the shared models folder is not beside the project";
  fs::create_directory(path("models"));
  fs::create_symlink(bunny, path("models/stanford-bunny.obj"));
  const RunResult run = vkray({"bench", "--suite", "moving", "--models", path("models").string(), "--size", "96x64", "--frames", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.err.find("skipped stanford-dragon-100k.obj"), std::string::npos) << run.err;
  const size_t row = run.out.find("stanford-bunny.obj");
  ASSERT_NE(row, std::string::npos) << run.out;
  std::istringstream fields(run.out.substr(row, run.out.find('\n', row) - row));
  std::string model;
  size_t vertices = 0;
  double refit = 0, rebuild = 0, ratio = 0, render_refit = 0, render_built = 0;
  fields >> model >> vertices >> refit >> rebuild >> ratio >> render_refit >> render_built;
  EXPECT_EQ(vertices, 35947u);
  EXPECT_GT(refit, 0.0);
  EXPECT_GT(rebuild, 0.0);
  EXPECT_GT(render_refit, 0.0);
  EXPECT_GT(render_built, 0.0);
  EXPECT_EQ(run.out.find("fell back"), std::string::npos) << run.out;  // every call refitted
  expect_error(vkray({"bench", "--suite", "moving", "--models", path("models").string(), "--json", "moving.json"}), 2,
               {"--json", "--suite moving"});
}

// --suite points: a row for each set of points on the bunny (the dragon and armadillo absent from
// the folder named as skipped), vkray's distance and signed distance beside Embree's rtcPointQuery;
// both within float32's rounding of the reference (16 units of 2^-24 of the distance and the
// longest edge, docs/points.md: under 1e-5 of the bunny's diagonal) and no sign unlike its winding
// number's away from the surface.
TEST_F(CliTest, BenchPointsSuitePrintsARowPerSet) {
  const fs::path bunny = fs::path(VKRAY_MODELS_DIR) / "stanford-bunny.obj";
  if (!fs::exists(bunny)) GTEST_SKIP() << bunny << " is absent: the shared models folder is not beside the project";
  fs::create_directory(path("models"));
  fs::create_symlink(bunny, path("models/stanford-bunny.obj"));
  const RunResult run = vkray({"bench", "--suite", "points", "--models", path("models").string(), "--points", "4096", "--frames", "1"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.err.find("skipped stanford-dragon-100k.obj"), std::string::npos) << run.err;
  for (const std::string set : {"uniform", "near-surface"}) {
    const size_t at = run.out.find(" " + set + " ");
    ASSERT_NE(at, std::string::npos) << run.out;
    const size_t start = run.out.rfind('\n', at) + 1;
    std::istringstream fields(run.out.substr(start, run.out.find('\n', at) - start));
    std::string model, name;
    size_t count = 0, flips = 1;
    double distance = 0, signed_distance = 0, embree = 0, ratio = 0, signed_ratio = 0, error = 1, embree_error = 1;
    fields >> model >> name >> count >> distance >> signed_distance >> embree >> ratio >> signed_ratio >> error >> embree_error >> flips;
    EXPECT_EQ(name, set);
    EXPECT_EQ(count, 4096u);
    EXPECT_GT(distance, 0.0);
    EXPECT_GT(signed_distance, 0.0);
    EXPECT_GT(embree, 0.0);
    EXPECT_LT(error, 1e-5) << run.out;
    EXPECT_LT(embree_error, 1e-5) << run.out;
    EXPECT_EQ(flips, 0u) << run.out;
  }
}

// --suite instances measures against the scene flattened: where that scene could not fit in the
// machine's memory it is refused at once, naming the most instances that fit (hostile campaign 3:
// 20000 instances grew to 6.9 GB and ended in std::bad_alloc).
TEST_F(CliTest, BenchInstancesBeyondMemoryIsRefused) {
  const fs::path bunny = fs::path(VKRAY_MODELS_DIR) / "stanford-bunny.obj";
  if (!fs::exists(bunny)) GTEST_SKIP() << bunny << " is absent: the shared models folder is not beside the project";
  fs::create_directory(path("models"));
  fs::create_symlink(bunny, path("models/stanford-bunny.obj"));
  const RunResult run = vkray({"bench", "--suite", "instances", "--models", path("models").string(), "--instances", "1000000"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.out, "");
  const std::string last = run.err.substr(run.err.rfind('\n', run.err.size() - 2) + 1);  // after the models skipped
  for (const char* text : {"vkray: --instances 1000000: ", "flattened", "at most"}) EXPECT_NE(last.find(text), std::string::npos) << last;
}

// The basic suite's JSON: every field of every row present and sane. Times are only required to be
// positive and consistent with each other, never fast.
TEST_F(CliTest, BenchBasicSuiteJsonHasEveryFieldAndSaneFigures) {
  constexpr uint32_t width = 48, height = 32;
  // The rows of every kind (the default, a shader variant, a search, Embree), not every variant: each
  // variant's row is made by the same code, and all of them took this test 75 s.
  const RunResult run = vkray({"bench", "--suite", "basic", "--size", "48x32", "--frames", "1", "--json", "bench.json",
                               "--csv", "bench.csv", "--variants", "default,generic,naive,per-ray,embree-8"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(read_text(path("bench.json")));
  EXPECT_EQ(json.at("schema"), "vkray-bench-1");
  EXPECT_EQ(json.at("suite"), "basic");
  EXPECT_EQ(json.at("frames"), 1);
  for (const char* field : {"vkray_version", "git_commit"}) EXPECT_FALSE(json.at(field).get<std::string>().empty());
  for (const char* field : {"name", "type", "driver", "api_version"}) {
    EXPECT_FALSE(json.at("device").at(field).get<std::string>().empty()) << field;
  }
  const std::vector<std::string> names = {"built-in", "one-sphere", "spheres-on-plane", "sphere-mesh-80k"};
  ASSERT_EQ(json.at("scenes").size(), names.size());
  const std::vector<std::string> fixed_fields = {
      "variant", "on_gpu", "device_triangles", "device_geometry_bytes", "bvh_nodes", "bvh_depth", "loop_budget",
      "upload_ms", "bvh_build_ms", "pipeline_ms", "gpu_median_ms", "gpu_min_ms", "gpu_max_ms", "gpu_frames", "frame_median_ms", "gpu_sustained_ms", "mrays_per_s",
      "unfinished_rays", "pixels", "hit_mismatches", "both_hit", "nan_pixels", "depth_rel_p50", "depth_rel_p99", "depth_rel_max",
      "depth_ulp_p50", "depth_ulp_p99", "depth_ulp_max",
      "normal_deg_p50", "normal_deg_p99", "normal_deg_max", "pareto", "outputs_compared"};
  // Then the outputs' error fields, one each (engine/frame.hpp's table; every output's is checked in
  // EveryOutputOfTheTableThroughRenderAndBench).
  std::vector<std::string> row_fields = fixed_fields;
  for (const auto& field : vkray::output_error_fields()) row_fields.push_back(field.name);
  size_t rows = 0;
  for (size_t s = 0; s < names.size(); ++s) {
    const auto& scene = json.at("scenes").at(s);
    SCOPED_TRACE(names[s]);
    EXPECT_EQ(scene.at("name"), names[s]);
    EXPECT_EQ(scene.at("hash").get<std::string>().size(), 16u);
    EXPECT_EQ(scene.at("width"), width);
    EXPECT_EQ(scene.at("height"), height);
    EXPECT_GT(scene.at("reference_ms").get<double>(), 0.0);
    bool on_front = false, has_default = false, has_generic = false, has_embree = false;
    for (const auto& row : scene.at("rows")) {
      ++rows;
      const std::string variant = row.at("variant");
      SCOPED_TRACE(variant);
      for (const auto& field : row_fields) EXPECT_TRUE(row.contains(field)) << field;
      EXPECT_EQ(row.size(), row_fields.size());
      const double median = row.at("gpu_median_ms"), minimum = row.at("gpu_min_ms"), maximum = row.at("gpu_max_ms");
      EXPECT_GT(minimum, 0.0);
      EXPECT_EQ(row.at("gpu_frames"), 2) << "1 frame in each of the default 2 rounds, pooled";
      EXPECT_LE(minimum, median);
      EXPECT_LE(median, maximum);
      EXPECT_EQ(row.at("pixels"), width * height);
      // Mrays/s is the pixels over the median time, to rounding.
      EXPECT_NEAR(row.at("mrays_per_s").get<double>(), width * height / (median * 1e3), 1e-9 * width * height / median);
      EXPECT_LE(row.at("hit_mismatches").get<size_t>(), width * height);
      EXPECT_LE(row.at("both_hit").get<size_t>() + row.at("hit_mismatches").get<size_t>(), width * height);
      for (const char* error : {"depth_rel_p50", "depth_rel_p99", "depth_rel_max", "normal_deg_p50",
                                "normal_deg_p99", "normal_deg_max"}) {
        const double value = row.at(error);
        EXPECT_TRUE(std::isfinite(value) && value >= 0.0) << error << " = " << value;
      }
      EXPECT_LE(row.at("depth_rel_p50").get<double>(), row.at("depth_rel_p99").get<double>());
      EXPECT_LE(row.at("depth_rel_p99").get<double>(), row.at("depth_rel_max").get<double>());
      EXPECT_LE(row.at("normal_deg_p99").get<double>(), row.at("normal_deg_max").get<double>());
      if (row.at("on_gpu")) {
        EXPECT_GE(row.at("frame_median_ms").get<double>(), 0.0);
        EXPECT_GT(row.at("pipeline_ms").get<double>(), 0.0);
      }
      on_front = on_front || row.at("pareto").get<bool>();
      has_default = has_default || variant == "default";
      has_generic = has_generic || variant == "generic";
      has_embree = has_embree || variant == "embree-8";
    }
    EXPECT_TRUE(on_front && has_default && has_generic && has_embree);
  }
  EXPECT_EQ(count_lines(read_text(path("bench.csv"))), rows + 1);

  // A run compared with itself: every row, time ratio 1.
  const RunResult compare = vkray({"bench", "--compare", "bench.json", "bench.json"});
  ASSERT_EQ(compare.exit_code, 0) << compare.err;
  EXPECT_EQ(count_lines(compare.out), rows + 3) << compare.out;  // two "A:"/"B:" lines and a header
  EXPECT_NE(compare.out.find("1.000"), std::string::npos) << compare.out;
  expect_error(vkray({"bench", "--compare", "bench.json", "absent.json"}), 2, {"absent.json"});
  expect_error(vkray({"bench", "--compare", "bench.json", "bench.csv"}), 2, {"bench.csv"});
}

// Ctrl-C ends vkray promptly with 130 and leaves nothing half-written: the older output is intact
// and no temporary file remains. The scaling suite runs for minutes on any machine (it generates a
// 4M-triangle mesh first), so the signal, sent after 2 s, always finds it working.
TEST_F(CliTest, InterruptExits130AndKeepsTheOlderOutput) {
  const auto old_json = write("bench.json", "older contents\n");
  const std::string command = "cd " + shell_quote(dir_.string()) + " && timeout -s INT --preserve-status 2 " +
                              shell_quote(VKRAY_BINARY) + " bench --suite scaling --frames 1 --json bench.json" +
                              " >/dev/null 2>&1 </dev/null";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(read_text(old_json), "older contents\n");
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".vkray-"), std::string::npos) << entry.path() << " left behind";
  }
}

// --plot runs the embedded matplotlib script on the report; it needs Debian's python3-matplotlib
// (cmake/debian-packages.txt), so the test says so and skips where that is missing.
// The "+..." rows time the outputs beside depth and normal and compare each with the reference's:
// on the built-in scene every one is compared, the ids agree but for pixels on an edge, and each
// figure is within what its output's bound allows (the camera outputs carry the depth's error, a
// few 1e-7; the surface outputs of triangles are the reference's exactly where the ids agree).
TEST_F(CliTest, BenchOutputRowsCompareEveryOutputWithTheReference) {
  const RunResult run = vkray({"bench", "--size", "64x48", "--frames", "1", "--variants", "default,+ids,+every-output",
                               "--json", "outputs.json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("outputs beside depth and normal"), std::string::npos) << run.out;
  const auto json = nlohmann::json::parse(read_text(path("outputs.json")));
  const auto& rows = json.at("scenes").at(0).at("rows");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_FALSE(rows.at(0).at("outputs_compared").get<bool>());
  for (size_t r = 1; r < 3; ++r) {
    const auto& row = rows.at(r);
    SCOPED_TRACE(row.at("variant").get<std::string>());
    EXPECT_TRUE(row.at("outputs_compared").get<bool>());
    EXPECT_LT(row.at("id_mismatches").get<size_t>(), 64u * 48u / 50u);
    EXPECT_LT(row.at("planar_depth_rel_p99").get<double>(), 1e-5);
    EXPECT_LT(row.at("position_rel_p99").get<double>(), 1e-5);
    EXPECT_EQ(row.at("barycentric_max").get<double>(), 0.0);
    // The triangles' are the reference's exactly; the sphere's comes from the device's depth, as the
    // normal output's error does (the suite's normal p99 bound).
    EXPECT_LT(row.at("shading_normal_deg_p99").get<double>(), 0.01);
    EXPECT_EQ(row.at("texcoord_max").get<double>(), 0.0);
  }
  EXPECT_GT(rows.at(2).at("planar_depth_rel_p99").get<double>(), 0.0);  // compared, and float32 rounding is not 0
}

TEST_F(CliTest, BenchPlotWritesAPng) {
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 with matplotlib is missing (Debian: python3-matplotlib)";
  }
  const RunResult run = vkray({"bench", "--size", "32x24", "--frames", "1", "--variants", "default,generic",
                               "--plot", "plot.png"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string png = read_text(path("plot.png"));
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  for (const auto& entry : fs::directory_iterator(dir_)) {  // the report the script read is gone again
    EXPECT_NE(entry.path().extension(), ".json") << entry.path();
    EXPECT_EQ(entry.path().filename().string().find(".vkray-"), std::string::npos) << entry.path() << " left behind";
  }
}

// Every offered compression is lossless: the channels read back bit for bit the same.
TEST_F(CliTest, EveryCompressionWritesTheSameFloats) {
  Image reference;
  for (const char* compression : {"zip", "zip:1", "zips:9", "zips", "piz", "rle", "none"}) {
    SCOPED_TRACE(compression);
    std::string name = std::string(compression) + ".exr";
    std::replace(name.begin(), name.end(), ':', '-');
    const RunResult run = vkray({"render", "--width", "40", "--height", "30", "--aov", "depth,normal,uv",
                                 "--compression", compression, "--no-preview", "-o", name});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image exr;
    ASSERT_NO_FATAL_FAILURE(read_image(path(name), exr, true));
    if (reference.channels.empty()) {
      reference = exr;
      continue;
    }
    for (const auto& [channel, values] : reference.channels) {
      ASSERT_EQ(exr.channels.count(channel), 1u) << channel;
      EXPECT_EQ(std::memcmp(values.data(), exr.channels.at(channel).data(), values.size() * sizeof(float)), 0) << channel;
    }
  }
}

// Every upload and readback path runs on any device: staging copies (what discrete GPUs take) and
// direct mapping give the same bits, under the validation layer's synchronization checks (the suite
// sets VKRAY_VALIDATION=1; an error aborts the run).
TEST_F(CliTest, StagingAndDirectTransfersWriteIdenticalImages) {
  std::vector<std::vector<std::string>> scenes = {{}};
  const fs::path bunny = fs::path(VKRAY_MODELS_DIR) / "stanford-bunny.obj";
  if (fs::exists(bunny)) {
    scenes.push_back({bunny.string()});
  } else {
    std::printf("    %s is absent: the built-in scene alone\n", bunny.c_str());
  }
  for (const auto& scene : scenes) {
    std::map<std::string, Image> images;
    for (const char* transfer : {"staging", "direct"}) {
      std::vector<std::string> args = {"render", "--width", "160", "--height", "120", "--aov", "depth,normal,uv",
                                       "--transfer", transfer, "--no-preview", "-o", std::string(transfer) + ".exr"};
      args.insert(args.begin() + 1, scene.begin(), scene.end());
      const RunResult run = vkray(args);
      ASSERT_EQ(run.exit_code, 0) << run.err;
      ASSERT_NO_FATAL_FAILURE(read_image(path(std::string(transfer) + ".exr"), images[transfer], true));
    }
    const Image& staging = images["staging"];
    const Image& direct = images["direct"];
    EXPECT_EQ(staging.channel_names, direct.channel_names);
    for (const auto& [channel, values] : staging.channels) {
      EXPECT_EQ(std::memcmp(values.data(), direct.channels.at(channel).data(), values.size() * sizeof(float)), 0)
          << channel << (scene.empty() ? " (built-in scene)" : " of " + scene[0]);
    }
  }
}

TEST_F(CliTest, DevicesAreChosenByNumberAndUuid) {
  const RunResult info = vkray({"info"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  std::smatch uuid;
  ASSERT_TRUE(std::regex_search(info.out, uuid, std::regex(R"(UUID ([0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}))")))
      << info.out;
  for (const std::string& choice : {std::string("0"), uuid[1].str()}) {
    const RunResult run = vkray({"render", "--device", choice, "--width", "8", "--height", "8", "--no-preview"});
    EXPECT_EQ(run.exit_code, 0) << choice << ": " << run.err;
  }
  const RunResult missing = vkray({"render", "--device", "99", "--width", "8", "--height", "8", "--no-preview"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no Vulkan device number 99"), std::string::npos) << missing.err;
}

// A CPU implementation of Vulkan is named in one line on stderr, and the render still succeeds;
// a GPU gets no such line.
TEST_F(CliTest, ACpuDeviceIsSaidInOneLine) {
  const RunResult info = vkray({"info"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const bool cpu = std::regex_search(info.out, std::regex(R"((^|\n)\* \[[0-9]+\] [^\n]*\(cpu, )"));
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "--no-preview"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  if (cpu) {
    EXPECT_EQ(count_lines(run.err), 1u) << run.err;
    EXPECT_TRUE(starts_with(run.err, "vkray: note: rendering on ")) << run.err;
    EXPECT_NE(run.err.find("a CPU implementation of Vulkan"), std::string::npos) << run.err;
  } else {
    EXPECT_EQ(run.err, "");
  }
}

TEST_F(CliTest, LossyOrUnknownCompressionExitsTwo) {
  expect_error(vkray({"render", "--compression", "b44"}), 2, {"--compression", "'b44'"});
  expect_error(vkray({"render", "--compression", "zip2"}), 2, {"--compression", "'zip2'"});
  expect_error(vkray({"render", "--compression", "zip:0"}), 2, {"--compression", "'zip:0'", "zip:1 to zip:9"});
  expect_error(vkray({"render", "--compression", "piz:3"}), 2, {"--compression", "'piz:3'"});
  expect_error(vkray({"render", "--compression", "zip:"}), 2, {"--compression", "'zip:'"});
}

// ---------------------------------------------------------------------------------------------
// 9. What a new user trips over: each of these failed before its fix

TEST_F(CliTest, CheckSaysWhatItDidNotCompute) {
  const RunResult run = vkray({"render", "--width", "32", "--height", "24", "--aov", "depth", "--check", "--no-preview"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("normal error not computed"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("normal error p50"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("depth rel. error p50"), std::string::npos) << run.out;
}

// --timings has a total, and the lines indented under it are parts of it: they add up to no more
// than the total (each printed to 0.1 ms).
TEST_F(CliTest, TimingsHaveATotalThatHoldsItsParts) {
  const RunResult run = vkray({"render", "--width", "64", "--height", "48", "--timings", "--check"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::smatch total;
  ASSERT_TRUE(std::regex_search(run.out, total, std::regex(R"(\n  total +([0-9.]+) ms)"))) << run.out;
  double parts = 0.0;
  size_t count = 0;
  std::istringstream lines(run.out);
  for (std::string line; std::getline(lines, line);) {
    std::smatch part;
    // A part that ran beside another, on another thread, is not in the sum.
    if (line.find("beside") != std::string::npos) continue;
    if (std::regex_match(line, part, std::regex(R"(    [a-zA-Z(][^ ].*? +([0-9.]+) ms.*)"))) parts += std::stod(part[1]), ++count;
  }
  EXPECT_TRUE(std::regex_search(run.out, std::regex(R"(\n    device open +[0-9.]+ ms +beside the scene load)"))) << run.out;
  for (const char* part : {"scene load", "waiting for the device", "upload", "render", "reference (CPU)", "file writing"}) {
    EXPECT_TRUE(has_line_starting_with(run.out, std::string("    ") + part)) << part << " missing:\n" << run.out;
  }
  EXPECT_GE(count, 6u) << run.out;
  EXPECT_LE(parts, std::stod(total[1]) + 0.05 * static_cast<double>(count + 1)) << run.out;
  EXPECT_TRUE(has_line_starting_with(run.out, "      pipeline creation")) << run.out;  // a part of render
}

// Output formats are the documented ones and are checked before the scene is even read: the
// scene named here does not exist, and the error is about the output, naming the user's path.
TEST_F(CliTest, OutputFormatsAndFoldersAreCheckedBeforeAnyWork) {
  expect_error(vkray({"render", "missing.json", "--preview", "x.bmpx"}), 2, {"--preview", "'x.bmpx'", ".png"});
  expect_error(vkray({"render", "missing.json", "--preview", "x.jpg"}), 2, {"--preview", "'x.jpg'", ".png"});
  expect_error(vkray({"view", "--screenshot", "x.exr"}), 2, {"--screenshot", "'x.exr'", ".png"});
  expect_error(vkray({"view", "--output", "position"}), 2, {"--output", "'position'", "depth, normal, uv"});
  // A folder the user cannot create files in (even as root: /proc takes no new files).
  const RunResult run = vkray({"render", "missing.json", "-o", "/proc/vkray-out.exr"});
  expect_error(run, 1, {"/proc/vkray-out.exr", "cannot write"});
  EXPECT_EQ(run.err.find(".vkray-"), std::string::npos) << "a temporary name the user never gave: " << run.err;
}

TEST_F(CliTest, ConflictingOptionsAreRefused) {
  expect_error(vkray({"render", "--no-preview", "--preview", "x.png"}), 2, {"--no-preview", "--preview"});
  expect_error(vkray({"render", "--reference", "--check"}), 2, {"--reference", "--check"});
  expect_error(vkray({"render", "--reference", "--precision", "double"}), 2, {"--reference", "--precision"});
  expect_error(vkray({"render", "--reference", "--device", "llvmpipe"}), 2, {"--reference", "--device"});
  expect_error(vkray({"bench", "--compare", "a.json", "b.json", "--suite", "basic"}), 2, {"--compare", "--suite"});
}

// A read-only file is not replaced, as cp refuses to (root included, whom permissions do not stop).
TEST_F(CliTest, ReadOnlyOutputIsRefusedAndKept) {
  const auto output = write("kept.exr", "older contents\n");
  fs::permissions(output, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "-o", "kept.exr", "--no-preview"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(count_lines(run.err), 1u) << run.err;
  EXPECT_NE(run.err.find("kept.exr: cannot write: the file is read-only"), std::string::npos) << run.err;
  EXPECT_EQ(read_text(output), "older contents\n");
  fs::permissions(output, fs::perms::owner_write, fs::perm_options::add);
}

// A link, device node or FIFO named as an output is refused and left as it was: the rename into
// place would replace it (`-o /dev/null` as root would replace the system's).
TEST_F(CliTest, OutputsThatAreNotRegularFilesAreRefusedAndKept) {
  const auto target = write("target.exr", "older contents\n");
  fs::create_symlink(target, dir_ / "link.exr");
  ASSERT_EQ(::mkfifo((dir_ / "fifo.exr").c_str(), 0600), 0);
  write("part.jsonl", "{\"index\": 0, \"views\": 1, \"exr\": \"v.exr\"}\n");
  for (const auto& [name, kind] : {std::pair{"link.exr", "a symbolic link"}, std::pair{"fifo.exr", "a FIFO"}}) {
    for (const std::vector<std::string>& arguments :
         {std::vector<std::string>{"render", "--width", "8", "--height", "8", "-o", name, "--no-preview"},
          std::vector<std::string>{"manifest", "merge", "part.jsonl", "-o", name}}) {
      const RunResult run = vkray(arguments);
      EXPECT_EQ(run.exit_code, 1) << arguments[0];
      EXPECT_EQ(count_lines(run.err), 1u) << run.err;
      EXPECT_NE(run.err.find(std::string(name) + ": cannot write: it is " + kind), std::string::npos) << run.err;
    }
  }
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.exr"));
  EXPECT_TRUE(fs::is_fifo(dir_ / "fifo.exr"));
  EXPECT_EQ(read_text(target), "older contents\n");
}

// In a many-view run, a link at a later view's name is refused before the first view renders, as
// bad input (exit 2): no view is written, and the link stays.
TEST_F(CliTest, ALinkAmongLaterViewsIsRefusedBeforeAnyViewRenders) {
  fs::create_directory(path("out"));
  fs::create_symlink("/dev/null", dir_ / "out" / "v-2.exr");
  const RunResult run = vkray({"render", "--width", "8", "--height", "8", "--orbit", "4", "-o", "out/v-{index}.exr"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(count_lines(run.err), 1u) << run.err;
  EXPECT_NE(run.err.find("v-2.exr: cannot write: it is a symbolic link"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(path("out/v-0.exr")));
  EXPECT_TRUE(fs::is_symlink(dir_ / "out" / "v-2.exr"));
}

// Many views, each placing instances of its own (a dataset's object poses per frame): each view's
// image is the image of the scene file placing them so, bit for bit; a view that places nothing has
// the scene's placements back, whatever the view before it placed; the manifest records the poses,
// and a resumed run whose views place them otherwise is refused.
TEST_F(CliTest, EachViewPlacesItsInstancesAsASceneFileWould) {
  const std::string meshes = R"("camera": {"from": [0, 1, 4], "to": [0, 0, 0], "fovy": 45},
                                "meshes": [{"name": "wedge", "positions": [[-0.5, 0, -0.5], [0.5, 0, -0.5], [0, 0.8, 0], [0, 0, 0.6]],
                                           "triangles": [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]]}],
                                "planes": [{"point": [0, -0.5, 0], "normal": [0, 1, 0]}])";
  const std::string left = R"({"mesh": "wedge", "transform": {"translate": [-0.8, 0, 0]}})";
  const std::string right = R"({"mesh": "wedge", "transform": {"translate": [0.8, 0, 0], "scale": 0.7}})";
  const std::string moved = R"({"translate": [0.5, 0.3, 0.4], "scale": [-1, 1.2, 1], "rotate": {"axis": [0, 1, 0], "degrees": 35}})";
  write("scene.json", "{" + meshes + R"(, "instances": [)" + left + ", " + right + "]}");
  const std::string cameras[] = {R"("from": [0, 1.5, 4], "to": [0, 0, 0], "fovy": 45)", R"("from": [1, 2, 3.5], "to": [0, 0.2, 0], "fovy": 50)",
                                 R"("from": [-1, 1, 4], "to": [0, 0, 0], "fovy": 40)"};
  write("views.jsonl", "{" + cameras[0] + "}\n{" + cameras[1] + R"(, "instances": [{"instance": 1, "transform": )" + moved + "}]}\n{" +
                           cameras[2] + "}\n");
  const std::vector<std::string> size = {"--width", "48", "--height", "32", "--aov", "depth,normal,instance-id"};
  std::vector<std::string> args = {"render", "scene.json", "--views", "views.jsonl", "-o", "out/v-{index}.exr"};
  args.insert(args.end(), size.begin(), size.end());
  const RunResult views = vkray(args);
  ASSERT_EQ(views.exit_code, 0) << views.err;
  // The same views one by one, from scene files placing the instances as each view does.
  const std::string right_moved = R"({"mesh": "wedge", "transform": )" + moved + "}";
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE("view " + std::to_string(k));
    write("scene-" + std::to_string(k) + ".json", "{" + meshes + R"(, "instances": [)" + left + ", " + (k == 1 ? right_moved : right) + "]}");
    std::vector<std::string> single = {"render", "scene-" + std::to_string(k) + ".json", "--camera", "{" + cameras[k] + "}",
                                       "-o", "out/single-" + std::to_string(k) + ".exr", "--no-preview"};
    single.insert(single.end(), size.begin(), size.end());
    const RunResult run = vkray(single);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image of_views, alone;
    read_image(path("out/v-" + std::to_string(k) + ".exr"), of_views);
    read_image(path("out/single-" + std::to_string(k) + ".exr"), alone);
    ASSERT_EQ(of_views.channel_names, alone.channel_names);
    for (const auto& [name, values] : alone.channels) {
      const std::vector<float>& posed = of_views.channels.at(name);
      size_t differing = 0;
      for (size_t p = 0; p < values.size(); ++p) differing += std::memcmp(&values[p], &posed[p], sizeof(float)) != 0;
      EXPECT_EQ(differing, 0u) << name;
    }
  }
  Image moved_view;  // the moved instance in sight, so that the comparison above compares it
  read_image(path("out/v-1.exr"), moved_view);
  EXPECT_GT(std::ranges::count(moved_view.channels.at("instance_id"), 1.0f), 20);

  const std::string manifest = read_text(path("out/manifest.jsonl"));
  ASSERT_EQ(count_lines(manifest), 3u) << manifest;
  EXPECT_NE(manifest.find(R"("instances":[{"instance":1,"transform":[[)"), std::string::npos) << manifest;
  EXPECT_EQ(manifest.find(R"("instances")"), manifest.rfind(R"("instances")")) << "only view 1 places an instance";

  write("views.jsonl", "{" + cameras[0] + "}\n{" + cameras[1] + "}\n{" + cameras[2] + "}\n");
  args = {"render", "scene.json", "--views", "views.jsonl", "-o", "out/v-{index}.exr"};
  args.insert(args.end(), size.begin(), size.end());
  const RunResult resumed = vkray(args);  // refused once the manifest is read, after the device's note
  EXPECT_EQ(resumed.exit_code, 2) << resumed.err;
  EXPECT_NE(resumed.err.find("out/manifest.jsonl: view 1 was rendered with other settings (the instances placed)"), std::string::npos)
      << resumed.err;

  write("views.jsonl", "{" + cameras[0] + "}\n{" + cameras[1] + R"(, "instances": [{"instance": 2, "transform": {}}]})" "\n");
  args = {"render", "scene.json", "--views", "views.jsonl", "-o", "refused/v-{index}.exr"};
  expect_error(vkray(args), 2, {"views.jsonl:2: instances[0].instance: 2 is not an instance of the scene's 2 (0..1)"});
  EXPECT_FALSE(fs::exists(path("refused")));
}

// A mirrored world_to_camera is exactly orthogonal: the message says it mirrors, with no "off by
// 0.000000"; a scaled one says by how much, in two digits.
TEST_F(CliTest, AMatrixThatIsNoRotationIsToldWithoutNoise) {
  RunResult run = vkray({"render", "--camera", R"({"world_to_camera": [[-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]]})"});
  expect_error(run, 2, {"world_to_camera", "it mirrors (det R < 0)"});
  EXPECT_EQ(run.err.find("off by"), std::string::npos) << run.err;
  run = vkray({"render", "--camera", R"({"world_to_camera": [[1.5, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 5], [0, 0, 0, 1]]})"});
  expect_error(run, 2, {"world_to_camera", "R R^T is off by 1.2"});
  EXPECT_EQ(run.err.find("mirrors"), std::string::npos) << run.err;
}

TEST_F(CliTest, DuplicateSceneKeysAreRefused) {
  write("twice.json", R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40, "fovy": 50}})");
  expect_error(vkray({"render", "twice.json"}), 2, {"twice.json", "camera.fovy", "'fovy'", "twice"});
}

TEST_F(CliTest, AMistypedCommandGetsTheNearestOne) {
  expect_error(vkray({"rendr"}), 2, {"unknown command 'rendr'", "did you mean 'render'?"});
  expect_error(vkray({"benhc", "--size", "8x8"}), 2, {"'benhc'", "'bench'"});
  expect_error(vkray({"xyzzy"}), 2, {"'xyzzy'", "render, info, bench, view"});
}

TEST_F(CliTest, AFolderAsTheSceneIsNamedAFolder) {
  fs::create_directory(path("scenes"));
  expect_error(vkray({"render", "scenes"}), 2, {"scenes", "is a folder"});
}

// --camera takes the scene file's JSON forms too: [x, y, z] vectors in key=value, or the camera
// object itself; each renders what the plain form renders, and a malformed one shows the forms.
TEST_F(CliTest, CameraOptionTakesTheSceneFilesJsonForms) {
  expect_error(vkray({"render", "--camera", "from=[0,1,5"}), 2, {"--camera", "from", "'{\"from\": [0, 1, 5]"});
  expect_error(vkray({"render", "--camera", R"({"from": [0, 1]})"}), 2, {"--camera", "from", "3 numbers"});
  expect_error(vkray({"render", "--camera", R"({"form": [0, 1, 5]})"}), 2, {"--camera", "'form'", "did you mean 'from'"});
  write("sphere.json", sphere_scene);
  for (const char* camera : {"from=0,0,10", "from=[0,0,10]", "from=[0, 0, 10];fovy=30", R"({"from": [0, 0, 10]})"}) {
    SCOPED_TRACE(camera);
    const RunResult run = vkray({"render", "sphere.json", "--camera", camera, "--aov", "depth", "-o", "far.exr"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image exr;
    ASSERT_NO_FATAL_FAILURE(read_image(path("far.exr"), exr, true));
    EXPECT_EQ(exr.at("Z", 16, 16), 9.0f);
  }
}

// Embree's rows are variants like any other: named in --variants, left out by leaving them out.
TEST_F(CliTest, EmbreeRowsAreChosenByTheVariantList) {
  RunResult run = vkray({"bench", "--size", "32x24", "--frames", "1", "--variants", "default,embree-8"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("embree-8"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("embree-1"), std::string::npos) << run.out;
  run = vkray({"bench", "--size", "32x24", "--frames", "1", "--variants", "default"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out.find("embree"), std::string::npos) << run.out;
  expect_error(vkray({"bench", "--no-embree"}), 2, {"--no-embree"});
}

// The bench's table fits 100 columns, the legend stands above the header, and the built-in scene is
// not called "default" beside the variant of that name.
TEST_F(CliTest, BenchTableFitsOneHundredColumns) {
  const RunResult run = vkray({"bench", "--size", "32x24", "--frames", "1", "--variants", "default,naive,embree-8"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream lines(run.out);
  std::vector<std::string> table;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LE(line.size(), 100u) << line;
    table.push_back(line);
  }
  const auto header = std::find_if(table.begin(), table.end(), [](const std::string& line) { return starts_with(line, "scene "); });
  ASSERT_NE(header, table.end()) << run.out;
  ASSERT_NE(header + 1, table.end());
  EXPECT_TRUE(starts_with(*(header + 1), "built-in ")) << "rows must follow the header: " << run.out;
  EXPECT_EQ(run.out.find("default default"), std::string::npos) << run.out;
  const RunResult wide = vkray({"bench", "--size", "32x24", "--frames", "1", "--variants", "default", "--wide"});
  ASSERT_EQ(wide.exit_code, 0) << wide.err;
  EXPECT_NE(wide.out.find("depth max"), std::string::npos) << wide.out;
}

// The help speaks the user's words: a scene, not the course it came from.
TEST_F(CliTest, HelpSpeaksOfScenes) {
  for (const char* command : {"", "render", "bench", "view", "info"}) {
    const RunResult run = command[0] ? vkray({command, "--help"}) : vkray({"--help"});
    ASSERT_EQ(run.exit_code, 0) << command;
    EXPECT_EQ(run.out.find("course"), std::string::npos) << command << ":\n" << run.out;
  }
}

}  // namespace

// The GPU report (engine/bench/gpu_report.hpp), its reduced sizes: the sections that take seconds
// here (CI's bundle check runs all of them). Every row ran, JSON and Markdown hold them, exit 0.
TEST_F(CliTest, ReportReducedWritesJsonAndMarkdown) {
  const RunResult run = vkray({"report", "report", "--reduced", "--only", "rays,views,process", "--models", VKRAY_MODELS_DIR});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray on ")) << "the first line names the device: " << run.out;
  const auto json = nlohmann::json::parse(read_text(path("report/report.json")));
  EXPECT_EQ(json.at("schema"), "vkray-gpu-report-1");
  EXPECT_FALSE(json.at("device").at("name").get<std::string>().empty());
  size_t rays = 0, views = 0, processes = 0;
  for (const auto& row : json.at("rows")) {
    EXPECT_EQ(row.at("status"), "ok") << row.dump();
    if (row.at("section") == "rays") {
      ++rays;
      EXPECT_EQ(row.at("hit_mismatches"), 0) << row.dump();
      EXPECT_GT(row.at("vkray_median_ms").get<double>(), 0.0);
      // Embree has no call for first hits: that row has no Embree figures.
      EXPECT_EQ(row.at("embree_median_ms").get<double>() > 0.0, row.at("row") != "first-4-hits") << row.dump();
    }
    views += row.at("section") == "views";
    if (row.at("section") == "process") {  // whole `vkray render` processes: their time and memory
      ++processes;
      EXPECT_GT(row.at("wall_min_ms").get<double>(), 0.0);
      const uint64_t output = uint64_t{row.at("width")} * uint64_t{row.at("height")} * 16;  // float depth, 3 float normals
      EXPECT_EQ(row.at("output_bytes"), output);
      EXPECT_GT(row.at("peak_bytes"), output);  // the process holds the frame
    }
  }
  EXPECT_EQ(rays, 5u);
  EXPECT_EQ(views, 2u);  // EXR and npy
  EXPECT_EQ(processes, 2u);
  const std::string markdown = read_text(path("report/report.md"));
  for (const char* heading : {"# vkray on ", "## Given rays", "## Many views", "## Whole processes", "| camera-rows | 65536 |",
                              "| occlusion | 65536 |", "| first-4-hits | 65536 |", "written to .npy files"}) {
    EXPECT_NE(markdown.find(heading), std::string::npos) << heading;
  }
}

// Asked for a GPU and given a CPU implementation of Vulkan, the report names the device in its
// first line and exits 1.
TEST_F(CliTest, ReportRequireGpuRefusesACpuDevice) {
  const RunResult run = vkray({"report", "report", "--reduced", "--require-gpu"});
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_TRUE(starts_with(run.out, "vkray on llvmpipe")) << run.out;
  EXPECT_NE(run.err.find("--require-gpu"), std::string::npos) << run.err;
}

// A device lost in a row (here: a fence timeout of 1 ms) ends that row with its reason; the report
// goes on, tries a failed variant no more, writes its files and exits 1, without hanging.
TEST_F(CliTest, ReportEndsRowsThatLoseTheDeviceAndGoesOn) {
  const RunResult run = vkray({"report", "report", "--reduced", "--only", "rays", "--models", VKRAY_MODELS_DIR},
                              "VKRAY_FENCE_TIMEOUT_MS=1");
  EXPECT_EQ(run.exit_code, 1) << run.out << run.err;
  const auto json = nlohmann::json::parse(read_text(path("report/report.json")));
  size_t failed = 0;
  for (const auto& row : json.at("rows")) {
    if (row.at("section") != "rays") continue;
    ASSERT_NE(row.at("status"), "ok") << row.dump();
    if (row.at("status") == "failed") {
      ++failed;
      EXPECT_NE(row.at("reason").get<std::string>().find("did not finish a submission within 1 ms"), std::string::npos)
          << row.dump();
    }
  }
  EXPECT_GE(failed, 1u);
  EXPECT_NE(read_text(path("report/report.md")).find("**failed**"), std::string::npos);
}

// Every output of the engine's table (engine/frame.hpp, outputs()) through the command line: --aov
// takes its name with '-' or '_', the help names it, the EXR holds its channels, and the bench's
// +every-output row measures each host output against the reference's (docs/bench.md).
TEST_F(CliTest, EveryOutputOfTheTableThroughRenderAndBench) {
  expect_error(vkray({"render", "--aov", "depth,planer_depth", "-o", "x.exr"}), 2, {"did you mean 'planar-depth'?"});
  const RunResult help = vkray({"render", "--help"});
  std::string dashed, underscored;
  std::set<std::string> channels = {"A"};
  for (const vkray::OutputInfo& output : vkray::outputs()) {
    EXPECT_NE(help.out.find(output.name), std::string::npos) << output.name << " not in render --help";
    dashed += (dashed.empty() ? "" : ",") + std::string(output.name);
    underscored += (underscored.empty() ? "" : ",") + vkray::python_key(output);
    for (uint32_t c = 0; c < output.components; ++c) channels.insert(output.channels[c]);
  }
  for (const std::string& list : {dashed, underscored}) {
    SCOPED_TRACE(list);
    const RunResult run = vkray({"render", "--aov", list, "--width", "24", "--height", "16", "-o", "all.exr", "--no-preview"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Image image;
    read_image(path("all.exr"), image);
    EXPECT_EQ(image.channel_names, channels);
  }

  const RunResult bench = vkray({"bench", "--variants", "default,+every-output", "--size", "32x24", "--frames", "1", "--json",
                                 "bench.json"});
  ASSERT_EQ(bench.exit_code, 0) << bench.err;
  const auto json = nlohmann::json::parse(read_text(path("bench.json")));
  const auto& every = json.at("scenes").at(0).at("rows").at(1);
  ASSERT_EQ(every.at("variant"), "+every-output");
  EXPECT_TRUE(every.at("outputs_compared").get<bool>());
  for (const vkray::OutputErrorField& field : vkray::output_error_fields()) {
    EXPECT_TRUE(every.contains(field.name)) << field.name;
    EXPECT_NE(bench.out.find("  " + field.label + " "), std::string::npos) << field.label << " not in the bench's table";
  }
  for (const vkray::OutputInfo& output : vkray::outputs()) {
    if (output.error == vkray::OutputError::none) continue;
    EXPECT_TRUE(every.contains(output.error_field)) << output.name;
  }
}

// Every search of the engine's table (engine/render/search.hpp): --traversal takes its name (and
// renders, or refuses in one line where the device cannot run it), the help names it, and the
// bench has its row under the same name.
TEST_F(CliTest, EverySearchOfTheTableThroughRenderAndBench) {
  const RunResult help = vkray({"render", "--help"});
  std::string rows = "default";
  for (const vkray::SearchInfo& search : vkray::searches()) {
    SCOPED_TRACE(search.name);
    EXPECT_NE(help.out.find(search.name), std::string::npos) << "not in render --help";
    const RunResult run = vkray({"render", "--traversal", search.name, "--width", "24", "--height", "16", "-o", "t.exr", "--no-preview"});
    EXPECT_TRUE(run.exit_code == 0 || (run.exit_code == 1 && run.err.find("cannot run on") != std::string::npos)) << run.err;
    rows += std::string(",") + search.name;
  }
  const RunResult bench = vkray({"bench", "--variants", rows, "--size", "24x16", "--frames", "1", "--json", "bench.json"});
  ASSERT_EQ(bench.exit_code, 0) << bench.err;
  const auto json = nlohmann::json::parse(read_text(path("bench.json")));
  std::set<std::string> named;
  for (const auto& row : json.at("scenes").at(0).at("rows")) named.insert(row.at("variant").get<std::string>());
  for (const auto& skipped : json.at("scenes").at(0).at("skipped")) named.insert(skipped.get<std::string>().substr(0, skipped.get<std::string>().find(' ')));
  for (const vkray::SearchInfo& search : vkray::searches()) EXPECT_EQ(named.count(search.name), 1u) << search.name;
}
