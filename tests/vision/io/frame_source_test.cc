#include "vision/io/frame_source.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/atomic_file.h"
#include "synthetic/synthetic.h"
#include "synthetic/x264_clip.h"
#include "tests/scratch_dir.h"
#include "vision/io/video_decoder.h"
#include "vision/io/video_io.h"
#include "vision/io/video_writer.h"
#include "vision/scene/batch.h"

namespace clogscope::vision {
namespace {

using synthetic::RenderFrame;
using synthetic::RenderSequence;
using synthetic::SceneParams;

namespace fs = std::filesystem;

fs::path FreshDir(const std::string& name) { return testutil::FreshDir("clogscope_fs_" + name); }

SceneParams SmallScene() {
  SceneParams p;
  p.width_px = 400;
  p.height_px = 300;
  p.tip_x_px = 200;
  p.tip_y_px = 80;
  return p;
}

std::string MessageOf(const std::string& path) {
  try {
    FrameSource::Open(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// Timestamps that jump by 10⁷ s (250 million frame periods): one entry for the gap, not one per
// missing frame number.
TEST(FrameSourceTest, ATimestampJumpIsOneGap) {
  auto source =
      FrameSource::Open(std::string(CLOGSCOPE_TESTDATA_DIR) + "/video/timestamp_jump.mkv");
  InputFrame f;
  int decoded = 0, gaps = 0, entries = 0;
  while (source->Next(&f) && entries < 100) {
    ++entries;
    if (!f.image.empty()) ++decoded;
    if (f.error.find("frames missing") != std::string::npos) {
      ++gaps;
      EXPECT_NE(f.error.find("jump of 1e+07 s"), std::string::npos) << f.error;
    }
  }
  EXPECT_EQ(decoded, 6);
  EXPECT_EQ(gaps, 1);
  EXPECT_EQ(entries, 7);
}

TEST(FrameSourceTest, BadPathsNameThePathAndTheProblem) {
  const fs::path dir = FreshDir("bad");
  EXPECT_NE(MessageOf((dir / "missing.mp4").string()).find("no such file"), std::string::npos);
  EXPECT_NE(MessageOf(dir.string()).find("holds no images"), std::string::npos);
  // A valid PNG header claiming 65535×65535 pixels: refused from its header, never decoded.
  const char kHuge[] =
      "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\xff\xff\x00"
      "\x00\xff\xff\x08\x00\x00\x00\x00\x93\x6e\x86\x8c\x00\x00\x00\x0c\x49\x44\x41\x54\x78"
      "\x9c\x63\x60\xa0\x3d\x00\x00\x00\x64\x00\x01\x86\x64\x3c\x35\x00\x00\x00\x00\x49\x45"
      "\x4e\x44\xae\x42\x60\x82";
  WriteFileAtomically((dir / "huge.png").string(), std::string(kHuge, sizeof(kHuge) - 1));
  const std::string huge = MessageOf((dir / "huge.png").string());
  EXPECT_NE(huge.find("huge.png: frames are 65535x65535"), std::string::npos) << huge;
  // A name longer than the system allows; a directory whose one entry is a link to itself.
  const std::string long_name = (dir / (std::string(300, 'a') + ".png")).string();
  EXPECT_NE(MessageOf(long_name).find("file name too long"), std::string::npos);
  const fs::path loop = dir / "loop";
  fs::create_directories(loop);
  fs::create_symlink(loop / "self.png", loop / "self.png");
  WriteImageAtomically((loop / "good.png").string(), RenderFrame(SmallScene(), 0, nullptr));
  EXPECT_NO_THROW(FrameSource::Open(loop.string()));
  EXPECT_NE(MessageOf((loop / "self.png").string()).find("symbolic links"), std::string::npos);
  // Writing a video into a folder that does not exist names the folder, not the encoder.
  try {
    VideoFileWriter w((dir / "nowhere" / "v.mp4").string(), VideoKind::kH264Mp4, 25, {64, 48});
    ADD_FAILURE() << "opened a video in a missing folder";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  WriteFileAtomically((dir / "corrupt.png").string(), "definitely not a png");
  const std::string msg = MessageOf((dir / "corrupt.png").string());
  EXPECT_NE(msg.find("corrupt.png"), std::string::npos);
  EXPECT_NE(msg.find("not an image format the tool reads"), std::string::npos) << msg;
  WriteFileAtomically((dir / "empty.mp4").string(), "");
  EXPECT_NE(MessageOf((dir / "empty.mp4").string()).find("empty.mp4"), std::string::npos);
  WriteFileAtomically((dir / "notes.txt").string(), "hello");
  EXPECT_NE(MessageOf((dir / "notes.txt").string()).find("neither"), std::string::npos);
}

TEST(FrameSourceTest, DirectoryIsSortedAndBadImagesAreReportedNotFatal) {
  const fs::path dir = FreshDir("dir");
  const SceneParams p = SmallScene();
  for (int i : {2, 0, 1}) {
    WriteImageAtomically((dir / ("f" + std::to_string(i) + ".png")).string(),
                         RenderFrame(p, i, nullptr));
  }
  WriteFileAtomically((dir / "f1b.png").string(), "garbage");
  auto src = FrameSource::Open(dir.string());
  EXPECT_EQ(src->expected_frames(), 4);
  std::vector<std::string> names;
  std::vector<bool> ok;
  InputFrame f;
  while (src->Next(&f)) {
    names.push_back(fs::path(f.source).filename().string());
    ok.push_back(!f.image.empty());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"f0.png", "f1.png", "f1b.png", "f2.png"}));
  EXPECT_EQ(ok, (std::vector<bool>{true, true, false, true}));
}

TEST(FrameSourceTest, SixteenBitAndColourImagesAreRead) {
  const fs::path dir = FreshDir("depth");
  SceneParams p = SmallScene();
  p.bit_depth = 16;
  WriteImageAtomically((dir / "deep.png").string(), RenderFrame(p, 0, nullptr));
  p.bit_depth = 8;
  p.colour = true;
  WriteImageAtomically((dir / "colour.png").string(), RenderFrame(p, 0, nullptr));
  InputFrame f;
  auto deep = FrameSource::Open((dir / "deep.png").string());
  ASSERT_TRUE(deep->Next(&f));
  EXPECT_EQ(f.image.type(), CV_16UC1);
  auto colour = FrameSource::Open((dir / "colour.png").string());
  ASSERT_TRUE(colour->Next(&f));
  EXPECT_EQ(f.image.type(), CV_8UC3);
}

// The writer's files read back as written: every frame, the rate, the size and the levels, by
// BT.601's luma of the colour written (full range in Motion JPEG, 16-235 in H.264, which the
// reader gives as stored, saying so).
TEST(VideoFileWriterTest, WhatIsWrittenReadsBackFrameForFrame) {
  const fs::path dir = FreshDir("writer");
  struct Case {
    const char* name;
    double fps;
    bool full_range;
  };
  for (const Case& c :
       {Case{"v.avi", 25, true}, Case{"v.mp4", 29.97, false}, Case{"v.mkv", 10, false}}) {
    const std::string path = (dir / c.name).string();
    std::vector<double> luma;
    {
      VideoFileWriter w(path, VideoKindForPath(path), c.fps, {96, 64});
      for (int i = 0; i < 12; ++i) {
        // Grey frames of rising level, and every third one colour (blue-heavy).
        const double level = 30 + 15 * i;
        if (i % 3 == 2) {
          w.Write(cv::Mat(64, 96, CV_8UC3, cv::Scalar(level + 40, level, level - 20)));
          luma.push_back(0.114 * (level + 40) + 0.587 * level + 0.299 * (level - 20));
        } else {
          w.Write(cv::Mat(64, 96, CV_8UC1, cv::Scalar(level)));
          luma.push_back(level);
        }
      }
      EXPECT_FALSE(fs::exists(path)) << "the name is taken only when the file is whole";
      w.Commit();
    }
    VideoDecoder d(path, 1);
    EXPECT_NEAR(d.fps(), c.fps, 0.01) << c.name;
    EXPECT_EQ(d.width(), 96);
    EXPECT_EQ(d.height(), 64);
    DecodedFrame f;
    size_t n = 0;
    while (d.Read(&f)) {
      ASSERT_LT(n, luma.size()) << c.name;
      const double expected = c.full_range ? luma[n] : 16 + luma[n] * 219 / 255;
      EXPECT_NEAR(cv::mean(f.grey)[0], expected, 2.0) << c.name << " frame " << n;
      // And the frame says which: where the measurement looks for clipped white and black.
      EXPECT_EQ(f.luma_range, c.full_range ? LumaRange::kFull : LumaRange::kLimited) << c.name;
      ++n;
    }
    EXPECT_EQ(n, luma.size()) << c.name;
  }
  // A writer dropped before Commit leaves nothing behind, not even its temporary file.
  {
    VideoFileWriter w((dir / "dropped.avi").string(), VideoKind::kMjpegAvi, 25, {96, 64});
    w.Write(cv::Mat(64, 96, CV_8UC1, cv::Scalar(50)));
  }
  EXPECT_FALSE(fs::exists(dir / "dropped.avi"));
  EXPECT_FALSE(fs::exists(dir / "dropped.partial.avi"));
}

TEST(FrameSourceTest, DamagedVideoKeepsGoingInOrder) {
  const fs::path dir = FreshDir("damaged");
  const std::string path = (dir / "v.avi").string();
  RenderSequence(SmallScene(), 20, 25.0, path, "");
  // Overwrite a stretch in the middle of the file with zeros.
  {
    std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(0, std::ios::end);
    const auto size = static_cast<long>(io.tellp());
    io.seekp(size / 2);
    const std::string zeros(size / 10, '\0');
    io.write(zeros.data(), zeros.size());
  }
  auto src = FrameSource::Open(path);
  StrandMeasureOptions opt;
  opt.band_start_px = 10;
  opt.band_height_px = 40;
  int expected_index = 0, valid = 0;
  const int n = MeasureFrames(*src, opt, [&](InputFrame& f, StrandMeasurement& m) {
    EXPECT_GE(f.index, expected_index);  // a gap of several frames is one entry
    expected_index = f.index + 1;
    valid += m.valid();
    if (f.image.empty()) {
      EXPECT_EQ(m.status, FrameStatus::kUnreadable);
    }
  });
  EXPECT_GE(n, 10);
  EXPECT_GE(valid, 10);
}

// A step of `run` made of images: read by index, seeking forward and back.
TEST(FrameSourceTest, AnImageFolderSeeksByIndexAndNamesItsProblems) {
  const fs::path dir = FreshDir("folder_seek");
  const SceneParams p = SmallScene();
  for (int i : {0, 1, 2}) {
    WriteImageAtomically((dir / ("f" + std::to_string(i) + ".png")).string(),
                         RenderFrame(p, i, nullptr));
  }
  auto src = FrameSource::OpenImageFolder(dir.string());
  EXPECT_EQ(src->kind(), SourceKind::kImages);
  EXPECT_EQ(src->expected_frames(), 3);
  InputFrame f;
  ASSERT_TRUE(src->SeekToFrame(2));
  ASSERT_TRUE(src->Next(&f));
  EXPECT_EQ(fs::path(f.source).filename(), "f2.png");
  EXPECT_EQ(f.index, 2);
  EXPECT_EQ(f.time_s, -1);
  EXPECT_FALSE(src->Next(&f));
  ASSERT_TRUE(src->SeekToFrame(0));
  ASSERT_TRUE(src->Next(&f));
  EXPECT_EQ(fs::path(f.source).filename(), "f0.png");
  EXPECT_FALSE(f.image.empty());
  ASSERT_TRUE(src->SeekToFrame(7));
  EXPECT_EQ(src->Read(&f), FrameRead::kEnd);

  auto message = [](const std::string& path) {
    try {
      FrameSource::OpenImageFolder(path);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const fs::path empty = FreshDir("folder_empty");
  EXPECT_EQ(message((dir / "none").string()), (dir / "none").string() + ": no such directory");
  EXPECT_EQ(message((dir / "f0.png").string()), (dir / "f0.png").string() + ": no such directory");
  EXPECT_EQ(message(empty.string()), empty.string() + ": directory holds no images");
}

// A video read for sampling: its frames at their times (k/25 s as rendered), after a seek too,
// and no entries for gaps when asked for none.
TEST(FrameSourceTest, AVideoSeeksToATimeAndCanLeaveOutGaps) {
  const fs::path dir = FreshDir("video_seek");
  const std::string path = (dir / "v.avi").string();
  RenderSequence(SmallScene(), 50, 25.0, path, "");
  VideoReadOptions o;
  o.decoder_threads = 1;
  auto src = FrameSource::OpenVideo(path, o);
  EXPECT_EQ(src->kind(), SourceKind::kVideo);
  EXPECT_NEAR(src->fps(), 25.0, 1e-9);
  EXPECT_NEAR(src->duration_s(), 2.0, 0.05);
  InputFrame f;
  ASSERT_TRUE(src->Next(&f));
  EXPECT_EQ(f.index, 0);
  EXPECT_NEAR(f.time_s, 0.0, 1e-9);
  ASSERT_TRUE(src->SeekToTime(1.2));
  ASSERT_TRUE(src->Next(&f));
  EXPECT_EQ(f.index, 30);
  EXPECT_NEAR(f.time_s, 1.2, 1e-9);
  EXPECT_FALSE(f.image.empty());
  int rest = 0;
  while (src->Next(&f)) ++rest;
  EXPECT_EQ(rest, 19);  // frames 31 … 49

  // The video with one jump of 10⁷ s in its timestamps: six frames decoded, no gap entry.
  o.gap_entries = false;
  auto jump =
      FrameSource::OpenVideo(std::string(CLOGSCOPE_TESTDATA_DIR) + "/video/timestamp_jump.mkv", o);
  int entries = 0, decoded = 0;
  while (jump->Next(&f) && entries < 100) {
    ++entries;
    decoded += !f.image.empty();
  }
  EXPECT_EQ(entries, 6);
  EXPECT_EQ(decoded, 6);
  // A file that is no video: the decoder's own line.
  WriteFileAtomically((dir / "notes.mp4").string(), "hello");
  try {
    FrameSource::OpenVideo((dir / "notes.mp4").string(), o);
    ADD_FAILURE() << "opened a text file as video";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "notes.mp4").string() + ": ", 0), 0u) << e.what();
  }
}

// Frames numbered 0, 1, 2, … without pixels; the read after `fail_at` frames throws (-1: never,
// and the frames never end).
class CountingSource : public FrameSource {
 public:
  explicit CountingSource(int fail_at)
      : FrameSource("counting", SourceKind::kImages), fail_at_(fail_at) {}
  FrameRead Read(InputFrame* frame, std::string*) override {
    if (next_ == fail_at_) throw std::runtime_error("reader failed at frame 3");
    frame->index = next_++;
    frame->error = "nothing to measure";  // an empty image: no measuring time spent
    return FrameRead::kFrame;
  }

 private:
  int fail_at_;
  int next_ = 0;
};

TEST(MeasureFramesTest, AReaderErrorReachesTheCallerAfterTheFramesReadBeforeIt) {
  CountingSource source(3);
  std::vector<int64_t> seen;
  try {
    MeasureFrames(source, StrandMeasureOptions{},
                  [&](InputFrame& f, StrandMeasurement&) { seen.push_back(f.index); });
    ADD_FAILURE() << "the reader's error was lost";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "reader failed at frame 3");
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{0, 1, 2}));
}

TEST(MeasureFramesTest, AMeasuringErrorStopsAReaderThatWouldNeverEnd) {
  CountingSource endless(-1);
  int calls = 0;
  EXPECT_THROW(MeasureFrames(endless, StrandMeasureOptions{},
                             [&](InputFrame& f, StrandMeasurement&) {
                               ++calls;
                               if (f.index == 4) throw std::invalid_argument("stop here");
                             }),
               std::invalid_argument);
  EXPECT_EQ(calls, 5);
  // And a stop request ends it too, after the frame that asked.
  calls = 0;
  CountingSource endless2(-1);
  const int n = MeasureFrames(
      endless2, StrandMeasureOptions{}, [&](InputFrame&, StrandMeasurement&) { ++calls; },
      [&] { return calls == 7; });
  EXPECT_EQ(n, 7);
}

// A strand at the camera's white, half its pixels clipped by the noise, through x264: the video's
// luma is limited range, where the clip decodes at 233-235, and every frame is measured in its
// own range: `saturated`. (Read as full range, the same frames gave widths.)
TEST(MeasureFramesTest, AStrandClippedBeforeX264IsSaturatedInTheVideosOwnRange) {
  const fs::path dir = FreshDir("clipped_x264");
  SceneParams p = SmallScene();
  p.strand_level = 255;
  p.noise_sigma = 1.5;
  std::vector<cv::Mat> rendered;
  for (int i = 0; i < 6; ++i) rendered.push_back(RenderFrame(p, i, nullptr));
  const std::string video = synthetic::EncodeX264Clip(rendered, dir, "clipped.mp4", 25);
  auto source = FrameSource::Open(video);
  int frames = 0, full_range_widths = 0;
  MeasureFrames(*source, StrandMeasureOptions{}, [&](InputFrame& f, StrandMeasurement& m) {
    ++frames;
    EXPECT_EQ(f.luma_range, LumaRange::kLimited);
    EXPECT_EQ(m.status, FrameStatus::kSaturated) << frames << ": " << m.width_px << " px";
    full_range_widths += MeasureStrand(f.image, StrandMeasureOptions{}).gave_width();
  });
  EXPECT_EQ(frames, 6);
  EXPECT_GT(full_range_widths, 0);  // what the range decides
}

}  // namespace
}  // namespace clogscope::vision
