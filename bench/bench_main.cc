// clogscope_bench: the speed and accuracy figures quoted in issue closing notes.
//   clogscope_bench [measure|accuracy|video|experiment|lag|speed|speed-codec [FIRST_SEED]|watch|
//                    watch-farm|adversarial [SCENES_PER_CLASS] [--list]|filament VIDEO|all] [--pi]
//                    (default all)
// --pi adds, beside every frames/s of `measure` and `video`, what a Raspberry Pi 5 and 4 would
// give on one core (this machine's figure ÷ 3 and ÷ 4) and whether that keeps up with 30 frames/s.
// Prints Markdown tables. Timings are wall-clock on this machine; run on an idle machine.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "bench/decode_timing.h"
#include "bench/pi_budget.h"
#include "common/robust.h"
#include "common/spawn.h"
#include "model/lag_fit.h"
#include "pipeline/experiment.h"
#include "pipeline/speed_summary.h"
#include "synthetic/synthetic.h"
#include "vision/io/frame_source.h"
#include "vision/io/video_decoder.h"
#include "vision/motion/feed_speed.h"
#include "vision/motion/gear_speed.h"
#include "vision/scene/batch.h"
#include "vision/scene/strand_measure.h"
#include "vision/scene/track.h"

namespace {

using clogscope::Median;
using clogscope::bench::DecodeOnlyFps;
using clogscope::bench::PiCells;
using clogscope::bench::TableHead;
using clogscope::synthetic::FrameTruth;
using clogscope::synthetic::SceneParams;
using clogscope::vision::MeasureStrand;
using clogscope::vision::StrandMeasureOptions;
using clogscope::vision::StrandTracker;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Runs a program (the ffmpeg CLI) without a shell, its output discarded; true when it exited 0.
bool RunQuietly(std::vector<std::string> argv) {
  clogscope::SpawnOptions o;
  o.argv = std::move(argv);
  o.stdout_path = o.stderr_path = "/dev/null";
  std::string why;
  const pid_t pid = clogscope::Spawn(o, &why);
  return pid > 0 && clogscope::WaitForExit(pid, &why);
}

// Words of a fixed argument string of ours ("-c:v mjpeg -q:v 8"): no quoting to honour.
std::vector<std::string> Words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// Single-core throughput of MeasureStrand on 720p frames.
void BenchMeasure() {
  fmt::print("\n## Measurement alone, 1280x720, one core\n\n{}",
             TableHead("| frames | frames/s | ms/frame |", "|---|---|---|"));
  for (bool colour : {false, true}) {
    SceneParams p;
    p.colour = colour;
    p.width_jitter_um = 2;
    std::vector<cv::Mat> frames;
    for (int i = 0; i < 16; ++i) frames.push_back(RenderFrame(p, i, nullptr));
    StrandMeasureOptions opt;
    // Each frame searched afresh (MeasureStrand, images), and a video's frames tracked.
    for (bool tracked : {false, true}) {
      StrandTracker tracker(opt);
      int n = 0, valid = 0;
      const auto t0 = Clock::now();
      while (Seconds(t0, Clock::now()) < 3.0) {
        for (const auto& f : frames)
          valid += (tracked ? tracker.Measure(f) : MeasureStrand(f, opt)).valid(), ++n;
      }
      const double s = Seconds(t0, Clock::now());
      fmt::print("| {}, {} ({} of {} valid) | {:.0f} | {:.3f} |{}\n",
                 colour ? "colour BGR" : "grey", tracked ? "tracked" : "found afresh", valid, n,
                 n / s, 1000 * s / n, PiCells(n / s));
    }
  }
}

struct Scenario {
  std::string name;
  SceneParams p;
  double target_px;
};

// Mean and spread of the width error against the rendered truth, per scenario.
void BenchAccuracy() {
  std::vector<Scenario> sc;
  SceneParams ref;
  sc.push_back({"reference (blur 1.5, noise 3, contrast 160)", ref, 0.05});
  for (double tilt : {-20.0, -10.0, 10.0, 20.0}) {
    SceneParams p;
    p.tilt_deg = tilt;
    sc.push_back({fmt::format("tilt {:+.0f}°", tilt), p, 0.1});
  }
  {
    SceneParams p;
    p.highlight = true;
    sc.push_back({"highlight stripe", p, 0.1});
    p = SceneParams();
    p.gradient_fraction = 0.3;
    p.gradient_angle_deg = 30;
    sc.push_back({"illumination gradient 30 %", p, 0.1});
    p = SceneParams();
    p.SetSilhouette();
    sc.push_back({"silhouette (dark on backlight)", p, 0.1});
    p = SceneParams();
    p.blur_sigma_px = 3;
    sc.push_back({"blur 3 px", p, 0.1});
    p = SceneParams();
    p.tilt_deg = -20;
    p.blur_sigma_px = 3;
    p.SetSilhouette();
    p.highlight = true;
    p.gradient_fraction = 0.3;
    sc.push_back({"all: tilt -20°, blur 3, silhouette, highlight, gradient", p, 0.1});
    p = SceneParams();
    p.tilt_deg = 20;
    p.blur_sigma_px = 3;
    p.highlight = true;
    p.gradient_fraction = -0.3;
    sc.push_back({"all: tilt +20°, blur 3, bright, highlight, gradient", p, 0.1});
    p = SceneParams();
    p.bed = true;
    p.tilt_deg = 10;
    sc.push_back({"bed 0.2 mm below tip, tilt 10°", p, 0.1});
    p = SceneParams();
    p.colour = true;
    sc.push_back({"colour frame", p, 0.05});
  }
  fmt::print(
      "\n## Accuracy against rendered truth (1280x720, 3 µm/px, 400 µm strand), 40 frames "
      "each\n\n");
  fmt::print(
      "| scenario | valid | mean error px | std px | max abs px | target |mean| px "
      "|\n|---|---|---|---|---|---|\n");
  for (auto& s : sc) {
    double s1 = 0, s2 = 0, mx = 0;
    int valid = 0;
    const int n = 40;
    for (int i = 0; i < n; ++i) {
      s.p.seed = 1000 + i;
      FrameTruth t;
      const auto m = MeasureStrand(RenderFrame(s.p, 0, &t), {});
      if (!m.valid()) continue;
      const double e = m.width_px - t.width_px;
      s1 += e;
      s2 += e * e;
      mx = std::max(mx, std::abs(e));
      ++valid;
    }
    const double mean = s1 / std::max(valid, 1);
    const double sd = std::sqrt(std::max(0.0, s2 / std::max(valid, 1) - mean * mean));
    fmt::print("| {} | {}/{} | {:+.4f} | {:.4f} | {:.4f} | {} |\n", s.name, valid, n, mean, sd, mx,
               s.target_px);
  }
}

// `measure` on a 10 s 720p H.264 video against decoding alone, in the same run.
void BenchVideo() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "clogscope_bench";
  fs::create_directories(dir);
  const std::string path = (dir / "bench_720p.mp4").string();
  SceneParams p;
  p.width_jitter_um = 2;
  p.sway_deg = 0.3;
  const auto truth = clogscope::synthetic::RenderSequence(p, 250, 25.0, path, "");

