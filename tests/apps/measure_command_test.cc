// End-to-end tests of `clogscope render` and `clogscope measure`: the binary on a small rendered
// video, its exit codes and one-line errors (the typed pipeline::MeasureInputs behind it:
// tests/pipeline/measure_inputs_test.cc).
#include "apps/measure_command.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "pipeline/measure_inputs.h"
#include "tests/apps/cli_test_util.h"
#include "vision/io/image_codec.h"
#include "vision/io/video_io.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

using testing::RunCli;
using testing::RunResult;

fs::path FreshDir(const std::string& name) { return testing::FreshDir("clogscope_cli_" + name); }

// A small scene: 640x360 frames, the tip at (320, 100), as render's options.
constexpr int kSmallWidthPx = 640, kSmallHeightPx = 360, kSmallTipXPx = 320, kSmallTipYPx = 100;
const std::string kSmall = "--size " + std::to_string(kSmallWidthPx) + "x" +
                           std::to_string(kSmallHeightPx) + " --tip-x-px " +
                           std::to_string(kSmallTipXPx) + " --tip-y-px " +
                           std::to_string(kSmallTipYPx) + " ";

TEST(MeasureCommandTest, VideoEndToEndAgainstTruth) {
  const fs::path d = FreshDir("e2e");
  ASSERT_EQ(RunCli("render --out " + (d / "v.mp4").string() + " --frames 30 --width-jitter-um 3 " +
                       kSmall + "--tilt-deg 4",
                   d)
                .exit_code,
            0);
  const RunResult r =
      RunCli("measure " + (d / "v.mp4").string() + " --scale-um-per-px 3 --out-frames " +
                 (d / "frames.csv").string() + " --overlay " + (d / "ov").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "frames.csv").string()), "frames.csv");
  for (const auto& col : pipeline::FrameCsvColumns()) EXPECT_GE(t.Column(col), 0) << col;
  std::ifstream in(d / "v.truth.json");
  const auto truth = nlohmann::json::parse(in);
  ASSERT_EQ(t.rows.size(), 30u);
  for (const auto& row : t.rows) {
    ASSERT_EQ(row[t.Column("valid")], "1") << row[t.Column("detail")];
    const int frame = std::stoi(row[t.Column("frame")]);
    const double w_um = std::stod(row[t.Column("width_um")]);
    const double truth_um = truth["frames"][frame]["width_um"].get<double>();
    EXPECT_NEAR(w_um, truth_um, 0.15 * 3.0) << "frame " << frame;
    EXPECT_NEAR(std::stod(row[t.Column("width_px")]) * 3.0, w_um, 0.002);
    EXPECT_NEAR(std::stod(row[t.Column("time_s")]), frame / 25.0, 1e-3);
  }
  // Overlays: every 25th video frame by default.
  EXPECT_TRUE(fs::exists(d / "ov" / "v.mp4_000000.png"));
  EXPECT_TRUE(fs::exists(d / "ov" / "v.mp4_000025.png"));
  // Provenance in the header comments.
  const std::string text = ReadFile((d / "frames.csv").string());
  EXPECT_EQ(text.rfind("# clogscope ", 0), 0u);
  EXPECT_NE(text.find("# command "), std::string::npos);
}

