#include "vision/io/image_header.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "common/atomic_file.h"
#include "tests/scratch_dir.h"
#include "vision/io/image_codec.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;

// Every format the tool reads, as OpenCV writes it (TIFF: libtiff puts the directory after the
// pixels), 8- and 16-bit, grey and colour: the header gives the encoded size.
TEST(ImageHeaderTest, SizesOfEveryFormatTheToolReads) {
  const testutil::ScratchDir scratch("clogscope_image_header");
  const fs::path& dir = scratch.path();
  struct Case {
    const char* ext;
    int type;
    const char* format;
  };
  for (const Case& c :
       {Case{".png", CV_8UC1, "png"}, Case{".png", CV_16UC1, "png"}, Case{".png", CV_8UC3, "png"},
        Case{".jpg", CV_8UC1, "jpeg"}, Case{".jpg", CV_8UC3, "jpeg"}, Case{".tif", CV_8UC1, "tiff"},
        Case{".tif", CV_16UC1, "tiff"}, Case{".tif", CV_8UC3, "tiff"}, Case{".bmp", CV_8UC3, "bmp"},
        Case{".pgm", CV_8UC1, "pnm"}, Case{".ppm", CV_8UC3, "pnm"}}) {
    cv::Mat img(523, 1037, c.type);
    cv::randu(img, 0, 200);
    const std::string path = (dir / (std::string("i") + c.ext)).string();
    WriteImageAtomically(path, img);
    const ImageHeader h = ParseImageHeader(ReadFile(path));
    EXPECT_EQ(h.format, c.format) << c.ext;
    EXPECT_EQ(h.width_px, 1037) << c.ext << " " << c.type;
    EXPECT_EQ(h.height_px, 523) << c.ext << " " << c.type;
  }
}

TEST(ImageHeaderTest, OtherFormatsAndCutHeaders) {
  // A 32-byte WebP lossless bitstream that OpenCV would decode as 16384x12164 pixels.
  const std::string webp("/\xff\xff\xe0\x0b\x8c\x8c\x8c\x8c\x8c\x8c\x8c\x8c\x8c\x8c\x8c", 16);
  EXPECT_EQ(ParseImageHeader(webp).format, "");
  EXPECT_EQ(ParseImageHeader("").format, "");
  EXPECT_EQ(ParseImageHeader("#?RADIANCE\n").format, "");  // HDR: not a camera's format
  // Cut short: the format is known, the size is not.
  const ImageHeader png = ParseImageHeader(std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIH", 14));
  EXPECT_EQ(png.format, "png");
  EXPECT_EQ(png.width_px, 0);
  const ImageHeader jpeg = ParseImageHeader("\xff\xd8\xff\xe0\x00\x10JFIF");
  EXPECT_EQ(jpeg.format, "jpeg");
  EXPECT_EQ(jpeg.width_px, 0);
  const ImageHeader tiff = ParseImageHeader(std::string("II*\0\xff\xff\xff\x7f", 8));
  EXPECT_EQ(tiff.format, "tiff");
  EXPECT_EQ(tiff.width_px, 0);
  const ImageHeader pgm = ParseImageHeader("P5\n# a comment\n 640  480\n255\n");
  EXPECT_EQ(pgm.width_px, 640);
  EXPECT_EQ(pgm.height_px, 480);
  EXPECT_EQ(ParseImageHeader("P5\n# no size").width_px, 0);
}

// A JPEG as libjpeg writes it ends with its end-of-image marker, padding after it allowed; cut
// short (even by the marker alone) it does not.
TEST(ImageHeaderTest, AJpegCutShortHasNoEnd) {
  cv::Mat img(120, 160, CV_8UC1);
  cv::randu(img, 0, 200);
  const std::string jpeg = EncodeImage(".jpg", img);
  EXPECT_TRUE(JpegEndsWhole(jpeg));
  EXPECT_TRUE(JpegEndsWhole(jpeg + std::string(3, '\0')));
  EXPECT_TRUE(JpegEndsWhole(jpeg + "\r\n"));
  EXPECT_FALSE(JpegEndsWhole(jpeg.substr(0, jpeg.size() - 2)));
  EXPECT_FALSE(JpegEndsWhole(jpeg.substr(0, jpeg.size() / 2)));
  EXPECT_FALSE(JpegEndsWhole(""));
}

}  // namespace
}  // namespace clogscope::vision
