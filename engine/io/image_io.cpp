#include "engine/io/image_io.hpp"

#include "engine/io/array_files.hpp"
#include "engine/io/preview.hpp"
#include "engine/scene/camera_description.hpp"
#include "engine/scene/scene.hpp"

#include <Imath/half.h>
#include <png.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <future>
#include <map>
#include <sstream>
#include <list>
#include <iomanip>
#include <optional>
#include <set>
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

// ".STEM.vkray-", how the temporary names beside `target` start. The stem is cut so that the whole
// name, with the process id, a counter and the extension, keeps within the 255 bytes a file name
// may have (max_file_name_bytes): a legal long name is never refused for its temporary one.
std::string partial_name_prefix(const std::filesystem::path& target) {
  constexpr size_t decoration = 1 + 7 + 10 + 1 + 10;  // '.', ".vkray-", a pid, '-', an unsigned counter
  const std::string stem = target.stem().string();
  const size_t room = max_file_name_bytes -
                      std::min(max_file_name_bytes, decoration + target.extension().string().size());
  return "." + stem.substr(0, room) + ".vkray-";
}


// fsync of a file or a folder; throws where the data could not be written.
void sync_to_disk(const std::filesystem::path& path) {
  const int descriptor = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (descriptor < 0) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(errno));
  const bool synced = ::fsync(descriptor) == 0 || errno == EINVAL || errno == EROFS;
  const int saved_errno = errno;
  ::close(descriptor);
  if (!synced) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(saved_errno));
}

// A file written under a temporary name beside `target`, renamed onto it by commit() and removed
// if never committed. It is created here and held under an exclusive flock until then: the lock,
// not the process id in its name, is what tells a live writer's file from one a killed writer left
// (a process id means nothing on another node of a shared file system, and a restarted container
// reuses its predecessor's). Linux's NFS client passes flock to the server's lock manager.
class PartialFile {
 public:
  explicit PartialFile(const std::filesystem::path& target) : target_(target) {
    // The extension stays last, so the temporary file is still recognised by its kind. Another node
    // may have the same process id and counter: then the next counter.
    for (int attempt = 0; attempt < 64; ++attempt) {
      temp_ = target.parent_path() / (partial_name_prefix(target) + std::to_string(getpid()) + "-" +
                                      std::to_string(partial_counter++) + target.extension().string());
      lock_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (lock_ >= 0 || errno != EEXIST) break;
    }
    if (lock_ < 0) {
      creation_errno_ = errno;
    } else {
      ::flock(lock_, LOCK_EX);
    }
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
    if (lock_ >= 0) ::close(lock_);  // releases the lock, after the file is gone or in place
    if (slot_ < max_partial_files) partial_states[slot_].store(slot_free);
  }
  PartialFile(const PartialFile&) = delete;
  PartialFile& operator=(const PartialFile&) = delete;

  const std::filesystem::path& path() const { return temp_; }
  // Why the temporary file could not be created (errno), or 0: the folder refuses new files.
  int creation_errno() const { return creation_errno_; }
  // The file's data reach the disk before its name does, and the name before the view is recorded:
  // after a node's crash a complete name never holds a zero-length or partial file (rename alone
  // orders nothing on ext4 or XFS). A file system without fsync (EINVAL) is taken as it is.
  void commit() {
    refuse_to_replace(target_);
    sync_to_disk(temp_);
    std::error_code error;
    std::filesystem::rename(temp_, target_, error);
    if (error) throw std::runtime_error(target_.string() + ": cannot write: " + error.message());
    committed_ = true;
    const std::filesystem::path folder = target_.parent_path();
    sync_to_disk(folder.empty() ? std::filesystem::path(".") : folder);
  }

 private:
  std::filesystem::path target_, temp_;
  int lock_ = -1;
  int creation_errno_ = 0;
  size_t slot_ = max_partial_files;
  bool committed_ = false;
};

// 8-bit RGB rows as PNG, through libpng directly: OpenImageIO would load ~260 shared libraries
// (OpenCV, FFmpeg, GDAL...) whose symbol binding took 0.2 s of every vkray process.
// Deflate level 1 with the "up" filter on every row: 4x faster than libpng's defaults (level 6, a
// filter chosen per row) for a 20% larger file (the bunny's 3840x1080 preview: 34 against 139 ms,
// 0.54 against 0.44 MB). libpng reports errors by longjmp: no C++ object with a destructor lives
// in the function that calls setjmp. Returns false with `error` set on failure.
void on_png_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<std::array<char, 256>*>(png_get_error_ptr(png));
  std::snprintf(error->data(), error->size(), "%s", message);
  png_longjmp(png, 1);
}

