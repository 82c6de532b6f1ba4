// Output files are replaced only by complete ones: written under a temporary name, renamed into
// place when done (engine/io/image_io.cpp).
#include "engine/io/image_io.hpp"
#include "engine/io/preview.hpp"
#include "tests/temp_dir_test.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

namespace vkray {
namespace {

class ImageIoTest : public test::TempDirTest {
 protected:
  static Frame frame(float depth) {
    Frame result(8, 6, {Aov::depth, Aov::normal});
    result.allocate();
    for (auto& z : result.depth) z = depth;
    return result;
  }
  std::string read(const std::filesystem::path& file) const {
    std::ifstream stream(file, std::ios::binary);
    std::ostringstream text;
    text << stream.rdbuf();
    return text.str();
  }
  void expect_no_temporary_files() const {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_)) {
      EXPECT_EQ(entry.path().filename().string().find(".vkray-"), std::string::npos) << entry.path() << " left behind";
    }
  }
};

TEST_F(ImageIoTest, FailedPreviewLeavesTheOlderExrAsItWas) {
  const auto exr = dir_ / "out.exr";
  write_exr(exr, frame(1.0f));
  const std::string older = read(exr);
  const std::filesystem::path preview = dir_ / "missing-folder" / "out.png";
  EXPECT_THROW(write_outputs(exr, &preview, frame(2.0f)), std::runtime_error);
  EXPECT_EQ(read(exr), older);
  expect_no_temporary_files();

  write_outputs(exr, nullptr, frame(2.0f));  // and a good write does replace it
  EXPECT_NE(read(exr), older);
  expect_no_temporary_files();
}

// A preview that may not be replaced (read-only, as a many-view run with --overwrite met it): the
// EXR beside it is not replaced either.
TEST_F(ImageIoTest, AReadOnlyPreviewLeavesTheOlderExrAsItWas) {
  const auto exr = dir_ / "out.exr";
  const auto preview = dir_ / "out.png";
  write_outputs(exr, &preview, frame(1.0f));
  const std::string older_exr = read(exr), older_png = read(preview);
  std::filesystem::permissions(preview, std::filesystem::perms::owner_write | std::filesystem::perms::group_write |
                                            std::filesystem::perms::others_write, std::filesystem::perm_options::remove);
  EXPECT_THROW(write_outputs(exr, &preview, frame(2.0f)), std::runtime_error);
  EXPECT_EQ(read(exr), older_exr);
  EXPECT_EQ(read(preview), older_png);
  expect_no_temporary_files();
  std::filesystem::permissions(preview, std::filesystem::perms::owner_write, std::filesystem::perm_options::add);
}

// A name of 250 bytes is legal (NAME_MAX is 255); its temporary name must be too.
TEST_F(ImageIoTest, ALongLegalNameIsWritten) {
  const auto file = dir_ / (std::string(245, 'n') + ".json");
  write_text_file(file, "whole\n");
  EXPECT_EQ(read(file), "whole\n");
  expect_no_temporary_files();
}

