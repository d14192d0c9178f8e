// The printer API's pure parts: URLs, the key file, the webcam chosen and its URL, the states.
#include "watch/printer_api.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/scratch_dir.h"
#include "watch/moonraker_client.h"
#include "watch/octoprint_client.h"

namespace clogscope::watch {
namespace {

TEST(PrinterApiTest, PrinterUrlsAreHttpWithoutCredentialsQueryOrTrailingSlash) {
  std::string base, why;
  ASSERT_TRUE(ParsePrinterUrl("--moonraker", "http://printer.local:7125/", &base, &why)) << why;
  EXPECT_EQ(base, "http://printer.local:7125");
  ASSERT_TRUE(ParsePrinterUrl("--octoprint", "https://octopi/prefix//", &base, &why)) << why;
  EXPECT_EQ(base, "https://octopi/prefix");
  for (const std::string bad : {"printer.local", "ftp://printer", "http://", "http://u:pw@printer",
                                "http://printer/?key=x"}) {
    EXPECT_FALSE(ParsePrinterUrl("--moonraker", bad, &base, &why)) << bad;
    EXPECT_EQ(why.rfind("--moonraker", 0), 0u) << why;
    EXPECT_EQ(why.find("pw@"), std::string::npos) << why;
  }
}

TEST(PrinterApiTest, TheKeyFileIsOneLineAndNeverQuoted) {
  const auto dir = testutil::FreshDir("clogscope_printer_api");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream((dir / name).string(), std::ios::binary) << text;
    return (dir / name).string();
  };
  std::string key, why;
  ASSERT_TRUE(ReadApiKeyFile(write("ok", "  ABCdef0123456789\r\n"), &key, &why)) << why;
  EXPECT_EQ(key, "ABCdef0123456789");
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"empty", "\n"}, {"two", "secretone\nsecrettwo\n"}, {"blank", "secret one\n"}}) {
    EXPECT_FALSE(ReadApiKeyFile(write(name, text), &key, &why)) << name;
    EXPECT_NE(why.find("--printer-api-key-file"), std::string::npos) << why;
    EXPECT_EQ(why.find("secret"), std::string::npos) << why;
  }
  EXPECT_FALSE(ReadApiKeyFile((dir / "missing").string(), &key, &why));
  std::filesystem::remove_all(dir);
}

TEST(PrinterApiTest, AWebcamsStreamUrlIsMadeWhole) {
  const std::string base = "http://printer.local";
  EXPECT_EQ(ResolveWebcamUrl(base, "/webcam/?action=stream"),
            "http://printer.local/webcam/?action=stream");
  EXPECT_EQ(ResolveWebcamUrl("http://pi:7125/moonraker", "webcam/?action=stream"),
            "http://pi:7125/webcam/?action=stream");
  EXPECT_EQ(ResolveWebcamUrl(base, "http://cam.lan:8080/?action=stream"),
            "http://cam.lan:8080/?action=stream");
  EXPECT_EQ(ResolveWebcamUrl(base, "rtsp://cam.lan/s1"), "rtsp://cam.lan/s1");
  EXPECT_EQ(ResolveWebcamUrl(base, "file:///home/pi/replay.mp4"), "/home/pi/replay.mp4");
}

TEST(PrinterApiTest, TheFirstEnabledWebcamOrTheNamedOne) {
  const std::vector<MoonrakerWebcam> webcams = {
      {"door", false, "/door", ""}, {"nozzle", true, "/nozzle", ""}, {"bed", true, "/bed", ""}};
  MoonrakerWebcam chosen;
  std::string why;
  ASSERT_TRUE(ChooseWebcam(webcams, "", &chosen, &why));
  EXPECT_EQ(chosen.name, "nozzle");
  ASSERT_TRUE(ChooseWebcam(webcams, "bed", &chosen, &why));
  EXPECT_EQ(chosen.name, "bed");
  EXPECT_FALSE(ChooseWebcam(webcams, "garage", &chosen, &why));
  EXPECT_NE(why.find("door, nozzle, bed"), std::string::npos) << why;
  EXPECT_FALSE(ChooseWebcam({}, "", &chosen, &why));
  EXPECT_FALSE(ChooseWebcam({{"door", false, "/door", ""}}, "", &chosen, &why));
}

TEST(PrinterApiTest, StatesAsTheApisSayThem) {
  EXPECT_EQ(MoonrakerPrintState("printing"), PrintState::kPrinting);
  EXPECT_EQ(MoonrakerPrintState("paused"), PrintState::kPaused);
  for (const std::string s : {"standby", "complete", "cancelled", "error"})
    EXPECT_EQ(MoonrakerPrintState(s), PrintState::kIdle) << s;
  EXPECT_EQ(OctoPrintState("Printing"), PrintState::kPrinting);
  EXPECT_EQ(OctoPrintState("Printing from SD"), PrintState::kPrinting);
  EXPECT_EQ(OctoPrintState("Pausing"), PrintState::kPaused);
  EXPECT_EQ(OctoPrintState("Paused"), PrintState::kPaused);
  for (const std::string s : {"Operational", "Offline", "Error", "Cancelling"})
    EXPECT_EQ(OctoPrintState(s), PrintState::kIdle) << s;
}

TEST(PrinterApiTest, HttpOutcomesBecomeReasons) {
  EXPECT_TRUE(ReplyOf({HttpError::kNone, 204, "", ""}, "x").ok());
  EXPECT_EQ(ReplyOf({HttpError::kNone, 401, "", ""}, "x").error, PrinterError::kUnauthorized);
  EXPECT_EQ(ReplyOf({HttpError::kNone, 403, "", ""}, "x").error, PrinterError::kUnauthorized);
  EXPECT_EQ(ReplyOf({HttpError::kNone, 409, "", ""}, "x").error, PrinterError::kNotPrinting);
  EXPECT_EQ(ReplyOf({HttpError::kNone, 503, "", ""}, "x").error, PrinterError::kRefused);
  EXPECT_EQ(ReplyOf({HttpError::kTimeout, 0, "", "t"}, "x").error, PrinterError::kTimeout);
  EXPECT_EQ(ReplyOf({HttpError::kUnreachable, 0, "", "u"}, "x").error, PrinterError::kUnreachable);
}

}  // namespace
}  // namespace clogscope::watch
