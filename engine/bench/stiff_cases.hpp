// The numerically hard scenes: each a named case of `vkray bench --suite stiff` and of the test
// suite (tests/stiff_cases_test.cpp), where the default shader must stay within the reference
// envelope and the textbook variant that the case is about must not. docs/accuracy.md tabulates
// them (vkray bench --suite accuracy --markdown docs/accuracy.md).
#pragma once

#include "engine/scene/scene.hpp"

#include <string>
#include <vector>

namespace vkray {

struct StiffCase {
  std::string name;
  std::string what;  // one line: what is hard about it
  Scene scene;       // at the size asked for, unless the size is the point of the case
  // The `vkray bench` variant (engine/bench/bench.cpp) that leaves the envelope on this case: the
  // textbook choice the default replaces. Empty where no variant does; `why` then says why.
  std::string fails_with;
  std::string why;
};

// Every case at width x height (cases about image sizes keep theirs).
std::vector<StiffCase> stiff_cases(uint32_t width, uint32_t height);

}  // namespace vkray
