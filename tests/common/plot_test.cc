#include "common/plot.h"

#include <gtest/gtest.h>
#include <sys/mount.h>

#include <filesystem>

#include "common/spawn.h"
#include "tests/scratch_dir.h"

namespace clogscope {
namespace {

namespace fs = std::filesystem;

using testutil::FreshDir;

PlotSpec Spec() {
  PlotSpec spec;
  spec.title = "t";
  PlotSeries s;
  for (int i = 0; i < 50; ++i) {
    s.x.push_back(i);
    s.y.push_back(i * i);
  }
  s.title = "y";
  spec.series.push_back(s);
  return spec;
}

TEST(PlotTest, DrawsAPngOrSaysWhyNot) {
  if (FindOnPath("gnuplot").empty()) GTEST_SKIP() << "no gnuplot";
  const fs::path d = FreshDir("clogscope_plot");
  std::string why;
  ASSERT_TRUE(PlotToPng(Spec(), (d / "ok.png").string(), &why)) << why;
  EXPECT_GT(fs::file_size(d / "ok.png"), 1000u);
  // A disk too small for the PNG (mounting needs root; elsewhere this part is skipped): gnuplot
  // exits 0 after its failed write, and the truncated file must not appear under the name.
  const fs::path small = d / "small";
  fs::create_directories(small);
  if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=8k") != 0)
    GTEST_SKIP() << "cannot mount a small tmpfs here (needs root): full-disk plot untested";
  EXPECT_FALSE(PlotToPng(Spec(), (small / "p.png").string(), &why));
  EXPECT_FALSE(why.empty());
  EXPECT_FALSE(fs::exists(small / "p.png"));
  EXPECT_FALSE(fs::exists(small / "p.png.partial.png"));
  ::umount(small.c_str());
}

// An output path is data, never a command: no shell sees it, and gnuplot reads it as a plain
// string (no backquote or macro substitution).
TEST(PlotTest, PathsWithShellOrGnuplotSyntaxAreOnlyNames) {
  if (FindOnPath("gnuplot").empty()) GTEST_SKIP() << "no gnuplot";
  const fs::path d = FreshDir("clogscope_plot_names");
  // The commands name files relative to the folder they would run in: this one.
  const fs::path cwd = fs::current_path();
  fs::current_path(d);
  for (const std::string& name :
       std::vector<std::string>{"p$(touch PWNED)", "q`touch PWNED2`", "r\"';@x"}) {
    std::string why;
    ASSERT_TRUE(PlotToPng(Spec(), (d / name).string(), &why)) << name << ": " << why;
    EXPECT_TRUE(fs::exists(d / name)) << name;
  }
  fs::current_path(cwd);
  EXPECT_FALSE(fs::exists(d / "PWNED"));
  EXPECT_FALSE(fs::exists(d / "PWNED2"));
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 3)
      << "the plots only: no script, error or partial file left";
}

}  // namespace
}  // namespace clogscope
