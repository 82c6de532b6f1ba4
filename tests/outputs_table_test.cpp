// The table of outputs (engine/frame.hpp, outputs()) is whole, and every front end takes each of
// its outputs: the names with either spelling, the EXR's channels, the bench's error fields. The
// command line's EXR against Python's dicts is tests/python/test_vkray.py's, for every output too.
#include "engine/frame.hpp"
#include "engine/reference/compare.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

namespace vkray {
namespace {

TEST(OutputsTable, EveryOutputIsDescribedWhole) {
  std::set<std::string> names, channels;
  std::set<uint32_t> bits;
  for (const OutputInfo& output : outputs()) {
    SCOPED_TRACE(output.name);
    EXPECT_TRUE(names.insert(output.name).second) << "a name twice";
    EXPECT_TRUE(bits.insert(static_cast<uint32_t>(output.aov)).second) << "a bit twice";
    EXPECT_TRUE(output.components >= 1 && output.components <= 3);
    for (uint32_t c = 0; c < 3; ++c) {
      if (c < output.components) {
        ASSERT_NE(output.channels[c], nullptr);
        EXPECT_TRUE(channels.insert(output.channels[c]).second) << "channel " << output.channels[c] << " twice";
      } else {
        EXPECT_EQ(output.channels[c], nullptr) << "a channel past the components";
      }
    }
    EXPECT_NE(output.integers == nullptr, output.floats == nullptr) << "planes of one type exactly";
    EXPECT_EQ(output.integers != nullptr, output.integer);
    EXPECT_EQ(output.error == OutputError::none, output.source == OutputSource::device)
        << "the host's outputs are measured against the reference's, the device's by FrameError";
    EXPECT_EQ(output_info(output.aov).name, output.name);
    // Either spelling, and the dict's key.
    std::string underscored = output.name;
    std::replace(underscored.begin(), underscored.end(), '-', '_');
    EXPECT_EQ(aov_from_name(output.name), output.aov);
    EXPECT_EQ(aov_from_name(underscored), output.aov);
    EXPECT_EQ(python_key(output), underscored);
    EXPECT_NE(output_names().find(output.name), std::string::npos);
  }
  EXPECT_EQ(channels.count("A"), 0u) << "A is the hit mask every file has beside them";
}

TEST(OutputsTable, OutputsSharingAnErrorFieldAreMeasuredAlike) {
  for (const OutputInfo& a : outputs()) {
    for (const OutputInfo& b : outputs()) {
      if (a.error != OutputError::none && std::string(a.error_field) == b.error_field) {
        EXPECT_EQ(a.error, b.error) << a.name << " and " << b.name;
        EXPECT_STREQ(a.error_label, b.error_label) << a.name << " and " << b.name;
      }
    }
  }
  // Every measured output has its field, counts first.
  const auto& fields = output_error_fields();
  bool measures_begun = false;
  for (const auto& field : fields) {
    measures_begun = measures_begun || !field.count;
    EXPECT_TRUE(field.count || measures_begun);
    EXPECT_FALSE(field.count && measures_begun) << field.name << " after a measure";
  }
  for (const OutputInfo& output : outputs()) {
    if (output.error == OutputError::none) continue;
    EXPECT_TRUE(std::any_of(fields.begin(), fields.end(), [&](const auto& f) { return f.name == output.error_field; }))
        << output.name;
  }
}

TEST(OutputsTable, UnknownNamesSuggestTheNearest) {
  EXPECT_EQ(unknown_output_message("planer_depth"), "unknown output 'planer_depth'; did you mean 'planar-depth'?");
  EXPECT_NE(unknown_output_message("albedo").find("(choose from depth, normal, uv"), std::string::npos);
  EXPECT_FALSE(aov_from_name("hit")) << "the device's own, not a user's";
}

}  // namespace
}  // namespace vkray
