// A source's credentials never shown: the password of a URL and secret query values are hidden.
#include "vision/io/source_name.h"

#include <gtest/gtest.h>

namespace clogscope::vision {
namespace {

TEST(RedactCredentialsTest, HidesTheUrlPasswordAndKeepsTheRest) {
  EXPECT_EQ(RedactCredentials("rtsp://admin:s3cret@cam.local:554/stream1"),
            "rtsp://admin:***@cam.local:554/stream1");
  EXPECT_EQ(RedactCredentials("http://u:p@10.0.0.5/?action=stream"),
            "http://u:***@10.0.0.5/?action=stream");
  // A password holding '@' or ':' (left unescaped): the userinfo ends at the last '@'.
  EXPECT_EQ(RedactCredentials("rtsp://u:p@ss:w@cam/s"), "rtsp://u:***@cam/s");
  // A user name alone may be a camera's key.
  EXPECT_EQ(RedactCredentials("http://abcdef0123@cam/mjpg"), "http://***@cam/mjpg");
  EXPECT_EQ(RedactCredentials("rtsp://u:p@cam"), "rtsp://u:***@cam");
}

TEST(RedactCredentialsTest, HidesSecretQueryValues) {
  EXPECT_EQ(RedactCredentials("http://cam/snapshot.cgi?user=admin&pwd=hunter2&res=1"),
            "http://cam/snapshot.cgi?user=admin&pwd=***&res=1");
  EXPECT_EQ(RedactCredentials("https://cam/s?access_token=xyz#frag"),
            "https://cam/s?access_token=***#frag");
  EXPECT_EQ(RedactCredentials("rtsp://u:p@cam/s?Password=x"), "rtsp://u:***@cam/s?Password=***");
}

TEST(RedactCredentialsTest, LeavesWhatIsNotAUrlAlone) {
  EXPECT_EQ(RedactCredentials("/dev/video0"), "/dev/video0");
  EXPECT_EQ(RedactCredentials("shots/me@home:1/"), "shots/me@home:1/");
  EXPECT_EQ(RedactCredentials("http://cam.local/webcam/?action=stream"),
            "http://cam.local/webcam/?action=stream");
  EXPECT_EQ(RedactCredentials("http://cam/path/with@sign"), "http://cam/path/with@sign");
  EXPECT_EQ(RedactCredentials(""), "");
}

}  // namespace
}  // namespace clogscope::vision
