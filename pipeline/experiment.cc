#include "pipeline/experiment.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/plot.h"
#include "common/provenance.h"
#include "common/robust.h"
#include "common/work_queue.h"
#include "pipeline/feedstock_io.h"
#include "pipeline/statistics.h"
#include "pipeline/step_file.h"
#include "vision/io/frame_source.h"
#include "vision/io/video_io.h"
#include "vision/overlay/overlay.h"
#include "vision/scene/track.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Floor on the MAD of a step's widths: identical widths must not make 0.01 px an outlier.
constexpr double kMinMadPx = 0.02;

void Summarise(StepResult* r, const ExperimentOptions& o) {
  FrameWidths widths;
  std::vector<FrameRecord*> valid;
  for (auto& f : r->frames) {
    if (f.m.valid()) {
      widths.Add(f.m.width_px, f.m.width_sigma_px, f.m.model_sigma_px);
      valid.push_back(&f);
    }
  }
  r->n_valid = static_cast<int>(widths.width.size());
  if (widths.width.empty()) {
    r->status = model::StepStatus::kFailed;
    if (r->detail.empty()) r->detail = "no valid frame";
    return;
  }
  const WidthStats st = RobustWidthStats(widths, o.outlier_mad_k, kMinMadPx);
  for (size_t i = 0; i < valid.size(); ++i) valid[i]->used = st.used[i];
  r->n_used = st.n_used;
  r->n_rejected = st.n_rejected;
  r->mean_px = st.mean;
  r->std_px = st.std;
  if (o.conversion) {
    const auto& c = *o.conversion;
    r->has_um = true;
    r->mean_um = c.ToMicrons(st.mean);
    r->std_um = st.std * c.scale_um_per_px;
    r->sem_um = st.sem * c.scale_um_per_px;
    r->ci95_um = MeanCi95Um(st, c, &r->cal_sigma_um);
  }
  r->status = r->n_valid >= o.samples ? model::StepStatus::kOk : model::StepStatus::kTooFewFrames;
  if (r->status == model::StepStatus::kTooFewFrames) {
    r->detail = fmt::format("{} valid of {} asked ({} frames examined)", r->n_valid, o.samples,
                            r->n_examined);
  }
  if (st.frames_repeat) {
    r->detail += (r->detail.empty() ? "" : "; ") + RepeatDetail(st);
  }
  for (auto& f : r->frames) f.fields = FrameFields(f.source, f.frame, f.time_s, f.m, o.conversion);
}

}  // namespace

bool ExperimentOptions::Validate(std::string* why) const {
  if (samples < 2)
    *why = "samples: need at least 2";
  else if (jobs < 0)
    *why = "jobs: must not be negative";
  else if (out_dir.empty())
    *why = "an output directory is required";
  else if (!strand.Validate(why))
    return false;
  else
    return true;
  return false;
}

double MeanCi95Um(const WidthStats& st, const calib::ScaleCalibration& c, double* cal_sigma_um) {
  *cal_sigma_um = std::hypot((st.mean - c.edge_bias_px) * c.scale_sigma_um_per_px,
                             c.scale_um_per_px * c.edge_bias_sigma_px);
  const double own = st.n_used >= 2 ? st.ci95_half_width : NAN;
  return std::hypot(own * c.scale_um_per_px, kZ95 * *cal_sigma_um);
}

calib::ScaleCalibration PlainScale(double scale) {
  calib::ScaleCalibration c;
  c.usable = true;
  c.method = "given";
  c.scale_um_per_px = scale;
  return c;
}

const std::vector<std::string>& FrameColumns() {
  static const std::vector<std::string> kColumns = {
      "source",   "frame",          "time_s",         "valid",    "width_px", "width_sigma_px",
      "width_um", "width_sigma_um", "angle_deg",      "contrast", "blur_px",  "tip_x_px",
      "tip_y_px", "calipers_used",  "calipers_total", "polarity", "reason",   "detail"};
  return kColumns;
}