  auto measure = [&]() {
    auto src = clogscope::vision::FrameSource::Open(path);
    StrandMeasureOptions opt;
    double s1 = 0, s2 = 0;
    int valid = 0;
    const auto t0 = Clock::now();
    const int n = clogscope::vision::MeasureFrames(
        *src, opt, [&](clogscope::vision::InputFrame& f, clogscope::vision::StrandMeasurement& m) {
          if (!m.valid()) return;
          const double e = m.width_px - truth[f.index].width_px;
          s1 += e;
          s2 += e * e;
          ++valid;
        });
    const double secs = Seconds(t0, Clock::now());
    const double mean = s1 / std::max(valid, 1);
    return std::make_tuple(n, secs, valid, mean,
                           std::sqrt(std::max(0.0, s2 / valid - mean * mean)));
  };
  // Alternate the passes and take medians: single passes of 250 frames vary by ±30 % here.
  constexpr int kRounds = 5;
  const int measure_threads = clogscope::vision::DecoderThreadsBesideMeasuring();
  std::vector<double> dec_fps, dec_as_measure_fps, meas_fps;
  int n = 0, valid = 0;
  double mean = 0, sd = 0;
  for (int r = 0; r < kRounds; ++r) {
    // Decoding alone with FFmpeg's threads (a thread per core), and as `measure` opens the file
    // (a core left to measuring).
    dec_fps.push_back(DecodeOnlyFps(path, 0));
    dec_as_measure_fps.push_back(DecodeOnlyFps(path, measure_threads));
    double ms = 0;
    std::tie(n, ms, valid, mean, sd) = measure();
    meas_fps.push_back(n / ms);
  }
  const double decode_fps = Median(dec_fps), measure_fps = Median(meas_fps);
  const double decode_as_measure_fps = Median(dec_as_measure_fps);
  fmt::print("\n## Video: 250 frames 1280x720 H.264 (libx264, crf 23), 2 cores, median of {}\n\n",
             kRounds);
  fmt::print("{}", TableHead("| pass | frames/s |", "|---|---|"));
  fmt::print("| decode only, clogscope reader (luma), FFmpeg's threads | {:.0f} |{}\n", decode_fps,
             PiCells(decode_fps));
  fmt::print(
      "| decode only, clogscope reader as `measure` opens it ({} decoder thread{}) | {:.0f} |{}\n",
      measure_threads, measure_threads == 1 ? "" : "s", decode_as_measure_fps,
      PiCells(decode_as_measure_fps));
  fmt::print("| decode + measure (clogscope pipeline, as `measure`) | {:.0f} |{}\n", measure_fps,
             PiCells(measure_fps));
  fmt::print(
      "\nmeasure / decode-only throughput: **{:.2f}** with the reader as `measure` opens it, "
      "{:.2f} against FFmpeg's threads; width error on these frames: mean {:+.4f} px, std {:.4f} "
      "px "
      "({} valid of {})\n",
      measure_fps / decode_as_measure_fps, measure_fps / decode_fps, mean, sd, valid, n);
  // ffmpeg's own decode, start-up subtracted (a 1-frame run measures it).
  auto ffmpeg_secs = [&](std::vector<std::string> frames) {
    std::vector<std::string> argv = {"ffmpeg", "-nostdin", "-v", "error", "-i", path};
    argv.insert(argv.end(), frames.begin(), frames.end());
    argv.insert(argv.end(), {"-f", "null", "-"});
    const auto t0 = Clock::now();
    return RunQuietly(argv) ? Seconds(t0, Clock::now()) : -1.0;
  };
  const double all = ffmpeg_secs({}), one = ffmpeg_secs({"-frames:v", "1"});
  if (all > 0 && one > 0 && all > one) {
    fmt::print("ffmpeg -f null decode of the same file (start-up subtracted): {:.0f} frames/s\n",
               249 / (all - one));
  }
}

