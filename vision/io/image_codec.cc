#include "vision/io/image_codec.h"

// setjmp.h after png.h: libpng checks that it is not included before it.
#include <png.h>
#include <setjmp.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

extern "C" {
#include <jpeglib.h>
// After jpeglib.h: the message codes (JWRN_EXTRANEOUS_DATA).
#include <jerror.h>
}

#include "common/ascii.h"
#include "vision/io/image_header.h"
#include "vision/io/libav_image.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

// A decoder's complaint as one short line.
std::string Shorten(std::string line) {
  while (!line.empty() && (line.back() == '\n' || line.back() == ' ')) line.pop_back();
  return line.size() > 120 ? line.substr(0, 117) + "..." : line;
}

// ---- PNG ----------------------------------------------------------------------------------------
// libpng reports an error by longjmp to the setjmp of the call that failed. The functions that
// call libpng with a setjmp hold no object with a destructor, so the jump skips none.

struct PngIo {
  std::string_view in;
  size_t pos = 0;
  std::string error;
  std::string out;  // when encoding
};

void PngError(png_structp png, png_const_charp message) {
  static_cast<PngIo*>(png_get_error_ptr(png))->error = message;
  png_longjmp(png, 1);
}
void PngWarning(png_structp, png_const_charp) {}  // warnings describe a picture decoded whole

void PngRead(png_structp png, png_bytep data, size_t n) {
  PngIo* io = static_cast<PngIo*>(png_get_io_ptr(png));
  if (n > io->in.size() - io->pos) png_error(png, "the file is cut short");
  std::memcpy(data, io->in.data() + io->pos, n);
  io->pos += n;
}

struct PngShape {
  png_uint_32 width = 0, height = 0;
  int channels = 0, depth = 0;
};

// Reads the header and sets the transforms that give OpenCV's layout: 16-bit in the machine's
// order, palettes and transparency expanded, grey with alpha as BGRA, colour as BGR(A).
bool PngHeader(png_structp png, png_infop info, PngShape* shape) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  const int color = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  const bool transparency = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  if (depth == 16) png_set_swap(png);
  if (color == PNG_COLOR_TYPE_PALETTE || depth < 8 || transparency) png_set_expand(png);
  if (color == PNG_COLOR_TYPE_GRAY_ALPHA || (color == PNG_COLOR_TYPE_GRAY && transparency))
    png_set_gray_to_rgb(png);
  png_set_bgr(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  shape->width = png_get_image_width(png, info);
  shape->height = png_get_image_height(png, info);
  shape->channels = png_get_channels(png, info);
  shape->depth = png_get_bit_depth(png, info);
  return true;
}

bool PngPixels(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, info);
  return true;
}

cv::Mat DecodePng(std::string_view bytes, std::string* error) {
  PngIo io;
  io.in = bytes;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, PngError, PngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw std::bad_alloc();
  }
  png_set_read_fn(png, &io, PngRead);
  cv::Mat img;
  PngShape s;
  bool ok = PngHeader(png, info, &s);
  if (ok && (!(s.channels == 1 || s.channels == 3 || s.channels == 4) ||
             !(s.depth == 8 || s.depth == 16))) {
    io.error = "unsupported layout";
    ok = false;
  }
  if (ok) {
    img.create(static_cast<int>(s.height), static_cast<int>(s.width),
               CV_MAKETYPE(s.depth == 16 ? CV_16U : CV_8U, s.channels));
    std::vector<png_bytep> rows(s.height);
    for (png_uint_32 y = 0; y < s.height; ++y) rows[y] = img.ptr(static_cast<int>(y));
    ok = PngPixels(png, info, rows.data());
  }
  png_destroy_read_struct(&png, &info, nullptr);
  if (ok) return img;
  *error = "cannot decode image (libpng: " + Shorten(io.error) + ")";
  return cv::Mat();
}

void PngWrite(png_structp png, png_bytep data, size_t n) {
  static_cast<PngIo*>(png_get_io_ptr(png))->out.append(reinterpret_cast<const char*>(data), n);
}
void PngFlush(png_structp) {}

bool PngWriteAll(png_structp png, png_infop info, const cv::Mat& img, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_write_fn(png, png_get_error_ptr(png), PngWrite, PngFlush);
  const int channels = img.channels();
  const int color = channels == 1   ? PNG_COLOR_TYPE_GRAY
                    : channels == 3 ? PNG_COLOR_TYPE_RGB
                                    : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, img.cols, img.rows, img.depth() == CV_16U ? 16 : 8, color,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // OpenCV's choice for speed: the Sub filter and zlib's fastest level with run-length matching.
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, 3 /* Z_RLE */);
  png_write_info(png, info);
  if (channels > 1) png_set_bgr(png);
  if (img.depth() == CV_16U) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

