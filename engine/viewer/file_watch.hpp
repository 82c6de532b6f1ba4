// Notices when a file changes on disk, by its modification time and size: polled a few times a
// second by the idle viewer, a stat() each time, which costs nothing measurable.
#pragma once

#include <filesystem>
#include <optional>

namespace vkray {

class FileWatch {
 public:
  explicit FileWatch(std::filesystem::path path);
  // True once after each change since the last call (a file that vanished and came back too).
  bool changed();

 private:
  struct Stamp {
    std::filesystem::file_time_type time;
    std::uintmax_t size;
    bool operator==(const Stamp&) const = default;
  };
  std::optional<Stamp> stamp() const;

  std::filesystem::path path_;
  std::optional<Stamp> last_;
};

}  // namespace vkray