// The batch job of the pipeline issue: six 10 s 720p H.264 step videos, 50 samples per step, two
// steps at a time, against decoding every frame once.
void BenchExperiment() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "clogscope_bench" / "experiment";
  fs::create_directories(dir);
  const double diams[] = {400.0, 396.9, 390.1, 381.3, 365.9, 345.4};
  clogscope::pipeline::Manifest m;
  m.name = "bench";
  m.path = (dir / "bench.yaml").string();
  std::vector<std::string> videos;
  for (int i = 0; i < 6; ++i) {
    const std::string path = (dir / fmt::format("step{}.mp4", i + 1)).string();
    if (!fs::exists(path)) {
      SceneParams p;
      p.strand_width_um = diams[i];
      p.width_jitter_um = 2;
      p.sway_deg = 0.3;
      p.seed = i + 1;
      clogscope::synthetic::RenderSequence(p, 250, 25.0, path, "");
    }
    videos.push_back(path);
    clogscope::pipeline::StepSpec s;
    s.step = i + 1;
    s.temperature_c = 220 - 10 * i;
    s.video = path;
    m.steps.push_back(s);
  }
  const int frames_total = 6 * 250;
  // Decoding every frame once: our reader (one file after another, FFmpeg's threads), and ffmpeg.
  auto decode_all = [&](int threads) {
    const auto t0 = Clock::now();
    int n = 0;
    for (const auto& v : videos) {
      clogscope::vision::VideoDecoder dec(v, threads);
      clogscope::vision::DecodedFrame f;
      while (dec.Read(&f)) ++n;
    }
    return std::make_pair(n, Seconds(t0, Clock::now()));
  };
  std::vector<std::string> ff_argv = {"ffmpeg", "-nostdin", "-v", "error"};
  for (const auto& v : videos) ff_argv.insert(ff_argv.end(), {"-i", v});
  for (size_t i = 0; i < videos.size(); ++i)
    ff_argv.insert(ff_argv.end(), {"-map", fmt::format("{}:v", i), "-f", "null", "-"});
  auto run_pipeline = [&](int jobs) {
    clogscope::pipeline::ExperimentOptions o;
    o.samples = 50;
    o.jobs = jobs;
    o.out_dir = (dir / "out").string();
    o.conversion = clogscope::pipeline::PlainScale(3.0);
    o.overlays_per_step = 0;
    const auto t0 = Clock::now();
    const auto r = clogscope::pipeline::RunExperiment(m, o);
    const double secs = Seconds(t0, Clock::now());
    int examined = 0;
    double worst = 0;
    for (size_t i = 0; i < r.size(); ++i) {
      examined += r[i].n_examined;
      worst = std::max(worst, std::abs(r[i].mean_um - diams[i]));
    }
    return std::make_tuple(secs, examined, worst);
  };
  constexpr int kRounds = 3;
  std::vector<double> ours_all, ours_one, ff, pipe2, pipe1;
  int examined = 0;
  double worst = 0;
  for (int r = 0; r < kRounds; ++r) {
    ours_all.push_back(decode_all(0).second);
    ours_one.push_back(decode_all(1).second);
    const auto t0 = Clock::now();
    if (RunQuietly(ff_argv)) ff.push_back(Seconds(t0, Clock::now()));
    double s2 = 0, s1 = 0;
    std::tie(s2, examined, worst) = run_pipeline(2);
    pipe2.push_back(s2);
    std::tie(s1, std::ignore, std::ignore) = run_pipeline(1);
    pipe1.push_back(s1);
  }
  fmt::print(
      "\n## Experiment: six 10 s 1280x720 H.264 steps ({} frames), 50 samples per step, median of "
      "{}\n\n",
      frames_total, kRounds);
  fmt::print("| job | wall s | frames/s (of all {} frames) |\n|---|---|---|\n", frames_total);
  auto row = [&](const std::string& name, double s) {
    fmt::print("| {} | {:.3f} | {:.0f} |\n", name, s, frames_total / s);
  };
  row("decode every frame once: ffmpeg -f null (all six files, its default threads, incl. "
      "start-up)",
      Median(ff));
  row("decode every frame once: clogscope reader, FFmpeg's threads", Median(ours_all));
  row("decode every frame once: clogscope reader, one thread", Median(ours_one));
  row("measure the experiment: clogscope, 2 steps at a time (--jobs 2)", Median(pipe2));
  row("measure the experiment: clogscope, 1 step at a time (--jobs 1)", Median(pipe1));
  fmt::print("\nframes measured: {} of {}; worst |step mean − rendered diameter|: {:.2f} µm\n",
             examined, frames_total, worst);
}

