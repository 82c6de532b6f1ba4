// An output path for many views: the view's index in it as "{index}" or, zero-padded to N digits,
// "{index:0N}" (out/view-{index:05}.exr -> out/view-00042.exr), as Python's format writes them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vkray {

class OutputPattern {
 public:
  // Throws InputError naming `option` for any other placeholder or an unmatched brace ("{{" and "}}"
  // stand for a brace).
  OutputPattern(const std::string& text, const std::string& option);

  bool has_index() const { return !widths_.empty(); }
  std::filesystem::path path(uint32_t index) const;
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  // Literal text between placeholders: pieces_[0], index, pieces_[1], index, ... (widths_[k] digits
  // for the k-th index, 0 for no padding).
  std::vector<std::string> pieces_;
  std::vector<int> widths_;
};

}  // namespace vkray