std::vector<std::string> FrameFields(const std::string& source, int frame, double time_s,
                                     const vision::StrandMeasurement& m,
                                     const std::optional<calib::ScaleCalibration>& conv) {
  const bool ok = m.valid();
  auto num = [&](double v, int d) { return ok ? CsvNumber(v, d) : std::string(); };
  auto geo = [&](double v, int d) { return m.has_geometry ? CsvNumber(v, d) : std::string(); };
  // Empty when no strand decided it (an unread frame, none in view): "auto" is only a request.
  const bool polarity_known =
      m.status != vision::FrameStatus::kNoStrand && m.polarity != vision::Polarity::kAuto;
  return {source,
          std::to_string(frame),
          time_s >= 0 ? CsvNumber(time_s, 4) : "",
          ok ? "1" : "0",
          num(m.width_px, 4),
          num(m.width_sigma_px, 4),
          conv ? num(conv->ToMicrons(m.width_px), 3) : "",
          conv ? num(conv->MicronsSigma(m.width_px, m.width_sigma_px), 3) : "",
          geo(m.angle_deg, 3),
          geo(m.contrast, 1),
          geo(m.blur_px, 3),
          geo(m.tip_x_px, 2),
          geo(m.tip_y_px, 2),
          std::to_string(m.calipers_used),
          std::to_string(m.calipers_total),
          polarity_known ? vision::PolarityName(m.polarity) : "",
          vision::FrameStatusName(m.status),
          m.detail};
}

static StepResult FailedStep(const StepSpec& spec, std::string detail) {
  StepResult r;
  r.spec = spec;
  r.status = model::StepStatus::kFailed;
  r.detail = std::move(detail);
  return r;
}

StepResult MeasureStep(const StepSpec& spec, const ExperimentOptions& o, int decoder_threads,
                       std::vector<std::pair<int, cv::Mat>>* overlay_frames) {
  StepResult r;
  r.spec = spec;
  std::unique_ptr<vision::FrameSource> frames;
  const bool video = !spec.video.empty();
  double a = 0, b = 0;  // the settled part: [a, b) in seconds (video) or image index
  try {
    if (video) {
      vision::VideoReadOptions vo;
      vo.decoder_threads = decoder_threads;
      vo.gap_entries = false;  // a step samples the frames decoded
      frames = vision::FrameSource::OpenVideo(spec.video, vo);
      const double duration = frames->duration_s();
      const double end = spec.end_s >= 0 ? spec.end_s : duration;
      a = spec.start_s + spec.settle_s;
      b = duration > 0 ? std::min(end, duration) : end;
    } else {
      frames = vision::FrameSource::OpenImageFolder(spec.images);
      a = 0;
      b = static_cast<double>(frames->expected_frames());
    }
  } catch (const std::invalid_argument& e) {
    r.status = model::StepStatus::kFailed;
    r.detail = e.what();
    return r;
  }
  if (!(b > a)) {
    r.status = model::StepStatus::kFailed;
    r.detail =
        fmt::format("nothing left after start {:g} s and settle {:g} s (source ends at {:g})",
                    spec.start_s, spec.settle_s, b);
    return r;
  }
  // A step's time: a video's seconds, or an image's index (a folder has no clock).
  const double period = !video ? 1.0 : frames->fps() > 0 ? 1.0 / frames->fps() : 0.04;
  const auto seek_to = [&](double t) {
    if (video)
      frames->SeekToTime(t);
    else
      frames->SeekToFrame(static_cast<int64_t>(std::max(0.0, std::floor(t))));
  };

  // N slots; in each, frames from the slot's middle on are measured until one is valid.
  const int n = o.samples;
  const double slot = (b - a) / n;
  std::vector<bool> filled(n, false);
  const std::vector<int> overlay_slots = {0, n / 2, n - 1};
  if (a > vision::kSeekAheadS) seek_to(a);
  vision::InputFrame in;
  // The step's frames show one scene: follow the strand from sample to sample.
  vision::StrandTracker tracker(o.strand);
  tracker.SetEncoder(frames->encoder());
  while (frames->Next(&in)) {
    const double t = video ? in.time_s : static_cast<double>(in.index);
    const cv::Mat& img = in.image;
    if (o.cancel && o.cancel->load()) break;
    if (t < a - 1e-9) continue;
    if (t >= b - 1e-9) break;
    const int k = std::min(n - 1, static_cast<int>((t - a) / slot));
    // A frame stands for [t − period/2, t + period/2): it may serve a slot whose middle it covers.
    if (filled[k] || t + 0.5 * period < a + (k + 0.5) * slot - 1e-6) continue;
    FrameRecord f;
    f.source = in.source;
    f.frame = static_cast<int>(in.index);
    f.time_s = video ? t : -1;
    if (img.empty()) {
      f.m.status = vision::FrameStatus::kUnreadable;
      f.m.detail = "cannot decode";
    } else {
      f.m = tracker.Measure(in);
    }
    ++r.n_examined;
    if (f.m.valid()) {
      filled[k] = true;
      if (overlay_frames &&
          std::find(overlay_slots.begin(), overlay_slots.end(), k) != overlay_slots.end() &&
          static_cast<int>(overlay_frames->size()) < o.overlays_per_step) {
        overlay_frames->push_back({static_cast<int>(r.frames.size()), img.clone()});
      }
    }
    r.frames.push_back(std::move(f));
    // Jump ahead when the next empty slot is far: decoding to it would cost more than a seek.
    int next = k;
    while (next < n && filled[next]) ++next;
    if (next >= n) break;
    const double target = a + (next + 0.5) * slot;
    if (target - t > vision::kSeekAheadS) seek_to(target);
  }
  Summarise(&r, o);
  return r;
}

