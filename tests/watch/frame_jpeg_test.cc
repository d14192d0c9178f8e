#include "watch/frame_jpeg.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "vision/io/image_codec.h"

namespace clogscope::watch {
namespace {

WatchSnapshot Frame(long long sequence, unsigned char grey) {
  WatchSnapshot s;
  s.frame = cv::Mat(48, 64, CV_8UC1, cv::Scalar(grey));
  s.sequence = sequence;
  return s;
}

// Drawn once per published frame, however many readers ask; a new frame is drawn anew, a state
// published without one keeps the picture.
TEST(OverlayJpegCacheTest, DrawsEachPublishedFrameOnce) {
  WatchBoard board;
  OverlayJpegCache cache(&board, std::nullopt);
  EXPECT_EQ(cache.Latest(), nullptr);  // no frame yet
  board.Publish(Frame(1, 40));
  const auto first = cache.Latest();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(cache.Latest(), first);  // the same bytes, not drawn again
  board.PublishState(board.Read().status, std::nullopt, {});
  EXPECT_EQ(cache.Latest(), first);
  board.Publish(Frame(2, 200));
  const auto second = cache.Latest();
  ASSERT_NE(second, nullptr);
  EXPECT_NE(second, first);
  // And it is the new frame's picture: its grey level, decoded (the median: the overlay writes
  // its reason over part of it).
  std::string why;
  cv::Mat decoded = vision::DecodeImage(
      std::string_view(reinterpret_cast<const char*>(second->data()), second->size()), &why);
  ASSERT_FALSE(decoded.empty()) << why;
  if (decoded.channels() == 3) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2GRAY);
  std::vector<unsigned char> levels(decoded.begin<unsigned char>(), decoded.end<unsigned char>());
  std::nth_element(levels.begin(), levels.begin() + levels.size() / 2, levels.end());
  EXPECT_NEAR(levels[levels.size() / 2], 200, 2);
}

}  // namespace
}  // namespace clogscope::watch
