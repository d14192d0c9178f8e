#pragma once

// `clogscope render`: synthetic frames with exact ground truth.

#include <string>

#include "model/lag_io.h"
#include "synthetic/synthetic.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunRender(int argc, char** argv);

struct RenderCommandOptions {
  synthetic::SceneParams scene;
  int frames = 1;
  double fps = 25.0;
  std::string out;         // directory of PNGs, or a .avi / .mp4 video
  std::string truth_path;  // empty: next to the output (DIR/truth.json or NAME.truth.json)
  // A strand whose width follows the first-order lag of a commanded flow profile: width =
  // lag_um_per_mm3_s · Q_out(frame time). Empty: no lag.
  std::string lag_commanded;
  model::ProfileForm lag_profile_form = model::ProfileForm::kMoves;
  double lag_k_s = 0.1;
  double lag_um_per_mm3_s = 40;
  double filament_diameter_mm = 1.75;
  // A clog sequence for `watch`: the strand narrows by drop_pct % at drop_at_s (0: no drop).
  double drop_pct = 0;
  double drop_at_s = 0;
  bool Validate(std::string* why) const;
};
// Renders and writes frames and truth; returns the truth path written.
std::string RenderToFiles(const RenderCommandOptions& options);

}  // namespace clogscope::apps
