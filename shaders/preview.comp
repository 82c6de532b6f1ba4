#version 460
// The 8-bit picture of one output the ray cast wrote into a storage image (the viewer's frame):
// the ramps of engine/io/preview.cpp, uploaded by the host, applied by exact comparisons so each byte
// is the one the PNG preview of `vkray render` holds. Written in the swapchain's channel order.
#extension GL_GOOGLE_include_directive : require

#include "gpu_layout.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform PushConstants { PreviewParams params; };
layout(binding = VKRAY_PREVIEW_BINDING_VALUES, rgba32f) uniform readonly image2D values;
// Bytes as integers (RGBA8UI): no float-to-UNORM conversion, whose rounding Vulkan leaves open.
layout(binding = VKRAY_PREVIEW_BINDING_PICTURE, rgba8ui) uniform writeonly uimage2D picture;
layout(std140, binding = VKRAY_PREVIEW_BINDING_RAMPS) uniform Ramps { GpuPreviewRamps ramps; };

float threshold(uint ramp, uint k) {
  uint index = ramp * VKRAY_RAMP_LEVELS + k;
  return ramps.thresholds[index / 4][index % 4];
}

// The largest k with threshold k <= v: PreviewRamp::byte's binary search, step for step.
uint ramp_byte(uint ramp, float v) {
  uint level = 0;
  for (uint step = VKRAY_RAMP_LEVELS / 2; step >= 1; step /= 2) {
    if (threshold(ramp, level + step) <= v) level += step;
  }
  return level;
}

void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  uint width = params.image.x, height = params.image.y;
  if (pixel.x >= width || pixel.y >= height) return;
  vec4 value = imageLoad(values, ivec2(pixel));
  uvec3 rgb = uvec3(0);  // misses stay black
  if (params.image.z == VKRAY_PREVIEW_DEPTH) {
    if (!isinf(value.x) && !isnan(value.x)) rgb = uvec3(ramp_byte(0, -value.x));
  } else if (params.image.z == VKRAY_PREVIEW_NORMAL) {
    if (any(notEqual(value.xyz, vec3(0.0)))) rgb = uvec3(ramp_byte(0, value.x), ramp_byte(0, value.y), ramp_byte(0, value.z));
  } else {
    // inside_unit_disk: on the integer numerators of uv. |x| or |y| beyond the shorter side is
    // outside; within it the squares sum below 2^28 (images hold at most 2^27 pixels).
    int x = int(2 * pixel.x + 1) - int(width), y = int(height) - int(2 * pixel.y + 1);
    int shorter = int(min(width, height));
    bool inside = abs(x) <= shorter && abs(y) <= shorter && x * x + y * y <= shorter * shorter;
    uint ramp = inside ? 0 : 1;
    rgb = uvec3(ramp_byte(ramp, value.x), ramp_byte(ramp, value.y), ramp_byte(ramp, 0.0));
  }
  if (params.image.w != 0) rgb = rgb.bgr;
  imageStore(picture, ivec2(pixel), uvec4(rgb, 255));
}
