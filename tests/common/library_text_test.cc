#include "common/library_text.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <thread>
#include <vector>

namespace clogscope {
namespace {

// What a library prints the way libpng's default handler and OpenCV's imread do.
void LibraryPrints(const char* text) {
  std::fprintf(stderr, "%s\n", text);
  std::cerr << "cerr: " << text << std::endl;
}

TEST(LibraryTextTest, CapturesWhatLibrariesPrintAndRestoresStderr) {
  const int before = ::dup(2);
  std::string text;
  {
    LibraryTextCapture capture;
    LibraryPrints("libpng error: IDAT: CRC error");
    text = capture.Text();
  }
  EXPECT_EQ(text, "libpng error: IDAT: CRC error\ncerr: libpng error: IDAT: CRC error\n");
  EXPECT_EQ(FirstLine("\n  " + text), "libpng error: IDAT: CRC error");
  // fd 2 is the terminal (or ctest's pipe) again: the same file as before.
  struct stat a {
  }, b{};
  ASSERT_EQ(::fstat(before, &a), 0);
  ASSERT_EQ(::fstat(2, &b), 0);
  EXPECT_EQ(a.st_ino, b.st_ino);
  EXPECT_EQ(a.st_dev, b.st_dev);
  ::close(before);
  // After the capture, nothing is diverted: a new capture sees only its own text.
  LibraryTextCapture later;
  EXPECT_EQ(later.Text(), "");
}

// The tool's own stream is never diverted: its messages reach the user even while a decoder on
// another thread has fd 2 diverted.
TEST(LibraryTextTest, ToolMessagesAreNotCaptured) {
  LibraryTextCapture capture;
  std::fprintf(ToolStderr(), "[test] the tool's own line (expected in the test log)\n");
  EXPECT_EQ(capture.Text(), "");
}

// Overlapping captures on several threads share one diversion; each sees at least its own text
// and fd 2 is restored once the last one ends.
TEST(LibraryTextTest, ConcurrentCapturesEachSeeTheirText) {
  std::vector<std::string> seen(8);
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i) {
    threads.emplace_back([i, &seen] {
      for (int k = 0; k < 50; ++k) {
        LibraryTextCapture capture;
        std::fprintf(stderr, "thread %d pass %d\n", i, k);
        const std::string text = capture.Text();
        if (text.find("thread " + std::to_string(i) + " pass " + std::to_string(k)) ==
            std::string::npos)
          seen[i] = "missing pass " + std::to_string(k) + " in: " + text;
      }
    });
  }
  for (auto& t : threads) t.join();
  for (int i = 0; i < 8; ++i) EXPECT_EQ(seen[i], "") << i;
  LibraryTextCapture after;
  EXPECT_EQ(after.Text(), "");
}

}  // namespace
}  // namespace clogscope
