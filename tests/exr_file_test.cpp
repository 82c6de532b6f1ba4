// The EXR writer (engine/io/exr_file.hpp), read back by OpenImageIO: every compression, sample kind
// and thread count gives the planes bit for bit, whether deflate shrinks a chunk or not.
#include "engine/io/exr_file.hpp"
#include "tests/temp_dir_test.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <csignal>
#include <cstring>
#include <random>
#include <thread>

namespace vkray {
namespace {

class ExrFileTest : public test::TempDirTest {
 protected:
  void TearDown() override {
    use_exr_threads(std::max(1u, std::thread::hardware_concurrency()));
    TempDirTest::TearDown();
  }
};

// Planes of each kind: smooth ones (what renders look like: deflate shrinks them) and random bits
// (deflate cannot: the chunk is stored as it is).
struct Planes {
  std::vector<float> smooth, noise;
  std::vector<uint16_t> half_bits;  // half floats as their bits: random, but none a NaN (OpenImageIO may quiet them)
  std::vector<uint32_t> ids;
};

Planes make_planes(uint32_t width, uint32_t height) {
  std::mt19937 random(width * 7919u + height);
  Planes planes;
  const size_t pixels = size_t{width} * height;
  for (size_t p = 0; p < pixels; ++p) {
    planes.smooth.push_back(0.25f + 1e-4f * static_cast<float>(p % width) + 3e-4f * static_cast<float>(p / width));
    uint32_t bits;
    do bits = static_cast<uint32_t>(random()); while ((bits & 0x7f800000u) == 0x7f800000u);  // no NaN or infinity
    float value;
    std::memcpy(&value, &bits, sizeof value);
    planes.noise.push_back(value);
    uint16_t half;
    do half = static_cast<uint16_t>(random()); while ((half & 0x7c00u) == 0x7c00u);
    planes.half_bits.push_back(half);
    planes.ids.push_back(static_cast<uint32_t>(p / 3));
  }
  return planes;
}

TEST_F(ExrFileTest, EveryCompressionSampleKindAndThreadCountReadsBackBitForBit) {
  for (const auto& [width, height] : {std::pair{1u, 1u}, {37u, 17u}, {64u, 33u}, {5u, 100u}}) {
    const Planes planes = make_planes(width, height);
    const std::vector<ExrChannel> channels = {{"Z", ExrSample::float32, planes.smooth.data()},
                                              {"noise", ExrSample::float32, planes.noise.data()},
                                              {"H", ExrSample::half, planes.half_bits.data()},
                                              {"id", ExrSample::uint32, planes.ids.data()}};
    const std::array<float, 16> matrix = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16.5f};
    const std::vector<ExrAttribute> attributes = {{"software", std::string("vkray")}, {"vkray:miss", 0.5f}, {"worldToCamera", matrix}};
    for (unsigned threads : {1u, 3u}) {
      use_exr_threads(threads);
      for (const char* compression : {"zip", "zip:1", "zip:9", "zips", "zips:1", "piz", "rle", "none"}) {
        SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height) + ", " + std::to_string(threads) + " threads, " + compression);
        const std::filesystem::path file = dir_ / "channels.exr";
        write_exr_file(file, width, height, channels, attributes, compression);
        auto input = OIIO::ImageInput::open(file.string());
        ASSERT_TRUE(input) << OIIO::geterror();
        const OIIO::ImageSpec& spec = input->spec();
        ASSERT_EQ(spec.width, static_cast<int>(width));
        ASSERT_EQ(spec.height, static_cast<int>(height));
        EXPECT_EQ(spec.get_string_attribute("software"), "vkray");
        EXPECT_EQ(spec.get_float_attribute("vkray:miss"), 0.5f);
        const OIIO::ParamValue* read_matrix = spec.find_attribute("worldToCamera", OIIO::TypeMatrix44);
        ASSERT_TRUE(read_matrix);
        EXPECT_EQ(std::memcmp(read_matrix->data(), matrix.data(), sizeof matrix), 0);
        for (const ExrChannel& channel : channels) {
          SCOPED_TRACE(channel.name);
          const int index = spec.channelindex(channel.name);
          ASSERT_GE(index, 0);
          const OIIO::TypeDesc type = channel.sample == ExrSample::half    ? OIIO::TypeDesc::HALF
                                      : channel.sample == ExrSample::uint32 ? OIIO::TypeDesc::UINT32
                                                                           : OIIO::TypeDesc::FLOAT;
          const size_t bytes = channel.sample == ExrSample::half ? 2 : 4;
          std::vector<uint8_t> read(size_t{width} * height * bytes);
          ASSERT_TRUE(input->read_image(0, 0, index, index + 1, type, read.data())) << input->geterror();
          EXPECT_EQ(std::memcmp(read.data(), channel.plane, read.size()), 0);
        }
      }
    }
  }
}

// A write that fails part way (the file size limit here, as a full disk would) throws OpenEXR's
// reason on any thread count: no thread waits for a chunk that will never be written.
TEST_F(ExrFileTest, AWriteFailingPartWayThrowsOnEveryThreadCount) {
  const Planes planes = make_planes(64, 200);
  const std::vector<ExrChannel> channels = {{"noise", ExrSample::float32, planes.noise.data()}};  // 51 kB, undeflatable
  rlimit unlimited;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &unlimited), 0);
  rlimit limited = unlimited;
  limited.rlim_cur = 20000;
  const auto default_action = std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  for (unsigned threads : {1u, 3u}) {
    use_exr_threads(threads);
    for (const char* compression : {"zip:1", "none"}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, " + compression);
      try {
        write_exr_file(dir_ / "cut.exr", 64, 200, channels, {}, compression);
        ADD_FAILURE() << "written past the size limit";
      } catch (const std::runtime_error& error) {
        EXPECT_NE(std::string(error.what()).find("File too large"), std::string::npos) << error.what();
      }
    }
  }
  setrlimit(RLIMIT_FSIZE, &unlimited);
  std::signal(SIGXFSZ, default_action);
}

// OpenEXR's reason reaches the caller (who names the file).
TEST_F(ExrFileTest, AFolderThatIsNotThereIsReported) {
  const float depth = 1.0f;
  try {
    write_exr_file(dir_ / "missing" / "a.exr", 1, 1, {{"Z", ExrSample::float32, &depth}}, {}, "zip:1");
    FAIL() << "written into a missing folder";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("No such file or directory"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace vkray
