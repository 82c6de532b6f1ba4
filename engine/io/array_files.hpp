// Outputs one a file, as depth datasets ship them: NumPy's .npy (any output, bit for bit the EXR's
// channels) and 16-bit PNG (depths, in steps of a recorded size). The files of one frame are named
// after its target: "view-00042.exr" gives "view-00042.depth.npy", "view-00042.normal.npy".
#pragma once

#include "engine/frame.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

enum class FileFormat { exr, npy, png16 };
inline constexpr const char* file_format_names = "exr, npy, png16";
std::optional<FileFormat> file_format_from_name(std::string_view name);

// Where `aovs` are written for the target path `target`: the target itself for an EXR (every
// output in one file); for npy and png16 one file an output, in outputs() order, the target's
// extension replaced by ".OUTPUT.npy" or ".OUTPUT.png".
struct OutputFile {
  Aov aov;  // unused for an EXR
  std::filesystem::path path;
};
std::vector<OutputFile> output_files(const std::filesystem::path& target, AovSet aovs, FileFormat format);

// Throws InputError naming the first output png16 cannot hold: it holds one-channel depths
// (depth, planar-depth) only.
void check_png16_outputs(AovSet aovs);

// The .npy file (format version 1.0) of output `aov` of `frame`: shape (height, width) or (height,
// width, components), rows from the top; float32 ('<f4'), half ('<f2') when `half`, or uint32 ('<u4')
// for ids. A depth holds `miss` where the ray missed, as the EXR does.
std::string npy_file(const Frame& frame, Aov aov, float miss, bool half);

// The header of a .npy file (format 1.0) of dtype `descr` ("<f4", "<f8", "<u4") and C-order `shape`;
// the data follows it, little-endian.
std::string npy_header(std::string_view descr, std::span<const size_t> shape);

// The points of a .npy file of shape (..., 3), float64 or float32, C order. Throws InputError naming
// the file and what is wrong with it.
std::vector<glm::dvec3> read_npy_points(const std::filesystem::path& path);

// The 16-bit samples (big-endian, as PNG stores them) of depth output `aov`: round(depth / step),
// and 0 where there is none, a miss or a depth past 65535 steps; `beyond` counts those past.
std::vector<uint8_t> png16_samples(const Frame& frame, Aov aov, double step, size_t& beyond);

}  // namespace vkray
