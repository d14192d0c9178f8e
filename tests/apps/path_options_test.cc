// Every file option of every command, given a path the file system cannot resolve (a loop of
// symbolic links): one line naming the option (or, for a positional input, the path) and the
// problem, exit 1, no library text ("filesystem error: status: …").
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using testing::RunCli;

const char* kTable =
    "step,temperature_c,mean_um\n1,220,400.0\n2,210,396.9\n3,200,390.1\n4,190,381.3\n";
const char* kProfile = "time_s,flow_mm3_s\n0,5\n1.0,10\n2.5,6\n4.0,11\n5.5,5\n";

TEST(PathOptionsTest, ASymlinkLoopIsRefusedInOneLineByEveryFileOption) {
  const fs::path d = testing::FreshDir("clogscope_path_options");
  const std::string loop = (d / "loop").string();
  fs::create_symlink(loop, loop);
  const std::string table = (d / "d.csv").string(), profile = (d / "p.csv").string(),
                    frames = (d / "f.csv").string(), folder = (d / "images").string();
  WriteFileAtomically(table, kTable);
  WriteFileAtomically(profile, kProfile);
  std::string rows = "source,frame,time_s,valid,width_px\n";
  for (int i = 0; i < 50; ++i)
    rows += "v.avi," + std::to_string(i) + "," + std::to_string(i * 0.04) + ",1,100\n";
  WriteFileAtomically(frames, rows);
  fs::create_directories(folder);
  const std::string image = std::string(CLOGSCOPE_TESTDATA_DIR) + "/frames/bright_tilt5.png";
  struct Case {
    std::string args;
    std::string option;  // empty: a positional input, named by its path
    int lines = 1;       // measure: each input's line, then "nothing could be measured"
  };
  const std::vector<Case> cases = {
      {"drive --roller 3 --pinch-force-n 80 --diameters " + table + " --extruder @", "--extruder"},
      {"drive --roller 3 --pinch-force-n 80 --diameters @", "--diameters"},
      {"thermal --material pla --fan-velocity-m-s 0.3 --diameters " + table +
           " --filament-modulus-pa 5e7 --extruder @",
       "--extruder"},
      {"thermal --material pla --fan-velocity-m-s 0.3 --filament-modulus-pa 5e7 --diameters @",
       "--diameters"},
      {"predict --extruder @ --diameters " + table + " --out o --no-plots", "--extruder"},
      {"predict --diameters @ --out o --no-plots", "--diameters"},
      {"predict --diameters " + table + " --fit @ --fit-params gain_m_s2_per_n --out o --no-plots",
       "--fit"},
      {"lag --frames @ --commanded " + profile + " --out o --no-plots", "--frames"},
      {"lag --frames " + frames + " --commanded @ --out o --no-plots", "--commanded"},
      {"lag --commanded @ --k-s 0.1 --out o --no-plots", "--commanded"},
      {"render --out r --size 160x120 --tip-x-px 80 --lag-commanded @ --lag-k-s 0.1",
       "--lag-commanded"},
      {"measure @ --out-frames f.csv", "", 2},
      {"measure " + image + " --calib @ --out-frames f.csv", "--calib"},
      {"measure --manifest @ --out o", "--manifest"},
      {"inspect @ --out i.png", ""},
      {"calibrate --pins @ --out c.yaml", "--pins"},
      {"calibrate --micrometer @ --pitch-um 100 --out c.yaml", "--micrometer"},
      {"run @ --out o", ""},
      {"watch @ --duration-s 5", ""},
      {"watch " + folder + " --calib @ --duration-s 5", "--calib"},
      {"watch " + folder + " --extruder @ --scale-um-per-px 3 --duration-s 5", "--extruder"},
  };
  for (const Case& c : cases) {
    std::string args = c.args;
    args.replace(args.find('@'), 1, loop);
    const auto r = RunCli(args, d);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), c.lines) << args << "\n" << r.err;
    const std::string named = c.option.empty() ? loop : c.option + " " + loop;
    EXPECT_NE(r.err.find(named + ": too many levels of symbolic links"), std::string::npos)
        << args << "\n"
        << r.err;
    EXPECT_EQ(r.err.find("filesystem error"), std::string::npos) << args << "\n" << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
