#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace clogscope::apps {

// "WxH" -> width, height (positive). Returns false on a malformed value (CLI11 callback form).
bool ParseSize(const std::string& text, int* width, int* height);

// "x,y,w,h" -> rectangle; throws std::invalid_argument naming --roi on a malformed value.
cv::Rect ParseRoi(const std::string& text);

// Writes spdlog output to stderr at the given level name ("info", "warn", "debug", …).
void SetUpLogging(const std::string& level);

}  // namespace clogscope::apps
