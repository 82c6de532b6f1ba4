// What a manifest line is: a complete view record, told from a line an interruption cut off or a
// file that is no manifest. The one place manifest lines are parsed (resume, merge, the check of
// --manifest), with nothing it does not need, so the fuzzers (tests/fuzz) build it too.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace vkray {

// The index of a manifest line that is a complete record; nothing for any other line.
std::optional<uint32_t> manifest_line_index(const std::string& line);

}  // namespace vkray
