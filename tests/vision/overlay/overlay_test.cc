#include "vision/overlay/overlay.h"

#include <gtest/gtest.h>

namespace clogscope::vision {
namespace {

// The overlay's font draws ASCII only: the signs of the tool's status lines are spelled out, not
// left for the font to draw as "??".
TEST(OverlayTextTest, SpellsOutTheSignsOfStatusLines) {
  EXPECT_EQ(OverlayText("width 9.12 \u00b1 0.16 px: \u03c3 above 0.10 px"),
            "width 9.12 +/- 0.16 px: sigma above 0.10 px");
  EXPECT_EQ(OverlayText("angle \u22124.62\u00b0, 5.45 \u00b5m/px, 2\u00d73"),
            "angle -4.62 deg, 5.45 um/px, 2x3");
  // Anything else one "?" a character, however many bytes it takes; a stray byte alone.
  EXPECT_EQ(OverlayText("caf\u00e9 \u4e2d \U0001F600"), "caf? ? ?");
  EXPECT_EQ(OverlayText(std::string("a\x80"
                                    "b")),
            "a?b");
  for (char c : OverlayText("\u00b1\u03c3\u00b0\u00b5\u2212\u00b7\u00d7\u2013\u2014\u2192\u2026"))
    EXPECT_LT(static_cast<unsigned char>(c), 0x80);
}

}  // namespace
}  // namespace clogscope::vision
