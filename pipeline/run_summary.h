#pragma once

// The summary of a manifest run: summary.md (the step table, feedstock, predicted vibration, the
// files) and summary.json.

#include <string>

#include "pipeline/feedstock.h"
#include "pipeline/manifest_run.h"

namespace clogscope::pipeline {

// "filament 1749.91 ± 0.07 µm (10 of 10 pairs), feed 4.502 mm/s, gear 5.001 mm/s, slip 9.98 ±
// 0.31 % (10 pairs)", or why not.
std::string FeedstockLine(const FeedstockResult& feedstock);

// Writes out_dir/summary.md and summary.json atomically and adds them to report->files (the JSON
// lists both).
void WriteRunSummary(const std::string& out_dir, ManifestRunReport* report);

}  // namespace clogscope::pipeline
