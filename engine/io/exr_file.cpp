#include "engine/io/exr_file.hpp"

#include <OpenEXR/openexr.h>
#include <libdeflate.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace vkray {

bool is_exr_compression(std::string_view name) {
  const size_t colon = name.find(':');
  const std::string_view method = name.substr(0, colon);
  if (std::find(std::begin(exr_compressions), std::end(exr_compressions), method) == std::end(exr_compressions)) return false;
  if (colon == std::string_view::npos) return true;
  const std::string_view level = name.substr(colon + 1);
  return (method == "zip" || method == "zips") && level.size() == 1 && level[0] >= '1' && level[0] <= '9';
}

namespace {

std::atomic<unsigned> exr_threads{std::max(1u, std::thread::hardware_concurrency())};

// OpenEXR's default deflate level for "zip" without one (ImfHeader: zipCompressionLevel).
constexpr int openexr_default_zip_level = 4;

struct Compression {
  exr_compression_t method;
  int zip_level;
};

// The compression of a name is_exr_compression accepts.
Compression compression_of(std::string_view name) {
  const size_t colon = name.find(':');
  const std::string_view method = name.substr(0, colon);
  const int level = colon == std::string_view::npos ? openexr_default_zip_level : name[colon + 1] - '0';
  if (method == "zip") return {EXR_COMPRESSION_ZIP, level};
  if (method == "zips") return {EXR_COMPRESSION_ZIPS, level};
  if (method == "piz") return {EXR_COMPRESSION_PIZ, level};
  if (method == "rle") return {EXR_COMPRESSION_RLE, level};
  return {EXR_COMPRESSION_NONE, level};
}

exr_pixel_type_t pixel_type(ExrSample sample) {
  switch (sample) {
    case ExrSample::uint32: return EXR_PIXEL_UINT;
    case ExrSample::half: return EXR_PIXEL_HALF;
    case ExrSample::float32: return EXR_PIXEL_FLOAT;
  }
  return EXR_PIXEL_FLOAT;
}

int16_t sample_bytes(ExrSample sample) { return sample == ExrSample::half ? 2 : 4; }

// What the threads writing one file share: the context, the channels, and whose turn it is to
// write (a scanline file's chunks go to disk in order; they are encoded in any order).
struct FileWrite {
  exr_context_t context = nullptr;
  uint32_t width = 0;
  const std::vector<ExrChannel>* channels = nullptr;
  int zip_level = openexr_default_zip_level;
  int32_t chunk_count = 0, lines_per_chunk = 0;
  std::atomic<int32_t> next_to_encode{0};
  std::mutex mutex;
  std::condition_variable turn;
  int32_t next_to_write = 0;  // guarded by mutex
  bool failed = false;        // guarded by mutex: one thread's failure stops the others
  std::string error;          // guarded by mutex: OpenEXR's first message

