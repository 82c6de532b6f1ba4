// Writing an EXR of planar channels through OpenEXR's core API (OpenEXRCore), its ZIP chunks
// deflated by libdeflate, its chunks encoded on several threads and written in order.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace vkray {

// OpenEXR's lossless compressions, by the name OpenEXR gives them; zip and zips (deflate over
// blocks of 16 rows and of 1 row) also as "zip:LEVEL", deflate level 1 (fastest) to 9, plain "zip"
// being OpenEXR's default level 4. Their deflate streams are libdeflate's: at level 1 as fast as
// zlib's on the bunny's depth and normals at 1920x1080 (about 2.5 ns a byte) and 7% smaller
// (docs/speed.md has the measured table). Lossy ones (pxr24, b44, dwa) would change the
// float32 values and are not offered.
inline constexpr const char* exr_compressions[] = {"zip", "zips", "piz", "rle", "none"};
inline constexpr const char* default_exr_compression = "zip:1";
bool is_exr_compression(std::string_view name);

enum class ExrSample { uint32, half, float32 };

// One channel: width x height samples of its kind, rows from the top, in the host's byte order.
struct ExrChannel {
  const char* name;
  ExrSample sample;
  const void* plane;
};

// A header attribute: a string, a float, or a 4x4 float matrix (m44f) in Imath's memory order
// (row-major, for row vectors).
struct ExrAttribute {
  std::string name;
  std::variant<std::string, float, std::array<float, 16>> value;
};

// Threads that encode one file's chunks: by default one a core, for one file at a time; 1 for
// several threads each writing its own file.
void use_exr_threads(unsigned count);

// Writes a scanline EXR at `path` (its own name, which OpenEXR truncates and fills). Throws
// std::runtime_error with OpenEXR's reason; the caller names the file.
void write_exr_file(const std::filesystem::path& path, uint32_t width, uint32_t height, const std::vector<ExrChannel>& channels,
                    const std::vector<ExrAttribute>& attributes, std::string_view compression);

}  // namespace vkray
