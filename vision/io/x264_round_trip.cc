#include "vision/io/x264_round_trip.h"

#include <fmt/format.h>

#include <cstring>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "vision/io/av_error.h"
#include "vision/io/av_handles.h"

extern "C" {
#include <libavcodec/avcodec.h>
}

namespace clogscope::vision {
namespace {

constexpr double kX264DefaultCrf = 23.0;
// The image is coded as the key frame of a steady run this long. Coded alone, x264 gives a key
// frame the quantiser of a lone picture; in a stream of a steady scene its macroblock tree gives
// it a finer one (the frames after it copy it). On a rendered strand that one x264 stream had
// left within 0.01 px, a lone key frame moved the width by 0.07–0.30 px; the first of 8 by
// −0.03 to +0.06 px.
constexpr int kSteadyRunFrames = 8;
constexpr int kNeutralChroma = 128;

[[noreturn]] void Fail(const char* what, int err) {
  throw std::runtime_error(fmt::format("x264 round trip: {}: {}", what, AvError(err)));
}

AvCodecContextPtr OpenEncoder(const X264Settings& s, int width, int height) {
  const AVCodec* codec = avcodec_find_encoder_by_name("libx264");
  if (!codec) throw std::runtime_error("x264 round trip: FFmpeg has no libx264 encoder");
  AvCodecContextPtr c(avcodec_alloc_context3(codec));
  c->width = width;
  c->height = height;
  c->pix_fmt = AV_PIX_FMT_YUV420P;
  c->time_base = {1, 25};
  c->thread_count = 1;  // one frame: threads would only change the output from run to run
  AVDictionary* opts = nullptr;
  av_dict_set(&opts, "crf", fmt::format("{}", s.crf >= 0 ? s.crf : kX264DefaultCrf).c_str(), 0);
  if (s.aq_mode >= 0) av_dict_set(&opts, "aq-mode", fmt::format("{}", s.aq_mode).c_str(), 0);
  if (s.aq_strength >= 0)
    av_dict_set(&opts, "aq-strength", fmt::format("{}", s.aq_strength).c_str(), 0);
  const int err = avcodec_open2(c.get(), codec, &opts);
  av_dict_free(&opts);
  if (err < 0) Fail("opening libx264", err);
  return c;
}

AvCodecContextPtr OpenDecoder() {
  const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
  if (!codec) throw std::runtime_error("x264 round trip: FFmpeg has no H.264 decoder");
  AvCodecContextPtr c(avcodec_alloc_context3(codec));
  c->thread_count = 1;
  if (const int err = avcodec_open2(c.get(), codec, nullptr); err < 0)
    Fail("opening the H.264 decoder", err);
  return c;
}

// Copies rows of `plane` (w×h bytes) into or out of a frame's plane of the given line size.
void CopyPlane(const uint8_t* src, int src_step, uint8_t* dst, int dst_step, int w, int h) {
  for (int y = 0; y < h; ++y) std::memcpy(dst + y * dst_step, src + y * src_step, w);
}

}  // namespace

bool X264RoundTrip::Available() {
  return avcodec_find_encoder_by_name("libx264") && avcodec_find_decoder(AV_CODEC_ID_H264);
}

X264RoundTrip::X264RoundTrip(const X264Settings& settings) : settings_(settings) { QuietFfmpeg(); }

cv::Mat X264RoundTrip::Apply(const cv::Mat& image) {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3) ||
      image.cols % 2 != 0 || image.rows % 2 != 0 || image.empty())
    throw std::invalid_argument(
        fmt::format("x264 round trip: needs an 8-bit grey or BGR image of even size, not {}x{}, "
                    "{} channels, depth {}",
                    image.cols, image.rows, image.channels(), image.depth()));
  const int w = image.cols, h = image.rows;
  // 4:2:0 planes one after another (OpenCV's I420 layout: Y, then U, then V).
  cv::Mat yuv;
  if (image.channels() == 3) {
    cv::cvtColor(image, yuv, cv::COLOR_BGR2YUV_I420);
  } else {
    yuv.create(h * 3 / 2, w, CV_8U);
    image.copyTo(yuv.rowRange(0, h));
    yuv.rowRange(h, yuv.rows).setTo(kNeutralChroma);
  }
  const uint8_t* planes[3] = {yuv.ptr(), yuv.ptr(h), yuv.ptr(h) + (w / 2) * (h / 2)};

  AvCodecContextPtr enc = OpenEncoder(settings_, w, h);
  AvFramePtr in(av_frame_alloc());
  in->format = AV_PIX_FMT_YUV420P;
  in->width = w;
  in->height = h;
  if (const int err = av_frame_get_buffer(in.get(), 0); err < 0) Fail("a frame buffer", err);
  for (int p = 0; p < 3; ++p)
    CopyPlane(planes[p], p == 0 ? w : w / 2, in->data[p], in->linesize[p], p == 0 ? w : w / 2,
              p == 0 ? h : h / 2);
  // The image as a steady scene's run of frames (each a reference to the same pixels), then the
  // end of the stream.
  std::vector<AvFramePtr> run;
  std::vector<AVFrame*> sends;
  for (int i = 0; i < kSteadyRunFrames; ++i) {
    run.emplace_back(av_frame_clone(in.get()));
    if (!run.back()) Fail("a frame reference", AVERROR(ENOMEM));
    run.back()->pts = i;
    sends.push_back(run.back().get());
  }
  sends.push_back(nullptr);

  AvCodecContextPtr dec = OpenDecoder();
  AvFramePtr out(av_frame_alloc()), later(av_frame_alloc());
  AvPacketPtr packet(av_packet_alloc());
  bool decoded = false;
  // The run's first frame is kept; the decoder gives back the others too, and must.
  auto drain_decoder = [&] {
    for (;;) {
      const int err = avcodec_receive_frame(dec.get(), decoded ? later.get() : out.get());
      if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return;
      if (err < 0) Fail("decoding", err);
      decoded = true;
    }
  };
  for (AVFrame* send : sends) {
    if (const int err = avcodec_send_frame(enc.get(), send); err < 0) Fail("encoding", err);
    for (;;) {
      const int err = avcodec_receive_packet(enc.get(), packet.get());
      if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) break;
      if (err < 0) Fail("encoding", err);
      const int sent = avcodec_send_packet(dec.get(), packet.get());
      av_packet_unref(packet.get());
      if (sent < 0) Fail("decoding", sent);
      drain_decoder();
    }
  }
  if (const int err = avcodec_send_packet(dec.get(), nullptr); err < 0) Fail("decoding", err);
  drain_decoder();
  if (!decoded || out->width != w || out->height != h || out->format != AV_PIX_FMT_YUV420P)
    throw std::runtime_error("x264 round trip: the decoder gave back no frame of the same form");

  cv::Mat back(h * 3 / 2, w, CV_8U);
  uint8_t* dst[3] = {back.ptr(), back.ptr(h), back.ptr(h) + (w / 2) * (h / 2)};
  for (int p = 0; p < 3; ++p)
    CopyPlane(out->data[p], out->linesize[p], dst[p], p == 0 ? w : w / 2, p == 0 ? w : w / 2,
              p == 0 ? h : h / 2);
  if (image.channels() == 1) return back.rowRange(0, h).clone();
  cv::Mat bgr;
  cv::cvtColor(back, bgr, cv::COLOR_YUV2BGR_I420);
  return bgr;
}

}  // namespace clogscope::vision
