#include "engine/image_io.hpp"

#include "engine/preview.hpp"

#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <future>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vkray {
namespace {

// Temporary files being written, for remove_partial_outputs. A signal handler may read them at any
// moment, so they live in fixed storage, and a slot is claimed before its path is written and
// marked ready after: the handler only reads ready slots.
constexpr size_t max_partial_files = 8;
constexpr size_t max_partial_path = 4096;
enum SlotState : int { slot_free, slot_claimed, slot_ready };
std::array<std::array<char, max_partial_path>, max_partial_files> partial_paths;
std::array<std::atomic<int>, max_partial_files> partial_states;
std::atomic<unsigned> partial_counter{0};

// A file written under a temporary name beside `target`, renamed onto it by commit() and removed
// if never committed.
// vkray's own rule: a file with no write permission bit for anyone is not replaced, by root either
// (cp refuses such a file to other users, and the rename into place would replace it silently).
void refuse_read_only(const std::filesystem::path& target) {
  struct stat status {};
  if (stat(target.c_str(), &status) == 0 && S_ISREG(status.st_mode) && (status.st_mode & 0222) == 0) {
    throw std::runtime_error(target.string() + ": cannot write: the file is read-only (make it writable or remove it)");
  }
}

class PartialFile {
 public:
  explicit PartialFile(const std::filesystem::path& target) : target_(target) {
    // The extension stays last: OpenImageIO picks the format by it.
    temp_ = target.parent_path() / ("." + target.stem().string() + ".vkray-" + std::to_string(getpid()) + "-" +
                                    std::to_string(partial_counter++) + target.extension().string());
    const std::string text = temp_.string();
    if (text.size() >= max_partial_path) return;  // not removed on a signal; still never a truncated target
    for (size_t k = 0; k < max_partial_files; ++k) {
      int expected = slot_free;
      if (!partial_states[k].compare_exchange_strong(expected, slot_claimed)) continue;
      std::memcpy(partial_paths[k].data(), text.c_str(), text.size() + 1);
      partial_states[k].store(slot_ready);
      slot_ = k;
      break;
    }
  }
  ~PartialFile() {
    if (!committed_) std::remove(temp_.c_str());
    if (slot_ < max_partial_files) partial_states[slot_].store(slot_free);
  }
  PartialFile(const PartialFile&) = delete;
  PartialFile& operator=(const PartialFile&) = delete;

  const std::filesystem::path& path() const { return temp_; }
  void commit() {
    refuse_read_only(target_);
    std::error_code error;
    std::filesystem::rename(temp_, target_, error);
    if (error) throw std::runtime_error(target_.string() + ": cannot write: " + error.message());
    committed_ = true;
  }

 private:
  std::filesystem::path target_, temp_;
  size_t slot_ = max_partial_files;
  bool committed_ = false;
};

void write_image(const std::filesystem::path& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc type, const void* pixels,
                 const std::filesystem::path& shown_path) {
  auto output = OIIO::ImageOutput::create(path.string());
  if (!output) throw std::runtime_error(shown_path.string() + ": cannot write: " + OIIO::geterror());
  if (!output->open(path.string(), spec) || !output->write_image(type, pixels) || !output->close()) {
    throw std::runtime_error(shown_path.string() + ": cannot write: " + output->geterror());
  }
}

void write_exr_to(const PartialFile& file, const std::filesystem::path& target, const Frame& frame,
                  std::string_view compression);
void write_preview_png_to(const PartialFile& file, const std::filesystem::path& target, const Frame& frame);

}  // namespace

void check_output_path(const std::filesystem::path& path) {
  const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
  if (!std::filesystem::is_directory(folder)) {
    throw std::runtime_error(path.string() + ": cannot write: folder '" + folder.string() + "' does not exist");
  }
  if (std::filesystem::is_directory(path)) throw std::runtime_error(path.string() + ": cannot write: it is a folder");
  refuse_read_only(path);
  // Creating the temporary file is the one check that sees everything that can stop the write
  // (permissions, which root bypasses, a read-only file system, quotas on the folder).
  const PartialFile probe(path);
  const int descriptor = open(probe.path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (descriptor < 0) {
    throw std::runtime_error(path.string() + ": cannot write in folder '" + folder.string() + "': " + std::strerror(errno));
  }
  close(descriptor);
}

void write_text_file(const std::filesystem::path& path, std::string_view text) {
  PartialFile file(path);
  std::ofstream stream(file.path(), std::ios::binary);
  stream.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!stream.flush()) throw std::runtime_error(path.string() + ": cannot write");
  stream.close();
  file.commit();
}

void remove_partial_outputs() noexcept {
  for (size_t k = 0; k < max_partial_files; ++k) {
    if (partial_states[k].load() == slot_ready) unlink(partial_paths[k].data());
  }
}

bool is_exr_compression(std::string_view name) {
  return std::find(std::begin(exr_compressions), std::end(exr_compressions), name) != std::end(exr_compressions);
}

