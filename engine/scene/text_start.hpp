// Where the content of a text file the user wrote starts.
#pragma once

#include <string_view>

namespace vkray {

// `text` without a leading UTF-8 byte-order mark, which editors on Windows write and which would
// otherwise become part of the first statement (an OBJ's first `v` line, a views file's '[').
inline std::string_view without_byte_order_mark(std::string_view text) {
  constexpr std::string_view utf8_byte_order_mark = "\xEF\xBB\xBF";
  if (text.starts_with(utf8_byte_order_mark)) text.remove_prefix(utf8_byte_order_mark.size());
  return text;
}

}  // namespace vkray