// `measure VIDEO` alone, as a new user first types it: the table on standard output (pipeable),
// the log with each input's width summary on standard error.
TEST(MeasureCommandTest, WithoutOutFramesTheTableGoesToStandardOutput) {
  const fs::path d = FreshDir("stdout");
  ASSERT_EQ(RunCli("render --out " + (d / "v.mp4").string() + " --frames 6 " + kSmall, d).exit_code,
            0);
  std::ifstream in(d / "v.truth.json");
  const double truth_px = nlohmann::json::parse(in)["frames"][0]["width_px"].get<double>();
  const RunResult r = RunCli("measure " + (d / "v.mp4").string(), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(r.out, "stdout");
  ASSERT_EQ(t.rows.size(), 6u);
  for (const auto& row : t.rows) {
    EXPECT_EQ(row[t.Column("valid")], "1");
    EXPECT_NEAR(std::stod(row[t.Column("width_px")]), truth_px, 0.15);
  }
  EXPECT_EQ(r.out.find("[info]"), std::string::npos);  // no log lines in the table
  const size_t at = r.err.find("; width ");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_NEAR(std::stod(r.err.substr(at + 8)), truth_px, 0.15) << r.err;
  EXPECT_NE(r.err.find("wrote the table to standard output"), std::string::npos) << r.err;
  // "-" says the same explicitly.
  const RunResult dash = RunCli("measure " + (d / "v.mp4").string() + " --out-frames -", d);
  EXPECT_EQ(ParseCsv(dash.out, "stdout").rows, t.rows);
}

// A filament fed at 3 mm/s past a 30 frames/s camera (MJPEG): every pair after the first has a
// speed, their mean within 1 % of the truth; a featureless filament gets no number, a reason.
// Each row says whether the logged mean used it, and the logged mean is that of those rows.
TEST(MeasureCommandTest, FeedSpeedOfARenderedFilament) {
  const fs::path d = FreshDir("speed");
  const std::string scene =
      "--no-nozzle --scale-um-per-px 20 --strand-width-um 1750 --size 640x480 --tip-x-px 320 "
      "--tip-y-px 0 --fps 30 --frames 20 --feed-speed-mm-s 3";
  for (const char* texture : {"8", "0"}) {
    const std::string video = (d / (std::string("feed") + texture + ".avi")).string();
    RunResult r =
        RunCli("render --out " + video + " --surface-texture " + texture + " " + scene, d);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = RunCli("measure " + video + " --target filament --speed --scale-um-per-px 20", d);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const CsvTable t = ParseCsv(r.out, "stdout");
    ASSERT_EQ(t.rows.size(), 20u);
    const int c_speed = t.Column("filament_speed_mm_s"), c_reason = t.Column("speed_reason"),
              c_baseline = t.Column("speed_baseline_frames"), c_used = t.Column("speed_used"),
              c_left_out = t.Column("speed_left_out");
    ASSERT_GE(c_speed, 0);
    ASSERT_GE(c_left_out, 0);
    EXPECT_EQ(t.rows[0][c_reason], "first_frame");
    EXPECT_EQ(t.rows[0][c_used], "0");
    EXPECT_EQ(t.rows[0][c_left_out], "no_speed");
    double sum = 0, sum_used = 0;
    int n = 0, n_used = 0;
    for (size_t i = 1; i < t.rows.size(); ++i) {
      if (t.rows[i][c_speed].empty()) {
        EXPECT_FALSE(t.rows[i][c_reason].empty());
        EXPECT_EQ(t.rows[i][c_used], "0");
        continue;
      }
      sum += std::stod(t.rows[i][c_speed]);
      ++n;
      if (t.rows[i][c_used] == "1") {
        EXPECT_EQ(t.rows[i][c_left_out], "");
        sum_used += std::stod(t.rows[i][c_speed]);
        ++n_used;
      } else {
        EXPECT_FALSE(t.rows[i][c_left_out].empty());
      }
    }
    if (std::string(texture) == "8") {
      EXPECT_EQ(n, 19);
      EXPECT_NEAR(sum / n, 3.0, 0.03);
      // 5 px per frame: each frame is compared with the one two back (10 px), which the second
      // frame cannot be; its row is left out of the mean.
      EXPECT_EQ(t.rows[1][c_baseline], "1");
      EXPECT_EQ(t.rows[1][c_left_out], "short_baseline");
      EXPECT_EQ(t.rows[5][c_baseline], "2");
      EXPECT_GE(n_used, 16);  // the rest may hold an outlier or two
      EXPECT_NE(r.err.find(std::to_string(n_used) + " of 19 pairs used (1 with a short baseline"),
                std::string::npos)
          << r.err;
      const size_t at = r.err.find("feed speed ");
      ASSERT_NE(at, std::string::npos) << r.err;
      EXPECT_NEAR(std::stod(r.err.substr(at + 11)), sum_used / n_used, 0.00005 + 1e-9) << r.err;
      EXPECT_NEAR(sum_used / n_used, 3.0, 0.015);
    } else {
      EXPECT_EQ(n, 0);
      EXPECT_EQ(t.rows[5][c_reason], "no_texture");
      EXPECT_EQ(t.rows[5][c_left_out], "no_speed");
      EXPECT_NE(r.err.find("no_texture"), std::string::npos) << r.err;
    }
  }
  // --speed needs the filament target and a scale.
  RunResult r =
      RunCli("measure " + (d / "feed8.avi").string() + " --speed --scale-um-per-px 20", d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--target filament"), std::string::npos) << r.err;
  r = RunCli("measure " + (d / "feed8.avi").string() + " --target filament --speed", d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--scale-um-per-px or --calib"), std::string::npos) << r.err;
}

// Slip from the two speeds: the gear's surface runs at 5 mm/s, the filament at 4.5 (10 % slip).
TEST(MeasureCommandTest, GearSpeedAndSlip) {
  const fs::path d = FreshDir("slip");
  const std::string video = (d / "slip.avi").string();
  RunResult r = RunCli(
      "render --out " + video +
          " --no-nozzle --scale-um-per-px 20 --strand-width-um 1750 --size 640x480 --tip-x-px 320 "
          "--tip-y-px 0 --fps 30 --frames 20 --surface-texture 8 --feed-speed-mm-s 4.5 "
          "--drive-gear 176,240,100 --gear-surface-speed-mm-s 5",
      d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string speed = " --target filament --speed --scale-um-per-px 20";
  r = RunCli("measure " + video + speed + " --gear-roi 70,134,213,213 --gear-radius-mm 2", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(r.out, "stdout");
  const int c_gear = t.Column("gear_speed_mm_s"), c_slip = t.Column("slip_pct"),
            c_reason = t.Column("gear_reason");
  ASSERT_GE(c_slip, 0);
  EXPECT_EQ(t.rows[0][c_reason], "first_frame");
  double gear = 0, slip = 0;
  for (size_t i = 1; i < t.rows.size(); ++i) {
    gear += std::stod(t.rows[i][c_gear]) / (t.rows.size() - 1);
    slip += std::stod(t.rows[i][c_slip]) / (t.rows.size() - 1);
  }
  EXPECT_NEAR(gear, 5.0, 0.05);
  EXPECT_NEAR(slip, 10.0, 0.5);
  EXPECT_NE(r.err.find("slip "), std::string::npos) << r.err;
  // A gear ROI needs the gear's radius; the radius needs the ROI.
  r = RunCli("measure " + video + speed + " --gear-roi 70,134,213,213", d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--gear-radius-mm"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  r = RunCli("measure " + video + speed + " --gear-radius-mm 2", d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--gear-roi"), std::string::npos) << r.err;
  // The gear's centre is x,y.
  r = RunCli("measure " + video + speed +
                 " --gear-roi 70,134,213,213 --gear-radius-mm 2 --gear-centre 176,240,1",
             d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--gear-centre '176,240,1': expected x,y"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(MeasureCommandTest, BadInputsGiveOneLineErrorsAndExitCodes) {
  const fs::path d = FreshDir("bad");
  const std::string out = " --out-frames " + (d / "f.csv").string();
  RunResult r = RunCli("measure " + (d / "nope.mp4").string() + out, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nope.mp4: no such file or directory"), std::string::npos) << r.err;

  r = RunCli("measure x.png --scale-um-per-px -3" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--scale-um-per-px"), std::string::npos) << r.err;

  r = RunCli("measure x.png --roi 1,2,3" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--roi"), std::string::npos) << r.err;

  r = RunCli("measure x.png --band-start-um 50" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--scale-um-per-px"), std::string::npos) << r.err;

  // A frame without a strand: measured, reported in its row, exit 1 as nothing could be measured.
  ASSERT_EQ(RunCli("render --out " + (d / "frames").string() +
                       " --size 640x360 --tip-x-px 320 --tip-y-px=-500",
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "frames").string() + out, d);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0][t.Column("reason")], "no_tip");

  // One good input and one missing: the good one is measured, exit 2.
  ASSERT_EQ(RunCli("render --out " + (d / "good").string() + " " + kSmall, d).exit_code, 0);
  r = RunCli("measure " + (d / "good").string() + " " + (d / "missing").string() + out, d);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("missing: no such file"), std::string::npos);

  // An input whose frames are smaller than the ROI is reported and skipped; the good one is
  // measured and the table written (once the whole run ended with no table at all).
  ASSERT_EQ(RunCli("render --out " + (d / "tiny").string() +
                       " --size 160x120 --tip-x-px 80 --tip-y-px 30 --strand-width-um 60",
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "good").string() + " " + (d / "tiny").string() +
                 " --roi 100,50,440,300" + out,
             d);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("tiny"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("outside"), std::string::npos) << r.err;
  const CsvTable both = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  ASSERT_EQ(both.rows.size(), 1u);
  EXPECT_EQ(both.rows[0][both.Column("valid")], "1");

  // Usage errors read like every other error: one line, exit 1 (CLI11 exited 104–114 with two).
  for (const std::string& bad : std::vector<std::string>{"measure --bogus", "measure x.png --roi",
                                                         "render --out r --frames abc"}) {
    r = RunCli(bad, d);
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_EQ(r.err.rfind("clogscope ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }

  r = RunCli("frobnicate", d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("unknown command"), std::string::npos);
}

// Every line of stderr is the tool's own: "clogscope …: …" or "[level] …".
void ExpectOnlyToolLines(const std::string& err) {
  std::istringstream lines(err);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_TRUE(line.empty() || line.rfind("clogscope ", 0) == 0 || line.rfind("[", 0) == 0)
        << "library text: " << line;
  }
}

// Damaged images (libpng and libjpeg complain) and files that would block
// (a FIFO): the decoder's reason inside the tool's one line, nothing else on the terminal.
TEST(MeasureCommandTest, DamagedImagesAndFifosGiveTheToolsOwnLine) {
  const fs::path d = FreshDir("damaged");
  ASSERT_EQ(RunCli("render --out " + (d / "f").string() + " " + kSmall, d).exit_code, 0);
  const std::string png = ReadFile((d / "f" / "frame_000000.png").string());
  const size_t idat = png.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  std::string crc = png;
  crc[idat + 40] ^= 0x5a;  // inside the compressed data
  WriteFileAtomically((d / "crc.png").string(), crc);
  // Every output inside the test's folder (a bare name would land in the working directory).
  const std::string x_csv = " --out-frames " + (d / "x.csv").string();
  RunResult r = RunCli("measure " + (d / "crc.png").string() + x_csv, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("crc.png: cannot decode image (libpng: IDAT: "), std::string::npos) << r.err;
  ExpectOnlyToolLines(r.err);

  // A JPEG cut short decodes with grey where data is missing: refused, not measured.
  std::string why;
  const std::string jpg =
      vision::EncodeImage(".jpg", vision::ReadImage((d / "f" / "frame_000000.png").string(), &why));
  WriteFileAtomically((d / "cut.jpg").string(), jpg.substr(0, jpg.size() * 6 / 10));
  r = RunCli("measure " + (d / "cut.jpg").string() + x_csv, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cut.jpg: damaged image (Premature end of JPEG file)"), std::string::npos)
      << r.err;
  ExpectOnlyToolLines(r.err);

  // Inspect and calibrate read images the same way.
  r = RunCli("inspect " + (d / "crc.png").string() + " --out " + (d / "i.png").string(), d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot decode image (libpng: IDAT: "), std::string::npos) << r.err;
  ExpectOnlyToolLines(r.err);
  r = RunCli("calibrate --micrometer " + (d / "crc.png").string() + " --pitch-um 100 --out " +
                 (d / "c.yaml").string(),
             d);
  EXPECT_EQ(r.exit_code, 1);
  ExpectOnlyToolLines(r.err);

  ASSERT_EQ(::mkfifo((d / "fifo").c_str(), 0600), 0);
  const std::string fifo = (d / "fifo").string();
  for (const std::string& cmd :
       std::vector<std::string>{"measure " + fifo + x_csv, "inspect " + fifo,
                                "measure " + (d / "f").string() + " --calib " + fifo,
                                "calibrate --pins " + fifo + " --out " + (d / "c.yaml").string()}) {
    r = RunCli(cmd, d);
    EXPECT_EQ(r.exit_code, 1) << cmd;
    EXPECT_NE(r.err.find("fifo: not a regular file"), std::string::npos) << cmd << ": " << r.err;
  }
}

// Peak resident memory of one command (run through the shell in a child of a child, so that
// earlier commands of this test do not count), in MB.
double PeakMemoryMb(const std::string& command) {
  int fds[2];
  EXPECT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    const int rc = std::system(command.c_str());
    struct rusage ru {};
    ::getrusage(RUSAGE_CHILDREN, &ru);
    const long kb = rc == 0 ? ru.ru_maxrss : -1;
    (void)!::write(fds[1], &kb, sizeof kb);
    ::_exit(0);
  }
  ::close(fds[1]);
  long kb = -1;
  (void)!::read(fds[0], &kb, sizeof kb);
  ::close(fds[0]);
  ::waitpid(pid, nullptr, 0);
  return kb / 1024.0;
}

// Memory is bounded by the frame size the tool accepts, not by what a small file claims.
TEST(MeasureCommandTest, LargeFramesAreBoundedOrRefused) {
  const fs::path d = FreshDir("large");
  const std::string bin = CLOGSCOPE_BINARY;
  // The largest frames measured: a 4096x4096 H.264 video (under 0.2 MB) stays under 500 MB.
  ASSERT_EQ(RunCli("render --out " + (d / "big.mp4").string() +
                       " --size 4096x4096 --frames 2 --tip-x-px 2048 --tip-y-px 1000",
                   d)
                .exit_code,
            0);
  ASSERT_LT(fs::file_size(d / "big.mp4"), 1u << 20);
  const double mb = PeakMemoryMb(bin + " measure " + (d / "big.mp4").string() + " --out-frames " +
                                 (d / "f.csv").string() + " 2>/dev/null");
  EXPECT_GT(mb, 0) << "measure failed";
#if !defined(CLOGSCOPE_SANITIZED)  // ASan's shadow memory and quarantine are not the tool's
  EXPECT_LT(mb, 500) << "peak memory measuring 4096x4096 frames";
#endif
  std::printf("peak memory measuring 4096x4096 H.264: %.0f MB\n", mb);
  // A 0.3 MB stream of such frames with 16 reference frames (testdata/video/refs16_4096.mp4):
  // refused once the decoder's frames pass 128 MB, still under 500 MB in all (800 MB before).
  const std::string refs16 = std::string(CLOGSCOPE_TESTDATA_DIR) + "/video/refs16_4096.mp4";
  const std::string x_csv = " --out-frames " + (d / "x.csv").string();
  RunResult r = RunCli("measure " + refs16 + x_csv, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("refs16_4096.mp4: decoding would hold over 128 MB of frames"),
            std::string::npos)
      << r.err;
  const double refs16_mb =
      PeakMemoryMb(bin + " measure " + refs16 + x_csv + " 2>/dev/null || true");
#if !defined(CLOGSCOPE_SANITIZED)
  EXPECT_LT(refs16_mb, 500) << "peak memory refusing a 16-reference-frame 4096x4096 stream";
#endif
  std::printf("peak memory refusing 16 reference frames of 4096x4096: %.0f MB\n", refs16_mb);
  // One row more each way is refused before decoding.
  ASSERT_EQ(RunCli("render --out " + (d / "over.mp4").string() +
                       " --size 4112x4096 --frames 1 --tip-x-px 2048 --tip-y-px 1000",
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "over.mp4").string() + x_csv, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("over.mp4: frames are 4112x4096 (16.8 Mpx), over the 16.8 Mpx"),
            std::string::npos)
      << r.err;
  // A PNG whose header claims 40000x40000 (what follows does not matter): refused, not allocated.
  ASSERT_EQ(RunCli("render --out " + (d / "small").string() + " " + kSmall, d).exit_code, 0);
  std::string png = ReadFile((d / "small" / "frame_000000.png").string());
  const unsigned char claim[8] = {0, 0, 0x9c, 0x40, 0, 0, 0x9c, 0x40};  // 40000, 40000
  png.replace(16, 8, reinterpret_cast<const char*>(claim), 8);
  WriteFileAtomically((d / "claims.png").string(), png);
  r = RunCli("inspect " + (d / "claims.png").string() + " --out " + (d / "i.png").string(), d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("claims.png: frames are 40000x40000"), std::string::npos) << r.err;
}

// `measure --manifest` measures with the options given beside it (as the step files record them),
// and refuses, in one line, those that mean nothing for a manifest; none is silently dropped.
TEST(MeasureCommandTest, ManifestModeTakesTheMeasurementOptions) {
  const fs::path d = FreshDir("manifest_options");
  ASSERT_EQ(RunCli("render --out " + (d / "v.mp4").string() + " --frames 8 " + kSmall, d).exit_code,
            0);
  WriteFileAtomically((d / "m.yaml").string(),
                      "samples: 2\nroi: 0,0,640,360\nsteps:\n"
                      "  - {step: 1, temperature_c: 200, video: v.mp4}\n");
  const std::string manifest = "measure --manifest " + (d / "m.yaml").string() + " --out ";
  const auto spec_of = [&](const fs::path& out) {
    return nlohmann::json::parse(ReadFile((out / "steps" / "step_0001.json").string()))["spec"];
  };
  // In px, with the caliper, blur, contrast and shading options and an overlay folder.
  const fs::path a = d / "a";
  RunResult r = RunCli(manifest + a.string() +
                           " --scale-um-per-px 3 --roi 10,20,600,330 --polarity dark "
                           "--band-start-px 10 --band-height-px 40 --caliper-px 3 "
                           "--max-blur-px 5 --min-contrast 20 --no-shading --overlay " +
                           (d / "ov").string(),
                       d);
  ASSERT_TRUE(fs::exists(a / "steps" / "step_0001.json")) << r.err;
  nlohmann::json spec = spec_of(a);
  EXPECT_EQ(spec["roi"], nlohmann::json({10, 20, 600, 330}));
  EXPECT_EQ(spec["polarity"], static_cast<int>(vision::Polarity::kDarkOnBright));
  EXPECT_EQ(spec["target"], static_cast<int>(vision::MeasureTarget::kStrand));
  EXPECT_EQ(spec["band_px"], nlohmann::json({10.0, 40.0}));
  EXPECT_EQ(spec["caliper_spacing_px"], 3.0);
  EXPECT_EQ(spec["max_blur_px"], 5.0);
  EXPECT_NEAR(spec["min_contrast_fraction"].get<double>(), 20 / 255.0, 1e-12);
  EXPECT_EQ(spec["shading"], false);
  EXPECT_TRUE(fs::is_directory(d / "ov"));
  EXPECT_FALSE(fs::exists(a / "overlays") && !fs::is_empty(a / "overlays"));
  // In µm through the scale, and the target; the manifest's ROI stays when none is given.
  const fs::path b = d / "b";
  r = RunCli(manifest + b.string() +
                 " --scale-um-per-px 2 --band-start-um 30 --band-height-um 120 --target filament",
             d);
  ASSERT_TRUE(fs::exists(b / "steps" / "step_0001.json")) << r.err;
  spec = spec_of(b);
  EXPECT_EQ(spec["roi"], nlohmann::json({0, 0, 640, 360}));
  EXPECT_EQ(spec["target"], static_cast<int>(vision::MeasureTarget::kFilament));
  EXPECT_EQ(spec["band_px"], nlohmann::json({15.0, 60.0}));
  // Options of the per-frame mode: refused by name, nothing measured.
  for (const std::string option :
       {"--speed", "--out-frames f.csv", "--overlay-every 2", "--no-outlier-flags",
        "--gear-roi 1,2,30,40", "--gear-radius-mm 2", "--speed-max-shift-px 9"}) {
    const fs::path c = d / "c";
    r = RunCli(manifest + c.string() + " " + option, d);
    EXPECT_EQ(r.exit_code, 1) << option;
    EXPECT_NE(r.err.find(option.substr(0, option.find(' ')) + ": "), std::string::npos)
        << option << ": " << r.err;
    EXPECT_NE(r.err.find("--manifest"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(c / "steps")) << option;
  }
}

// One 12000x12000 JPEG inside an MJPEG stream of small frames: that frame is reported (its size in
// its row) and skipped, the others measured; `watch` goes on too. A stream whose frames together
// would take too much memory ends with one line naming the right sizes, never an abort.
TEST(MeasureCommandTest, AnOversizedFrameInsideAVideoIsSkipped) {
  const fs::path d = FreshDir("oversized_frame");
  ASSERT_EQ(RunCli("render --out " + (d / "a.avi").string() + " --frames 4 " + kSmall, d).exit_code,
            0);
  const auto ffmpeg = [](const std::string& args) {
    return std::system(("ffmpeg -nostdin -v error -y " + args).c_str());
  };
  ASSERT_EQ(
      ffmpeg("-i " + (d / "a.avi").string() + " -c:v copy -f mjpeg " + (d / "a.mjpeg").string()),
      0);
  ASSERT_EQ(ffmpeg("-f lavfi -i color=c=gray:s=12000x12000 -frames:v 1 -f mjpeg " +
                   (d / "big.jpg").string()),
            0);
  const std::string small = ReadFile((d / "a.mjpeg").string());
  WriteFileAtomically((d / "raw.mjpeg").string(),
                      small + ReadFile((d / "big.jpg").string()) + small);
  ASSERT_EQ(ffmpeg("-f mjpeg -framerate 25 -i " + (d / "raw.mjpeg").string() + " -c:v copy -r 25 " +
                   (d / "v.avi").string()),
            0);
  RunResult r =
      RunCli("measure " + (d / "v.avi").string() + " --out-frames " + (d / "f.csv").string(), d);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  ASSERT_EQ(t.rows.size(), 9u) << r.err;
  for (const auto& row : t.rows) {
    const bool big = row[t.Column("frame")] == "4";
    EXPECT_EQ(row[t.Column("valid")], big ? "0" : "1") << row[t.Column("detail")];
    if (!big) continue;
    EXPECT_EQ(row[t.Column("reason")], "unreadable");
    EXPECT_NE(row[t.Column("detail")].find("12000x12000"), std::string::npos)
        << row[t.Column("detail")];
  }
  r = RunCli("watch " + (d / "v.avi").string() + " --log " + (d / "w.log").string(), d);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  // Sixteen reference frames of 4096x4096: ends with one line, the frames' own size in it.
  const std::string refs16 = std::string(CLOGSCOPE_TESTDATA_DIR) + "/video/refs16_4096.mp4";
  r = RunCli("watch " + refs16 + " --log " + (d / "w2.log").string(), d);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("refs16_4096.mp4: decoding would hold over 128 MB of frames (4096x4096"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace clogscope::apps