void on_png_warning(png_structp, png_const_charp) {}

// The pixels a PNG is written from, rows from the top: 8-bit RGB, or 16-bit grey (big-endian).
enum class PngPixels { rgb8, gray16 };

// A PNG's text chunks, by keyword.
using PngTexts = std::vector<std::pair<std::string, std::string>>;

bool write_png_rows(std::FILE* file, const uint8_t* pixels, PngPixels kind, uint32_t width, uint32_t height,
                    const PngTexts& texts, std::array<char, 256>& error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, on_png_error, on_png_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  const bool rgb = kind == PngPixels::rgb8;
  png_set_IHDR(png, info, width, height, rgb ? 8 : 16, rgb ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  PngTexts owned = texts;  // libpng takes non-const pointers
  std::vector<png_text> chunks(owned.size());
  for (size_t k = 0; k < owned.size(); ++k) {
    chunks[k].compression = PNG_TEXT_COMPRESSION_NONE;
    chunks[k].key = owned[k].first.data();
    chunks[k].text = owned[k].second.data();
  }
  if (!chunks.empty()) png_set_text(png, info, chunks.data(), static_cast<int>(chunks.size()));
  png_set_compression_level(png, 1);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_write_info(png, info);
  const size_t row_bytes = size_t{width} * (rgb ? 3 : 2);
  for (uint32_t row = 0; row < height; ++row) png_write_row(png, pixels + row * row_bytes);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

void write_png(const std::filesystem::path& path, size_t width, size_t height, const uint8_t* pixels, PngPixels kind,
               const std::filesystem::path& shown_path, const PngTexts& texts = {}) {
  if (width > PNG_UINT_31_MAX || height > PNG_UINT_31_MAX) {
    throw std::runtime_error(shown_path.string() + ": cannot write: too large for PNG");
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) throw std::runtime_error(shown_path.string() + ": cannot write: " + std::strerror(errno));
  std::array<char, 256> error{"libpng failed"};
  const bool written = write_png_rows(file, pixels, kind, static_cast<uint32_t>(width), static_cast<uint32_t>(height), texts, error);
  const bool flushed = std::fflush(file) == 0 && !std::ferror(file);
  const int saved_errno = errno;
  std::fclose(file);
  if (!written) throw std::runtime_error(shown_path.string() + ": cannot write: " + error.data());
  if (!flushed) throw std::runtime_error(shown_path.string() + ": cannot write: " + std::strerror(saved_errno));
}

void write_exr_to(const PartialFile& file, const std::filesystem::path& target, const Frame& frame,
                  const OutputSettings& settings);
void write_preview_png_to(const PartialFile& file, const std::filesystem::path& target, const Frame& frame);
size_t write_output_file_to(const PartialFile& partial, const OutputFile& file, const Frame& frame, const OutputSettings& settings);

}  // namespace

// What an output may replace: nothing yet, or a writable regular file. The rename that puts an
// output in place would replace a link, a device node or a FIFO of that name (`-o /dev/null` as root,
// the system's): each is refused, and left as it is. So is a file with no write permission bit for
// anyone, by root too: vkray's own rule (cp refuses such a file to other users, and the rename
// would replace it silently).
void refuse_to_replace(const std::filesystem::path& target) {
  struct stat status {};
  if (lstat(target.c_str(), &status) != 0) return;
  const char* kind = S_ISLNK(status.st_mode)                              ? "a symbolic link"
                     : S_ISCHR(status.st_mode) || S_ISBLK(status.st_mode) ? "a device"
                     : S_ISFIFO(status.st_mode)                           ? "a FIFO"
                     : S_ISSOCK(status.st_mode)                           ? "a socket"
                                                                           : nullptr;
  if (kind) {
    throw std::runtime_error(target.string() + ": cannot write: it is " + kind +
                             ", which an output never replaces (name a new file or a regular one)");
  }
  if (S_ISREG(status.st_mode) && (status.st_mode & 0222) == 0) {
    throw std::runtime_error(target.string() + ": cannot write: the file is read-only (make it writable or remove it)");
  }
}

void check_output_path(const std::filesystem::path& path) {
  const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
  if (!std::filesystem::is_directory(folder)) {
    throw std::runtime_error(path.string() + ": cannot write: folder '" + folder.string() + "' does not exist");
  }
  if (std::filesystem::is_directory(path)) throw std::runtime_error(path.string() + ": cannot write: it is a folder");
  refuse_to_replace(path);
  // Creating the temporary file is the one check that sees everything that can stop the write
  // (permissions, which root bypasses, a read-only file system, quotas on the folder).
  const PartialFile probe(path);
  if (probe.creation_errno() != 0) {
    throw std::runtime_error(path.string() + ": cannot write in folder '" + folder.string() + "': " + std::strerror(probe.creation_errno()));
  }
}

void refuse_one_file_twice(const std::vector<NamedFile>& files) {
  const std::filesystem::path working = std::filesystem::current_path();
  std::vector<std::filesystem::path> normal;
  for (const NamedFile& file : files) {
    normal.push_back((working / file.path).lexically_normal());
    for (size_t other = 0; other + 1 < normal.size(); ++other) {
      if (normal[other] != normal.back()) continue;
      throw InputError(file.path.string() + ": " + files[other].role + " and " + file.role +
                       " would write this one file: give them names of their own (-o, --preview, --manifest)");
    }
  }
}

void write_text_file(const std::filesystem::path& path, std::string_view text) {
  PartialFile file(path);
  std::ofstream stream(file.path(), std::ios::binary);
  stream.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!stream.flush()) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(errno));
  stream.close();
  file.commit();
}

