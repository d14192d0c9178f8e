#include "vision/io/video_decoder.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string_view>

#include "common/atomic_file.h"
#include "vision/io/av_error.h"
#include "vision/io/av_handles.h"
#include "vision/io/image_header.h"
#include "vision/io/source_name.h"
#include "vision/io/video_io.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

namespace clogscope::vision {

// Counts the bytes of the frame buffers the decoder holds (every buffer it asks for is wrapped so
// that its release is seen) and refuses a buffer past kMaxDecoderBytes. Shared with the buffers,
// which may outlive the decoder's context.
struct FrameMemory {
  std::atomic<size_t> held_bytes{0};
  std::atomic<size_t> peak_bytes{0};
  std::atomic<bool> over{false};
  // The buffer refused: its frame's size, its bytes and those held when it was asked for.
  std::atomic<int> refused_width{0}, refused_height{0};
  std::atomic<size_t> refused_bytes{0}, refused_held_bytes{0};
};

struct VideoDecoder::Impl {
  std::shared_ptr<FrameMemory> memory;  // the decoder's frame buffers (video_decoder.cc)
  AVFormatContext* format = nullptr;
  AvCodecContextPtr codec;
  AvPacketPtr packet;
  AvFramePtr frame;
  SwsContextPtr sws;  // only for formats without a luma plane (RGB, palette)
  int stream = -1;
  bool jpeg = false;                  // Motion JPEG: every frame stands alone
  int64_t sent_pts = AV_NOPTS_VALUE;  // of the last packet sent to the decoder
  double time_base = 0;
  int64_t start_pts = 0;
  bool flushing = false;
  bool finished = false;
  // Live streams: blocking FFmpeg calls give up past the deadline or when *stop turns true.
  const std::atomic<bool>* stop = nullptr;
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  bool interrupted = false;

  void ArmDeadline(double seconds) {
    deadline = seconds > 0 ? std::chrono::steady_clock::now() +
                                 std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                     std::chrono::duration<double>(seconds))
                           : std::chrono::steady_clock::time_point::max();
  }
  static int Interrupt(void* opaque) {
    auto* d = static_cast<Impl*>(opaque);
    if ((d->stop && d->stop->load()) || std::chrono::steady_clock::now() > d->deadline) {
      d->interrupted = true;
      return 1;
    }
    return 0;
  }

  ~Impl() { avformat_close_input(&format); }
};

