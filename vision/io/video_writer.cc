#include "vision/io/video_writer.h"

#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/io/av_error.h"
#include "vision/io/av_handles.h"

extern "C" {
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

namespace clogscope::vision {

// Motion JPEG's smallest quantiser, as OpenCV's writer (which this replaced) set it.
constexpr int kMjpegMinQuantiser = 3;
constexpr const char* kX264Crf = "23";

// The frame rate as a rational of a power of ten within 0.001 (25/1, 2997/100), as OpenCV's
// writer had it: Motion JPEG's rate control spends bits per tick of it.
AVRational FrameRate(double fps) {
  int rate = static_cast<int>(fps + 0.5), base = 1;
  while (std::fabs(static_cast<double>(rate) / base - fps) > 0.001 && base < 1000000) {
    base *= 10;
    rate = static_cast<int>(fps * base + 0.5);
  }
  return AVRational{rate, base};
}

struct VideoFileWriter::Impl {
  AVFormatContext* format = nullptr;
  AvCodecContextPtr codec;
  AVStream* stream = nullptr;
  AvFramePtr frame{av_frame_alloc()};
  AvPacketPtr packet{av_packet_alloc()};
  SwsContextPtr sws;
  cv::Mat bgr;  // a grey frame as BGR, reused from frame to frame
  int64_t next_pts = 0;

  ~Impl() {
    if (format) {
      if (format->pb) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }

  // Sends a frame (nullptr: the end) and writes every packet the encoder has ready.
  int Encode(const AVFrame* f) {
    int rc = avcodec_send_frame(codec.get(), f);
    while (rc >= 0) {
      rc = avcodec_receive_packet(codec.get(), packet.get());
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return 0;
      if (rc < 0) break;
      av_packet_rescale_ts(packet.get(), codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      rc = av_interleaved_write_frame(format, packet.get());
    }
    return rc;
  }
};

VideoFileWriter::VideoFileWriter(const std::string& path, VideoKind kind, double fps, cv::Size size)
    : impl_(std::make_unique<Impl>()), path_(path) {
  // The temporary name keeps the extension: the container is chosen from it.
  std::filesystem::path p(path);
  temp_path_ =
      (p.parent_path() / (p.stem().string() + ".partial" + p.extension().string())).string();
  if (!(fps > 0)) throw std::invalid_argument(path + ": frame rate must be positive");
  if (kind == VideoKind::kNone)
    throw std::invalid_argument(path + ": not a video file type the tool writes (.avi, .mp4)");
  if (size.width <= 0 || size.height <= 0 || size.width % 2 || size.height % 2)
    throw std::invalid_argument(path + ": video frames need an even width and height");
  // The encoder cannot tell a missing folder from a codec it lacks: look first.
  const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw std::invalid_argument(path + ": folder " + dir.string() + " does not exist");
  if (access(dir.c_str(), W_OK) != 0)
    throw std::invalid_argument(path + ": folder " + dir.string() + " is not writable");

  QuietFfmpeg();
  Impl& d = *impl_;
  const bool mjpeg = kind == VideoKind::kMjpegAvi;
  const AVCodec* codec = avcodec_find_encoder_by_name(mjpeg ? "mjpeg" : "libx264");
  // The container from the extension, as for any FFmpeg output: AVI, MP4, MOV, Matroska.
  // No destructor runs for a constructor that throws: the temporary file goes here.
  const auto cannot_open = [&](int rc) {
    std::remove(temp_path_.c_str());
    throw std::invalid_argument(path + ": cannot open a video encoder for this file type (" +
                                AvError(rc) + ")");
  };
  int rc = codec ? avformat_alloc_output_context2(&d.format, nullptr, nullptr, temp_path_.c_str())
                 : AVERROR_ENCODER_NOT_FOUND;
  if (rc >= 0) {
    d.codec.reset(avcodec_alloc_context3(codec));
    d.stream = avformat_new_stream(d.format, nullptr);
    if (!d.codec || !d.stream) rc = AVERROR(ENOMEM);
  }
  if (rc < 0) cannot_open(rc);
  AVCodecContext* c = d.codec.get();
  c->width = size.width;
  c->height = size.height;
  c->framerate = FrameRate(fps);
  c->time_base = av_inv_q(c->framerate);
  c->pix_fmt = mjpeg ? AV_PIX_FMT_YUVJ420P : AV_PIX_FMT_YUV420P;
  c->color_range = mjpeg ? AVCOL_RANGE_JPEG : AVCOL_RANGE_MPEG;
  if (d.format->oformat->flags & AVFMT_GLOBALHEADER) c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  AVDictionary* opts = nullptr;
  if (mjpeg) {
    // OpenCV's settings: a rate of 3 bits a pixel (twice over, as it added half of it twice) and
    // a quantiser of at least 3.
    const double rate = std::min(3.0 * fps * size.width * size.height, INT_MAX / 2.0);
    const int64_t asked = static_cast<int>(rate + 0.5);
    c->bit_rate = std::min<int64_t>(asked + asked / 2 + static_cast<int64_t>(rate / 2), INT_MAX);
    c->bit_rate_tolerance = static_cast<int>(c->bit_rate);
    c->qmin = kMjpegMinQuantiser;
    c->gop_size = 12;
  } else {
    av_dict_set(&opts, "crf", kX264Crf, 0);
  }
  rc = avcodec_open2(c, codec, &opts);
  av_dict_free(&opts);
  if (rc >= 0) rc = avcodec_parameters_from_context(d.stream->codecpar, c);
  if (rc >= 0) {
    d.stream->time_base = c->time_base;
    d.stream->avg_frame_rate = c->framerate;
    rc = avio_open(&d.format->pb, temp_path_.c_str(), AVIO_FLAG_WRITE);
  }
  if (rc >= 0) rc = avformat_write_header(d.format, nullptr);
  if (rc < 0) cannot_open(rc);
  d.frame->format = c->pix_fmt;
  d.frame->width = c->width;
  d.frame->height = c->height;
  if (av_frame_get_buffer(d.frame.get(), 0) < 0) {
    std::remove(temp_path_.c_str());
    throw std::bad_alloc();
  }
}

VideoFileWriter::~VideoFileWriter() {
  if (!committed_) {
    impl_.reset();
    std::remove(temp_path_.c_str());
  }
}

void VideoFileWriter::Write(const cv::Mat& frame) {
  Impl& d = *impl_;
  if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3) ||
      frame.cols != d.codec->width || frame.rows != d.codec->height)
    throw std::invalid_argument(path_ + ": a frame must be 8-bit grey or BGR of the video's size");
  // Grey goes in as BGR and BGR through swscale's bicubic conversion, as OpenCV's writer did:
  // the same pictures reach the encoder, so the videos the tests and benchmarks render are the
  // ones they were tuned on (a grey source gives x264 cleaner chroma, and other choices).
  if (frame.channels() == 1) cv::cvtColor(frame, d.bgr, cv::COLOR_GRAY2BGR);
  const cv::Mat& bgr = frame.channels() == 1 ? d.bgr : frame;
  int rc = FitSws(&d.sws, bgr.cols, bgr.rows, AV_PIX_FMT_BGR24, d.codec->pix_fmt, SWS_BICUBIC)
               ? av_frame_make_writable(d.frame.get())
               : AVERROR(EINVAL);
  if (rc >= 0) {
    const uint8_t* src[4] = {bgr.data, nullptr, nullptr, nullptr};
    const int stride[4] = {static_cast<int>(bgr.step[0]), 0, 0, 0};
    sws_scale(d.sws.get(), src, stride, 0, frame.rows, d.frame->data, d.frame->linesize);
    d.frame->pts = d.next_pts++;
    rc = d.Encode(d.frame.get());
  }
  if (rc < 0) throw std::runtime_error(path_ + ": encoding a frame failed (" + AvError(rc) + ")");
}

void VideoFileWriter::Commit() {
  Impl& d = *impl_;
  int rc = d.Encode(nullptr);
  if (rc >= 0) rc = av_write_trailer(d.format);
  if (rc >= 0) rc = avio_closep(&d.format->pb);
  if (rc < 0)
    throw std::runtime_error(path_ + ": finishing the video failed (" + AvError(rc) + ")");
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0)
    throw std::runtime_error(path_ + ": cannot rename from " + temp_path_);
  committed_ = true;
}

}  // namespace clogscope::vision
