#pragma once

// A watch held at its first level change, for tests that look at what its HTTP server serves then.
#include <gtest/gtest.h>

#include <atomic>
#include <functional>

#include "apps/watch_command.h"

namespace clogscope::apps::testing {

// Runs the watch `o` with --http 127.0.0.1:0 and calls check(port, state) at its first level
// change, while the server serves that state (the watch waits for check); fails the test when the
// level never changes.
inline void WatchHeldAtFirstChange(
    WatchCommandOptions o, const std::function<void(int port, const watch::WatchStatus&)>& check) {
  o.http = "127.0.0.1:0";
  int port = 0;
  bool called = false;
  WatchObservers observers;
  observers.on_started = [&](int p) { port = p; };
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    if (called) return;
    called = true;
    check(port, s);
  };
  std::atomic<bool> stop{false};
  WatchNozzle(o, &stop, observers);
  EXPECT_TRUE(called) << "the watch never changed level";
}

}  // namespace clogscope::apps::testing
