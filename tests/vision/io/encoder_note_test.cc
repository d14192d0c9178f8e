#include "vision/io/encoder_note.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "common/spawn.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;

// A few frames of FFmpeg's test pattern through Debian's ffmpeg and libx264 with `extra` options.
std::string EncodeWithX264(const fs::path& dir, const std::string& name,
                           const std::vector<std::string>& extra) {
  const std::string out = (dir / name).string();
  SpawnOptions o;
  o.argv = {"ffmpeg",    "-nostdin", "-v",
            "error",     "-y",       "-f",
            "lavfi",     "-i",       "testsrc=size=96x64:rate=5",
            "-frames:v", "5",        "-c:v",
            "libx264",   "-threads", "1"};
  o.argv.insert(o.argv.end(), extra.begin(), extra.end());
  o.argv.push_back(out);
  std::string why;
  const pid_t pid = Spawn(o, &why);
  EXPECT_TRUE(pid > 0 && WaitForExit(pid, &why)) << "ffmpeg: " << why;
  return out;
}

// What x264 wrote into the files, against the options it was given: the advice only where edges
// move (adaptive quantisation on, CRF above 18).
TEST(EncoderNoteTest, ReadsX264sSettingsAndAdvisesOnlyWhereEdgesMove) {
  const fs::path dir = fs::temp_directory_path() / ("encoder_note_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const X264Settings defaults = ReadX264Settings(EncodeWithX264(dir, "defaults.mp4", {}));
  EXPECT_TRUE(defaults.found);
  EXPECT_EQ(defaults.aq_mode, 1);
  EXPECT_DOUBLE_EQ(defaults.aq_strength, 1.0);
  EXPECT_DOUBLE_EQ(defaults.crf, 23.0);
  EXPECT_NE(X264EdgeAdvice(defaults).find("-aq-mode 0"), std::string::npos);

  const X264Settings aq_off =
      ReadX264Settings(EncodeWithX264(dir, "aq_off.mkv", {"-aq-mode", "0"}));
  EXPECT_TRUE(aq_off.found);
  EXPECT_TRUE(aq_off.aq_mode == 0 || aq_off.aq_strength == 0);
  EXPECT_EQ(X264EdgeAdvice(aq_off), "");

  const X264Settings crf18 = ReadX264Settings(EncodeWithX264(dir, "crf18.mp4", {"-crf", "18"}));
  EXPECT_DOUBLE_EQ(crf18.crf, 18.0);
  EXPECT_EQ(X264EdgeAdvice(crf18), "");

  // Not x264's: an MJPEG file, and a path that is not there.
  SpawnOptions o;
  const std::string mjpeg = (dir / "mjpeg.avi").string();
  o.argv = {"ffmpeg",    "-nostdin", "-v",
            "error",     "-y",       "-f",
            "lavfi",     "-i",       "testsrc=size=96x64:rate=5",
            "-frames:v", "3",        "-c:v",
            "mjpeg",     mjpeg};
  std::string why;
  const pid_t pid = Spawn(o, &why);
  ASSERT_TRUE(pid > 0 && WaitForExit(pid, &why)) << why;
  EXPECT_FALSE(ReadX264Settings(mjpeg).found);
  EXPECT_FALSE(ReadX264Settings((dir / "missing.mp4").string()).found);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace clogscope::vision