// Extrusion lag from rendered frames: the strand's width follows the lagged outlet flow of a
// flow-step profile (25 frames/s, 2 µm of width jitter per frame); measured, then K fitted. Over
// 20 renders per K: the error of the mean, and the spread of K against the mean reported σ.
void BenchLag() {
  namespace model = clogscope::model;
  fmt::print(
      "\n## Extrusion lag K from rendered video (640x480, 25 frames/s, 175 frames, 2 µm width "
      "jitter)\n\nRendered: 20 renders, each measured and fitted; the measurement's own share is "
      "K(measured widths) − K(the rendered true widths). σ check: 300 series of true widths (no "
      "rendering), spread of K over mean σ.\n\n| K s | mean K s | error | measurement's share s "
      "(rms) | spread / σ, 20 renders | spread / σ, 300 series | fit ms |\n"
      "|---|---|---|---|---|---|---|\n");
  const model::FlowProfile profile =
      model::ProfileFromMoves({0, 1.0, 2.5, 4.0, 5.5}, {5, 10, 6, 11, 5});
  std::vector<double> times;
  for (int i = 0; i < 175; ++i) times.push_back(i / 25.0);
  auto ratio = [](const std::vector<double>& ks, const std::vector<double>& sigmas) {
    double mean = 0, mean_sigma = 0, var = 0;
    for (size_t i = 0; i < ks.size(); ++i) {
      mean += ks[i] / ks.size();
      mean_sigma += sigmas[i] / ks.size();
    }
    for (double x : ks) var += (x - mean) * (x - mean) / (ks.size() - 1);
    return std::make_pair(mean, std::sqrt(var) / mean_sigma);
  };
  for (double k : {0.1, 0.5}) {
    std::vector<double> ks, sigmas, truth_ks, truth_sigmas, fit_s;
    double share2 = 0;
    int unusable = 0;
    for (int seed = 1; seed <= 300; ++seed) {
      SceneParams p;
      p.width_px = 640;
      p.height_px = 480;
      p.tip_x_px = 320;
      p.tip_y_px = 120;
      p.width_jitter_um = 2;
      p.seed = seed;
      for (double q : model::OutletFlow(profile, k, 0.0, times)) p.frame_width_um.push_back(40 * q);
      std::vector<model::WidthSample> truth;
      for (int i = 0; i < 175; ++i) truth.push_back({times[i], FrameTruthFor(p, i).width_um});
      const auto tf = model::FitLag(profile, truth, model::LagFitOptions{});
      if (!tf.usable) ++unusable;
      truth_ks.push_back(tf.k_s);
      truth_sigmas.push_back(tf.k_sigma_s);
      if (seed > 20) continue;
      StrandTracker tracker(StrandMeasureOptions{});
      std::vector<model::WidthSample> widths;
      for (int i = 0; i < 175; ++i) {
        const auto m = tracker.Measure(RenderFrame(p, i, nullptr));
        if (m.valid()) widths.push_back({times[i], m.width_px * p.scale_um_per_px});
      }
      const auto t0 = Clock::now();
      const auto fit = model::FitLag(profile, widths, model::LagFitOptions{});
      fit_s.push_back(Seconds(t0, Clock::now()));
      if (!fit.usable) {
        fmt::print("K {} seed {}: {}\n", k, seed, fit.message);
        ++unusable;
        continue;
      }
      ks.push_back(fit.k_s);
      sigmas.push_back(fit.k_sigma_s);
      share2 += (fit.k_s - tf.k_s) * (fit.k_s - tf.k_s);
    }
    const auto [mean, rendered_ratio] = ratio(ks, sigmas);
    const auto [truth_mean, truth_ratio] = ratio(truth_ks, truth_sigmas);
    std::sort(fit_s.begin(), fit_s.end());
    fmt::print("| {:.1f} | {:.5f} | {:+.2f} % | {:.6f} | {:.2f} | {:.2f} | {:.1f} |\n", k, mean,
               100 * (mean - k) / k, std::sqrt(share2 / ks.size()), rendered_ratio, truth_ratio,
               1e3 * fit_s[fit_s.size() / 2]);
    if (unusable > 0) fmt::print("({} fits not usable)\n", unusable);
  }
}