void remove_partial_outputs() noexcept {
  for (size_t k = 0; k < max_partial_files; ++k) {
    if (partial_states[k].load() == slot_ready) unlink(partial_paths[k].data());
  }
}

void write_exr(const std::filesystem::path& path, const Frame& frame, const OutputSettings& settings) {
  PartialFile file(path);
  write_exr_to(file, path, frame, settings);
  file.commit();
}

void write_preview(const std::filesystem::path& path, const Frame& frame) {
  PartialFile file(path);
  write_preview_png_to(file, path, frame);
  file.commit();
}

void write_rgb_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb) {
  PartialFile file(path);
  if (rgb.size() != size_t{width} * height * 3) throw std::invalid_argument("write_rgb_png: not width x height RGB pixels");
  write_png(file.path(), width, height, rgb.data(), PngPixels::rgb8, path);
  file.commit();
}

namespace {

// Imath's matrices act on row vectors (p' = p M): the transpose of a matrix for column vectors,
// in Imath's memory order.
std::array<float, 16> row_vector_matrix(const Matrix4& m) {
  std::array<float, 16> transposed;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) transposed[c * 4 + r] = static_cast<float>(m[r][c]);
  }
  return transposed;
}

// The camera in OpenEXR's standard attributes worldToCamera and, for a perspective camera (the one
// a matrix projects), worldToNDC (float32, as the standard defines them) and, exactly, as
// vkray:camera (engine/scene/camera_description.hpp).
void describe_camera(std::vector<ExrAttribute>& attributes, const Camera& camera, uint32_t width, uint32_t height) {
  attributes.push_back({"worldToCamera", row_vector_matrix(world_to_openexr_camera(camera, width, height))});
  if (camera.projection == Projection::perspective) {
    attributes.push_back({"worldToNDC", row_vector_matrix(world_to_openexr_ndc(camera, width, height))});
  }
  attributes.push_back({"vkray:camera", camera_description(camera, width, height).dump()});
}

