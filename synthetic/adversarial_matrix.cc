#include "synthetic/adversarial_matrix.h"

#include <fmt/format.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "synthetic/adversarial_bound.h"
#include "vision/scene/codec_doubt.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::synthetic {
namespace {

constexpr int kStatusCount = vision::kFrameStatusCount;

void Add(ClassSummary* s, const FrameRecord& r) {
  if (s->refusals.empty()) s->refusals.assign(kStatusCount, 0);
  ++s->frames;
  if (r.status == vision::FrameStatus::kValid)
    ++s->valid;
  else
    ++s->refusals[static_cast<int>(r.status)];
  if (r.bound_allows) {
    ++s->allowed;
    if (r.status == vision::FrameStatus::kValid) ++s->allowed_valid;
  }
  if (r.wrong) ++s->wrong;
  if (r.wrong_beyond_sigma) ++s->wrong_beyond_sigma;
}

// Bias and spread over the valid, not-wrong frames of one class (all classes when trouble < 0),
// and error/σ over every width given.
void Moments(const std::vector<FrameRecord>& frames, int trouble, ClassSummary* s) {
  double sum = 0, sum2 = 0, z2 = 0;
  int n = 0, nz = 0;
  for (const auto& r : frames) {
    if (trouble >= 0 && static_cast<int>(r.trouble) != trouble) continue;
    if (!r.strand || !vision::GivesWidth(r.status)) continue;
    const double e = r.width_px - r.truth_px;
    if (r.sigma_px > 0) z2 += std::pow(e / r.sigma_px, 2), ++nz;
    if (r.status != vision::FrameStatus::kValid || r.wrong) continue;
    sum += e;
    sum2 += e * e;
    ++n;
  }
  if (nz > 0) s->error_sigmas_rms = std::sqrt(z2 / nz);
  if (n == 0) return;
  s->bias_px = sum / n;
  s->sd_px = n > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1))) : 0.0;
}

}  // namespace

MatrixResult RunAdversarialMatrix(const MatrixOptions& o) {
  // H.264 round trips go through files: a directory of this run's own, so that two runs (a test
  // and a bench) never share a name.
  namespace fs = std::filesystem;
  std::string own = (fs::temp_directory_path() / "clogscope_adversarial_XXXXXX").string();
  if (o.temp_dir.empty() && !::mkdtemp(own.data()))
    throw std::runtime_error("cannot create a temporary directory under " +
                             fs::temp_directory_path().string());
  const std::string temp = o.temp_dir.empty() ? own : o.temp_dir;
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      std::error_code ec;
      if (!dir.empty()) fs::remove_all(dir, ec);
    }
  } cleanup{o.temp_dir.empty() ? own : std::string()};
  MatrixResult out;
  for (int c = 0; c < kTroubleClassCount; ++c) {
    const auto trouble = static_cast<TroubleClass>(c);
    for (int k = 0; k < o.scenes_per_class; ++k) {
      const uint64_t seed = o.first_seed + k;
      AdversarialScene scene = RandomAdversarialScene(trouble, seed);
      scene.noise_sigma *= o.noise_scale;
      AdversarialTruth truth;
      ClipFacts clip;
      const std::vector<cv::Mat> frames =
          RenderAdversarial(scene, o.frames_per_scene, temp, &truth, &clip);
      const double bound_px = WidthBoundSigmaPx(scene, truth.width_px);
      const bool allows =
          truth.strand &&
          bound_px <= vision::MaxValidSigmaPx(vision::StrandMeasureOptions{}, truth.width_px);
      for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
        const vision::StrandMeasurement m = MeasureAdversarialFrame(frames[i], scene, clip);
        FrameRecord r;
        r.trouble = trouble;
        r.seed = seed;
        r.frame = i;
        r.status = m.status;
        r.detail = m.detail;
        r.truth_px = truth.width_px;
        r.width_px = m.width_px;
        r.sigma_px = m.width_sigma_px;
        r.model_sigma_px = m.model_sigma_px;
        r.codec_sigma_px = m.codec_sigma_px;
        r.doubt = m.doubt;
        r.strand = truth.strand;
        r.bound_sigma_px = bound_px;
        r.bound_allows = allows;
        if (m.valid()) {
          const double err = std::abs(m.width_px - truth.width_px);
          r.wrong = !truth.strand || err > WrongTolerancePx(truth.width_px);
          r.wrong_beyond_sigma =
              r.wrong && (!truth.strand || err > kCoveredSigmas * m.width_sigma_px);
        }
        r.scene = Describe(scene);
        Add(&out.classes[c], r);
        Add(&out.all, r);
        if (r.strand) Add(&out.strands, r);
        out.frames.push_back(std::move(r));
      }
    }
    Moments(out.frames, c, &out.classes[c]);
  }
  Moments(out.frames, -1, &out.all);
  Moments(out.frames, -1, &out.strands);  // Moments counts strand frames only
  return out;
}

vision::StrandMeasureOptions AdversarialMeasureOptions(const AdversarialScene& scene,
                                                       const ClipFacts& clip) {
  vision::StrandMeasureOptions o;
  o.luma_range = clip.luma_range;
  const vision::BandPx band =
      vision::DefaultBand(vision::MeasureTarget::kStrand, scene.scale_um_per_px);
  o.band_start_px = band.start_px;
  o.band_height_px = band.height_px;
  return o;
}

vision::StrandMeasurement MeasureAdversarialFrame(const cv::Mat& frame,
                                                  const AdversarialScene& scene,
                                                  const ClipFacts& clip) {
  const vision::StrandMeasureOptions o = AdversarialMeasureOptions(scene, clip);
  vision::StrandMeasurement m = vision::MeasureStrand(frame, o);
  // Each frame stands alone: its own check.
  if (clip.encoder.found) vision::CodecDoubt(clip.encoder, 1).Apply(frame, o, &m);
  return m;
}

std::string MatrixTable(const MatrixResult& r) {
  std::string t =
      "| class | frames | valid % | bound allows % | valid of those % | confident-wrong % | "
      "of them beyond 4σ | bias px | σ px | error/σ RMS | refused as |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto row = [&](const std::string& name, const ClassSummary& s) {
    std::string why;
    for (int k = 0; k < static_cast<int>(s.refusals.size()); ++k) {
      if (s.refusals[k] == 0) continue;
      why +=
          fmt::format("{}{} {}", why.empty() ? "" : ", ",
                      vision::FrameStatusName(static_cast<vision::FrameStatus>(k)), s.refusals[k]);
    }
    t += fmt::format(
        "| {} | {} | {:.1f} | {:.1f} | {} | {:.2f} | {} | {:+.3f} | {:.3f} | {:.2f} | {} |\n", name,
        s.frames, s.frames ? 100.0 * s.valid / s.frames : 0.0,
        s.frames ? 100.0 * s.allowed / s.frames : 0.0,
        s.allowed ? fmt::format("{:.1f}", 100.0 * s.allowed_valid / s.allowed) : "–",
        s.frames ? 100.0 * s.wrong / s.frames : 0.0, s.wrong_beyond_sigma, s.bias_px, s.sd_px,
        s.error_sigmas_rms, why);
  };
  for (int c = 0; c < kTroubleClassCount; ++c)
    row(TroubleClassName(static_cast<TroubleClass>(c)), r.classes[c]);
  row("**all**", r.all);
  row("**all with a strand**", r.strands);
  return t;
}

}  // namespace clogscope::synthetic