// Filament feed speed (640x480, 20 µm/px, 30 frames/s, surface texture ±8 grey levels under noise
// σ 3): the error of the mean speed over 60 frame pairs as `measure --speed` logs it (the rows the
// summary uses), the rows' spread, and what the speed adds per frame on one core
// (FeedSpeedTracker::Next after the width measurement).
void BenchFeedSpeed() {
  cv::setNumThreads(1);
  fmt::print(
      "\n## Filament feed speed (640x480, 20 µm/px, 30 frames/s, 60 pairs, one core)\n\n"
      "| speed mm/s | tilt ° | mean mm/s | error | 95 % half-width mm/s | per-row sd mm/s | rows "
      "used | ms per frame |\n|---|---|---|---|---|---|---|---|\n");
  for (auto [v, tilt] :
       std::vector<std::pair<double, double>>{{0, 0}, {0.5, 0}, {2, 0}, {5, 0}, {15, 0}, {2, 7}}) {
    SceneParams p = clogscope::synthetic::FeedstockScene(v);
    p.tilt_deg = tilt;
    StrandMeasureOptions o;
    o.target = clogscope::vision::MeasureTarget::kFilament;
    StrandTracker tracker(o);
    clogscope::vision::FeedSpeedTracker speed(clogscope::vision::FeedSpeedOptions{});
    std::vector<clogscope::vision::FeedSpeedSample> rows;
    double seconds = 0;
    for (int i = 0; i <= 60; ++i) {
      FrameTruth t;
      const cv::Mat f = RenderFrame(p, i, &t);
      const auto m = tracker.Measure(f);
      const auto t0 = Clock::now();
      rows.push_back(speed.Next(f, t.time_s, m));
      seconds += Seconds(t0, Clock::now());
    }
    const auto st = clogscope::pipeline::SummariseFeedSpeeds(rows);
    const double mm_per_px = p.scale_um_per_px * 1e-3, mean = st.mean_px_per_s * mm_per_px;
    fmt::print(
        "| {:g} | {:g} | {:.4f} | {} | {:.4f} | {:.4f} | {} of {} | {:.3f} |\n", v, tilt, mean,
        v > 0 ? fmt::format("{:+.2f} %", 100 * (mean - v) / v) : fmt::format("{:+.4f} mm/s", mean),
        st.ci95_px_per_s * mm_per_px, st.std_px_per_s * mm_per_px, st.used, st.pairs,
        1e3 * seconds / 61);
  }
}