void write_exr_to(const PartialFile& file, const std::filesystem::path& path, const Frame& frame,
                  const OutputSettings& settings) {
  if (frame.aovs.empty()) {
    throw std::runtime_error(path.string() + ": no outputs to write");
  }
  std::vector<ExrAttribute> attributes{{"software", std::string("vkray")}};
  if (frame.camera) describe_camera(attributes, *frame.camera, frame.width, frame.height);
  if (!frame.mesh_id.empty() && !frame.object_names.empty()) {
    attributes.push_back({"vkray:objects", nlohmann::json(frame.object_names).dump()});
  }
  // OpenEXR reads each channel from the frame's own planes: no copy.
  std::vector<ExrChannel> channels;
  const size_t pixels = frame.pixel_count();
  // Depths with the chosen value where the ray missed (OutputSettings::miss), in copies: the frame
  // keeps +inf, by which hits are known.
  const bool miss_replaced = !(std::isinf(settings.miss) && settings.miss > 0.0f);
  std::vector<std::vector<float>> with_misses;
  with_misses.reserve(outputs().size());  // their planes stay where they are while the file is written
  std::vector<std::vector<Imath::half>> halves;  // the planes of OutputSettings::half, rounded
  halves.reserve(outputs().size());
  bool has_miss_value = false;
  for (const OutputInfo& output : outputs()) {
    if (!frame.aovs.has(output.aov)) continue;
    if (output.integers) {
      const uint32_t* planes = (frame.*output.integers).data();
      for (size_t c = 0; c < output.components; ++c) channels.push_back({output.channels[c], ExrSample::uint32, planes + c * pixels});
      continue;
    }
    const float* planes = (frame.*output.floats).data();
    if (output.takes_miss_value) {
      has_miss_value = true;
      if (miss_replaced) {
        std::vector<float>& written = with_misses.emplace_back(frame.*output.floats);
        for (size_t p = 0; p < pixels; ++p) {
          if (!frame.hit(p)) written[p] = settings.miss;
        }
        planes = written.data();
      }
    }
    if (settings.half.has(output.aov)) {  // rounded by Imath, as stored_as_half rounds them
      std::vector<Imath::half>& rounded = halves.emplace_back(planes, planes + output.components * pixels);
      for (size_t c = 0; c < output.components; ++c) channels.push_back({output.channels[c], ExrSample::half, rounded.data() + c * pixels});
      continue;
    }
    for (size_t c = 0; c < output.components; ++c) channels.push_back({output.channels[c], ExrSample::float32, planes + c * pixels});
  }
  if (has_miss_value) attributes.push_back({"vkray:miss", settings.miss});
  // A holds 0 or 1, which half holds exactly: as half, it is a tenth of the bytes deflate reads for
  // depth and normal rather than a fifth (deflate is half of a many-view run's time).
  std::vector<Imath::half> alpha;
  if (frame.aovs.needs_rays()) {
    alpha.resize(pixels);
    for (size_t p = 0; p < pixels; ++p) alpha[p] = frame.hit(p) ? 1.0f : 0.0f;
    channels.push_back({"A", ExrSample::half, alpha.data()});
  }
  try {
    write_exr_file(file.path(), frame.width, frame.height, channels, attributes, settings.compression);
  } catch (const std::exception& failure) {
    throw std::runtime_error(path.string() + ": cannot write: " + failure.what());
  }
}

// One of output_files' files: the EXR, or one output's .npy or 16-bit PNG. Returns the depths a
// 16-bit PNG could not hold (past 65535 steps).
size_t write_output_file_to(const PartialFile& partial, const OutputFile& file, const Frame& frame, const OutputSettings& settings) {
  if (settings.format == FileFormat::exr) {
    write_exr_to(partial, file.path, frame, settings);
    return 0;
  }
  if (settings.format == FileFormat::npy) {
    const std::string bytes = npy_file(frame, file.aov, settings.miss, settings.half.has(file.aov));
    std::ofstream stream(partial.path(), std::ios::binary);
    stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!stream.flush()) throw std::runtime_error(file.path.string() + ": cannot write: " + std::strerror(errno));
    return 0;
  }
  size_t beyond = 0;
  const std::vector<uint8_t> samples = png16_samples(frame, file.aov, settings.depth_step, beyond);
  std::ostringstream step;
  step << std::setprecision(17) << settings.depth_step;
  write_png(partial.path(), frame.width, frame.height, samples.data(), PngPixels::gray16, file.path,
            {{"Comment", "depth = value x " + step.str() + "; 0 where there is none (a miss, or past 65535 steps)"},
             {"vkray:depth_step", step.str()}});
  return beyond;
}

void write_preview_png_to(const PartialFile& file, const std::filesystem::path& path, const Frame& frame) {
  const std::vector<Aov> shown = preview_panels(frame);
  if (shown.empty()) throw std::runtime_error(path.string() + ": no outputs to preview");
  const uint32_t scale = preview_scale(frame.width, frame.height);
  const size_t width = (frame.width + scale - 1) / scale, height = (frame.height + scale - 1) / scale;
  const size_t row_width = width * shown.size();
  std::vector<uint8_t> rgb(row_width * height * 3);
  for (size_t panel = 0; panel < shown.size(); ++panel) {
    const std::vector<uint8_t> panel_rgb = preview_rgb(frame, shown[panel], scale);
    for (size_t row = 0; row < height; ++row) {
      std::copy_n(&panel_rgb[row * width * 3], width * 3, &rgb[(row * row_width + panel * width) * 3]);
    }
  }

  // The depth panel's scale, for whoever reads a value off it.
  const bool depth_shown = std::find(shown.begin(), shown.end(), Aov::depth) != shown.end();
  PngTexts texts;
  if (depth_shown) texts.emplace_back("Comment", depth_legend(finite_depth_range(frame)));
  write_png(file.path(), row_width, height, rgb.data(), PngPixels::rgb8, path, texts);
}

}  // namespace

