#include "vision/scene/codec_doubt.h"

#include <gtest/gtest.h>

#include "synthetic/synthetic.h"
#include "tests/vision/x264_test_settings.h"

namespace clogscope::vision {
namespace {

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
  ASSERT_TRUE(check.done());
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

TEST(CodecDoubtTest, ACheckWithoutAShiftIsTriedAgainSoonAndLeavesTheWidthsAlone) {
  // A faint strand (20 grey levels over its background, noise 1) is measured valid on the
  // lossless frame; x264 at its coarsest (CRF 51) smears it into something that is not a
  // silhouette, so no check gives a shift. Checks are tried on frames 0, 1, 3 and 7 of eight
  // (then ever more rarely), and the widths go out as measured.
  synthetic::SceneParams p;
  p.strand_level = p.background_level + 20;
  p.noise_sigma = 1;
  synthetic::FrameTruth truth;
  const StrandMeasureOptions options;
  X264RoundTrip coarsest(X264AtCrf(51));
  const cv::Mat first = synthetic::RenderFrame(p, 0, &truth);
  ASSERT_EQ(CheckCodec(first, options, &coarsest).outcome, CodecCheck::Outcome::kLostInSecondPass);
  CodecDoubt codec(X264AtCrf(51), 50);
  const int tried_by_frame[] = {1, 2, 2, 3, 3, 3, 3, 4};
  for (int i = 0; i < 8; ++i) {
    const cv::Mat f = synthetic::RenderFrame(p, i, &truth);
    const StrandMeasurement measured = MeasureStrand(f, options);
    ASSERT_TRUE(measured.valid()) << i << ": " << measured.detail;
    StrandMeasurement m = measured;
    codec.Apply(f, options, &m);
    EXPECT_EQ(codec.attempts(), tried_by_frame[i]) << "frame " << i;
    EXPECT_TRUE(m.valid()) << i << ": " << m.detail;
    EXPECT_EQ(m.width_sigma_px, measured.width_sigma_px) << i;
  }
  EXPECT_EQ(codec.checks(), 0);
}

}  // namespace
}  // namespace clogscope::vision