// Gear surface speed and slip: a 20-tooth gear of 2 mm tip radius beside the filament, the
// filament at (1 − slip) of the gear's surface speed; 30 pairs each. The slip's mean, as `measure`
// logs it, is over the rows whose feed speed the summary uses.
void BenchSlip() {
  cv::setNumThreads(1);
  fmt::print(
      "\n## Gear surface speed and slip (640x480, 20 µm/px, 30 frames/s, 30 pairs, one core)\n\n"
      "| gear mm/s | slip % | gear mean mm/s | gear error | slip mean % | slip error pp | gear ms "
      "per frame |\n|---|---|---|---|---|---|---|\n");
  for (double vg : {0.5, 5.0, 15.0}) {
    for (double slip : {0.0, 10.0, 20.0}) {
      const SceneParams p = clogscope::synthetic::FeedstockScene(vg * (1 - slip / 100), vg);
      StrandMeasureOptions o;
      o.target = clogscope::vision::MeasureTarget::kFilament;
      StrandTracker tracker(o);
      clogscope::vision::FeedSpeedTracker feed(clogscope::vision::FeedSpeedOptions{});
      clogscope::vision::GearSpeedOptions go;
      go.roi = cv::Rect(70, 134, 213, 213);
      go.outer_radius_px = 100;
      clogscope::vision::GearSpeedTracker gear(go);
      std::vector<clogscope::vision::FeedSpeedSample> feeds;
      std::vector<clogscope::vision::GearSpeedSample> gears;
      double seconds = 0;
      for (int i = 0; i <= 30; ++i) {
        FrameTruth t;
        const cv::Mat f = RenderFrame(p, i, &t);
        feeds.push_back(feed.Next(f, t.time_s, tracker.Measure(f)));
        const auto t0 = Clock::now();
        gears.push_back(gear.Next(f, t.time_s));
        seconds += Seconds(t0, Clock::now());
      }
      const auto used = clogscope::pipeline::SummariseFeedSpeeds(feeds).use;
      double gear_sum = 0, slip_sum = 0;
      int n_gear = 0, n_slip = 0;
      for (size_t i = 0; i < feeds.size(); ++i) {
        if (!gears[i].valid) continue;
        const double g = std::abs(gears[i].RadPerS()) * 2.0;  // R = 2 mm
        gear_sum += g;
        ++n_gear;
        if (used[i] != clogscope::pipeline::SpeedUse::kUsed) continue;
        slip_sum += 100 * (1 - feeds[i].SpeedPxPerS() * p.scale_um_per_px * 1e-3 / g);
        ++n_slip;
      }
      fmt::print("| {:g} | {:g} | {:.4f} | {:+.2f} % | {:.3f} | {:+.3f} | {:.2f} |\n", vg, slip,
                 gear_sum / n_gear, 100 * (gear_sum / n_gear - vg) / vg, slip_sum / n_slip,
                 slip_sum / n_slip - slip, 1e3 * seconds / 31);
    }
  }
}

// One codec of the feed-speed bench: RenderSequence's own encoders (VideoFileWriter at its
// fixed settings) or, with ffmpeg_args, the ffmpeg CLI on a lossless render (a camera's settings).
struct SpeedCodec {
  std::string name, extension, ffmpeg_args;
};

