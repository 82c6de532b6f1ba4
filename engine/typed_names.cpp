#include "engine/typed_names.hpp"

#include <algorithm>
#include <limits>

namespace vkray {

std::vector<std::string> split_list(std::string_view list) {
  std::vector<std::string> items;
  for (size_t start = 0; start <= list.size() && !list.empty();) {
    const size_t comma = std::min(list.find(',', start), list.size());
    items.emplace_back(list.substr(start, comma - start));
    start = comma + 1;
  }
  return items;
}

size_t edit_distance(std::string_view a, std::string_view b) {
  // Three rows of the table: a transposition looks two rows back.
  std::vector<size_t> before(b.size() + 1), previous(b.size() + 1), row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    before.swap(previous);
    previous.swap(row);
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      row[j] = std::min({previous[j] + 1, row[j - 1] + 1, previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) row[j] = std::min(row[j], before[j - 2] + 1);
    }
  }
  return row[b.size()];
}

std::optional<std::string> nearest_name(std::string_view given, const std::vector<std::string>& names) {
  const std::string* nearest = nullptr;
  size_t nearest_distance = std::numeric_limits<size_t>::max();
  for (const std::string& name : names) {
    const size_t distance = edit_distance(given, name);
    if (distance < nearest_distance) nearest = &name, nearest_distance = distance;
  }
  if (!nearest || nearest_distance > std::max<size_t>(2, given.size() / 3)) return std::nullopt;
  return *nearest;
}

}  // namespace vkray