// A resumed many-view run removes what killed writers left beside the files it will write, in one
// read of each folder: not another target's, not one a live writer holds locked (whatever the
// process id in the names: the lock decides).
TEST_F(ImageIoTest, StaleTemporaryFilesOfTheTargetsGoInOneCall) {
  const std::string dead = "4194305";  // above Linux's largest pid_max (2^22): no process has it
  const std::string live = std::to_string(getpid());
  // A long name's temporary names cut its stem to 255 - 1 ('.') - 7 (".vkray-") - 10 (a pid) - 1 -
  // 10 (a counter) - 4 (".exr") = 222 bytes.
  const std::string long_stem(250, 'n');
  const auto stale_a = write(".a.vkray-" + dead + "-0.exr", "half");
  const auto stale_long = write("." + long_stem.substr(0, 222) + ".vkray-" + dead + "-3.exr", "half");
  const auto other_target = write(".b.vkray-" + dead + "-1.exr", "half");
  const auto other_kind = write(".a.vkray-" + dead + "-2.png", "half");
  const auto in_progress = write(".a.vkray-" + dead + "-4.exr", "half");
  const auto left_by_a_reused_pid = write(".a.vkray-" + live + "-5.exr", "half");
  const int writer = ::open(in_progress.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(writer, 0);
  ASSERT_EQ(::flock(writer, LOCK_EX), 0);
  remove_stale_partial_files({dir_ / "a.exr", dir_ / (long_stem + ".exr")});
  ::close(writer);
  EXPECT_FALSE(std::filesystem::exists(stale_a));
  EXPECT_FALSE(std::filesystem::exists(stale_long));
  EXPECT_FALSE(std::filesystem::exists(left_by_a_reused_pid));
  for (const auto& kept : {other_target, other_kind, in_progress}) EXPECT_TRUE(std::filesystem::exists(kept)) << kept;
}

// A frame larger than 1920x1080 is previewed at a whole fraction of its size: a 3840x2160 frame's
// panels at 1920x1080, each pixel the rounded mean of its 2x2 block's bytes (it was written whole:
// two 3840x2160 panels took longer to make and deflate than the EXR).
TEST_F(ImageIoTest, ALargeFramesPreviewIsItsBlocksMeans) {
  Frame large(3840, 2160, {Aov::depth, Aov::normal});
  large.allocate();
  const size_t pixels = large.pixel_count();
  for (size_t p = 0; p < pixels; ++p) {
    const double x = static_cast<double>(p % 3840) / 3840, y = static_cast<double>(p / 3840) / 2160;
    large.depth[p] = (p % 7 == 0) ? INFINITY : static_cast<float>(1.0 + x + 2.0 * y);
    const double n[3] = {x - 0.5, y - 0.5, 0.7};
    for (size_t c = 0; c < 3; ++c) large.normal[c * pixels + p] = static_cast<float>(n[c]);
  }
  ASSERT_EQ(preview_scale(3840, 2160), 2u);
  EXPECT_EQ(preview_scale(1920, 1080), 1u);
  EXPECT_EQ(preview_scale(1921, 10), 2u);
  write_preview(dir_ / "large.png", large);
  auto input = OIIO::ImageInput::open((dir_ / "large.png").string());
  ASSERT_TRUE(input);
  ASSERT_EQ(input->spec().width, 2 * 1920);
  ASSERT_EQ(input->spec().height, 1080);
  std::vector<uint8_t> png(size_t{2 * 1920} * 1080 * 3);
  ASSERT_TRUE(input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, png.data()));
  input->close();
  size_t checked = 0;
  for (const auto& [panel, aov] : {std::pair{0, Aov::depth}, std::pair{1, Aov::normal}}) {
    const std::vector<uint8_t> whole = preview_rgb(large, aov);
    for (uint32_t y = 0; y < 1080; y += 37) {
      for (uint32_t x = 0; x < 1920; x += 41, ++checked) {
        for (size_t c = 0; c < 3; ++c) {
          uint32_t sum = 0;
          for (uint32_t j = 2 * y; j < 2 * y + 2; ++j) {
            for (uint32_t i = 2 * x; i < 2 * x + 2; ++i) sum += whole[(size_t{j} * 3840 + i) * 3 + c];
          }
          ASSERT_EQ(png[(size_t{y} * 2 * 1920 + panel * 1920 + x) * 3 + c], (sum + 2) / 4) << x << ", " << y;
        }
      }
    }
  }
  EXPECT_GT(checked, 2000u);
}

TEST_F(ImageIoTest, TextFilesAreReplacedWhole) {
  const auto file = dir_ / "report.json";
  write_text_file(file, "first\n");
  write_text_file(file, "second\n");
  EXPECT_EQ(read(file), "second\n");
  try {
    write_text_file(dir_ / "missing-folder" / "report.json", "x");
    ADD_FAILURE() << "no error for a missing folder";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("report.json: cannot write: No such file or directory"), std::string::npos)
        << error.what();  // with the reason
  }
  expect_no_temporary_files();
}

TEST_F(ImageIoTest, OutputPathsAreCheckedUpFront) {
  EXPECT_NO_THROW(check_output_path(dir_ / "new.exr"));
  EXPECT_THROW(check_output_path(dir_ / "missing-folder" / "new.exr"), std::runtime_error);
  EXPECT_THROW(check_output_path(dir_), std::runtime_error);  // a folder
}

}  // namespace
}  // namespace vkray
