// Writing results: OpenEXR with the output contract's channels, a PNG preview, and text files.
#pragma once

#include "engine/frame.hpp"
#include "engine/io/array_files.hpp"
#include "engine/io/exr_file.hpp"

#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// How an EXR is written: its compression (is_exr_compression), and the value its depth channels
// (Z, planar.Z) hold where the ray missed: +inf by default, which vkray's contract uses; 0, NaN or
// another number for loaders that want one (the header's vkray:miss says which).
struct OutputSettings {
  FileFormat format = FileFormat::exr;  // one EXR, or one file an output (array_files.hpp)
  double depth_step = 0.001;            // png16: the depth of one step of the 16-bit value
  std::string compression = default_exr_compression;
  float miss = INFINITY;
  // Float outputs whose channels are stored as half (OpenEXR rounds each value to nearest even:
  // a relative error of at most 2^-11; beyond 65504, infinity).
  AovSet half;
};

// `frame` with the float outputs of `half` rounded through half as write_exr stores them: what a
// reader of the file gets (render --check measures it).
Frame stored_as_half(const Frame& frame, AovSet half);

// Every file is written to a temporary file beside its target (".NAME.vkray-PID-N.EXT"), which its
// writer holds under an exclusive flock, and renamed into place once complete, so a failed or
// interrupted write never leaves a truncated file where a good one was.

// The longest file name (one path component) Linux file systems take: NAME_MAX.
inline constexpr size_t max_file_name_bytes = 255;

// Throws std::runtime_error naming the path when it cannot be written: its folder is missing or
// refuses a new file, it is a folder, a link, a device, a FIFO or a socket (which the rename into
// place would replace), or it is a read-only file (no write bit for anyone: refused to root too).
// For checking outputs before any work is done; the rename checks again.
void check_output_path(const std::filesystem::path& path);

// The part of check_output_path that needs no folder scan or trial file, for many outputs in one
// folder: throws when `path` is a link, a device, a FIFO, a socket or a read-only file.
void refuse_to_replace(const std::filesystem::path& path);

// A file a render writes, with what it holds as messages name it ("the preview", "view 3's depth").
struct NamedFile {
  std::filesystem::path path;
  std::string role;
};

// Throws InputError where two of `files` are one file (compared as absolute, normal paths): one
// would replace the other (a png16 depth and a preview both named r.depth.png).
void refuse_one_file_twice(const std::vector<NamedFile>& files);

// A text file (the bench's JSON and CSV), written the same way. Throws std::runtime_error.
void write_text_file(const std::filesystem::path& path, std::string_view text);

// Removes the temporary files of writes in progress. Async-signal-safe: for signal handlers, which
// then end the process (see cli/main.cpp).
void remove_partial_outputs() noexcept;

// Removes the temporary files beside each of `targets` that no writer holds locked: those a killed
// vkray left (SIGKILL leaves no chance to clean up), whatever process now has its process id, on
// this node or another. A resumed many-view run starts clean. Each folder is read once.
void remove_stale_partial_files(const std::vector<std::filesystem::path>& targets);

// float32 channels, by output: depth -> Z; normal -> N.X N.Y N.Z; uv -> U V; planar-depth ->
// planar.Z; position -> P.X P.Y P.Z; camera-position -> camera.P.X camera.P.Y camera.P.Z; and A (a
// half: 1 on a hit, 0 on a miss) whenever an output other than uv is present; barycentric -> barycentric.U
// barycentric.V; shading-normal -> Ns.X Ns.Y Ns.Z; texcoord -> texcoord.U texcoord.V. mesh-id ->
// mesh_id and primitive-id -> primitive_id are 32-bit unsigned, and the header's vkray:objects (a JSON
// array) names what each mesh_id stands for. A frame with a camera has it in the header:
// OpenEXR's worldToCamera and worldToNDC (engine/scene/camera.hpp) and vkray:camera, JSON
// (engine/scene/camera_description.hpp). Throws std::runtime_error naming the file.
void write_exr(const std::filesystem::path& path, const Frame& frame, const OutputSettings& settings = {});

// The panels of `frame`'s preview, left to right: depth, normal and uv where the frame has them, or
// depth alone for a frame of camera outputs or ids. A depth panel's PNG carries depth_legend
// (engine/io/preview.hpp) as its "Comment".
std::vector<Aov> preview_panels(const Frame& frame);

// The PNG preview of `frame` alone, as write_outputs writes it beside the outputs (the host bench
// times it apart).
void write_preview(const std::filesystem::path& path, const Frame& frame);

// 8-bit RGB pixels, 3 bytes a pixel, rows from the top, as PNG (the viewer's screenshots).
void write_rgb_png(const std::filesystem::path& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgb);

// The files of `target` (output_files: the EXR, or one file an output in settings.format) and,
// when `preview` is set, the PNG preview, written at the same time on two threads (each takes about
// as long at 1920x1080), and renamed into place only when all are complete.
// The preview is 8-bit RGB, one panel per output side by side in the order depth, normal, uv:
// depth as grey (near bright, far dark, misses black), normals as (N+1)/2, uv as (u+1)/2, (v+1)/2
// with the unit disk drawn brighter (it must touch the shorter borders).
// Throws the outputs' failure, else the preview's. Returns the depth samples of 16-bit PNGs that lie
// past 65535 steps (stored as 0, as a miss): 0 for the other formats.
size_t write_outputs(const std::filesystem::path& target, const std::filesystem::path* preview, const Frame& frame,
                     const OutputSettings& settings = {});

}  // namespace vkray