namespace {
constexpr int kMaxFrameIndex = 1 << 30;  // frame numbers from timestamps stop here

// True when plane 0 of the format is luma (YUV, grey): it is the grey image as is.
bool HasLumaPlane(AVPixelFormat fmt) {
  const AVPixFmtDescriptor* d = av_pix_fmt_desc_get(fmt);
  if (!d) return false;
  if (d->flags & (AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_PAL | AV_PIX_FMT_FLAG_BITSTREAM))
    return false;
  if (!(d->flags & AV_PIX_FMT_FLAG_PLANAR) && d->nb_components > 1) return false;  // packed YUYV …
  return d->comp[0].plane == 0 && d->comp[0].step <= 2;
}

// Limited-range luma unless the frame says otherwise: a YUV frame's luma plane (MPEG's
// convention) but for JPEG's full-range "yuvj" formats and frames flagged full range. Grey, and
// the grey swscale makes of RGB or a palette, are full range.
LumaRange LumaRangeOf(const AVFrame* frame) {
  const AVPixelFormat fmt = static_cast<AVPixelFormat>(frame->format);
  if (!HasLumaPlane(fmt)) return LumaRange::kFull;
  const AVPixFmtDescriptor* d = av_pix_fmt_desc_get(fmt);
  if (d->nb_components < 3 || frame->color_range == AVCOL_RANGE_JPEG ||
      std::string_view(d->name).substr(0, 4) == "yuvj")
    return LumaRange::kFull;
  return LumaRange::kLimited;
}

// Frame memory the decoder may hold at once: reference frames, frames delayed for reordering,
// frames in flight on its threads (their per-picture tables come on top, about as much again).
// A 4096×4096 H.264 video from x264's defaults holds 72 MB; a 0.4 MB one with 16 reference frames
// took 800 MB before this cap and now stops near 400 MB.
constexpr size_t kMaxDecoderBytes = size_t{128} << 20;
constexpr long long kLargeFramePixels = 2560LL * 1440;

struct HeldBuffer {
  std::shared_ptr<FrameMemory> memory;
  AVBufferRef* original = nullptr;
};

void ReleaseBuffer(void* opaque, uint8_t*) {
  auto* h = static_cast<HeldBuffer*>(opaque);
  h->memory->held_bytes -= h->original->size;
  av_buffer_unref(&h->original);
  delete h;
}

int CountedGetBuffer(AVCodecContext* codec, AVFrame* frame, int flags) {
  auto& memory = *static_cast<std::shared_ptr<FrameMemory>*>(codec->opaque);
  const int err = avcodec_default_get_buffer2(codec, frame, flags);
  if (err < 0) return err;
  size_t bytes = 0;
  for (AVBufferRef* buf : frame->buf) bytes += buf ? buf->size : 0;
  for (int i = 0; i < frame->nb_extended_buf; ++i) bytes += frame->extended_buf[i]->size;
  if (memory->held_bytes + bytes > kMaxDecoderBytes || frame->nb_extended_buf > 0) {
    memory->refused_width = frame->width;
    memory->refused_height = frame->height;
    memory->refused_bytes = bytes;
    memory->refused_held_bytes = memory->held_bytes.load();
    memory->over = true;
    av_frame_unref(frame);
    return AVERROR(ENOMEM);
  }
  for (AVBufferRef*& buf : frame->buf) {
    if (!buf) continue;
    auto* h = new HeldBuffer{memory, buf};
    AVBufferRef* wrapped = av_buffer_create(buf->data, buf->size, ReleaseBuffer, h, 0);
    if (!wrapped) {
      delete h;
      av_frame_unref(frame);
      return AVERROR(ENOMEM);
    }
    memory->held_bytes += buf->size;
    buf = wrapped;
  }
  size_t peak = memory->peak_bytes;
  while (memory->held_bytes > peak &&
         !memory->peak_bytes.compare_exchange_weak(peak, memory->held_bytes)) {
  }
  return 0;
}

// Why a Motion JPEG packet is refused before decoding, or empty. Its header's size is checked
// before the decoder allocates a frame for it; a JPEG cut short would be concealed (the missing
// rows filled in) and measured.
std::string JpegPacketProblem(const AVPacket& packet) {
  const std::string_view bytes(reinterpret_cast<const char*>(packet.data), packet.size);
  const ImageHeader header = ParseImageHeader(bytes);
  if (header.format == "jpeg") {
    if (header.width_px <= 0 || header.height_px <= 0)
      return "not a JPEG frame (no frame header before its data)";
    if (std::string big = FrameSizeProblem(header.width_px, header.height_px); !big.empty())
      return big;
  }
  if (!JpegEndsWhole(bytes)) return "a JPEG cut short (no end-of-image marker)";
  return std::string();
}

}  // namespace

VideoDecoder::VideoDecoder(const std::string& path, int threads)
    : VideoDecoder(path, VideoDecoderOptions{threads}) {}

