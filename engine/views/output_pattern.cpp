#include "engine/views/output_pattern.hpp"

#include "engine/scene/scene.hpp"

#include <string>

namespace vkray {

OutputPattern::OutputPattern(const std::string& text, const std::string& option) : text_(text) {
  std::string piece;
  for (size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if ((c == '{' || c == '}') && k + 1 < text.size() && text[k + 1] == c) {
      piece += c;
      ++k;
      continue;
    }
    if (c == '}') throw InputError(option + ": '" + text + "' has a '}' with no '{' (write '}}' for a brace)");
    if (c != '{') {
      piece += c;
      continue;
    }
    const size_t close = text.find('}', k);
    if (close == std::string::npos) throw InputError(option + ": '" + text + "' has a '{' with no '}' (write '{{' for a brace)");
    const std::string field = text.substr(k + 1, close - k - 1);
    int width = 0;
    if (field.rfind("index:0", 0) == 0 && field.size() > 7 && field.size() <= 9 &&
        field.find_first_not_of("0123456789", 7) == std::string::npos) {
      width = std::stoi(field.substr(7));
    } else if (field != "index") {
      throw InputError(option + ": '" + text + "': unknown field {" + field + "} (use {index} or {index:05}, zero-padded to 5 digits)");
    }
    pieces_.push_back(piece);
    widths_.push_back(width);
    piece.clear();
    k = close;
  }
  pieces_.push_back(piece);
}

std::filesystem::path OutputPattern::path(uint32_t index) const {
  std::string result = pieces_[0];
  const std::string digits = std::to_string(index);
  for (size_t k = 0; k < widths_.size(); ++k) {
    const size_t width = static_cast<size_t>(widths_[k]);  // up to 99: any padding asked for, never cut
    if (digits.size() < width) result.append(width - digits.size(), '0');
    result += digits;
    result += pieces_[k + 1];
  }
  return result;
}

}  // namespace vkray
