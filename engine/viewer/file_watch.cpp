#include "engine/viewer/file_watch.hpp"

namespace vkray {

FileWatch::FileWatch(std::filesystem::path path) : path_(std::move(path)), last_(stamp()) {}

std::optional<FileWatch::Stamp> FileWatch::stamp() const {
  std::error_code error;
  const auto time = std::filesystem::last_write_time(path_, error);
  if (error) return std::nullopt;
  const auto size = std::filesystem::file_size(path_, error);
  if (error) return std::nullopt;
  return Stamp{time, size};
}

bool FileWatch::changed() {
  const std::optional<Stamp> now = stamp();
  if (now == last_) return false;
  last_ = now;
  return now.has_value();  // a file being replaced is reloaded once it is back
}

}  // namespace vkray