std::vector<StepResult> RunExperiment(const Manifest& m, const ExperimentOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const fs::path out(o.out_dir), steps_dir = out / "steps";
  const fs::path overlay_dir = o.overlay_dir.empty() ? out / "overlays" : fs::path(o.overlay_dir);
  std::error_code ec;
  fs::create_directories(steps_dir, ec);
  fs::create_directories(overlay_dir, ec);
  if (!fs::is_directory(steps_dir))
    throw std::invalid_argument(o.out_dir + ": cannot create output directory");

  const int total = static_cast<int>(m.steps.size());
  std::vector<std::optional<StepResult>> results(total);
  std::vector<int> todo;
  for (int i = 0; i < total; ++i) {
    const std::string file = (steps_dir / StepFileName(m.steps[i].step)).string();
    if (o.resume && fs::exists(file)) {
      // A step that failed last time (say, its video was missing), was measured another way or
      // whose file does not add up is measured again.
      StepResult r;
      std::string why;
      std::string text;
      try {
        text = ReadFile(file);
      } catch (const std::exception&) {
      }
      if (ReadStepFile(text, m.steps[i], o, &r, &why)) {
        results[i] = std::move(r);
        continue;
      }
    }
    todo.push_back(i);
  }
  std::mutex mu;
  int done = 0;
  for (int i = 0; i < total; ++i) {
    if (!results[i]) continue;
    ++done;
    if (o.on_step) o.on_step(*results[i], done, total);
  }
  const int jobs =
      std::max(1, std::min<int>(o.jobs > 0 ? o.jobs : std::thread::hardware_concurrency(),
                                static_cast<int>(todo.size())));
  // With several steps at once each decoder gets one thread; a lone step lets FFmpeg choose.
  const int decoder_threads = jobs > 1 ? 1 : 0;
  // One step from its frames to its step file; whatever goes wrong in it is its own.
  const auto run_step = [&](int i) {
    std::vector<std::pair<int, cv::Mat>> overlays;
    // Whatever goes wrong in one step (a library error, no memory, a full disk) fails that
    // step with its reason; the other steps, the tables and the summary still get done.
    StepResult r;
    try {
      r = MeasureStep(m.steps[i], o, decoder_threads, &overlays);
      const StepSpec& s = m.steps[i];
      if (o.feedstock && !s.feedstock_video.empty()) {
        try {
          r.feedstock =
              MeasureFeedstock(s.feedstock_video, s.start_s + s.settle_s, s.end_s, *o.feedstock);
        } catch (const std::exception& e) {
          // The strand's diameter stands without the feedstock's.
          r.feedstock = FeedstockResult{};
          r.feedstock->status = FeedstockStatus::kFailed;
          r.feedstock->detail = e.what();
          r.feedstock->video = s.feedstock_video;
        }
      }
    } catch (const std::exception& e) {
      r = FailedStep(m.steps[i], fmt::format("measuring stopped: {}", e.what()));
    } catch (...) {
      r = FailedStep(m.steps[i], "measuring stopped: unknown error");
    }
    if (o.cancel && o.cancel->load()) return;  // a partial step is not kept
    std::vector<std::string> unsaved;
    try {
      for (const auto& [frame_idx, image] : overlays) {
        const FrameRecord& f = r.frames[frame_idx];
        const std::string name =
            (overlay_dir / fmt::format("step{:02d}_{:.0f}C_f{:06d}.png", r.spec.step,
                                       r.spec.temperature_c, f.frame))
                .string();
        const double scale = o.conversion ? o.conversion->scale_um_per_px : 0.0;
        const double bias = o.conversion ? o.conversion->edge_bias_px : 0.0;
        vision::WriteImageAtomically(name, vision::DrawOverlay(image, f.m, scale, bias));
      }
    } catch (const std::exception& e) {
      unsaved.push_back(fmt::format("overlay not written: {}", e.what()));
    }
    try {
      WriteFileAtomically((steps_dir / StepFileName(r.spec.step)).string(), StepFileText(r, o));
    } catch (const std::exception& e) {
      unsaved.push_back(
          fmt::format("step file not written (--resume will measure it again): {}", e.what()));
    }
    // The measurement stands; the step's detail says what could not be saved.
    for (const auto& u : unsaved) r.detail += (r.detail.empty() ? "" : "; ") + u;
    std::lock_guard<std::mutex> lock(mu);
    ++done;
    if (o.on_step) o.on_step(r, done, total);
    results[i] = std::move(r);
  };
  // Steps are taken in manifest order; each reports as it finishes. Cancelling stops taking new
  // steps; an error that escapes a step (a callback's) reaches the caller after the others end.
  ParallelFor(
      todo.size(), jobs, [&](size_t j) { run_step(todo[j]); }, o.cancel);
  std::vector<StepResult> out_results;
  for (auto& r : results) {
    if (r) out_results.push_back(std::move(*r));
  }
  return out_results;
}

