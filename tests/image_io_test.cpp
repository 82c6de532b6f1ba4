// Output files are replaced only by complete ones: written under a temporary name, renamed into
// place when done (engine/io/image_io.cpp).
#include "engine/io/image_io.hpp"
#include "tests/temp_dir_test.hpp"

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
