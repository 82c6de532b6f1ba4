// Scanning JSON text by hand, before parsing it: where each element starts (view_list.cpp), how
// deep a line nests (manifest.cpp). Brackets and commas inside strings are not structure.
#pragma once

namespace vkray {

class JsonStringTracker {
 public:
  // Whether `c`, the text's next character, is outside every string: structure, or the quote that
  // opens a string. Escaped quotes and the quote that closes a string are inside.
  bool outside_strings(char c) {
    if (in_string_) {
      if (escaped_) {
        escaped_ = false;
      } else if (c == '\\') {
        escaped_ = true;
      } else if (c == '"') {
        in_string_ = false;
      }
      return false;
    }
    in_string_ = c == '"';
    return true;
  }

 private:
  bool in_string_ = false, escaped_ = false;
};

}  // namespace vkray
