#include "engine/views/manifest_record.hpp"

#include "engine/views/json_strings.hpp"

#include <nlohmann/json.hpp>

#include <string_view>

namespace vkray {
namespace {

using Json = nlohmann::json;

// Whether `line` nests arrays and objects deeper than `limit`, counted outside strings.
bool nested_deeper_than(std::string_view line, int limit) {
  int depth = 0;
  JsonStringTracker strings;
  for (const char c : line) {
    if (!strings.outside_strings(c)) continue;
    if ((c == '[' || c == '{') && ++depth > limit) return true;
    if (c == ']' || c == '}') --depth;
  }
  return false;
}

// A record nests three deep (world_to_camera's rows). A line nested far deeper is no record, and is
// refused before nlohmann builds it: copying a 200,000-deep value recursed off the stack.
constexpr int max_record_depth = 8;

// The record a line holds, or nothing.
std::optional<Json> parse_record(const std::string& line) {
  if (nested_deeper_than(line, max_record_depth)) return std::nullopt;
  const Json record = Json::parse(line, nullptr, false);
  if (!record.is_object() || !record.contains("index") || !record["index"].is_number_unsigned() ||
      record["index"].get<uint64_t>() > UINT32_MAX ||
      !((record.contains("exr") && record["exr"].is_string()) || (record.contains("files") && record["files"].is_object() && !record["files"].empty()))) {
    return std::nullopt;
  }
  return record;
}

}  // namespace

std::optional<uint32_t> manifest_line_index(const std::string& line) {
  const auto record = parse_record(line);
  if (!record) return std::nullopt;
  return (*record)["index"].get<uint32_t>();
}

}  // namespace vkray
