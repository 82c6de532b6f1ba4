// libFuzzer target: manifest lines (what resume and `manifest merge` read back) on arbitrary bytes,
// one line at a time as they read them. Any line must give a record's index or nothing: an
// exception, a crash, a hang or a sanitizer report is a finding (a 200,000-deep array once overran
// the stack).
#include "engine/views/manifest_record.hpp"

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (size_t start = 0; start <= text.size();) {
    const size_t end = std::min(text.find('\n', start), text.size());
    vkray::manifest_line_index(std::string(text.substr(start, end - start)));
    start = end + 1;
  }
  return 0;
}
