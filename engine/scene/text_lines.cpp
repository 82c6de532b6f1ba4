#include "engine/scene/text_lines.hpp"

#include "engine/scene/scene.hpp"
#include "engine/scene/text_start.hpp"

#include <fstream>
#include <vector>

namespace vkray {
namespace {

InputError line_too_long(const std::string& name, size_t number) {
  return InputError(name + ":" + std::to_string(number) + ": a line longer than " + std::to_string(max_line_bytes >> 20) +
                    " MiB: no input of vkray has one");
}

// Hands on the complete lines at the start of `data` (and, `at_end`, the unterminated rest); returns
// how many bytes they took.
size_t handle_lines(std::string_view data, bool at_end, const std::string& name, size_t& number, const LineHandler& handle) {
  size_t start = 0;
  while (start < data.size()) {
    const size_t newline = data.find('\n', start);
    if (newline == std::string_view::npos && !at_end) break;
    const size_t end = newline == std::string_view::npos ? data.size() : newline;
    ++number;
    if (end - start > max_line_bytes) throw line_too_long(name, number);
    handle({data.substr(start, end - start), number, newline != std::string_view::npos});
    start = end + 1;
  }
  if (!at_end && data.size() - start > max_line_bytes) throw line_too_long(name, number + 1);
  return std::min(start, data.size());
}

}  // namespace

void for_each_line(std::string_view text, const std::string& name, const LineHandler& handle) {
  size_t number = 0;
  handle_lines(without_byte_order_mark(text), true, name, number, handle);
}

void for_each_file_line(const std::filesystem::path& path, const std::string& what, const LineHandler& handle) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw InputError(path.string() + (std::filesystem::exists(path, error) ? ": is not a regular file" : ": no such " + what));
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path.string() + ": cannot open the " + what);
  constexpr size_t block_bytes = size_t{1} << 20;
  std::string pending;
  size_t number = 0;
  bool first_block = true;
  std::vector<char> block(block_bytes);
  while (file) {
    file.read(block.data(), static_cast<std::streamsize>(block.size()));
    const auto got = static_cast<size_t>(file.gcount());
    if (file.bad()) throw InputError(path.string() + ": cannot read the " + what);
    std::string_view data(block.data(), got);
    if (first_block) data = without_byte_order_mark(data);  // a file's first block holds all 3 bytes
    first_block = false;
    pending.append(data);
    const bool at_end = file.eof();
    pending.erase(0, handle_lines(pending, at_end, path.string(), number, handle));
  }
}

}  // namespace vkray
