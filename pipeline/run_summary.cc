#include "pipeline/run_summary.h"

#include <fmt/format.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/provenance.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

std::string Summary(const ManifestRunReport& rep, const Provenance& prov) {
  std::string md = fmt::format("# {}\n\nclogscope {} — {} — `{}`\n\n", rep.manifest.name,
                               prov.version, prov.created_utc, prov.command_line);
  if (rep.conversion) {
    md += fmt::format("Pixel scale ({}): {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} ± {:.4f} px.\n\n",
                      rep.conversion->method, rep.conversion->scale_um_per_px,
                      rep.conversion->scale_sigma_um_per_px, rep.conversion->edge_bias_px,
                      rep.conversion->edge_bias_sigma_px);
  } else {
    md += "No pixel scale: widths in px only.\n\n";
  }
  md +=
      "| step | T °C | n | mean µm | ± 95 % CI µm | std µm | rejected | status "
      "|\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rep.steps) {
    md += fmt::format("| {} | {:g} | {} | {} | {} | {} | {} | {}{} |\n", r.spec.step,
                      r.spec.temperature_c, r.n_used,
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.mean_um) : "",
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.ci95_um) : "",
                      r.has_um && r.n_used ? fmt::format("{:.2f}", r.std_um) : "", r.n_rejected,
                      model::StepStatusName(r.status), r.detail.empty() ? "" : ": " + r.detail);
  }
  bool feedstock_header = false;
  for (const auto& r : rep.steps) {
    if (!r.feedstock) continue;
    if (!feedstock_header) md += "\n## Feedstock (95 % CI)\n\n";
    feedstock_header = true;
    md += fmt::format("- step {}: {}\n", r.spec.step, FeedstockLine(*r.feedstock));
  }
  if (rep.prediction) {
    const auto& pr = rep.prediction->prediction;
    md += fmt::format(
        "\n## Predicted bar-mount vibration ({})\n\n| step | D µm | F_bp N | A/A0 | +% "
        "|{}\n|---|---|---|---|---|{}\n",
        rep.prediction->params.origin, pr.gain_m_s2_per_n ? " A m/s² |" : "",
        pr.gain_m_s2_per_n ? "---|" : "");
    for (const auto& s : pr.steps) {
      md += fmt::format("| {} | {:.1f} | {:.3f} | {:.4f} | {:.1f} |{}\n", s.step, s.diameter_um,
                        s.f_bp_n, s.relative_amplitude, s.amplitude_increase_pct,
                        s.amplitude_m_s2 ? fmt::format(" {:.4f} |", *s.amplitude_m_s2) : "");
    }
  }
  md += "\n## Files\n\n";
  for (const auto& f : rep.files) md += "- " + f + "\n";
  if (rep.cancelled)
    md += "\n**Interrupted**: only the steps above finished; run again with --resume.\n";
  return md;
}

}  // namespace

// "filament 1749.91 ± 0.07 µm (10 of 10 pairs), feed 4.502 mm/s, gear 5.001 mm/s, slip 9.98 ±
// 0.31 % (10 pairs)", or why not.
std::string FeedstockLine(const pipeline::FeedstockResult& f) {
  if (f.n_diameter == 0)
    return fmt::format("feedstock {}: {}", FeedstockStatusName(f.status), f.detail);
  std::string out =
      f.has_um ? fmt::format("filament {:.2f} ± {:.2f} µm", f.diameter_um, f.diameter_ci95_um)
               : fmt::format("filament {:.3f} px", f.diameter_px);
  out += fmt::format(" ({} of {} pairs)", f.n_diameter, f.n_pairs);
  if (f.speed_mm_s) out += fmt::format(", feed {:.3f} mm/s", *f.speed_mm_s);
  if (f.gear_mm_s) out += fmt::format(", gear {:.3f} mm/s", *f.gear_mm_s);
  if (f.slip_pct) {
    out += fmt::format(", slip {:.2f}{} % ({} pairs)", *f.slip_pct,
                       f.slip_ci95_pct ? fmt::format(" ± {:.2f}", *f.slip_ci95_pct) : "", f.n_slip);
  }
  if (f.status != FeedstockStatus::kOk)
    out += fmt::format("; {}: {}", FeedstockStatusName(f.status), f.detail);
  return out;
}

void WriteRunSummary(const std::string& out_dir, ManifestRunReport* report) {
  ManifestRunReport& rep = *report;
  const Manifest& m = rep.manifest;
  const Provenance prov = CurrentProvenance();
  const std::string md_path = (fs::path(out_dir) / "summary.md").string();
  const std::string json_path = (fs::path(out_dir) / "summary.json").string();
  rep.files.push_back(md_path);
  rep.files.push_back(json_path);
  WriteFileAtomically(md_path, Summary(rep, prov));
  nlohmann::ordered_json j;
  j["experiment"] = m.name;
  j["provenance"] = {{"version", prov.version},
                     {"created_utc", prov.created_utc},
                     {"command_line", prov.command_line}};
  j["cancelled"] = rep.cancelled;
  if (rep.conversion) {
    j["scale_um_per_px"] = rep.conversion->scale_um_per_px;
    j["scale_sigma_um_per_px"] = rep.conversion->scale_sigma_um_per_px;
    j["edge_bias_px"] = rep.conversion->edge_bias_px;
  }
  auto steps = nlohmann::ordered_json::array();
  for (const auto& r : rep.steps) {
    nlohmann::ordered_json s = {{"step", r.spec.step},
                                {"temperature_c", r.spec.temperature_c},
                                {"n", r.n_used},
                                {"n_rejected", r.n_rejected},
                                {"status", model::StepStatusName(r.status)},
                                {"detail", r.detail}};
    if (r.has_um && r.n_used) {
      s["mean_um"] = r.mean_um;
      s["ci95_um"] = r.ci95_um;
      s["std_um"] = r.std_um;
    }
    steps.push_back(s);
  }
  j["steps"] = steps;
  if (rep.prediction) {
    auto pred = nlohmann::ordered_json::array();
    for (const auto& s : rep.prediction->prediction.steps) {
      pred.push_back(
          {{"step", s.step}, {"relative_amplitude", s.relative_amplitude}, {"f_bp_n", s.f_bp_n}});
    }
    j["prediction"] = pred;
  }
  j["files"] = rep.files;
  WriteFileAtomically(json_path,
                      j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

}  // namespace clogscope::pipeline
