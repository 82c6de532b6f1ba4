// The driver's pipeline cache, kept on disk between runs: a second run on the same device and
// driver hands the driver what it compiled before. One file per device and driver version, in the
// user's cache folder (pipeline_cache_folder, engine/device/gpu_device.hpp). Only engine/ code includes this file.
#pragma once

#include <vulkan/vulkan_raii.hpp>

#include <cstddef>
#include <filesystem>
#include <mutex>

namespace vkray {

class PipelineCache {
 public:
  // Reads the device's file in `folder` where it exists and was written for this very device and
  // driver (vendor, device, driver version and the driver's cache UUID in its name, checked again
  // in the driver's header, and a checksum of the whole): anything else starts empty, since a cache
  // is only ever an optimization. An empty `folder`: memory only.
  PipelineCache(const vk::raii::Device& device, const vk::PhysicalDeviceProperties& properties,
                const std::filesystem::path& folder);

  const vk::raii::PipelineCache& handle() const { return cache_; }

  // Writes the driver's data back when it grew since it was read or last written. Through a
  // temporary file in the same folder renamed over the old one: two processes saving at once each
  // write a whole file and the last rename wins, and a reader never sees half of one. A folder that
  // cannot be written leaves the cache in memory: no run fails for its cache.
  void save();

  const std::filesystem::path& file() const { return file_; }  // empty: memory only
  size_t bytes_read() const { return bytes_read_; }             // the driver's data taken from the file

 private:
  vk::raii::PipelineCache cache_{nullptr};
  std::filesystem::path file_;
  size_t bytes_read_ = 0;
  size_t bytes_saved_ = 0;
  std::mutex saving_;  // pipelines are made on two threads (the renderer's early pipeline)
};

}  // namespace vkray
