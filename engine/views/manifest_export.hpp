// A many-view manifest as the camera files reconstruction tools read: NeRF's transforms.json
// (nerfstudio, instant-ngp) and COLMAP's text model. The manifest holds exactly their data; what
// differs is each format's conventions, written down here once:
// - vkray's intrinsics are OpenCV's with pixel (i, j)'s centre at (u, v) = (i, j); COLMAP and NeRF
//   put the top-left pixel's centre at (0.5, 0.5), so their cx, cy are vkray's plus 0.5.
// - vkray's world_to_camera is OpenCV's (x right, y down, z along the view), which is COLMAP's;
//   its rotation goes out as a unit quaternion (w, x, y, z), w >= 0.
// - NeRF's transform_matrix is camera-to-world in OpenGL's camera axes (x right, y up, z towards
//   the viewer): the inverse of world_to_camera with its y and z axes negated.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vkray {

enum class ManifestFormat { nerf, colmap };

// "nerf" or "colmap"; throws InputError naming the choices for another name.
ManifestFormat manifest_format_from_name(const std::string& name);

// The files of `manifest` exported into `folder`, by name within it: transforms.json for nerf;
// cameras.txt (one PINHOLE camera for each distinct size and intrinsics), images.txt (image id =
// view index + 1) and an empty points3D.txt for colmap. Image names are the views' EXRs relative
// to `folder`. Throws InputError where the manifest is not a complete set of views (as a merge
// does) or holds a view without a pinhole camera (orthographic and panoramic views have none).
std::vector<std::pair<std::string, std::string>> export_manifest(const std::filesystem::path& manifest,
                                                                 ManifestFormat format,
                                                                 const std::filesystem::path& folder);

}  // namespace vkray
