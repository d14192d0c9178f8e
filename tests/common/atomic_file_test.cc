#include "common/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

namespace clogscope {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  fs::path d =
      fs::temp_directory_path() /
      ("clogscope_atomic_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
       ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
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

}  // namespace
}  // namespace clogscope
