#include "vision/io/image_codec.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <string>

#include "vision/io/image_header.h"

namespace clogscope::vision {
namespace {

cv::Mat RandomImage(int type, uint64_t seed) {
  cv::Mat img(47, 61, type);  // odd sizes: rows padded in BMP, 4:2:0 blocks cut in JPEG
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  return img;
}

std::string TypeName(int type) {
  return std::to_string(CV_MAT_DEPTH(type) == CV_16U ? 16 : 8) + "-bit x" +
         std::to_string(CV_MAT_CN(type));
}

// Lossless formats give back every pixel, in the layout stored (1 channel grey, 3 BGR, 4 BGRA),
// 16-bit where the format holds it.
TEST(ImageCodecTest, LosslessFormatsGiveBackEveryPixel) {
  struct Case {
    const char* ext;
    int type;
  };
  for (const Case& c : {Case{".png", CV_8UC1}, Case{".png", CV_16UC1}, Case{".png", CV_8UC3},
                        Case{".png", CV_16UC3}, Case{".png", CV_8UC4}, Case{".tif", CV_8UC1},
                        Case{".tif", CV_16UC1}, Case{".tif", CV_8UC3}, Case{".tif", CV_16UC3},
                        Case{".bmp", CV_8UC1}, Case{".bmp", CV_8UC3}, Case{".pgm", CV_8UC1},
                        Case{".pgm", CV_16UC1}, Case{".ppm", CV_8UC3}, Case{".ppm", CV_16UC3}}) {
    const cv::Mat img = RandomImage(c.type, static_cast<uint64_t>(c.type) * 7 + c.ext[1]);
    const std::string bytes = EncodeImage(c.ext, img);
    const ImageHeader h = ParseImageHeader(bytes);
    EXPECT_EQ(h.width_px, 61) << c.ext;
    std::string why;
    const cv::Mat back = DecodeImage(bytes, &why);
    ASSERT_FALSE(back.empty()) << c.ext << " " << TypeName(c.type) << ": " << why;
    ASSERT_EQ(back.type(), img.type()) << c.ext << " " << TypeName(c.type);
    EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0) << c.ext << " " << TypeName(c.type);
  }
}

// JPEG keeps grey as grey and colour as BGR (a channel swap would move the means apart), within
// what its quantisation loses on smooth content at the quality asked.
TEST(ImageCodecTest, JpegKeepsLayoutAndColourOrderWithinItsLoss) {
  cv::Mat grey(96, 128, CV_8UC1), colour(96, 128, CV_8UC3);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) {
      grey.at<uchar>(y, x) = static_cast<uchar>(40 + x + y / 2);
      colour.at<cv::Vec3b>(y, x) = cv::Vec3b(30, static_cast<uchar>(60 + x), 220);
    }
  for (const cv::Mat& img : {grey, colour}) {
    for (int quality : {50, 95}) {
      std::string why;
      const cv::Mat back = DecodeImage(EncodeImage(".jpg", img, quality), &why);
      ASSERT_EQ(back.type(), img.type()) << why;
      cv::Mat diff;
      cv::absdiff(back, img, diff);
      const cv::Scalar mean = cv::mean(diff);
      for (int k = 0; k < img.channels(); ++k)
        EXPECT_LT(mean[k], quality == 95 ? 1.0 : 3.0) << "channel " << k << " q" << quality;
    }
  }
  // A lower quality is a smaller file: the quality reaches libjpeg.
  EXPECT_LT(EncodeImage(".jpg", RandomImage(CV_8UC1, 3), 30).size(),
            EncodeImage(".jpg", RandomImage(CV_8UC1, 3), 90).size());
}

// A damaged file is refused with the decoder's reason, never returned with pixels filled in.
TEST(ImageCodecTest, DamagedFilesAreRefusedWithTheDecodersReason) {
  const cv::Mat img = RandomImage(CV_8UC1, 5);
  std::string png = EncodeImage(".png", img);
  png[png.find("IDAT") + 40] ^= 0x5a;  // inside the compressed data: its CRC no longer matches
  std::string why;
  EXPECT_TRUE(DecodeImage(png, &why).empty());
  EXPECT_EQ(why.rfind("cannot decode image (libpng: IDAT: ", 0), 0u) << why;

  const std::string jpeg = EncodeImage(".jpg", img);
  EXPECT_TRUE(DecodeImage(std::string_view(jpeg).substr(0, jpeg.size() * 6 / 10), &why).empty());
  EXPECT_EQ(why, "damaged image (Premature end of JPEG file)");

  for (const char* ext : {".png", ".tif", ".bmp", ".pgm"}) {
    const std::string whole = EncodeImage(ext, img);
    why.clear();
    EXPECT_TRUE(DecodeImage(std::string_view(whole).substr(0, whole.size() * 6 / 10), &why).empty())
        << ext;
    EXPECT_EQ(why.rfind("cannot decode image (", 0), 0u) << ext << ": " << why;
  }
  EXPECT_TRUE(DecodeImage("GIF89a and so on", &why).empty());
  EXPECT_EQ(why, "not an image format the tool reads (PNG, JPEG, TIFF, BMP, PGM/PPM)");
}

