#include "vision/io/libav_image.h"

#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "vision/io/av_error.h"
#include "vision/io/av_handles.h"
#include "vision/io/video_io.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/imgutils.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

namespace clogscope::vision {
namespace {

// The Mat layouts as FFmpeg pixel formats (16-bit in the machine's order: little-endian on amd64
// and arm64).
AVPixelFormat MatFormat(bool colour, bool deep) {
  if (colour) return deep ? AV_PIX_FMT_BGR48LE : AV_PIX_FMT_BGR24;
  return deep ? AV_PIX_FMT_GRAY16LE : AV_PIX_FMT_GRAY8;
}

// Pixels from one format to another of the same size: a reordering or an expansion of a palette
// or of packed bits, done exactly (no scaling, no dither); rows copied when the formats are one
// (8-bit grey TIFF and PGM, 24-bit BMP), with no converter set up for them. `to` is one plane.
bool ConvertPixels(const uint8_t* const src[4], const int src_stride[4], AVPixelFormat from,
                   uint8_t* const dst[4], const int dst_stride[4], AVPixelFormat to, int width,
                   int height) {
  if (from == to) {
    av_image_copy_plane(dst[0], dst_stride[0], src[0], src_stride[0],
                        av_image_get_linesize(to, width, 0), height);
    return true;
  }
  const SwsContextPtr sws(sws_getContext(width, height, from, width, height, to,
                                         SWS_POINT | SWS_ACCURATE_RND | SWS_BITEXACT, nullptr,
                                         nullptr, nullptr));
  if (!sws) return false;
  sws_scale(sws.get(), src, src_stride, 0, height, dst, dst_stride);
  return true;
}

// FFmpeg's palettes are 256 entries of 0xAARRGGBB.
bool GreyPalette(const uint8_t* data) {
  const uint32_t* palette = reinterpret_cast<const uint32_t*>(data);
  for (int i = 0; i < 256; ++i) {
    const uint32_t c = palette[i];
    if (((c >> 16) & 0xFF) != (c & 0xFF) || ((c >> 8) & 0xFF) != (c & 0xFF)) return false;
  }
  return true;
}

AVCodecID DecoderFor(std::string_view bytes, const std::string& format) {
  if (format == "tiff") return AV_CODEC_ID_TIFF;
  if (format == "bmp") return AV_CODEC_ID_BMP;
  // PNM: P1/P4 bitmaps, P2/P5 grey, P3/P6 colour.
  const char kind = bytes.size() > 1 ? bytes[1] : '0';
  if (kind == '1' || kind == '4') return AV_CODEC_ID_PBM;
  if (kind == '2' || kind == '5') return AV_CODEC_ID_PGM;
  return AV_CODEC_ID_PPM;
}

}  // namespace

cv::Mat DecodeWithLibav(std::string_view bytes, const std::string& format, std::string* error) {
  const AVCodec* codec = avcodec_find_decoder(DecoderFor(bytes, format));
  AvCodecContextPtr ctx(codec ? avcodec_alloc_context3(codec) : nullptr);
  if (!ctx) {
    *error = "cannot decode image (no " + format + " decoder)";
    return cv::Mat();
  }
  // Not AV_EF_EXPLODE: the TIFF decoder then refuses files for tags it does not know (a
  // ResolutionUnit). A frame it reports damaged is refused below.
  ctx->thread_count = 1;
  // The largest frame measured: what a file decodes to may be larger than its header said.
  ctx->max_pixels = kMaxFramePixels;
  QuietFfmpeg();
  AvPacketPtr packet(av_packet_alloc());
  AvFramePtr frame(av_frame_alloc());
  int rc = avcodec_open2(ctx.get(), codec, nullptr);
  if (rc >= 0) rc = av_new_packet(packet.get(), static_cast<int>(bytes.size()));
  if (rc >= 0) {
    std::memcpy(packet->data, bytes.data(), bytes.size());
    rc = avcodec_send_packet(ctx.get(), packet.get());
  }
  if (rc >= 0) rc = avcodec_send_packet(ctx.get(), nullptr);
  if (rc >= 0) rc = avcodec_receive_frame(ctx.get(), frame.get());
  if (rc < 0) {
    *error = "cannot decode image (" + AvError(rc) + ")";
    return cv::Mat();
  }
  if (frame->decode_error_flags != 0 || (frame->flags & AV_FRAME_FLAG_CORRUPT)) {
    *error = "damaged image (the decoder filled in what it could not read)";
    return cv::Mat();
  }
  const AVPixelFormat from = static_cast<AVPixelFormat>(frame->format);
  const AVPixFmtDescriptor* d = av_pix_fmt_desc_get(from);
  if (!d) {
    *error = "cannot decode image (unknown pixel format)";
    return cv::Mat();
  }
  // A palette of greys (an 8-bit grey BMP) is grey, as OpenCV read it.
  const bool grey_palette = from == AV_PIX_FMT_PAL8 && GreyPalette(frame->data[1]);
  const bool colour = !grey_palette && (d->nb_components >= 3 || (d->flags & AV_PIX_FMT_FLAG_PAL));
  const bool deep = !(d->flags & AV_PIX_FMT_FLAG_PAL) && d->comp[0].depth > 8;
  if (d->comp[0].depth > 16 || (d->flags & AV_PIX_FMT_FLAG_FLOAT)) {
    *error = "unsupported pixel type (need 8- or 16-bit integer)";
    return cv::Mat();
  }
  cv::Mat img(frame->height, frame->width, CV_MAKETYPE(deep ? CV_16U : CV_8U, colour ? 3 : 1));
  if (grey_palette) {
    const uint32_t* palette = reinterpret_cast<const uint32_t*>(frame->data[1]);
    for (int y = 0; y < img.rows; ++y) {
      const uint8_t* in = frame->data[0] + static_cast<ptrdiff_t>(y) * frame->linesize[0];
      uint8_t* out = img.ptr(y);
      for (int x = 0; x < img.cols; ++x) out[x] = static_cast<uint8_t>(palette[in[x]] & 0xFF);
    }
    return img;
  }
  uint8_t* dst[4] = {img.data, nullptr, nullptr, nullptr};
  const int dst_stride[4] = {static_cast<int>(img.step[0]), 0, 0, 0};
  if (!ConvertPixels(frame->data, frame->linesize, from, dst, dst_stride, MatFormat(colour, deep),
                     frame->width, frame->height)) {
    *error = std::string("cannot decode image (pixel format ") + d->name + " not converted)";
    return cv::Mat();
  }
  return img;
}

std::string EncodeWithLibav(const std::string& format, const cv::Mat& image) {
  const bool colour = image.channels() == 3, deep = image.depth() == CV_16U;
  const char* name = format == "tiff" ? "tiff" : format == "bmp" ? "bmp" : colour ? "ppm" : "pgm";
  AVPixelFormat to;
  if (format == "tiff")
    to = colour ? (deep ? AV_PIX_FMT_RGB48LE : AV_PIX_FMT_RGB24)
                : (deep ? AV_PIX_FMT_GRAY16LE : AV_PIX_FMT_GRAY8);
  else if (format == "bmp")
    to = colour ? AV_PIX_FMT_BGR24 : AV_PIX_FMT_GRAY8;
  else
    to = colour ? (deep ? AV_PIX_FMT_RGB48BE : AV_PIX_FMT_RGB24)
                : (deep ? AV_PIX_FMT_GRAY16BE : AV_PIX_FMT_GRAY8);
  const AVCodec* codec = avcodec_find_encoder_by_name(name);
  AvCodecContextPtr ctx(codec ? avcodec_alloc_context3(codec) : nullptr);
  if (!ctx) throw std::runtime_error(std::string("no ") + name + " encoder");
  ctx->width = image.cols;
  ctx->height = image.rows;
  ctx->pix_fmt = to;
  ctx->time_base = AVRational{1, 1};
  QuietFfmpeg();
  AvFramePtr frame(av_frame_alloc());
  AvPacketPtr packet(av_packet_alloc());
  frame->format = to;
  frame->width = image.cols;
  frame->height = image.rows;
  int rc = avcodec_open2(ctx.get(), codec, nullptr);
  if (rc >= 0) rc = av_frame_get_buffer(frame.get(), 0);
  if (rc >= 0) {
    const uint8_t* src[4] = {image.data, nullptr, nullptr, nullptr};
    const int src_stride[4] = {static_cast<int>(image.step[0]), 0, 0, 0};
    if (!ConvertPixels(src, src_stride, MatFormat(colour, deep), frame->data, frame->linesize, to,
                       image.cols, image.rows))
      rc = AVERROR(EINVAL);
  }
  if (rc >= 0) rc = avcodec_send_frame(ctx.get(), frame.get());
  if (rc >= 0) rc = avcodec_send_frame(ctx.get(), nullptr);
  std::string out;
  while (rc >= 0) {
    rc = avcodec_receive_packet(ctx.get(), packet.get());
    if (rc >= 0) {
      out.append(reinterpret_cast<const char*>(packet->data), static_cast<size_t>(packet->size));
      av_packet_unref(packet.get());
    }
  }
  if (rc != AVERROR_EOF) throw std::runtime_error(std::string(name) + " encoder: " + AvError(rc));
  return out;
}

}  // namespace clogscope::vision
