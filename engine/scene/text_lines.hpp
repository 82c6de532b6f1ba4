// Text inputs handed on line by line, a file read a block at a time: an input is checked as it is
// read and never held whole, so a 20 GB file with a fault on its third line fails there, and a good
// one costs what its parse keeps, not its size on top.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace vkray {

struct TextLine {
  std::string_view text;  // without its '\n'
  size_t number;          // from 1
  bool terminated;        // a newline ends it: a last line without one may be cut off
};
using LineHandler = std::function<void(const TextLine&)>;

// The longest line taken. Real ones stay far below: an OBJ face of 4096 corners is about 100 KB, a
// camera record under 10 KB. Past it the input is refused at that line instead of growing a buffer
// without end.
inline constexpr size_t max_line_bytes = size_t{1} << 20;

// Each line of `text`, a leading UTF-8 byte-order mark dropped. Throws InputError "<name>:<line>: ..."
// for a line over max_line_bytes.
void for_each_line(std::string_view text, const std::string& name, const LineHandler& handle);

// The same for the file at `path`, read 1 MiB at a time. Throws InputError naming the path where it
// is missing ("no such <what>"), not a regular file, or cannot be read.
void for_each_file_line(const std::filesystem::path& path, const std::string& what, const LineHandler& handle);

}  // namespace vkray
