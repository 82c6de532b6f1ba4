// The pipeline cache on disk (engine/vulkan/pipeline_cache.hpp): where it lives, that a second
// device reads what the first saved, that damaged or foreign files are ignored and replaced, that
// a folder it cannot write costs nothing, and that processes saving at once leave one whole file.
#include "engine/fnv1a.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"
#include "tests/temp_dir_test.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace vkray {
namespace {

namespace fs = std::filesystem;
using namespace test;

// Sets an environment variable for one scope, restoring what was there.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    value ? setenv(name, value, 1) : unsetenv(name);
  }
  ~ScopedEnvironment() { old_ ? setenv(name_, old_->c_str(), 1) : unsetenv(name_); }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

std::vector<char> read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& file, const std::vector<char>& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The file's frame (pipeline_cache.cpp): 8 bytes of magic, the data's size, its FNV-1a, the data.
constexpr size_t frame_bytes = 24;

// Opens a device, renders the built-in scene (making its pipelines) and returns the cache file.
fs::path render_with_new_device(size_t* bytes_read = nullptr) {
  GpuDevice gpu;
  if (bytes_read) *bytes_read = gpu.pipeline_cache_bytes_read();
  const Scene scene = sized(default_scene(), 32, 24);
  Renderer renderer(gpu, scene);
  const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
  EXPECT_GT(frame.pixel_count(), 0u);
  return gpu.pipeline_cache_file();
}

class PipelineCacheTest : public TempDirTest {};

TEST_F(PipelineCacheTest, FolderFollowsTheXdgRules) {
  {
    ScopedEnvironment chosen("VKRAY_CACHE_DIR", "/somewhere/else");
    EXPECT_EQ(pipeline_cache_folder(), fs::path("/somewhere/else"));
  }
  ScopedEnvironment none("VKRAY_CACHE_DIR", nullptr);
  {
    ScopedEnvironment xdg("XDG_CACHE_HOME", "/xdg/cache");
    EXPECT_EQ(pipeline_cache_folder(), fs::path("/xdg/cache/vkray"));
  }
  ScopedEnvironment home("HOME", "/home/user");
  {
    ScopedEnvironment relative("XDG_CACHE_HOME", "relative/cache");  // invalid by the specification
    EXPECT_EQ(pipeline_cache_folder(), fs::path("/home/user/.cache/vkray"));
  }
  ScopedEnvironment unset("XDG_CACHE_HOME", nullptr);
  EXPECT_EQ(pipeline_cache_folder(), fs::path("/home/user/.cache/vkray"));
  ScopedEnvironment off("VKRAY_CACHE_DIR", "off");
  EXPECT_EQ(pipeline_cache_folder(), fs::path());
  EXPECT_EQ(render_with_new_device(), fs::path()) << "off: no file";
}

TEST_F(PipelineCacheTest, ASecondDeviceReadsWhatTheFirstSaved) {
  ScopedEnvironment folder("VKRAY_CACHE_DIR", (dir_ / "cache").c_str());
  size_t first_read = 1;
  const fs::path file = render_with_new_device(&first_read);
  EXPECT_EQ(first_read, 0u) << "nothing was saved yet";
  ASSERT_EQ(file.parent_path(), dir_ / "cache");
  ASSERT_TRUE(fs::exists(file));
  const std::vector<char> bytes = read_bytes(file);
  ASSERT_GT(bytes.size(), frame_bytes);
  EXPECT_EQ(std::string(bytes.data(), 8), "vkraypc1");
  size_t second_read = 0;
  render_with_new_device(&second_read);
  EXPECT_EQ(second_read, bytes.size() - frame_bytes);
}

TEST_F(PipelineCacheTest, DamagedOrForeignFilesAreIgnoredAndReplaced) {
  ScopedEnvironment folder("VKRAY_CACHE_DIR", (dir_ / "cache").c_str());
  const fs::path file = render_with_new_device();
  const std::vector<char> good = read_bytes(file);
  ASSERT_GE(good.size(), frame_bytes + 32) << "no driver header";

  // Another device's data with a checksum that fits it: only the driver header tells.
  std::vector<char> foreign = good;
  foreign[frame_bytes + 8] ^= 0x5a;  // VkPipelineCacheHeaderVersionOne::vendorID
  Fnv1a fnv;
  fnv.add_bytes(foreign.data() + frame_bytes, foreign.size() - frame_bytes);
  std::memcpy(foreign.data() + 16, &fnv.hash, sizeof fnv.hash);

  std::vector<char> flipped = good;
  flipped[good.size() - 1] = static_cast<char>(flipped[good.size() - 1] ^ 1);
  std::vector<char> bad_magic = good;
  bad_magic[0] = 'X';
  const std::vector<std::pair<const char*, std::vector<char>>> damaged = {
      {"cut in half", std::vector<char>(good.begin(), good.begin() + static_cast<long>(good.size() / 2))},
      {"a flipped bit", flipped},
      {"another magic", bad_magic},
      {"another device's", foreign},
      {"empty", {}},
      {"longer than it says", [&] {
         std::vector<char> longer = good;
         longer.push_back(0);
         return longer;
       }()},
  };
  for (const auto& [what, bytes] : damaged) {
    SCOPED_TRACE(what);
    write_bytes(file, bytes);
    size_t read = 1;
    render_with_new_device(&read);
    EXPECT_EQ(read, 0u) << "the file was used";
    render_with_new_device(&read);
    EXPECT_EQ(read, good.size() - frame_bytes) << "the file was not replaced by a whole one";
  }
}

TEST_F(PipelineCacheTest, AFolderThatCannotBeWrittenLeavesTheCacheInMemory) {
  write("not-a-folder", "a file where the cache folder would be");
  ScopedEnvironment folder("VKRAY_CACHE_DIR", (dir_ / "not-a-folder").c_str());
  size_t read = 1;
  render_with_new_device(&read);
  EXPECT_EQ(read, 0u);
  EXPECT_TRUE(fs::is_regular_file(dir_ / "not-a-folder"));
}

// Four `vkray render` processes with one cache folder, started together: each renders, and the
// folder ends with one whole file and no temporary one.
TEST_F(PipelineCacheTest, ProcessesSavingAtOnceLeaveOneWholeFile) {
  const fs::path cache = dir_ / "cache";
  std::string command = "cd '" + dir_.string() + "' && export VKRAY_CACHE_DIR='" + cache.string() + "'; pids=''; ";
  for (int k = 0; k < 4; ++k) {
    command += "'" + std::string(VKRAY_BINARY) + "' render --width 32 --height 24 --no-preview -o out" +
               std::to_string(k) + ".exr >/dev/null 2>&1 & pids=\"$pids $!\"; ";
  }
  command += "status=0; for pid in $pids; do wait $pid || status=1; done; exit $status";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(cache)) files.push_back(entry.path());
  ASSERT_EQ(files.size(), 1u) << "a temporary file was left, or two names were used";
  ScopedEnvironment folder("VKRAY_CACHE_DIR", cache.c_str());
  size_t read = 0;
  render_with_new_device(&read);
  EXPECT_EQ(read, read_bytes(files[0]).size() - frame_bytes);
}

}  // namespace
}  // namespace vkray
