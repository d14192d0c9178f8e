#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "vision/io/frame_source.h"

namespace clogscope::vision {

struct LiveSourceOptions {
  bool realtime = false;  // file: deliver each frame at its timestamp (replays, tests)
  // How realtime waits for a frame's time, `due_s` after the source opened; false: stopped.
  // Empty: the steady clock (SleepUnlessStopped). Tests pass simulated time.
  std::function<bool(double due_s)> wait_until;
  double open_timeout_s = 10;  // a stream that yields no frame within this is refused
  double read_timeout_s = 5;   // a stream silent this long has dropped
  double folder_poll_s = 0.1;  // how often a folder is listed
  bool Validate(std::string* why) const;
};

// Which kind SOURCE names for `watch`: /dev/… a device, "scheme://…" a stream, a directory a
// folder a camera writes into, else a video file.
SourceKind LiveSourceKindOf(const std::string& source);

// Opens SOURCE for watching and waits for its first frame (streams and devices, within
// open_timeout_s). Blocking reads return within the read timeout (or the folder poll) and as soon
// as the stop flag turns true; a live source that stops delivering reads kDropped (reopen it), a
// video file kEnd. Frames are grey (8- or 16-bit), or as stored for a folder's images. Throws
// std::invalid_argument with one line naming SOURCE and why when it cannot be opened.
std::unique_ptr<FrameSource> OpenLiveSource(const std::string& source,
                                            const LiveSourceOptions& options,
                                            const std::atomic<bool>* stop);

// Sleeps until `until` in slices of at most 20 ms, so that a raised stop flag is seen soon.
// Returns false when stopped.
bool SleepUnlessStopped(std::chrono::steady_clock::time_point until, const std::atomic<bool>* stop);

}  // namespace clogscope::vision
