#include "vision/io/live_source.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"
#include "vision/io/video_io.h"

namespace clogscope::vision {
namespace {

using synthetic::RenderSequence;
using synthetic::SceneParams;

namespace fs = std::filesystem;

fs::path Fresh(const std::string& name) { return testutil::FreshDir(name); }

cv::Mat Grey(int level) { return cv::Mat(48, 64, CV_8UC1, cv::Scalar(level)); }

// A fresh folder holding one image already (not to be delivered), watched every 20 ms.
std::unique_ptr<FrameSource> OpenFolderWithAnOldImage(const fs::path& d, std::atomic<bool>* stop) {
  WriteImageAtomically((d / "old.png").string(), Grey(10));
  LiveSourceOptions o;
  o.folder_poll_s = 0.02;
  return OpenLiveSource(d.string(), o, stop);
}

TEST(LiveSourceTest, KindFromTheSourceName) {
  const fs::path d = Fresh("clogscope_live_kind");
  EXPECT_EQ(LiveSourceKindOf("/dev/video0"), SourceKind::kDevice);
  EXPECT_EQ(LiveSourceKindOf("http://printer.local/webcam/?action=stream"), SourceKind::kStream);
  EXPECT_EQ(LiveSourceKindOf("rtsp://cam/1"), SourceKind::kStream);
  EXPECT_EQ(LiveSourceKindOf(d.string()), SourceKind::kFolder);
  EXPECT_EQ(LiveSourceKindOf("replay.mp4"), SourceKind::kVideo);
  fs::remove_all(d);
}

TEST(LiveSourceTest, AFolderDeliversNewImagesInOrderAndIgnoresThoseAlreadyThere) {
  const fs::path d = Fresh("clogscope_live_folder");
  std::atomic<bool> stop{false};
  auto source = OpenFolderWithAnOldImage(d, &stop);
  EXPECT_TRUE(source->live());
  // A camera writes three frames, one after the other (names out of order on purpose: arrival
  // decides), and a text file that is not an image. Each read returns the frame written before
  // it: the folder is listed when the read comes, so no clock is involved.
  std::vector<int> levels;
  InputFrame f;
  std::string why;
  int k = 0;
  for (int i : {3, 1, 2}) {
    WriteImageAtomically((d / ("shot" + std::to_string(i) + ".png")).string(), Grey(40 * i));
    if (i == 2) std::ofstream((d / "notes.txt").string()) << "not an image";
    ASSERT_EQ(source->Read(&f, &why), FrameRead::kFrame);
    ASSERT_FALSE(f.image.empty()) << f.error;
    levels.push_back(f.image.at<uchar>(0, 0));
    EXPECT_EQ(f.index, k++);
  }
  EXPECT_EQ(levels, (std::vector<int>{120, 40, 80}));
  // Nothing new (the text file is no frame): the read waits until the stop flag rises, whether
  // it rises before the read begins or while it waits.
  std::thread stopper([&] { stop = true; });
  EXPECT_EQ(source->Read(&f, &why), FrameRead::kStopped);
  stopper.join();
  fs::remove_all(d);
}

// Raises the stop flag if the test is not over within a generous limit, so that a read that would
// wait forever fails the test instead of hanging it. Not pacing: a passing test never waits on it.
class Watchdog {
 public:
  explicit Watchdog(std::atomic<bool>* stop)
      : thread_([this, stop] {
          std::unique_lock<std::mutex> lock(mutex_);
          if (!done_cv_.wait_for(lock, std::chrono::seconds(30), [this] { return done_; }))
            *stop = true;
        }) {}
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    done_cv_.notify_all();
    thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::thread thread_;
};

// A camera whose clock runs ahead stamps one image a day into the future: the images after it are
// still delivered, in the order they arrived (a folder is not read by a clock it cannot trust).
TEST(LiveSourceTest, AnImageStampedInTheFutureDoesNotHideTheNextOnes) {
  const fs::path d = Fresh("clogscope_live_future");
  std::atomic<bool> stop{false};
  auto source = OpenFolderWithAnOldImage(d, &stop);
  Watchdog watchdog(&stop);
  const auto now = fs::file_time_type::clock::now();
  struct Shot {
    std::string name;
    int level;
    fs::file_time_type mtime;
  };
  const Shot shots[] = {{"c.png", 40, now + std::chrono::hours(24)},
                        {"b.png", 80, now - std::chrono::hours(1)},
                        {"a.png", 120, now - std::chrono::hours(2)}};
  InputFrame f;
  std::string why;
  for (size_t k = 0; k < std::size(shots); ++k) {
    const std::string path = (d / shots[k].name).string();
    WriteImageAtomically(path, Grey(shots[k].level));
    fs::last_write_time(path, shots[k].mtime);
    ASSERT_EQ(source->Read(&f, &why), FrameRead::kFrame) << shots[k].name << ": " << why;
    ASSERT_FALSE(f.image.empty()) << f.error;
    EXPECT_EQ(fs::path(f.source).filename().string(), shots[k].name);
    EXPECT_EQ(f.image.at<uchar>(0, 0), shots[k].level);
    EXPECT_EQ(f.index, static_cast<int64_t>(k));
  }
  fs::remove_all(d);
}

TEST(LiveSourceTest, AFileEndsAndARealtimeFileIsPacedAtItsFrameRate) {
  const fs::path d = Fresh("clogscope_live_file");
  SceneParams s;
  s.width_px = 160;
  s.height_px = 120;
  s.tip_x_px = 80;
  s.tip_y_px = 30;
  s.strand_width_um = 120;
  const std::string video = (d / "v.avi").string();
  RenderSequence(s, 10, 20, video, (d / "t.json").string());
  std::atomic<bool> stop{false};
  LiveSourceOptions o;
  o.realtime = true;
  // Simulated time: the source says when each frame is due; nothing waits.
  std::vector<double> due_s;
  o.wait_until = [&](double due) {
    due_s.push_back(due);
    return true;
  };
  auto source = OpenLiveSource(video, o, &stop);
  EXPECT_FALSE(source->live());
  InputFrame f;
  std::string why;
  int n = 0;
  double last_t = -1;
  while (source->Read(&f, &why) == FrameRead::kFrame) {
    EXPECT_GT(f.time_s, last_t);
    last_t = f.time_s;
    ++n;
  }
  EXPECT_EQ(n, 10);
  EXPECT_NEAR(last_t, 9 / 20.0, 1e-6);
  // Each frame waited for its own timestamp from the first: 0, 0.05, …, 0.45 s at 20 frames/s.
  ASSERT_EQ(due_s.size(), 10u);
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(due_s[i], i / 20.0, 1e-6) << i;
  // A wait cut short by the stop flag ends the read.
  o.wait_until = [&](double) { return false; };
  auto stopped = OpenLiveSource(video, o, &stop);
  EXPECT_EQ(stopped->Read(&f, &why), FrameRead::kStopped);
  EXPECT_THROW(OpenLiveSource((d / "missing.avi").string(), o, &stop), std::invalid_argument);
  fs::remove_all(d);
}

}  // namespace
}  // namespace clogscope::vision
