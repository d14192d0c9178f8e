#pragma once

// The watch's web page (watch/web/index.html): the live overlay, the diameter's history with its
// CI and the baseline, the level and why, drift and clog index, drawn in the browser from
// /status, /history.json and /frame.jpg. Embedded in the binary at build time: no file to find
// at run time.

#include <string_view>

namespace clogscope::watch {

std::string_view WatchPageHtml();

}  // namespace clogscope::watch