Frame stored_as_half(const Frame& frame, AovSet half) {
  Frame stored = frame;
  for (const OutputInfo& output : outputs()) {
    if (!half.has(output.aov) || !output.floats || (stored.*output.floats).empty()) continue;
    for (float& value : stored.*output.floats) value = static_cast<float>(Imath::half(value));
  }
  // The float32 planes are what measure_error reads: doubles of the float64 shader round first.
  stored.depth64.clear(), stored.normal64.clear();
  return stored;
}

std::vector<Aov> preview_panels(const Frame& frame) {
  std::vector<Aov> shown;
  for (Aov aov : {Aov::depth, Aov::normal, Aov::uv}) {
    if (frame.aovs.has(aov)) shown.push_back(aov);
  }
  // Camera outputs or ids alone: the depth they come with stands for them.
  if (shown.empty() && !frame.depth.empty()) shown.push_back(Aov::depth);
  return shown;
}

void remove_stale_partial_files(const std::vector<std::filesystem::path>& targets) {
  // Each folder is read once for all its targets: read once a target, a folder of 40k other files
  // made resuming 2,000 views take 43 s.
  std::map<std::filesystem::path, std::set<std::pair<std::string, std::string>>> targets_by_folder;
  for (const auto& target : targets) {
    targets_by_folder[target.parent_path().empty() ? "." : target.parent_path()].emplace(
        partial_name_prefix(target), target.extension().string());
  }
  constexpr std::string_view marker = ".vkray-";
  for (const auto& [folder, prefixes] : targets_by_folder) {
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
      // ".NAME.vkray-PID-N.EXT": a target's prefix, the writer's process id, a counter.
      const std::string name = entry.path().filename().string();
      const size_t marked = name.rfind(marker);
      if (marked == std::string::npos) continue;
      const size_t prefix_end = marked + marker.size();
      if (!prefixes.contains({name.substr(0, prefix_end), entry.path().extension().string()})) continue;
      // Stale when no writer holds its lock (PartialFile); removed while this process holds it.
      const int descriptor = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
      if (descriptor < 0) continue;
      if (::flock(descriptor, LOCK_EX | LOCK_NB) == 0) std::filesystem::remove(entry.path(), error);
      ::close(descriptor);
    }
  }
}

size_t write_outputs(const std::filesystem::path& target, const std::filesystem::path* preview, const Frame& frame,
                     const OutputSettings& settings) {
  const std::vector<OutputFile> files = output_files(target, frame.aovs, settings.format);
  std::list<PartialFile> partials;  // each stays where it is: its slot names it to the signal handler
  for (const OutputFile& file : files) partials.emplace_back(file.path);
  std::optional<PartialFile> png_file;
  if (preview) png_file.emplace(*preview);
  std::future<void> png;
  if (preview) png = std::async(std::launch::async, [&] { write_preview_png_to(*png_file, *preview, frame); });
  std::exception_ptr output_failure;
  size_t beyond_png16 = 0;
  try {
    auto partial = partials.begin();
    for (const OutputFile& file : files) beyond_png16 += write_output_file_to(*partial++, file, frame, settings);
  } catch (...) {
    output_failure = std::current_exception();
  }
  std::exception_ptr png_failure;
  try {
    if (png.valid()) png.get();
  } catch (...) {
    png_failure = std::current_exception();
  }
  // The outputs are what was asked for: their failure is the one to report. No file replaces an
  // older one unless all are complete.
  if (output_failure) std::rethrow_exception(output_failure);
  if (png_failure) std::rethrow_exception(png_failure);
  // Nor when one of them may not be replaced: every target is checked before any moves.
  for (const OutputFile& file : files) refuse_to_replace(file.path);
  if (preview) refuse_to_replace(*preview);
  for (PartialFile& partial : partials) partial.commit();
  if (png_file) png_file->commit();
  return beyond_png16;
}

}  // namespace vkray
