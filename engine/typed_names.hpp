// Names a user types: comma-separated lists of them (--aov, --variants, Python's aovs), and "did you
// mean ...?" for one mistyped (scene-file keys, subcommands, outputs).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// The items of a comma-separated list, empty ones kept ("a,,b" has three); none for "".
std::vector<std::string> split_list(std::string_view list);

// Damerau-Levenshtein distance (optimal string alignment): insertions, deletions, substitutions of
// one character and swaps of two neighbours each cost 1, so "fvoy" is 1 from "fovy", 2 from "from".
size_t edit_distance(std::string_view a, std::string_view b);

// The name in `names` closest to `given`, when it is close enough to be the one meant: at most 2
// edits, or a third of the typed length for longer names (a typo, not a different word).
std::optional<std::string> nearest_name(std::string_view given, const std::vector<std::string>& names);

}  // namespace vkray
