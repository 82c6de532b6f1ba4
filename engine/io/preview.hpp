// The 8-bit picture of one output, shared by the PNG preview (image_io.cpp) and the viewer's GPU
// pass (shaders/preview.comp), so that what the viewer shows is byte for byte the panel
// `vkray render` writes. Both map floats to bytes through the same ramps of float thresholds:
// comparisons are exact on any device, where the arithmetic of a formula would round differently.
#pragma once

#include "engine/frame.hpp"
#include "shaders/gpu_layout.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vkray {

// A rising map from floats to bytes: the byte of v is the largest k with thresholds[k] <= v
// (thresholds[0] is -infinity; NaN maps to 0).
struct PreviewRamp {
  std::array<float, VKRAY_RAMP_LEVELS> thresholds;
  uint8_t byte(float v) const;
};

// The ramps `aov` is mapped with: depth as grey from inverse depth (near bright, far dark, every
// hit at 10% or brighter) through [0] applied to -depth, given the image's depth range; normals as
// (N+1)/2 through [0]; uv as (u+1)/2, (v+1)/2 and 1/2 through [0] inside the unit disk and [1],
// 0.3 as bright, outside it. Misses are black.
std::array<PreviewRamp, 2> preview_ramps(Aov aov, DepthRange depths);

// How to read a depth picture mapped with `depths` (preview_ramps), in one line: the depth of its
// white and of its darkest grey. The viewer's overlay, `render`'s output and the PNG's comment.
std::string depth_legend(DepthRange depths);

// Whether the centre of pixel (i, j) lies in the unit disk of uv: decided on the integer numerators
// of uv (see pixel_uv), exactly, so every device draws the same disk.
bool inside_unit_disk(uint32_t i, uint32_t j, uint32_t width, uint32_t height);

// A preview panel is at most this large: a larger frame is previewed at 1/scale of its size (each
// side rounded up), scale the smallest whole number that fits it. A preview is for looking, the
// EXR holds the values: a 3840x2160 frame's two full-size panels took longer to make and deflate
// than its EXR.
inline constexpr uint32_t max_preview_panel_width = 1920, max_preview_panel_height = 1080;
uint32_t preview_scale(uint32_t width, uint32_t height);

// `aov` of `frame` (which must hold it) as 8-bit RGB, 3 bytes a pixel, row-major from the top row,
// at 1/scale of the frame's size: each pixel the rounded mean of its scale x scale block's bytes.
std::vector<uint8_t> preview_rgb(const Frame& frame, Aov aov, uint32_t scale = 1);

}  // namespace vkray