std::vector<std::string> WriteExperimentTables(const Manifest& m,
                                               const std::vector<StepResult>& results,
                                               const ExperimentOptions& o,
                                               std::vector<std::string>* warnings) {
  const fs::path out(o.out_dir);
  const Provenance prov = CurrentProvenance();
  std::string conv_line;
  if (o.conversion) {
    conv_line = fmt::format(
        "# conversion ({}): scale {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} ± {:.4f} px\n",
        o.conversion->method, o.conversion->scale_um_per_px, o.conversion->scale_sigma_um_per_px,
        o.conversion->edge_bias_px, o.conversion->edge_bias_sigma_px);
  }
  std::vector<std::string> written;
  // Per-frame rows of every step.
  std::string frames = ProvenanceCsvComment(prov) + conv_line;
  std::vector<std::string> cols = {"step"};
  cols.insert(cols.end(), FrameColumns().begin(), FrameColumns().end());
  cols.push_back("used");
  frames += CsvLine(cols) + "\n";
  for (const auto& r : results) {
    for (const auto& f : r.frames) {
      std::vector<std::string> row = {std::to_string(r.spec.step)};
      row.insert(row.end(), f.fields.begin(), f.fields.end());
      row.push_back(f.used ? "1" : "0");
      frames += CsvLine(row) + "\n";
    }
  }
  WriteFileAtomically((out / "frames.csv").string(), frames);
  written.push_back((out / "frames.csv").string());

  // The diameter table; with feedstock, its columns after the strand's.
  const bool feedstock = std::any_of(results.begin(), results.end(),
                                     [](const StepResult& r) { return r.feedstock.has_value(); });
  std::string table = ProvenanceCsvComment(prov) + conv_line;
  table +=
      "step,temperature_c,n,mean_um,std_um,sem_um,ci95_um,cal_sigma_um,mean_px,std_px,n_rejected,"
      "n_valid,n_examined,status,detail";
  if (feedstock) table += "," + CsvLine(FeedstockColumns());
  table += "\n";
  json rows = json::array();
  for (const auto& r : results) {
    const bool have = r.n_used > 0;
    auto um = [&](double v, int d) { return have && r.has_um ? CsvNumber(v, d) : std::string(); };
    std::vector<std::string> cells = {std::to_string(r.spec.step),
                                      CsvNumber(r.spec.temperature_c, kTableTemperatureDecimals),
                                      std::to_string(r.n_used),
                                      um(r.mean_um, kTableUmDecimals),
                                      um(r.std_um, kTableUmDecimals),
                                      um(r.sem_um, kTableUmDecimals),
                                      um(r.ci95_um, kTableUmDecimals),
                                      um(r.cal_sigma_um, kTableUmDecimals),
                                      have ? CsvNumber(r.mean_px, 4) : "",
                                      have ? CsvNumber(r.std_px, 4) : "",
                                      std::to_string(r.n_rejected),
                                      std::to_string(r.n_valid),
                                      std::to_string(r.n_examined),
                                      model::StepStatusName(r.status),
                                      r.detail};
    if (feedstock) {
      const std::vector<std::string> f =
          r.feedstock ? FeedstockFields(*r.feedstock)
                      : std::vector<std::string>(FeedstockColumns().size(), "");
      cells.insert(cells.end(), f.begin(), f.end());
    }
    table += CsvLine(cells) + "\n";
    json row = {{"step", r.spec.step},
                {"temperature_c", r.spec.temperature_c},
                {"n", r.n_used},
                {"mean_px", have ? json(r.mean_px) : json()},
                {"std_px", have ? json(r.std_px) : json()},
                {"n_rejected", r.n_rejected},
                {"n_valid", r.n_valid},
                {"n_examined", r.n_examined},
                {"status", model::StepStatusName(r.status)},
                {"detail", r.detail},
                {"source", r.spec.video.empty() ? r.spec.images : r.spec.video}};
    if (r.feedstock) row["feedstock"] = FeedstockJson(*r.feedstock);
    if (have && r.has_um) {
      row["mean_um"] = r.mean_um;
      row["std_um"] = r.std_um;
      row["sem_um"] = r.sem_um;
      row["ci95_um"] = r.ci95_um;
      row["cal_sigma_um"] = r.cal_sigma_um;
    }
    rows.push_back(row);
  }
  WriteFileAtomically((out / "diameters.csv").string(), table);
  written.push_back((out / "diameters.csv").string());
  json j = {{"provenance",
             {{"version", prov.version},
              {"created_utc", prov.created_utc},
              {"command_line", prov.command_line}}},
            {"experiment", m.name},
            {"manifest", m.path},
            {"samples", o.samples},
            {"steps", rows}};
  if (o.conversion) {
    j["conversion"] = {{"method", o.conversion->method},
                       {"scale_um_per_px", o.conversion->scale_um_per_px},
                       {"scale_sigma_um_per_px", o.conversion->scale_sigma_um_per_px},
                       {"edge_bias_px", o.conversion->edge_bias_px},
                       {"edge_bias_sigma_px", o.conversion->edge_bias_sigma_px}};
  }
  WriteFileAtomically((out / "diameters.json").string(),
                      j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  written.push_back((out / "diameters.json").string());

  // Diameter against temperature with 95 % error bars.
  PlotSeries s{"effective diameter, 95 % CI", {}, {}, {}, ""};
  for (const auto& r : results) {
    if (r.n_used == 0) continue;
    s.x.push_back(r.spec.temperature_c);
    s.y.push_back(r.has_um ? r.mean_um : r.mean_px);
    s.y_error.push_back(r.has_um ? r.ci95_um : 0.0);
  }
  if (!s.x.empty()) {
    PlotSpec spec;
    spec.title =
        fmt::format("{}: effective nozzle diameter, {} samples per step", m.name, o.samples);
    spec.x_label = "temperature (°C)";
    spec.y_label = results.front().has_um ? "diameter (µm)" : "width (px)";
    spec.series.push_back(s);
    std::string why;
    const std::string png = (out / "diameter_vs_temperature.png").string();
    if (PlotToPng(spec, png, &why)) {
      written.push_back(png);
    } else {
      warnings->push_back("diameter_vs_temperature.png not drawn: " + why);
    }
  }
  return written;
}

double TableValue(double value, int decimals) {
  return std::strtod(CsvNumber(value, decimals).c_str(), nullptr);
}

}  // namespace clogscope::pipeline