std::string EncodePng(const cv::Mat& img) {
  PngIo io;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, PngError, PngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::bad_alloc();
  }
  std::vector<png_bytep> rows(img.rows);
  for (int y = 0; y < img.rows; ++y) rows[y] = const_cast<png_bytep>(img.ptr(y));
  const bool ok = PngWriteAll(png, info, img, rows.data());
  png_destroy_write_struct(&png, &info);
  if (!ok) throw std::runtime_error("libpng: " + io.error);
  return std::move(io.out);
}

// ---- JPEG ---------------------------------------------------------------------------------------
// libjpeg's error_exit jumps back like libpng's; its warnings (data cut short or corrupt, where it
// paints the missing blocks grey) are counted, and the first kept as the reason.

struct JpegErrors {
  jpeg_error_mgr mgr;
  jmp_buf jump;
  char first_warning[JMSG_LENGTH_MAX] = {0};
  char error[JMSG_LENGTH_MAX] = {0};
};

void JpegErrorExit(j_common_ptr c) {
  JpegErrors* e = reinterpret_cast<JpegErrors*>(c->err);
  c->err->format_message(c, e->error);
  longjmp(e->jump, 1);
}

void JpegMessage(j_common_ptr c, int level) {
  if (level >= 0) return;  // trace messages
  JpegErrors* e = reinterpret_cast<JpegErrors*>(c->err);
  // Stray bytes before a marker (some cameras pad their frames) lose no picture data.
  if (c->err->msg_code == JWRN_EXTRANEOUS_DATA) return;
  if (c->err->num_warnings++ == 0) c->err->format_message(c, e->first_warning);
}

void JpegErrorsInit(JpegErrors* e) {
  jpeg_std_error(&e->mgr);
  e->mgr.error_exit = JpegErrorExit;
  e->mgr.emit_message = JpegMessage;
}

struct JpegShape {
  int width = 0, height = 0, channels = 0;
};

bool JpegHeader(jpeg_decompress_struct* d, JpegErrors* e, std::string_view bytes,
                JpegShape* shape) {
  if (setjmp(e->jump)) return false;
  jpeg_create_decompress(d);  // after the setjmp: it can fail (memory)
  jpeg_mem_src(d, reinterpret_cast<const unsigned char*>(bytes.data()),
               static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(d, TRUE);
  const bool grey = d->num_components == 1;
  d->out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(d);
  shape->width = static_cast<int>(d->output_width);
  shape->height = static_cast<int>(d->output_height);
  shape->channels = d->output_components;
  return true;
}

bool JpegPixels(jpeg_decompress_struct* d, JpegErrors* e, cv::Mat* img) {
  if (setjmp(e->jump)) return false;
  while (d->output_scanline < d->output_height) {
    JSAMPROW row = img->ptr(static_cast<int>(d->output_scanline));
    jpeg_read_scanlines(d, &row, 1);
  }
  jpeg_finish_decompress(d);
  return true;
}

cv::Mat DecodeJpeg(std::string_view bytes, std::string* error) {
  jpeg_decompress_struct d{};  // zeroed: destroying one never created does nothing
  JpegErrors e;
  d.err = &e.mgr;
  JpegErrorsInit(&e);
  JpegShape s;
  cv::Mat img;
  bool ok = JpegHeader(&d, &e, bytes, &s);
  if (ok) {
    img.create(s.height, s.width, CV_8UC(s.channels));
    ok = JpegPixels(&d, &e, &img);
  }
  jpeg_destroy_decompress(&d);
  // A warning first, failing or not: a file cut inside its tables warns of its end, then fails on
  // the marker libjpeg put there ("missing SOS marker").
  if (e.mgr.num_warnings > 0) {
    *error = "damaged image (" + Shorten(e.first_warning) + ")";
    return cv::Mat();
  }
  if (!ok) {
    *error = "cannot decode image (" + Shorten(e.error) + ")";
    return cv::Mat();
  }
  return img;
}

bool JpegWriteAll(jpeg_compress_struct* c, JpegErrors* e, const cv::Mat& img, int quality,
                  unsigned char** out, unsigned long* size) {
  if (setjmp(e->jump)) return false;
  jpeg_create_compress(c);  // after the setjmp: it can fail (memory)
  jpeg_mem_dest(c, out, size);
  c->image_width = static_cast<JDIMENSION>(img.cols);
  c->image_height = static_cast<JDIMENSION>(img.rows);
  c->input_components = img.channels();
  c->in_color_space = img.channels() == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_set_defaults(c);
  jpeg_set_quality(c, quality, TRUE);  // baseline tables, as OpenCV writes them
  jpeg_start_compress(c, TRUE);
  while (c->next_scanline < c->image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(img.ptr(static_cast<int>(c->next_scanline)));
    jpeg_write_scanlines(c, &row, 1);
  }
  jpeg_finish_compress(c);
  return true;
}

std::string EncodeJpeg(const cv::Mat& img, int quality) {
  jpeg_compress_struct c{};  // zeroed: destroying one never created does nothing
  JpegErrors e;
  c.err = &e.mgr;
  JpegErrorsInit(&e);
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const bool ok = JpegWriteAll(&c, &e, img, quality, &out, &size);
  jpeg_destroy_compress(&c);
  // On failure `out` may be a buffer libjpeg has already freed and replaced (it tells the new one
  // only when it finishes): left alone. Only running out of memory fails mid-way.
  if (!ok) throw std::runtime_error(std::string("libjpeg: ") + e.error);
  std::string bytes(reinterpret_cast<const char*>(out), size);
  std::free(out);
  return bytes;
}

}  // namespace

