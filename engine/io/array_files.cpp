#include "engine/io/array_files.hpp"

#include "engine/scene/scene.hpp"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace vkray {
namespace {

template <typename T>
void append(std::string& bytes, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  bytes.append(raw, sizeof(T));
}

}  // namespace

std::optional<FileFormat> file_format_from_name(std::string_view name) {
  if (name == "exr") return FileFormat::exr;
  if (name == "npy") return FileFormat::npy;
  if (name == "png16") return FileFormat::png16;
  return std::nullopt;
}

std::vector<OutputFile> output_files(const std::filesystem::path& target, AovSet aovs, FileFormat format) {
  if (format == FileFormat::exr) return {{Aov::depth, target}};
  std::vector<OutputFile> files;
  for (const OutputInfo& output : outputs()) {
    if (!aovs.has(output.aov)) continue;
    std::filesystem::path path = target;
    path.replace_extension(std::string(".") + output.name + (format == FileFormat::npy ? ".npy" : ".png"));
    files.push_back({output.aov, path});
  }
  return files;
}

void check_png16_outputs(AovSet aovs) {
  for (const OutputInfo& output : outputs()) {
    if (aovs.has(output.aov) && !(output.takes_miss_value && output.components == 1)) {
      throw InputError(std::string("--format png16: '") + output.name +
                       "' is not a depth (a 16-bit PNG holds depth or planar-depth; npy and exr hold every output)");
    }
  }
}

std::string npy_file(const Frame& frame, Aov aov, float miss, bool half) {
  const OutputInfo& output = output_info(aov);
  const char* descr = output.integer ? "<u4" : half ? "<f2" : "<f4";
  const std::string shape = std::to_string(frame.height) + ", " + std::to_string(frame.width) +
                            (output.components > 1 ? ", " + std::to_string(output.components) : "");
  // NumPy's format 1.0: magic, version, the header's length, a Python dict padded with spaces to a
  // newline that makes the data start at a multiple of 64 bytes (numpy/lib/format.py).
  std::string header = "{'descr': '" + std::string(descr) + "', 'fortran_order': False, 'shape': (" + shape + "), }";
  const size_t preamble = 10;
  header.append(63 - (preamble + header.size()) % 64, ' ');
  header += '\n';
  std::string bytes = "\x93NUMPY";
  bytes += '\x01';
  bytes += '\x00';
  append(bytes, static_cast<uint16_t>(header.size()));
  bytes += header;
  const size_t pixels = frame.pixel_count();
  bytes.reserve(bytes.size() + pixels * output.components * 4);
  // The frame's planes are one a component; the file interleaves them pixel by pixel.
  for (size_t p = 0; p < pixels; ++p) {
    for (size_t c = 0; c < output.components; ++c) {
      if (output.integer) {
        append(bytes, (frame.*output.integers)[c * pixels + p]);
        continue;
      }
      float value = (frame.*output.floats)[c * pixels + p];
      if (output.takes_miss_value && !frame.hit(p)) value = miss;
      if (half) {
        append(bytes, Imath::half(value).bits());
      } else {
        append(bytes, value);
      }
    }
  }
  return bytes;
}

std::vector<uint8_t> png16_samples(const Frame& frame, Aov aov, double step, size_t& beyond) {
  const OutputInfo& output = output_info(aov);
  const std::vector<float>& depths = frame.*output.floats;
  std::vector<uint8_t> samples(2 * depths.size());
  beyond = 0;
  for (size_t p = 0; p < depths.size(); ++p) {
    const double steps = std::round(depths[p] / step);
    uint16_t value = 0;
    if (frame.hit(p) && steps <= 65535.0) {
      value = static_cast<uint16_t>(std::max(steps, 0.0));
    } else if (frame.hit(p)) {
      ++beyond;
    }
    samples[2 * p] = static_cast<uint8_t>(value >> 8);
    samples[2 * p + 1] = static_cast<uint8_t>(value & 0xff);
  }
  return samples;
}

}  // namespace vkray
