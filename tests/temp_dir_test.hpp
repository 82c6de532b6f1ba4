// Test fixture with a fresh folder per test under the system temp directory. The folder name holds
// the suite, the test and the process id, so parallel ctest runs never share one; it is removed
// after a passing test and kept after a failing one, for inspection.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

namespace vkray::test {

class TempDirTest : public testing::Test {
 protected:
  void SetUp() override {
    const auto* test = testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "vkray-" + std::string(test->test_suite_name()) + "-" + test->name() + "-" + std::to_string(getpid());
    std::replace(name.begin(), name.end(), '/', '_');  // parameterized tests' names hold slashes
    dir_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }

  void TearDown() override {
    std::error_code ignored;
    if (!HasFailure()) std::filesystem::remove_all(dir_, ignored);
  }

  // Writes `contents` to `relative` inside the folder (creating sub-folders) and returns its path.
  std::filesystem::path write(const std::filesystem::path& relative, const std::string& contents) const {
    const auto path = dir_ / relative;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }

  std::filesystem::path dir_;
};

}  // namespace vkray::test
