// clogscope_bench adversarial [SCENES_PER_CLASS] [--first-seed N] [--noise-scale F] [--list]
//                             [--frames-tsv PATH]:
// the adversarial matrix (issue 22): every trouble class rendered by synthetic/adversarial.cc,
// 4 frames a scene, measured with the default options; valid %, the share of frames whose
// Cramér–Rao bound lets a valid width be measured at all and how many of those are valid,
// confident-wrong %, bias and σ by class. Seeds from N (default 1: the slow test's scenes; another
// N gives scenes no one tuned for); every scene's noise times F (default 1; below 1 shows biases
// the noise hid). H.264 clips are read as `measure` reads a video (docs/accuracy.md, *How the
// matrix reads H.264*). --list prints every frame that was confidently wrong, with its scene;
// --frames-tsv writes every frame (class, seed, frame, status, width, σ and its parts, truth,
// bound σ, scene, reason) for analysis.
#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <string>

#include "common/atomic_file.h"
#include "synthetic/adversarial_matrix.h"
#include "vision/scene/frame_status.h"

namespace {
// Text as one TSV field: tabs and line breaks as spaces.
std::string OneField(std::string text) {
  for (char& c : text)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return text;
}
}  // namespace

void BenchAdversarial(int argc, char** argv) {
  namespace syn = clogscope::synthetic;
  syn::MatrixOptions o;
  bool list = false;
  std::string tsv_path;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--list")
      list = true;
    else if (a == "--first-seed" && i + 1 < argc)
      o.first_seed = std::max(1L, std::atol(argv[++i]));
    else if (a == "--frames-tsv" && i + 1 < argc)
      tsv_path = argv[++i];
    else if (a == "--noise-scale" && i + 1 < argc)
      o.noise_scale = std::max(0.0, std::atof(argv[++i]));
    else
      o.scenes_per_class = std::max(1, std::atoi(a.c_str()));
  }
  const auto t0 = std::chrono::steady_clock::now();
  const syn::MatrixResult r = syn::RunAdversarialMatrix(o);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print(
      "\n## Adversarial matrix: {} scenes per class × {} frames, seeds from {}, noise × {} "
      "({:.0f} s)\n\n",
      o.scenes_per_class, o.frames_per_scene, o.first_seed, o.noise_scale, secs);
  fmt::print(
      "Confident-wrong: valid but off by more than max({} px, {} %) (or any width where "
      "there is no strand). Bias and σ over the other valid frames. Bound allows: the "
      "Cramér–Rao bound on the width's σ (camera blur and noise, the strand's cross-section) is "
      "within what a valid width may carry. Error/σ RMS: over every width given (valid or "
      "imprecise), 1 for an honest σ.\n\n",
      syn::kWrongPx, 100 * syn::kWrongFraction);
  fmt::print("{}", syn::MatrixTable(r));
  if (!tsv_path.empty()) {
    std::string tsv =
        "class\tseed\tframe\tstatus\twidth_px\tsigma_px\tmodel_sigma_px\tcodec_sigma_px\t"
        "spread_px\tshading_px\tcylinder_px\ttip_px\tstructure_px\ttwo_slope_px\tmissing_px\t"
        "inner_level_px\tedge_blur_px\tone_edge_px\t"
        "truth_px\twrong\tbound_sigma_px\tscene\tdetail\n";
    for (const auto& f : r.frames) {
      const clogscope::vision::WidthDoubt& d = f.doubt;
      tsv += fmt::format(
          "{}\t{}\t{}\t{}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t"
          "{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{:.4f}\t{}\t{:.4f}\t{}\t{}\n",
          syn::TroubleClassName(f.trouble), f.seed, f.frame,
          f.status == clogscope::vision::FrameStatus::kValid
              ? "valid"
              : clogscope::vision::FrameStatusName(f.status),
          f.width_px, f.sigma_px, f.model_sigma_px, f.codec_sigma_px, d.spread_px, d.shading_px,
          d.cylinder_px, d.tip_px, d.structure_px, d.two_slope_px, d.missing_px, d.inner_level_px,
          d.edge_blur_px, d.one_edge_px, f.truth_px, f.wrong ? 1 : 0, f.bound_sigma_px,
          OneField(f.scene), OneField(f.detail));
    }
    clogscope::WriteFileAtomically(tsv_path, tsv);
  }
  if (!list) return;
  fmt::print("\n### Confidently wrong frames\n");
  for (const auto& f : r.frames) {
    if (!f.wrong) continue;
    fmt::print("- {} frame {}: {:.2f} ± {:.3f} px, truth {:.2f} px\n", f.scene, f.frame, f.width_px,
               f.sigma_px, f.truth_px);
  }
}
