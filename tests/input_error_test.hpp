// Helpers for tests of bad input: catching the InputError a loader throws and checking that its
// message is one line naming the file and the place.
#pragma once

#include "engine/scene/scene.hpp"

#include <gtest/gtest.h>

#include <string>

namespace vkray::test {

// The InputError message of `load`, or "" when it throws nothing. Any other exception type fails.
template <class F>
std::string error_of(F&& load) {
  try {
    load();
  } catch (const InputError& error) {
    return error.what();
  }
  return {};
}

// The message is one line, starts with `prefix` (file and place) and contains `detail`.
inline void expect_error(const std::string& message, const std::string& prefix, const std::string& detail) {
  ASSERT_FALSE(message.empty()) << "no InputError raised (expected '" << prefix << "... " << detail << "')";
  EXPECT_EQ(message.rfind(prefix, 0), 0u) << message;
  EXPECT_NE(message.find(detail), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "message is not one line: " << message;
}

}  // namespace vkray::test