  void fail(const std::string& reason) {
    const std::lock_guard lock(mutex);
    if (error.empty()) error = reason;
    failed = true;
    turn.notify_all();
  }
};

// One encoding thread's deflate state and buffers, reused chunk after chunk.
struct ChunkDeflater {
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> compressor{nullptr, libdeflate_free_compressor};
  std::vector<uint8_t> predicted, deflated;
};

struct EncodingThread {
  FileWrite* file;
  ChunkDeflater deflater;
};

// OpenEXR's ZIP chunk (Technical Introduction to OpenEXR, "ZIP compression"; OpenEXRCore's
// internal_zip.c): the packed bytes at even offsets, then those at odd offsets, each byte then
// replaced by its difference from the byte before it plus 128 (mod 256), the first kept; all of it
// a zlib stream. Floats' high bytes, split from their noisy low bytes, change slowly across a row.
// A chunk deflate does not make smaller is stored as it is, which a reader knows by its size.
exr_result_t deflate_chunk(exr_encode_pipeline_t* encode) {
  ChunkDeflater& deflater = static_cast<EncodingThread*>(encode->encoding_user_data)->deflater;
  const auto* packed = static_cast<const uint8_t*>(encode->packed_buffer);
  const size_t size = encode->packed_bytes, evens = (size + 1) / 2;
  deflater.predicted.resize(size);
  uint8_t* predicted = deflater.predicted.data();
  predicted[0] = packed[0];
  for (size_t i = 1; i < evens; ++i) predicted[i] = static_cast<uint8_t>(packed[2 * i] - packed[2 * i - 2] + 128);
  if (size > 1) predicted[evens] = static_cast<uint8_t>(packed[1] - packed[2 * evens - 2] + 128);
  for (size_t i = 1; i < size / 2; ++i) predicted[evens + i] = static_cast<uint8_t>(packed[2 * i + 1] - packed[2 * i - 1] + 128);

  deflater.deflated.resize(size);
  // Room for one byte less than the chunk: a stream that does not fit is no smaller (returns 0).
  const size_t deflated = libdeflate_zlib_compress(deflater.compressor.get(), predicted, size, deflater.deflated.data(), size - 1);
  // The buffer stays vkray's (an alloc size of 0 tells OpenEXR not to free it).
  encode->compressed_buffer = deflated ? deflater.deflated.data() : encode->packed_buffer;
  encode->compressed_bytes = deflated ? deflated : size;
  encode->compressed_alloc_size = 0;
  return EXR_ERR_SUCCESS;
}

exr_result_t wait_for_turn(exr_encode_pipeline_t* encode) {
  FileWrite& file = *static_cast<EncodingThread*>(encode->encoding_user_data)->file;
  std::unique_lock lock(file.mutex);
  file.turn.wait(lock, [&] { return file.failed || file.next_to_write == encode->chunk.idx; });
  return file.failed ? EXR_ERR_UNKNOWN : EXR_ERR_SUCCESS;
}

exr_result_t write_in_turn(exr_encode_pipeline_t* encode) {
  FileWrite& file = *static_cast<EncodingThread*>(encode->encoding_user_data)->file;
  const exr_result_t result = exr_write_scanline_chunk(file.context, encode->part_index, encode->chunk.start_y,
                                                       encode->compressed_buffer, encode->compressed_bytes);
  if (result == EXR_ERR_SUCCESS) {
    const std::lock_guard lock(file.mutex);
    ++file.next_to_write;
    file.turn.notify_all();
  }
  return result;
}

// Encodes and writes chunks, taking the next one not yet taken, until none is left.
void encode_chunks(FileWrite& file) {
  EncodingThread thread{&file, {}};
  exr_encode_pipeline_t encode = EXR_ENCODE_PIPELINE_INITIALIZER;
  bool initialized = false;
  exr_result_t result = EXR_ERR_SUCCESS;
  for (int32_t chunk; result == EXR_ERR_SUCCESS && (chunk = file.next_to_encode++) < file.chunk_count;) {
    exr_chunk_info_t info;
    result = exr_write_scanline_chunk_info(file.context, 0, chunk * file.lines_per_chunk, &info);
    if (result != EXR_ERR_SUCCESS) break;
    const bool first = !initialized;
    result = first ? exr_encoding_initialize(file.context, 0, &info, &encode) : exr_encoding_update(file.context, 0, &info, &encode);
    if (result != EXR_ERR_SUCCESS) break;
    initialized = true;  // from here on, destroyed whatever happens
    for (int16_t c = 0; c < encode.channel_count; ++c) {
      exr_coding_channel_info_t& channel = encode.channels[c];
      // OpenEXR keeps its channels sorted by name; each is found in ours by its name.
      const ExrChannel& source = *std::find_if(file.channels->begin(), file.channels->end(), [&](const ExrChannel& ours) {
        return std::string_view(ours.name) == channel.channel_name;
      });
      const int16_t bytes = sample_bytes(source.sample);
      channel.user_data_type = static_cast<uint16_t>(pixel_type(source.sample));
      channel.user_bytes_per_element = bytes;
      channel.user_pixel_stride = bytes;
      channel.user_line_stride = static_cast<int32_t>(bytes * file.width);
      channel.encode_from_ptr = static_cast<const uint8_t*>(source.plane) + size_t(info.start_y) * file.width * bytes;
    }
    if (first) {  // the routines once the channels are described: the packing follows their types
      result = exr_encoding_choose_default_routines(file.context, 0, &encode);
      if (result != EXR_ERR_SUCCESS) break;
      if (info.compression == EXR_COMPRESSION_ZIP || info.compression == EXR_COMPRESSION_ZIPS) {
        thread.deflater.compressor.reset(libdeflate_alloc_compressor(file.zip_level));
        if (!thread.deflater.compressor) {
          file.fail("out of memory for the deflate compressor");
          break;
        }
        encode.compress_fn = deflate_chunk;
      }
      encode.yield_until_ready_fn = wait_for_turn;
      encode.write_fn = write_in_turn;
      encode.encoding_user_data = &thread;
    }
    result = exr_encoding_run(file.context, 0, &encode);
  }
  if (result != EXR_ERR_SUCCESS) file.fail(exr_get_default_error_message(result));
  // OpenEXR frees the buffers it allocated, those with a size: not the deflater's (size 0).
  if (initialized) exr_encoding_destroy(file.context, &encode);
}

// OpenEXR reports its errors here, with more detail than the error code: the first is kept.
void keep_first_error(exr_const_context_t context, exr_result_t code, const char* message) {
  void* user_data = nullptr;
  exr_get_user_data(context, &user_data);
  if (user_data) static_cast<FileWrite*>(user_data)->fail(message ? message : exr_get_default_error_message(code));
}

}  // namespace