void write_exr(const std::filesystem::path& path, const Frame& frame, std::string_view compression) {
  PartialFile file(path);
  write_exr_to(file, path, frame, compression);
  file.commit();
}

void write_preview_png(const std::filesystem::path& path, const Frame& frame) {
  PartialFile file(path);
  write_preview_png_to(file, path, frame);
  file.commit();
}

void write_rgb_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb) {
  PartialFile file(path);
  const OIIO::ImageSpec spec(static_cast<int>(width), static_cast<int>(height), 3, OIIO::TypeDesc::UINT8);
  write_image(file.path(), spec, OIIO::TypeDesc::UINT8, rgb.data(), path);
  file.commit();
}

namespace {

void write_exr_to(const PartialFile& file, const std::filesystem::path& path, const Frame& frame,
                  std::string_view compression) {
  if (!is_exr_compression(compression)) throw std::invalid_argument("unknown EXR compression " + std::string(compression));
  const bool has_hits = frame.aovs.needs_rays();
  std::vector<std::string> names;
  if (frame.aovs.has(Aov::depth)) names.push_back("Z");
  if (frame.aovs.has(Aov::normal)) names.insert(names.end(), {"N.X", "N.Y", "N.Z"});
  if (frame.aovs.has(Aov::uv)) names.insert(names.end(), {"U", "V"});
  if (has_hits) names.push_back("A");
  if (names.empty()) throw std::runtime_error(path.string() + ": no outputs to write");

  const size_t channels = names.size();
  std::vector<float> pixels(frame.pixel_count() * channels);
  for (size_t p = 0; p < frame.pixel_count(); ++p) {
    float* out = &pixels[p * channels];
    if (frame.aovs.has(Aov::depth)) *out++ = frame.depth[p];
    if (frame.aovs.has(Aov::normal)) {
      const glm::vec3 n = frame.normal_at(p);
      *out++ = n.x, *out++ = n.y, *out++ = n.z;
    }
    if (frame.aovs.has(Aov::uv)) {
      const glm::vec2 uv = frame.uv_at(p);
      *out++ = uv.x, *out++ = uv.y;
    }
    if (has_hits) *out++ = frame.hit(p) ? 1.0f : 0.0f;
  }

  OIIO::ImageSpec spec(static_cast<int>(frame.width), static_cast<int>(frame.height), static_cast<int>(channels),
                       OIIO::TypeDesc::FLOAT);
  spec.channelnames = names;
  spec.alpha_channel = has_hits ? static_cast<int>(channels) - 1 : -1;
  spec.z_channel = frame.aovs.has(Aov::depth) ? 0 : -1;
  spec.attribute("compression", std::string(compression));
  spec.attribute("Software", "vkray");
  write_image(file.path(), spec, OIIO::TypeDesc::FLOAT, pixels.data(), path);
}

void write_preview_png_to(const PartialFile& file, const std::filesystem::path& path, const Frame& frame) {
  std::vector<Aov> shown;
  for (Aov aov : {Aov::depth, Aov::normal, Aov::uv}) {
    if (frame.aovs.has(aov)) shown.push_back(aov);
  }
  if (shown.empty()) throw std::runtime_error(path.string() + ": no outputs to preview");
  const size_t width = frame.width, height = frame.height, row_width = width * shown.size();
  std::vector<uint8_t> rgb(row_width * height * 3);
  for (size_t panel = 0; panel < shown.size(); ++panel) {
    const std::vector<uint8_t> panel_rgb = preview_rgb(frame, shown[panel]);
    for (size_t row = 0; row < height; ++row) {
      std::copy_n(&panel_rgb[row * width * 3], width * 3, &rgb[(row * row_width + panel * width) * 3]);
    }
  }

  OIIO::ImageSpec spec(static_cast<int>(row_width), static_cast<int>(height), 3, OIIO::TypeDesc::UINT8);
  write_image(file.path(), spec, OIIO::TypeDesc::UINT8, rgb.data(), path);
}

}  // namespace

void write_outputs(const std::filesystem::path& exr, const std::filesystem::path* preview, const Frame& frame,
                   std::string_view compression) {
  PartialFile exr_file(exr);
  std::optional<PartialFile> png_file;
  if (preview) png_file.emplace(*preview);
  std::future<void> png;
  if (preview) png = std::async(std::launch::async, [&] { write_preview_png_to(*png_file, *preview, frame); });
  std::exception_ptr exr_failure;
  try {
    write_exr_to(exr_file, exr, frame, compression);
  } catch (...) {
    exr_failure = std::current_exception();
  }
  std::exception_ptr png_failure;
  try {
    if (png.valid()) png.get();
  } catch (...) {
    png_failure = std::current_exception();
  }
  // The EXR is the output asked for: its failure is the one to report. Neither file replaces an
  // older one unless both are complete.
  if (exr_failure) std::rethrow_exception(exr_failure);
  if (png_failure) std::rethrow_exception(png_failure);
  exr_file.commit();
  if (png_file) png_file->commit();
}

}  // namespace vkray