// A JPEG cut anywhere after its frame header is damaged, whatever libjpeg then trips on: cut
// inside its tables, it warns of the end and fails on the end marker it put there.
TEST(ImageCodecTest, AJpegCutAnywhereAfterItsFrameHeaderIsDamaged) {
  const std::string jpeg = EncodeImage(".jpg", RandomImage(CV_8UC3, 9), 90);
  const size_t sof = jpeg.find("\xFF\xC0");
  ASSERT_NE(sof, std::string::npos);
  int cuts = 0;
  for (size_t cut = sof + 20; cut + 2 < jpeg.size(); cut += 7, ++cuts) {
    std::string why;
    EXPECT_TRUE(DecodeImage(std::string_view(jpeg).substr(0, cut), &why).empty()) << cut;
    EXPECT_EQ(why.rfind("damaged image (", 0), 0u) << "cut at " << cut << ": " << why;
  }
  EXPECT_GT(cuts, 100);
}

// A TIFF's first directory describes what callers check (ParseImageHeader); one that is a
// thumbnail pointing to a larger sub-directory, which FFmpeg decodes instead, is refused.
TEST(ImageCodecTest, ATiffThatDecodesToAnotherSizeThanItsHeaderIsRefused) {
  const auto u16 = [](std::string* b, unsigned v) {
    b->push_back(static_cast<char>(v & 0xFF));
    b->push_back(static_cast<char>(v >> 8));
  };
  const auto u32 = [&](std::string* b, unsigned v) {
    u16(b, v & 0xFFFF);
    u16(b, v >> 16);
  };
  // Little-endian: header, directory 0 (8x8 thumbnail, SubIFDs -> directory 1), directory 1
  // (64x48), the two uncompressed 8-bit grey strips.
  const unsigned kW = 64, kH = 48, n0 = 11, n1 = 9;
  const unsigned ifd0 = 8, ifd1 = ifd0 + 2 + 12 * n0 + 4, small = ifd1 + 2 + 12 * n1 + 4;
  const unsigned big = small + 64;
  struct Entry {
    unsigned tag, type, value;
  };
  const auto directory = [&](std::string* b, const std::vector<Entry>& entries) {
    u16(b, static_cast<unsigned>(entries.size()));
    for (const Entry& e : entries) {
      u16(b, e.tag);
      u16(b, e.type);
      u32(b, 1);
      if (e.type == 3) {
        u16(b, e.value);
        u16(b, 0);
      } else {
        u32(b, e.value);
      }
    }
    u32(b, 0);
  };
  std::string tiff = "II*";
  tiff.push_back('\0');
  u32(&tiff, ifd0);
  directory(&tiff, {{254, 4, 1},
                    {256, 3, 8},
                    {257, 3, 8},
                    {258, 3, 8},
                    {259, 3, 1},
                    {262, 3, 1},
                    {273, 4, small},
                    {277, 3, 1},
                    {278, 3, 8},
                    {279, 4, 64},
                    {330, 4, ifd1}});
  directory(&tiff, {{256, 4, kW},
                    {257, 4, kH},
                    {258, 3, 8},
                    {259, 3, 1},
                    {262, 3, 1},
                    {273, 4, big},
                    {277, 3, 1},
                    {278, 4, kH},
                    {279, 4, kW * kH}});
  ASSERT_EQ(tiff.size(), small);
  tiff += std::string(64, '\x40') + std::string(kW * kH, '\x80');
  ASSERT_EQ(ParseImageHeader(tiff).width_px, 8);
  std::string why;
  const cv::Mat img = DecodeImage(tiff, &why);
  EXPECT_TRUE(img.empty()) << img.cols << "x" << img.rows;
  EXPECT_NE(why.find("where its header says 8x8"), std::string::npos) << why;
}

// What a format cannot hold is refused with the extension named, not written some other way.
TEST(ImageCodecTest, AFormatThatCannotHoldTheImageIsNamed) {
  const auto refusal = [](const char* ext, int type) {
    try {
      EncodeImage(ext, RandomImage(type, 1));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("written");
  };
  EXPECT_EQ(refusal(".jpg", CV_16UC1).rfind(".jpg: cannot hold", 0), 0u);
  EXPECT_EQ(refusal(".BMP", CV_16UC3).rfind(".bmp: cannot hold", 0), 0u);
  EXPECT_EQ(refusal(".tif", CV_8UC4).rfind(".tif: cannot hold", 0), 0u);
  EXPECT_EQ(refusal(".ppm", CV_8UC1), ".ppm: PPM holds colour, not grey");
  EXPECT_EQ(refusal(".gif", CV_8UC1).rfind(".gif: not an image format the tool writes", 0), 0u);
}

}  // namespace
}  // namespace clogscope::vision