void use_exr_threads(unsigned count) { exr_threads = std::max(1u, count); }

void write_exr_file(const std::filesystem::path& path, uint32_t width, uint32_t height, const std::vector<ExrChannel>& channels,
                    const std::vector<ExrAttribute>& attributes, std::string_view compression) {
  if (!is_exr_compression(compression)) throw std::invalid_argument("unknown EXR compression " + std::string(compression));
  const Compression chosen = compression_of(compression);
  FileWrite file;
  file.width = width;
  file.channels = &channels;
  file.zip_level = chosen.zip_level;
  exr_context_initializer_t initializer = EXR_DEFAULT_CONTEXT_INITIALIZER;
  initializer.error_handler_fn = keep_first_error;
  initializer.user_data = &file;
  auto reason = [&](exr_result_t result) {
    const std::lock_guard lock(file.mutex);
    return file.error.empty() ? std::string(exr_get_default_error_message(result)) : file.error;
  };
  exr_result_t result = exr_start_write(&file.context, path.c_str(), EXR_WRITE_FILE_DIRECTLY, &initializer);
  if (result != EXR_ERR_SUCCESS) throw std::runtime_error(reason(result));
  // The context is finished whatever happens: on failure OpenEXR removes the file it began.
  std::unique_ptr<exr_context_t, void (*)(exr_context_t*)> finish_on_failure(&file.context, [](exr_context_t* context) {
    if (*context) exr_finish(context);
  });
  auto check = [&](exr_result_t outcome) {
    if (outcome != EXR_ERR_SUCCESS) throw std::runtime_error(reason(outcome));
  };
  int part = 0;
  check(exr_add_part(file.context, "", EXR_STORAGE_SCANLINE, &part));
  check(exr_initialize_required_attr_simple(file.context, part, static_cast<int32_t>(width), static_cast<int32_t>(height),
                                            chosen.method));
  for (const ExrChannel& channel : channels) {
    // Logarithmic is what OpenEXR's C++ Channel() declares by default; it only guides lossy codecs.
    check(exr_add_channel(file.context, part, channel.name, pixel_type(channel.sample), EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1));
  }
  for (const ExrAttribute& attribute : attributes) {
    const char* name = attribute.name.c_str();
    if (const auto* text = std::get_if<std::string>(&attribute.value)) check(exr_attr_set_string(file.context, part, name, text->c_str()));
    if (const auto* number = std::get_if<float>(&attribute.value)) check(exr_attr_set_float(file.context, part, name, *number));
    if (const auto* matrix = std::get_if<std::array<float, 16>>(&attribute.value)) {
      exr_attr_m44f_t m;
      std::copy(matrix->begin(), matrix->end(), m.m);
      check(exr_attr_set_m44f(file.context, part, name, &m));
    }
  }
  check(exr_write_header(file.context));
  check(exr_get_chunk_count(file.context, part, &file.chunk_count));
  check(exr_get_scanlines_per_chunk(file.context, part, &file.lines_per_chunk));

  const unsigned thread_count = std::min<unsigned>(exr_threads, static_cast<unsigned>(file.chunk_count));
  {
    std::vector<std::jthread> helpers;
    for (unsigned t = 1; t < thread_count; ++t) helpers.emplace_back([&file] { encode_chunks(file); });
    encode_chunks(file);
  }
  {
    const std::lock_guard lock(file.mutex);
    if (file.failed) throw std::runtime_error(file.error);
  }
  finish_on_failure.release();
  check(exr_finish(&file.context));
}

}  // namespace vkray