// Renders the feedstock scene at speed_mm_s through `codec` (frames at 30 frames/s) into dir.
std::string RenderFeed(const SpeedCodec& codec, double speed_mm_s, uint64_t seed, int frames,
                       const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  SceneParams p = clogscope::synthetic::FeedstockScene(speed_mm_s);
  p.seed = seed;
  const std::string video = (dir / fmt::format("feed{}", codec.extension)).string();
  if (codec.ffmpeg_args.empty()) {
    clogscope::synthetic::RenderSequence(p, frames, 30, video, "");
    return video;
  }
  const fs::path frames_dir = dir / "png";
  fs::remove_all(frames_dir);
  clogscope::synthetic::RenderSequence(p, frames, 30, frames_dir.string(), "");
  std::vector<std::string> argv = {"ffmpeg", "-nostdin", "-v",
                                   "error",  "-y",       "-framerate",
                                   "30",     "-i",       (frames_dir / "frame_%06d.png").string()};
  for (std::string& w : Words(codec.ffmpeg_args)) argv.push_back(std::move(w));
  argv.push_back(video);
  if (!RunQuietly(argv)) throw std::runtime_error(video + ": ffmpeg could not encode it");
  fs::remove_all(frames_dir);
  return video;
}

// What `measure --speed` reports for a video: the tracked filament, the feed speed of every frame.
std::vector<clogscope::vision::FeedSpeedSample> MeasureFeedVideo(const std::string& video) {
  auto source = clogscope::vision::FrameSource::Open(video);
  StrandMeasureOptions o;
  o.target = clogscope::vision::MeasureTarget::kFilament;
  clogscope::vision::FeedSpeedTracker speed(clogscope::vision::FeedSpeedOptions{});
  std::vector<clogscope::vision::FeedSpeedSample> rows;
  clogscope::vision::MeasureFrames(
      *source, o, [&](clogscope::vision::InputFrame& f, clogscope::vision::StrandMeasurement& m) {
        rows.push_back(speed.Next(f.image, f.time_s, m));
      });
  return rows;
}

// Feed speed through real codecs (640x480, 20 µm/px, 30 frames/s, 61 frames per render): per codec
// and speed over seeds first_seed…, the error of the mean that `measure --speed` logs, how often
// its 95 % interval covers the rendered speed, and how the rows' σ match their errors.
void BenchFeedSpeedCodec(int first_seed) {
  namespace fs = std::filesystem;
  cv::setNumThreads(1);
  const fs::path dir = fs::temp_directory_path() / "clogscope_bench" / "speed_codec";
  fs::create_directories(dir);
  const std::vector<SpeedCodec> codecs = {
      {"MJPEG (RenderSequence: FFmpeg mjpeg, quantiser 3)", ".avi", ""},
      {"MJPEG -q:v 8 (ffmpeg)", ".avi", "-c:v mjpeg -q:v 8"},
      {"H.264 crf 23 (RenderSequence: libx264)", ".mp4", ""},
      {"MPEG-4 part 2 -q:v 5 (ffmpeg)", ".avi", "-c:v mpeg4 -q:v 5"},
  };
  const std::vector<double> speeds = {0.3, 0.8, 2, 5, 15};
  constexpr int kSeeds = 6, kFrames = 61;
  const double kMmPerPx = clogscope::synthetic::FeedstockScene(0).scale_um_per_px / 1e3;
  fmt::print(
      "\n## Feed speed through codecs (640x480, 20 µm/px, 30 frames/s, {} frames, seeds {}-{} "
      "per row)\n\nError: the logged mean against the rendered speed (mean over seeds, worst); "
      "tolerance 0.5 % + 0.005 mm/s; covered: the logged 95 % interval holds the truth; row "
      "error/σ: rms over the used rows of (row speed − truth) / its σ as the CSV gives it.\n\n"
      "| codec | speed mm/s | mean error | worst error | within tolerance | covered | mean 95 % "
      "half-width | row error/σ rms | rows used |\n|---|---|---|---|---|---|---|---|---|\n",
      kFrames, first_seed, first_seed + kSeeds - 1);
  int all_cases = 0, all_within = 0, all_covered = 0;
  const auto t0 = Clock::now();
  for (const SpeedCodec& codec : codecs) {
    int codec_cases = 0, codec_covered = 0;
    for (double v : speeds) {
      double sum_err = 0, worst = 0, sum_ci = 0, sum_z2 = 0;
      int within = 0, covered = 0, used = 0, pairs = 0;
      for (int seed = first_seed; seed < first_seed + kSeeds; ++seed) {
        const std::string video = RenderFeed(codec, v, seed, kFrames, dir);
        const auto rows = MeasureFeedVideo(video);
        fs::remove(video);
        const clogscope::pipeline::FeedSpeedSummary st =
            clogscope::pipeline::SummariseFeedSpeeds(rows);
        const double mean_mm_s = st.mean_px_per_s * kMmPerPx;
        const double ci_mm_s = st.ci95_px_per_s * kMmPerPx;
        const double err_mm_s = mean_mm_s - v, err_pct = 100 * err_mm_s / v;
        sum_err += err_pct;
        if (std::abs(err_pct) > std::abs(worst)) worst = err_pct;
        within += std::abs(err_mm_s) <= 0.005 * v + 0.005;
        covered += std::abs(err_mm_s) <= ci_mm_s;
        sum_ci += 100 * ci_mm_s / v;
        used += st.used;
        pairs += st.pairs;
        for (size_t i = 0; i < rows.size(); ++i) {
          if (st.use[i] != clogscope::pipeline::SpeedUse::kUsed) continue;
          const double z =
              (rows[i].SpeedPxPerS() * kMmPerPx - v) / (st.RowSigmaPxPerS(rows[i]) * kMmPerPx);
          sum_z2 += z * z;
        }
      }
      fmt::print(
          "| {} | {:g} | {:+.3f} % | {:+.3f} % | {} of {} | {} of {} | {:.3f} % | {:.2f} | {} of "
          "{} |\n",
          codec.name, v, sum_err / kSeeds, worst, within, kSeeds, covered, kSeeds, sum_ci / kSeeds,
          std::sqrt(sum_z2 / std::max(used, 1)), used, pairs);
      codec_cases += kSeeds;
      codec_covered += covered;
      all_cases += kSeeds;
      all_within += within;
      all_covered += covered;
    }
    fmt::print("| {}: all speeds | | | | | {} of {} ({:.0f} %) | | | |\n", codec.name,
               codec_covered, codec_cases, 100.0 * codec_covered / codec_cases);
  }
  fmt::print(
      "\nAll {} cases: {} within tolerance, 95 % interval covers the truth in {} ({:.0f} %); "
      "{:.0f} "
      "s\n",
      all_cases, all_within, all_covered, 100.0 * all_covered / all_cases,
      Seconds(t0, Clock::now()));
}

}  // namespace

