#include "pipeline/band.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace clogscope::pipeline {
namespace {

std::string ErrorOf(const std::string& text, const std::string& what) {
  try {
    ParsePoint(text, what);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// A point is two whole, non-negative px; anything else is refused in one line naming the option
// or key it came from.
TEST(ParsePointTest, TwoWholeNonNegativePixels) {
  EXPECT_EQ(ParsePoint("176,240", "--gear-centre"), cv::Point(176, 240));
  EXPECT_EQ(ParsePoint("0,0", "--gear-centre"), cv::Point(0, 0));
  for (const std::string bad :
       {"176", "176,240,1", "176,240,1,1", "a,2", "1.5,2", "-1,2", "1,-2", "", ",", "1,,2"}) {
    EXPECT_EQ(ErrorOf(bad, "--gear-centre"), "--gear-centre '" + bad + "': expected x,y") << bad;
  }
  EXPECT_EQ(ErrorOf("5", "m.yaml: feedstock: gear_centre"),
            "m.yaml: feedstock: gear_centre '5': expected x,y");
}

TEST(ParseRoiTest, FourWholePixelsWithAPositiveSize) {
  EXPECT_EQ(ParseRoi("1,2,30,40"), cv::Rect(1, 2, 30, 40));
  EXPECT_THROW(ParseRoi("1,2,30"), std::invalid_argument);
  EXPECT_THROW(ParseRoi("1,2,30,x"), std::invalid_argument);
  EXPECT_THROW(ParseRoi("-1,2,30,40"), std::invalid_argument);
  EXPECT_THROW(ParseRoi("1,2,0,40"), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::pipeline
