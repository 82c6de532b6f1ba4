// Output files are replaced only by complete ones: written under a temporary name, renamed into
// place when done (engine/io/image_io.cpp).
#include "engine/io/image_io.hpp"
#include "tests/temp_dir_test.hpp"

#include <gtest/gtest.h>

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

TEST_F(ImageIoTest, TextFilesAreReplacedWhole) {
  const auto file = dir_ / "report.json";
  write_text_file(file, "first\n");
  write_text_file(file, "second\n");
  EXPECT_EQ(read(file), "second\n");
  EXPECT_THROW(write_text_file(dir_ / "missing-folder" / "report.json", "x"), std::runtime_error);
  expect_no_temporary_files();
}

TEST_F(ImageIoTest, OutputPathsAreCheckedUpFront) {
  EXPECT_NO_THROW(check_output_path(dir_ / "new.exr"));
  EXPECT_THROW(check_output_path(dir_ / "missing-folder" / "new.exr"), std::runtime_error);
  EXPECT_THROW(check_output_path(dir_), std::runtime_error);  // a folder
}

}  // namespace
}  // namespace vkray
