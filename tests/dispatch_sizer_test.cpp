// Dispatch sizes from measured times (engine/render/dispatch_sizer.hpp), with the times given: the
// rules the GPU tests cannot check exactly, since a loaded machine changes what they measure.
#include "engine/render/dispatch_sizer.hpp"

#include <gtest/gtest.h>

namespace vkray {
namespace {

// 1024-pixel rows, 160 of them, taken in workgroups of 8 rows, under the default 200 ms budget.
TEST(DispatchSizer, FirstDispatchThenSixteenTimesAsManyRowsWhileTheBudgetAllows) {
  DispatchSizer sizer(1024, 160, 200.0, 0.0, 8);
  EXPECT_EQ(sizer.next_rows(), 64u);  // 65536 pixels
  sizer.measured(64, 6.4);            // 0.1 ms a row: 1000 rows would fit half the budget
  EXPECT_EQ(sizer.next_rows(), 160u);  // sixteen times 64, capped by the rows the buffers hold
}

TEST(DispatchSizer, SlowRowsKeepADispatchWithinHalfTheBudget) {
  DispatchSizer sizer(1024, 160, 200.0, 0.0, 8);
  sizer.measured(64, 128.0);          // 2 ms a row, as under a sanitizer on a busy machine
  EXPECT_EQ(sizer.next_rows(), 48u);  // 100 ms / 2 ms = 50 rows, in whole workgroups
  sizer.measured(48, 480.0);          // 10 ms a row: the slowest seen holds
  EXPECT_EQ(sizer.next_rows(), 8u);   // 10 rows, one workgroup
  EXPECT_DOUBLE_EQ(sizer.slowest_ms_per_pixel(), 10.0 / 1024);
}

// After a render of the scene, a quarter of the budget at its slowest pixels' cost: one dispatch a
// frame where the frame fits.
TEST(DispatchSizer, AKnownCostSizesTheFirstDispatch) {
  EXPECT_EQ(DispatchSizer(1024, 160, 200.0, 0.1 / 1024, 8).next_rows(), 160u);  // 500 rows fit
  EXPECT_EQ(DispatchSizer(1024, 160, 200.0, 1.0 / 1024, 8).next_rows(), 48u);   // 50 rows fit
}

TEST(DispatchSizer, NoBudgetIsOneDispatchAndATinyOneIsAWorkgroupEach) {
  EXPECT_EQ(DispatchSizer(1024, 160, 0.0, 0.0, 8).next_rows(), 160u);
  DispatchSizer tight(1024, 160, 1e-6, 0.0, 32);
  tight.measured(64, 1.0);
  EXPECT_EQ(tight.next_rows(), 32u);
}

}  // namespace
}  // namespace vkray
