#include "vision/scene/codec_doubt.h"

#include <gtest/gtest.h>

#include "synthetic/synthetic.h"

namespace clogscope::vision {
namespace {

X264Settings X264AtCrf(double crf) {
  X264Settings s;
  s.found = true;
  s.crf = crf;
  s.aq_mode = 1;
  s.aq_strength = 1.0;
  return s;
}

cv::Mat Frame(int index) {
  synthetic::FrameTruth truth;
  return synthetic::RenderFrame(synthetic::SceneParams{}, index, &truth);
}

TEST(CodecDoubtTest, ALosslessSecondPassMovesNoWidth) {
  // x264 at CRF 0 gives the region back to the bit: the same frame, the same width, no doubt.
  const StrandMeasureOptions options;
  const cv::Mat frame = Frame(0);
  StrandMeasurement m = MeasureStrand(frame, options);
  ASSERT_TRUE(m.valid()) << m.detail;
  X264RoundTrip lossless(X264AtCrf(0));
  const CodecCheck check = CheckCodec(frame, options, &lossless);
  ASSERT_TRUE(check.done);
  EXPECT_EQ(check.shift_px, 0.0);
  EXPECT_EQ(check.DoubtPx(), 0.0);
  const double sigma = m.width_sigma_px;
  CodecDoubt(X264AtCrf(0), 1).Apply(frame, options, &m);
  EXPECT_TRUE(m.valid());
  EXPECT_EQ(m.width_sigma_px, sigma);
}

TEST(CodecDoubtTest, ChecksTheFirstWidthAndEveryNthAfterIt) {
  // Frames with a width 0, 3 and 6 of seven are checked; a frame without one is left alone and
  // not counted. (Lossless, so that every check gives a shift: a lossy second pass may leave a
  // frame without a width, and that check then counts for nothing.)
  const StrandMeasureOptions options;
  CodecDoubt codec(X264AtCrf(0), 3);
  StrandMeasurement none;
  none.status = FrameStatus::kNoStrand;
  codec.Apply(Frame(0), options, &none);
  EXPECT_EQ(codec.checks(), 0);
  EXPECT_EQ(none.status, FrameStatus::kNoStrand);
  for (int i = 0; i < 7; ++i) {
    const cv::Mat frame = Frame(i);
    StrandMeasurement m = MeasureStrand(frame, options);
    ASSERT_TRUE(m.gave_width()) << m.detail;
    codec.Apply(frame, options, &m);
    EXPECT_EQ(codec.checks(), i / 3 + 1) << "frame " << i;
  }
  EXPECT_EQ(codec.doubt_px(), 0.0);
}

}  // namespace
}  // namespace clogscope::vision