void BenchWatch();                             // watch_bench.cc
void BenchWatchFarm();                         // watch_farm_bench.cc
void BenchFilament(const std::string& video);  // filament_bench.cc
void BenchAdversarial(int argc, char** argv);  // adversarial_bench.cc

int main(int argc, char** argv) {
  // --pi may stand anywhere; the rest is positional.
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (i > 0 && std::string(argv[i]) == "--pi")
      clogscope::bench::EnablePiColumns();
    else
      args.push_back(argv[i]);
  }
  argc = static_cast<int>(args.size());
  argv = args.data();
  const std::string what = argc > 1 ? argv[1] : "all";
  if (what != "all" && what != "measure" && what != "accuracy" && what != "video" &&
      what != "experiment" && what != "lag" && what != "speed" && what != "speed-codec" &&
      what != "watch" && what != "watch-farm" && what != "adversarial" &&
      !(what == "filament" && argc > 2)) {
    std::fprintf(
        stderr,
        "usage: clogscope_bench [measure|accuracy|video|experiment|lag|speed|speed-codec "
        "[FIRST_SEED]|watch|watch-farm|adversarial [SCENES_PER_CLASS] [--list]|filament VIDEO|all] "
        "[--pi]\n");
    return 2;
  }
  fmt::print("# clogscope benchmarks ({} hardware threads)\n", std::thread::hardware_concurrency());
  if (what == "all" || what == "measure") BenchMeasure();
  if (what == "all" || what == "accuracy") BenchAccuracy();
  if (what == "all" || what == "video") BenchVideo();
  if (what == "all" || what == "experiment") BenchExperiment();
  if (what == "all" || what == "lag") BenchLag();
  if (what == "all" || what == "speed") {
    BenchFeedSpeed();
    BenchSlip();
  }
  // speed-codec [first seed]: other seeds check that the figures are not those seeds' luck.
  if (what == "all" || what == "speed-codec")
    BenchFeedSpeedCodec(what == "speed-codec" && argc > 2 ? std::atoi(argv[2]) : 1);
  if (what == "all" || what == "watch") BenchWatch();
  if (what == "all" || what == "watch-farm") BenchWatchFarm();
  if (what == "all" || what == "adversarial") BenchAdversarial(argc, argv);
  if (what == "filament") {
    // A video of one's own: a file that cannot be read is one line and exit 1.
    try {
      BenchFilament(argv[2]);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "clogscope_bench filament: error: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}
