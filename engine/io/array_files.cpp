#include "engine/io/array_files.hpp"

#include "engine/scene/scene.hpp"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

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

std::string npy_header(std::string_view descr, std::span<const size_t> shape) {
  std::string dims;
  for (const size_t d : shape) dims += std::to_string(d) + ", ";
  if (shape.size() > 1) dims.resize(dims.size() - 2);  // (n,) for one dimension, (a, b) for more
  // NumPy's format 1.0: magic, version, the header's length, a Python dict padded with spaces to a
  // newline that makes the data start at a multiple of 64 bytes (numpy/lib/format.py).
  std::string header = "{'descr': '" + std::string(descr) + "', 'fortran_order': False, 'shape': (" + dims + "), }";
  const size_t preamble = 10;
  header.append(63 - (preamble + header.size()) % 64, ' ');
  header += '\n';
  std::string bytes = "\x93NUMPY";
  bytes += '\x01';
  bytes += '\x00';
  append(bytes, static_cast<uint16_t>(header.size()));
  return bytes + header;
}

std::string npy_file(const Frame& frame, Aov aov, float miss, bool half) {
  const OutputInfo& output = output_info(aov);
  const char* descr = output.integer ? "<u4" : half ? "<f2" : "<f4";
  std::vector<size_t> shape{frame.height, frame.width};
  if (output.components > 1) shape.push_back(output.components);
  std::string bytes = npy_header(descr, shape);
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

std::vector<glm::dvec3> read_npy_points(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path.string() + ": cannot be read");
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const auto refuse = [&](const std::string& why) -> std::vector<glm::dvec3> {
    throw InputError(path.string() + ": " + why + " (expected a .npy file of float64 or float32 points, shape (..., 3), C order)");
  };
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) return refuse("not a .npy file");
  const auto major = static_cast<uint8_t>(bytes[6]);
  const size_t length_bytes = major == 1 ? 2 : 4, start = 8 + length_bytes;
  if (major < 1 || major > 3 || bytes.size() < start) return refuse("an unknown .npy version");
  size_t header_length = 0;
  for (size_t b = 0; b < length_bytes; ++b) header_length |= size_t{static_cast<uint8_t>(bytes[8 + b])} << (8 * b);
  if (bytes.size() < start + header_length) return refuse("its header runs past its end");
  const std::string header = bytes.substr(start, header_length);
  const auto value_of = [&](const std::string& key) {
    const size_t at = header.find("'" + key + "':");
    return at == std::string::npos ? std::string() : header.substr(at + key.size() + 3);
  };
  const std::string descr = value_of("descr"), order = value_of("fortran_order"), shape_text = value_of("shape");
  const bool doubles = descr.rfind(" '<f8'", 0) == 0 || descr.rfind("'<f8'", 0) == 0;
  const bool floats = descr.rfind(" '<f4'", 0) == 0 || descr.rfind("'<f4'", 0) == 0;
  if (!doubles && !floats) return refuse("its dtype is not float64 or float32 (little-endian)");
  if (order.find("False") > 1) return refuse("it is in Fortran order");
  const size_t open = shape_text.find('('), close = shape_text.find(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return refuse("its shape cannot be read");
  std::vector<size_t> shape;
  std::string dims = shape_text.substr(open + 1, close - open - 1);
  for (size_t at = 0; at < dims.size();) {
    const size_t comma = std::min(dims.find(',', at), dims.size());
    const std::string dim = dims.substr(at, comma - at);
    if (dim.find_first_not_of(' ') != std::string::npos) {
      try {
        shape.push_back(std::stoull(dim));
      } catch (const std::exception&) {
        return refuse("its shape cannot be read");
      }
    }
    at = comma + 1;
  }
  if (shape.empty() || shape.back() != 3) return refuse("its last dimension is not 3");
  size_t count = 1;
  for (const size_t d : shape) {
    if (d != 0 && count > (size_t{1} << 40) / d) return refuse("it holds too many points");
    count *= d;
  }
  const size_t item = doubles ? 8 : 4, data = start + header_length;
  if (bytes.size() - data != count * item) return refuse("it holds " + std::to_string(bytes.size() - data) + " bytes of data, not the " + std::to_string(count * item) + " its shape says");
  std::vector<glm::dvec3> points(count / 3);
  for (size_t k = 0; k < count; ++k) {
    double value;
    if (doubles) {
      std::memcpy(&value, bytes.data() + data + 8 * k, 8);
    } else {
      float single;
      std::memcpy(&single, bytes.data() + data + 4 * k, 4);
      value = single;
    }
    points[k / 3][static_cast<glm::length_t>(k % 3)] = value;
  }
  return points;
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
