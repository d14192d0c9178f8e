// The live watch against faulty frames and outages: Motion JPEG files of a rendered strand with
// frames too large, cut short, damaged, of another size or garbage, read through the real decoder;
// and outages of 1–30 s (silent, then down) in simulated time. A faulty frame is a frame without a
// view with its reason, never a crash, a measured width or a level change.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "pipeline/experiment.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"
#include "vision/io/image_codec.h"
#include "watch/live_watch.h"

namespace clogscope::watch {
namespace {

namespace fs = std::filesystem;

// JPEGs of a 400 µm strand (3 µm/px) below a nozzle, one noise draw each.
std::vector<std::string> StrandJpegs(int count, int width_px, int height_px) {
  synthetic::SceneParams s;
  s.width_px = width_px;
  s.height_px = height_px;
  s.tip_x_px = width_px / 2.0;
  s.tip_y_px = height_px * 0.22;
  s.width_jitter_um = 2.0;
  std::vector<std::string> out;
  for (int i = 0; i < count; ++i) {
    synthetic::FrameTruth truth;
    out.push_back(vision::EncodeImage(".jpg", synthetic::RenderFrame(s, i, &truth), 90));
  }
  return out;
}

enum class Fault { kHuge, kCutShort, kEndCut, kDamaged, kResized, kGarbage };
constexpr Fault kFaults[] = {Fault::kHuge,    Fault::kCutShort, Fault::kEndCut,
                             Fault::kDamaged, Fault::kResized,  Fault::kGarbage};

const char* FaultName(Fault f) {
  switch (f) {
    case Fault::kHuge:
      return "huge";
    case Fault::kCutShort:
      return "cut short";
    case Fault::kEndCut:
      return "end marker cut";
    case Fault::kDamaged:
      return "damaged";
    case Fault::kResized:
      return "resized";
    case Fault::kGarbage:
      return "garbage";
  }
  return "?";
}

// What the watch's reason for the refused frame must say.
const char* ReasonOf(Fault f) {
  switch (f) {
    case Fault::kHuge:
      return "12000x12000";
    case Fault::kCutShort:
    case Fault::kEndCut:
      return "cut short";
    case Fault::kDamaged:
      return "damaged JPEG";
    case Fault::kResized:
      return "the frame is 480×270, the watch started on 640×360";
    case Fault::kGarbage:
      return "not a JPEG frame";
  }
  return "?";
}

// A random byte that is not 0xFF (a marker's first byte would split the packet).
char NotAMarker(std::mt19937_64& rng) {
  return static_cast<char>(std::uniform_int_distribution<int>(0, 254)(rng));
}

// The JPEG `good` made faulty; `resized` is a JPEG of another size.
std::string Faulty(Fault f, std::string good, const std::string& resized, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0, 1);
  switch (f) {
    case Fault::kHuge: {
      // The frame header (SOF0) claims 12000×12000: refused from it, never decoded.
      const size_t sof = good.find("\xff\xc0");
      const std::string size = "\x2e\xe0\x2e\xe0";  // height, width: 12000 each
      good.replace(sof + 5, 4, size);
      return good;
    }
    case Fault::kCutShort:
      return good.substr(0, static_cast<size_t>(good.size() * (0.2 + 0.7 * uni(rng))));
    case Fault::kEndCut:
      return good.substr(0, good.size() - 2);  // every pixel there, no end-of-image marker
    case Fault::kDamaged: {
      // 400 bytes of the entropy-coded data overwritten (the marker's end kept).
      const size_t from = good.size() / 3 + static_cast<size_t>(good.size() / 3 * uni(rng));
      for (size_t i = from; i < from + 400 && i + 2 < good.size(); ++i) good[i] = NotAMarker(rng);
      return good;
    }
    case Fault::kResized:
      return resized;
    case Fault::kGarbage: {
      // A JPEG's start (its first marker, as a parser wants) and then junk where the frame should
      // be.
      std::string junk = good.substr(0, 4) + std::string("\x00\x10", 2);
      for (int i = 0; i < 3000; ++i) junk += NotAMarker(rng);
      return junk + "\xff\xd9";
    }
  }
  return good;
}

struct Outcome {
  LiveWatchSummary summary;
  std::vector<std::string> warnings;
  nlohmann::json last_line;
  long long refused = 0;
};

// Watches the Motion JPEG file at `path` (its own clock: 25 frames/s) to its end.
Outcome Watch(const std::string& path) {
  LiveWatchOptions o;
  o.source = path;
  o.conversion = pipeline::PlainScale(3.0);
  o.strand.band_start_px = 50.0 / 3;
  o.strand.band_height_px = 50;
  o.watch.baseline_s = 4;
  Outcome out;
  LiveWatchEvents events;
  events.on_warning = [&](const std::string& w) { out.warnings.push_back(w); };
  events.on_line = [&](const std::string& line) { out.last_line = nlohmann::json::parse(line); };
  WatchBoard board;
  std::atomic<bool> stop{false};
  out.summary = RunLiveWatch(o, events, &board, &stop);
  out.refused = board.Read().counters.frames_refused_total;
  return out;
}

void WriteFile(const fs::path& path, const std::vector<std::string>& jpegs) {
  std::ofstream out(path, std::ios::binary);
  for (const std::string& j : jpegs) out << j;
}

TEST(LiveWatchFaultsTest, EveryFaultyFrameIsAFrameWithoutAViewWithItsReason) {
  const testutil::ScratchDir scratch("clogscope_watch_faults");
  const std::vector<std::string> good = StrandJpegs(8, 640, 360);
  const std::string resized = StrandJpegs(1, 480, 270)[0];
  std::mt19937_64 rng(1);
  std::vector<std::string> frames;
  std::map<int, Fault> faults;  // frame number → its fault
  for (int i = 0; i < 150; ++i) {
    frames.push_back(good[i % good.size()]);
    if (i >= 20 && i % 20 == 0 && faults.size() < std::size(kFaults)) {
      const Fault f = kFaults[faults.size()];
      frames.back() = Faulty(f, frames.back(), resized, rng);
      faults[i] = f;
    }
  }
  ASSERT_EQ(faults.size(), std::size(kFaults));
  const fs::path path = scratch.path() / "faults.mjpeg";
  WriteFile(path, frames);
  const Outcome o = Watch(path.string());
  // Every frame is counted; the faulty ones without a width, each told with its reason; the level
  // held (the faulty frames are few).
  EXPECT_EQ(o.summary.ended_because, "the file ended");
  EXPECT_TRUE(o.summary.error.empty()) << o.summary.error;
  EXPECT_EQ(o.summary.frames, 150);
  EXPECT_EQ(o.refused, static_cast<long long>(faults.size()));
  EXPECT_EQ(o.summary.valid_frames, 150 - static_cast<long long>(faults.size()));
  EXPECT_EQ(o.summary.level_changes, 0);
  EXPECT_EQ(o.last_line["event"], "stop");
  EXPECT_EQ(o.last_line["counters"]["frames_refused_total"], faults.size());
  ASSERT_EQ(o.warnings.size(), faults.size());
  size_t k = 0;
  for (const auto& [index, fault] : faults) {
    const std::string& w = o.warnings[k++];
    EXPECT_NE(w.find("frame " + std::to_string(index) + " not measured"), std::string::npos) << w;
    EXPECT_NE(w.find(ReasonOf(fault)), std::string::npos) << FaultName(fault) << ": " << w;
  }
}

// The campaign: each fault 75 times in random places (15 files of five; 30 files took 40 s of
// CI's budget more for no fault seen), and outages of 1–30 s 30 times each (simulated time);
// every run must end cleanly with no level change but those an outage owes (no_view, then back).
TEST(LiveWatchFaultsTest, Campaign) {
  constexpr int kFileRuns = 15, kRuns = 30;
  const testutil::ScratchDir scratch("clogscope_watch_campaign");
  const std::vector<std::string> good = StrandJpegs(16, 640, 360);
  const std::string resized = StrandJpegs(1, 480, 270)[0];
  std::mt19937_64 rng(7);
  for (const Fault fault : kFaults) {
    int crashes = 0, false_changes = 0, wrong_counts = 0;
    long long undecoded_damage = 0;
    for (int run = 0; run < kFileRuns; ++run) {
      // 10 s at 25 frames/s with five faulty frames anywhere but the first (a file whose first
      // frame is not one is refused at the start, as a source that cannot be opened).
      std::vector<std::string> frames;
      for (int i = 0; i < 250; ++i)
        frames.push_back(good[std::uniform_int_distribution<size_t>(0, good.size() - 1)(rng)]);
      std::set<int> at;
      while (at.size() < 5) at.insert(std::uniform_int_distribution<int>(1, 249)(rng));
      for (int i : at) frames[i] = Faulty(fault, frames[i], resized, rng);
      const fs::path path = scratch.path() / "run.mjpeg";
      WriteFile(path, frames);
      try {
        const Outcome o = Watch(path.string());
        crashes += o.summary.ended_because != "the file ended" || o.last_line["event"] != "stop";
        false_changes += o.summary.level_changes;
        // Every frame counted, none refused but a faulty one; a damaged JPEG whose junk still
        // reads as valid codes decodes without an error (JPEG has no checksum) and is measured.
        const long long undetected = 5 - o.refused;
        undecoded_damage += undetected;
        wrong_counts += o.summary.frames != 250 || o.refused + o.summary.valid_frames < 245 ||
                        undetected < 0 || (fault != Fault::kDamaged && undetected != 0);
      } catch (const std::exception& e) {
        ++crashes;
        ADD_FAILURE() << FaultName(fault) << ": " << e.what();
      }
    }
    std::cout << "campaign: " << FaultName(fault) << " frames, " << kFileRuns
              << " runs of 250 frames with 5 each: " << crashes << " crashes, " << false_changes
              << " level changes, " << wrong_counts << " runs with a wrong count, "
              << undecoded_damage << " faulty frames decoded without an error\n";
    EXPECT_EQ(crashes, 0) << FaultName(fault);
    EXPECT_EQ(false_changes, 0) << FaultName(fault);
    EXPECT_EQ(wrong_counts, 0) << FaultName(fault);
  }

  // Outages in simulated time: a steady strand, then silence (a stall of up to 4.9 s, which the
  // read timeout of 5 s does not end, or one that it ends) and the source down for 1–30 s, then
  // the strand again. Owed: nothing for a stall or an outage shorter than the hold, else no_view
  // and then ok.
  std::normal_distribution<double> jitter_px(0, 0.7);
  for (const double down_s : {0.0, 1.0, 2.5, 4.0, 8.0, 15.0, 30.0}) {
    int false_changes = 0;
    for (int run = 0; run < kRuns; ++run) {
      WatchState state(WatchOptions{}, pipeline::PlainScale(3.0));
      std::vector<WatchLevel> seen;
      const auto note = [&](bool changed) {
        if (changed) seen.push_back(state.status().level);
      };
      const double t0 = 20 + 10 * std::uniform_real_distribution<double>(0, 1)(rng);
      const double stall_s = std::uniform_real_distribution<double>(0, 4.9)(rng);
      double t = 0;
      for (; t < t0; t += 0.04) note(state.Add(t, FrameView::kStrand, 133.3 + jitter_px(rng)));
      const double last_frame_s = t;
      for (; t < last_frame_s + stall_s; t += 0.1) note(state.Tick(t));
      if (down_s > 0) {
        state.SetSourceUp(false, t);
        for (const double end = t + down_s; t < end; t += 0.1) note(state.Tick(t));
        state.SetSourceUp(true, t);
      }
      for (const double end = t + 20; t < end; t += 0.04)
        note(state.Add(t, FrameView::kStrand, 133.3 + jitter_px(rng)));
      const std::vector<WatchLevel> owed =
          down_s >= WatchOptions{}.hold_s
              ? std::vector<WatchLevel>{WatchLevel::kNoView, WatchLevel::kOk}
              : std::vector<WatchLevel>{};
      false_changes += seen != owed;
    }
    std::cout << "campaign: outage of " << down_s << " s after a stall of 0–4.9 s, " << kRuns
              << " runs: " << false_changes << " with a level change not owed\n";
    EXPECT_EQ(false_changes, 0) << down_s << " s";
  }
}

}  // namespace
}  // namespace clogscope::watch
