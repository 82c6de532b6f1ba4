// The PLY file the header fuzzer (ply_header_fuzzer.cpp) and the corpus test make of an input: the
// input as the lines between "ply" and "end_header", then a fixed body. In ASCII the body is a
// triangle (three vertices, a face with a texcoord list of MeshLab's kind) and again; in binary the
// same bytes are small integers and tiny floats.
#pragma once

#include <string>
#include <string_view>

namespace vkray::test {

inline std::string ply_from_header(std::string_view header) {
  std::string file = "ply\n" + std::string(header) + "\nend_header\n";
  for (int k = 0; k < 32; ++k) file += "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0 0 1 0 0 1\n";
  return file;
}

}  // namespace vkray::test