VideoDecoder::VideoDecoder(const std::string& path, const VideoDecoderOptions& options)
    : impl_(std::make_unique<Impl>()), path_(path) {
  QuietFfmpeg();
  const std::string shown = RedactCredentials(path);  // a URL's password is never in a message
  std::string why;
  const bool url = path.find("://") != std::string::npos;
  if (!url && !IsRegularFile(path, &why))
    throw std::invalid_argument(shown + ": " + why);  // a FIFO would block FFmpeg's open
  Impl& d = *impl_;
  if (url) avformat_network_init();
  d.format = avformat_alloc_context();
  d.stop = options.stop;
  d.format->interrupt_callback = {&Impl::Interrupt, &d};
  AVDictionary* open_options = nullptr;
  if (options.low_latency) {
    // Probe briefly and hand packets on as they arrive: a live view wants the newest frame.
    av_dict_set(&open_options, "fflags", "nobuffer", 0);
    av_dict_set(&open_options, "analyzeduration", "500000", 0);
    av_dict_set(&open_options, "probesize", "500000", 0);
  }
  d.ArmDeadline(options.open_timeout_s);
  int err = avformat_open_input(&d.format, path.c_str(), nullptr, &open_options);
  av_dict_free(&open_options);
  const auto opening_failed = [&](const std::string& what) {
    if (d.interrupted && d.stop && d.stop->load()) return shown + ": stopped while opening";
    if (d.interrupted)
      return fmt::format("{}: no stream within {:g} s (--open-timeout-s)", shown,
                         options.open_timeout_s);
    return shown + ": " + what + " (" + AvError(err) + ")";
  };
  if (err < 0) throw std::invalid_argument(opening_failed("cannot open as video"));
  err = avformat_find_stream_info(d.format, nullptr);
  if (err < 0) throw std::invalid_argument(opening_failed("unreadable container"));
  d.ArmDeadline(0);
  const int threads = options.low_latency ? 1 : options.threads;
  read_timeout_s_ = options.read_timeout_s;
  const AVCodec* codec = nullptr;
  d.stream = av_find_best_stream(d.format, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
  if (d.stream < 0 || !codec) throw std::invalid_argument(shown + ": no decodable video stream");
  AVStream* st = d.format->streams[d.stream];
  const std::string too_large = FrameSizeProblem(st->codecpar->width, st->codecpar->height);
  if (!too_large.empty()) throw std::invalid_argument(shown + ": " + too_large);
  d.codec.reset(avcodec_alloc_context3(codec));
  avcodec_parameters_to_context(d.codec.get(), st->codecpar);
  // Frame threads each keep their own pool of frame buffers: large frames decode on one thread.
  const bool large =
      static_cast<long long>(st->codecpar->width) * st->codecpar->height > kLargeFramePixels;
  d.codec->thread_count = large ? 1 : threads;
  d.codec->thread_type = FF_THREAD_FRAME | FF_THREAD_SLICE;
  d.memory = std::make_shared<FrameMemory>();
  d.codec->opaque = &d.memory;
  d.codec->get_buffer2 = CountedGetBuffer;
  d.jpeg = codec->id == AV_CODEC_ID_MJPEG;
  // A damaged JPEG is an error, not a picture with its gaps concealed.
  if (d.jpeg) d.codec->err_recognition |= AV_EF_EXPLODE;
  err = avcodec_open2(d.codec.get(), codec, nullptr);
  if (err < 0) throw std::invalid_argument(shown + ": cannot open decoder (" + AvError(err) + ")");
  d.packet.reset(av_packet_alloc());
  d.frame.reset(av_frame_alloc());
  d.time_base = av_q2d(st->time_base);
  d.start_pts = st->start_time != AV_NOPTS_VALUE ? st->start_time : 0;
  const AVRational rate = st->avg_frame_rate.num ? st->avg_frame_rate : st->r_frame_rate;
  fps_ = rate.num && rate.den ? av_q2d(rate) : 0;
  if (st->duration != AV_NOPTS_VALUE) {
    duration_s_ = st->duration * d.time_base;
  } else if (d.format->duration != AV_NOPTS_VALUE) {
    duration_s_ = d.format->duration / double(AV_TIME_BASE);
  }
  frame_count_ = st->nb_frames > 0
                     ? static_cast<int>(st->nb_frames)
                     : (fps_ > 0 ? static_cast<int>(std::lround(duration_s_ * fps_)) : -1);
}

VideoDecoder::~VideoDecoder() = default;

bool VideoDecoder::interrupted() const { return impl_->interrupted; }

int VideoDecoder::width() const { return impl_->codec->width; }
int VideoDecoder::height() const { return impl_->codec->height; }

bool VideoDecoder::Read(DecodedFrame* out) {
  Impl& d = *impl_;
  // Frame number and time from a timestamp: the index from the timestamp, so frames lost to damage
  // leave a visible gap (clamped: a timestamp of 1e12 s must not overflow the frame number).
  const auto time_of = [&](int64_t pts) {
    return pts != AV_NOPTS_VALUE ? (pts - d.start_pts) * d.time_base
                                 : (fps_ > 0 ? next_index_ / fps_ : 0.0);
  };
  const auto stamp = [&](int64_t pts) {
    const double t = time_of(pts);
    const double from_time = fps_ > 0 && std::isfinite(t) ? std::round(t * fps_) : -1.0;
    out->index = from_time > next_index_
                     ? static_cast<int>(std::min(from_time, static_cast<double>(kMaxFrameIndex)))
                     : next_index_;
    next_index_ = out->index + 1;
    out->time_s = t;
  };
  // A Motion JPEG frame refused: returned without pixels, with the reason (false: it lies before
  // the time sought, and is dropped as a decoded one would be).
  const auto refuse = [&](std::string why, int64_t pts) {
    ++corrupt_packets_;
    if (skip_before_s_ >= 0 && time_of(pts) < skip_before_s_ - 1e-6) return false;
    skip_before_s_ = -1;
    out->grey.release();
    stamp(pts);
    out->corrupt = true;
    out->damage = std::move(why);
    out->skipped_reason = std::move(skipped_reason_);
    skipped_reason_.clear();
    return true;
  };
  // What the decoder's error on a JPEG means: a frame too large for the memory cap, or damage.
  const auto jpeg_error = [&](int err) {
    // (Over the cap at a measurable size: the loop's check below ends the stream with the reason.)
    const std::string big = FrameSizeProblem(d.memory->refused_width, d.memory->refused_height);
    if (d.memory->over && !big.empty()) {
      d.memory->over = false;
      return big;
    }
    return "a damaged JPEG (" + AvError(err) + ")";
  };
  while (!d.finished) {
    if (d.memory->over) {
      const FrameMemory& m = *d.memory;
      const std::string one_too_large = FrameSizeProblem(m.refused_width, m.refused_height);
      if (one_too_large.empty()) {
        constexpr double kMb = 1 << 20;
        throw std::invalid_argument(fmt::format(
            "decoding would hold over {} MB of frames ({}x{}: {:.0f} MB held, {:.0f} MB more "
            "asked): re-encode with fewer reference frames or smaller frames",
            kMaxDecoderBytes >> 20, m.refused_width.load(), m.refused_height.load(),
            m.refused_held_bytes / kMb, m.refused_bytes / kMb));
      }
      // One frame larger than any measured (a huge JPEG inside an MJPEG stream): that frame is
      // lost, the stream goes on, and the next frame says why the one before it is missing.
      d.memory->over = false;
      skipped_reason_ = one_too_large;
    }
    int err = avcodec_receive_frame(d.codec.get(), d.frame.get());
    if (err == 0) {
      const int64_t pts = d.frame->best_effort_timestamp != AV_NOPTS_VALUE
                              ? d.frame->best_effort_timestamp
                              : d.frame->pts;
      if (skip_before_s_ >= 0 && time_of(pts) < skip_before_s_ - 1e-6) {
        av_frame_unref(d.frame.get());
        continue;
      }
      skip_before_s_ = -1;
      const AVPixelFormat fmt = static_cast<AVPixelFormat>(d.frame->format);
      const int w = d.frame->width, h = d.frame->height;
      out->luma_range = LumaRangeOf(d.frame.get());
      if (!FrameSizeProblem(w, h).empty()) {
        // A stream that grows mid-way: that frame is unreadable, never converted.
        out->grey.release();
      } else if (HasLumaPlane(fmt)) {
        const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(fmt);
        const bool deep = desc->comp[0].depth > 8;
        const cv::Mat view(h, w, deep ? CV_16UC1 : CV_8UC1, d.frame->data[0], d.frame->linesize[0]);
        if (deep) {
          // Scale to the full 16-bit range so thresholds in fractions of full scale hold.
          view.convertTo(out->grey, CV_16U, double(1 << (16 - desc->comp[0].depth)));
        } else {
          out->grey = view.clone();
        }
      } else {
        FitSws(&d.sws, w, h, fmt, AV_PIX_FMT_GRAY8, SWS_POINT);
        out->grey.create(h, w, CV_8UC1);
        uint8_t* dst[4] = {out->grey.data, nullptr, nullptr, nullptr};
        int dst_stride[4] = {static_cast<int>(out->grey.step), 0, 0, 0};
        sws_scale(d.sws.get(), d.frame->data, d.frame->linesize, 0, h, dst, dst_stride);
      }
      stamp(pts);
      out->skipped_reason = std::move(skipped_reason_);
      skipped_reason_.clear();
      out->corrupt = (d.frame->flags & AV_FRAME_FLAG_CORRUPT) != 0 ||
                     d.frame->decode_error_flags != 0 || out->grey.empty();
      out->damage = !out->corrupt       ? ""
                    : out->grey.empty() ? FrameSizeProblem(w, h)
                                        : "the decoder reported damage";
      av_frame_unref(d.frame.get());
      return true;
    }
    if (err == AVERROR_EOF) {
      d.finished = true;
      break;
    }
    if (err != AVERROR(EAGAIN)) {
      // A frame the decoder could not reconstruct: count it and go on (a JPEG: say so).
      if (d.jpeg && refuse(jpeg_error(err), d.sent_pts)) return true;
      if (!d.jpeg) ++corrupt_packets_;
      continue;
    }
    if (d.flushing) {
      d.finished = true;
      break;
    }
    // Feed the next packet of our stream.
    while (true) {
      d.ArmDeadline(read_timeout_s_);
      err = av_read_frame(d.format, d.packet.get());
      if (err < 0) {
        avcodec_send_packet(d.codec.get(), nullptr);  // drain
        d.flushing = true;
        break;
      }
      if (d.packet->stream_index != d.stream) {
        av_packet_unref(d.packet.get());
        continue;
      }
      if (d.jpeg) {
        d.sent_pts = d.packet->pts;
        if (std::string why = JpegPacketProblem(*d.packet); !why.empty()) {
          av_packet_unref(d.packet.get());
          if (refuse(std::move(why), d.sent_pts)) return true;
          continue;
        }
      }
      err = avcodec_send_packet(d.codec.get(), d.packet.get());
      av_packet_unref(d.packet.get());
      if (err < 0 && err != AVERROR(EAGAIN)) {
        if (d.jpeg && refuse(jpeg_error(err), d.sent_pts)) return true;
        if (!d.jpeg) ++corrupt_packets_;
        continue;
      }
      break;
    }
  }
  return false;
}

bool VideoDecoder::SeekToTime(double time_s) {
  Impl& d = *impl_;
  const int64_t target = d.start_pts + static_cast<int64_t>(std::floor(time_s / d.time_base));
  if (av_seek_frame(d.format, d.stream, target, AVSEEK_FLAG_BACKWARD) < 0) return false;
  avcodec_flush_buffers(d.codec.get());
  d.flushing = false;
  d.finished = false;
  skip_before_s_ = time_s;
  next_index_ = fps_ > 0 ? static_cast<int>(std::lround(time_s * fps_)) : 0;
  return true;
}

}  // namespace clogscope::vision
