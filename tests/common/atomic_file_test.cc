#include "common/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/mount.h>

#include <filesystem>
#include <stdexcept>

#include "tests/scratch_dir.h"

namespace clogscope {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  return testutil::FreshDir(std::string("clogscope_atomic_") +
                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
}

TEST(AtomicFileTest, AppearsOnlyOnCommit) {
  const fs::path dir = TempDir();
  const std::string path = (dir / "out.csv").string();
  {
    AtomicTextFile f(path);
    f.stream() << "hello\n";
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::exists(f.partial_path()));
    f.Commit();
  }
  EXPECT_EQ(ReadFile(path), "hello\n");
  EXPECT_FALSE(fs::exists(path + ".partial"));
}

TEST(AtomicFileTest, AbandonedWriteLeavesOldFileIntact) {
  const fs::path dir = TempDir();
  const std::string path = (dir / "out.txt").string();
  WriteFileAtomically(path, "old");
  {
    AtomicTextFile f(path);
    f.stream() << "new but unfinished";
  }
  EXPECT_EQ(ReadFile(path), "old");
  EXPECT_FALSE(fs::exists(path + ".partial"));
}

TEST(AtomicFileTest, KeepPartialKeepsWhatWasWritten) {
  const fs::path dir = TempDir();
  const std::string path = (dir / "frames.csv").string();
  {
    AtomicTextFile f(path, /*keep_partial=*/true);
    f.stream() << "a,b\n1,2\n";
    f.stream().flush();
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(ReadFile(path + ".partial"), "a,b\n1,2\n");
}

TEST(AtomicFileTest, UnwritableDirectoryIsAClearError) {
  try {
    AtomicTextFile f("/nonexistent-dir/x.csv");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.csv"), std::string::npos);
  }
  EXPECT_THROW(ReadFile("/nonexistent-dir/y"), std::invalid_argument);
}

// A full disk: a 16 KiB tmpfs (mounting needs root; elsewhere the test says so and skips).
TEST(AtomicFileTest, FullDiskNamesTheReasonAndLeavesNoPartial) {
  const fs::path d = TempDir();
  if (::mount("tmpfs", d.c_str(), "tmpfs", 0, "size=16k") != 0)
    GTEST_SKIP() << "cannot mount a small tmpfs here (needs root): full-disk behaviour untested";
  const std::string big(256 * 1024, 'x');
  for (bool keep : {false, true}) {
    const std::string path = (d / "big.csv").string();
    try {
      AtomicTextFile f(path, keep);
      f.stream() << big;
      f.Commit();
      ADD_FAILURE() << "a 256 KiB write fitted in 16 KiB";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".partial")) << "keep_partial " << keep;
  }
  // Destroyed by an exception (an error path), a keep_partial file goes too.
  try {
    AtomicTextFile f((d / "small.csv").string(), /*keep_partial=*/true);
    f.stream() << "a,b\n";
    throw std::invalid_argument("something else failed");
  } catch (const std::invalid_argument&) {
  }
  EXPECT_FALSE(fs::exists(d / "small.csv.partial"));
  ::umount(d.c_str());
}

}  // namespace
}  // namespace clogscope
