#include "engine/vulkan/pipeline_cache.hpp"

#include "engine/fnv1a.hpp"
#include "engine/device/gpu_device.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace vkray {
namespace {

// vkray's frame around the driver's data: a magic, the data's size and its checksum. The driver
// checks its own header (VkPipelineCacheHeaderVersionOne), but a file cut short by a full disk or
// flipped bits after it are not every driver's concern, and a cache must never crash a run.
constexpr char file_magic[8] = {'v', 'k', 'r', 'a', 'y', 'p', 'c', '1'};
struct FileHeader {
  char magic[8];
  uint64_t data_bytes;
  uint64_t checksum;
};

uint64_t checksum_of(const std::vector<uint8_t>& data) {
  Fnv1a fnv;
  fnv.add_bytes(data.data(), data.size());
  return fnv.hash;
}

std::string hex(uint64_t value, int digits) {
  char text[17];
  std::snprintf(text, sizeof text, "%0*llx", digits, static_cast<unsigned long long>(value));
  return text;
}

// The file's name says which device and driver wrote it: another driver version never reads it.
std::string file_name(const vk::PhysicalDeviceProperties& properties) {
  std::string uuid;
  for (uint8_t byte : properties.pipelineCacheUUID) uuid += hex(byte, 2);
  return "pipelines-" + hex(properties.vendorID, 4) + "-" + hex(properties.deviceID, 4) + "-" +
         hex(properties.driverVersion, 8) + "-" + uuid + ".bin";
}

// The driver's data from `file`, or nothing where it is missing, damaged or another device's.
std::vector<uint8_t> read_data(const std::filesystem::path& file, const vk::PhysicalDeviceProperties& properties) {
  std::ifstream in(file, std::ios::binary);
  FileHeader header{};
  if (!in.read(reinterpret_cast<char*>(&header), sizeof header)) return {};
  if (std::memcmp(header.magic, file_magic, sizeof file_magic) != 0 || header.data_bytes > (uint64_t{1} << 30)) return {};
  std::vector<uint8_t> data(header.data_bytes);
  if (!in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size()))) return {};
  if (in.peek() != std::char_traits<char>::eof() || checksum_of(data) != header.checksum) return {};
  // VkPipelineCacheHeaderVersionOne: 32 bytes of header size, version, vendor, device and UUID.
  vk::PipelineCacheHeaderVersionOne driver_header;
  if (data.size() < sizeof driver_header) return {};
  std::memcpy(&driver_header, data.data(), sizeof driver_header);
  if (driver_header.headerVersion != vk::PipelineCacheHeaderVersion::eOne || driver_header.vendorID != properties.vendorID ||
      driver_header.deviceID != properties.deviceID || driver_header.pipelineCacheUUID != properties.pipelineCacheUUID) {
    return {};
  }
  return data;
}

}  // namespace

std::filesystem::path pipeline_cache_folder() {
  if (const char* chosen = std::getenv("VKRAY_CACHE_DIR"); chosen && *chosen) {
    return std::string(chosen) == "off" ? std::filesystem::path() : std::filesystem::path(chosen);
  }
  // The XDG base directory specification: a relative XDG_CACHE_HOME is invalid and ignored.
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg == '/') return std::filesystem::path(xdg) / "vkray";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "vkray";
  return {};
}

PipelineCache::PipelineCache(const vk::raii::Device& device, const vk::PhysicalDeviceProperties& properties,
                             const std::filesystem::path& folder) {
  std::vector<uint8_t> data;
  if (!folder.empty()) {
    file_ = folder / file_name(properties);
    data = read_data(file_, properties);
  }
  cache_ = vk::raii::PipelineCache(device, vk::PipelineCacheCreateInfo({}, data.size(), data.data()));
  bytes_read_ = data.size();
  bytes_saved_ = data.size();
}

void PipelineCache::save() {
  if (file_.empty()) return;
  const std::lock_guard lock(saving_);
  const std::vector<uint8_t> data = cache_.getData();
  if (data.size() <= bytes_saved_) return;
  std::error_code error;
  std::filesystem::create_directories(file_.parent_path(), error);
  // The process id makes the temporary name unique among processes on this machine; a shared
  // home over NFS adds the host name.
  char host[64] = "";
  gethostname(host, sizeof host - 1);
  const std::filesystem::path temp =
      file_.parent_path() / (file_.filename().string() + "." + host + "." + std::to_string(getpid()) + ".tmp");
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    FileHeader header{};
    std::memcpy(header.magic, file_magic, sizeof file_magic);
    header.data_bytes = data.size();
    header.checksum = checksum_of(data);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
    if (!out.flush()) {
      out.close();
      std::filesystem::remove(temp, error);
      return;
    }
  }
  std::filesystem::rename(temp, file_, error);
  if (error) {
    std::filesystem::remove(temp, error);
    return;
  }
  bytes_saved_ = data.size();
}

}  // namespace vkray