cv::Mat DecodeImage(std::string_view bytes, std::string* error) {
  const ImageHeader header = ParseImageHeader(bytes);
  const std::string& format = header.format;
  // A small file may claim a huge image: refused from its header before decoding.
  if (!format.empty()) {
    if (header.width_px <= 0 || header.height_px <= 0) {
      *error = "cannot decode image (its " + format + " header gives no size)";
      return cv::Mat();
    }
    if (!(*error = FrameSizeProblem(header.width_px, header.height_px)).empty()) return cv::Mat();
  }
  cv::Mat img;
  if (format == "png") {
    img = DecodePng(bytes, error);
  } else if (format == "jpeg") {
    img = DecodeJpeg(bytes, error);
  } else if (format == "tiff" || format == "bmp" || format == "pnm") {
    img = DecodeWithLibav(bytes, format, error);
  } else {
    *error = "not an image format the tool reads (PNG, JPEG, TIFF, BMP, PGM/PPM)";
  }
  // The picture decoded is the one its header describes, whose size was checked (a TIFF's
  // first directory may be a thumbnail whose sub-directory FFmpeg decodes instead).
  if (!img.empty() && header.width_px > 0 &&
      (img.cols != header.width_px || img.rows != header.height_px)) {
    *error = "cannot decode image (it holds a " + std::to_string(img.cols) + "x" +
             std::to_string(img.rows) + " picture where its header says " +
             std::to_string(header.width_px) + "x" + std::to_string(header.height_px) + ")";
    img.release();
  }
  return img;
}

std::string EncodeImage(const std::string& extension, const cv::Mat& image, int jpeg_quality) {
  const std::string ext = LowerAscii(extension);
  const int depth = image.depth(), channels = image.channels();
  const bool jpeg = ext == ".jpg" || ext == ".jpeg";
  const bool deep_ok = !(jpeg || ext == ".bmp");
  const bool alpha_ok = ext == ".png";
  if (image.empty() || !(depth == CV_8U || (depth == CV_16U && deep_ok)) ||
      !(channels == 1 || channels == 3 || (channels == 4 && alpha_ok)))
    throw std::invalid_argument(ext + ": cannot hold a " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " image of " +
                                std::to_string(channels) + " channels at " +
                                (depth == CV_16U  ? "16"
                                 : depth == CV_8U ? "8"
                                                  : "another") +
                                " bits");
  if (ext == ".png") return EncodePng(image);
  if (jpeg) {
    if (jpeg_quality < 1 || jpeg_quality > 100)
      throw std::invalid_argument("JPEG quality must be 1 to 100");
    return EncodeJpeg(image, jpeg_quality);
  }
  if (ext == ".tif" || ext == ".tiff") return EncodeWithLibav("tiff", image);
  if (ext == ".bmp") return EncodeWithLibav("bmp", image);
  if (ext == ".pgm" || ext == ".ppm") {
    if ((ext == ".pgm") != (channels == 1))
      throw std::invalid_argument(
          ext + ": " +
          (channels == 1 ? "PPM holds colour, not grey" : "PGM holds grey, not colour"));
    return EncodeWithLibav("pnm", image);
  }
  throw std::invalid_argument((ext.empty() ? "(no extension)" : ext) +
                              ": not an image format the tool writes (PNG, JPEG, TIFF, BMP, "
                              "PGM/PPM)");
}

}  // namespace clogscope::vision
