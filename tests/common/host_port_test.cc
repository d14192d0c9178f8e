#include "common/host_port.h"

#include <gtest/gtest.h>

namespace clogscope {
namespace {

TEST(HostPortTest, SplitsNamesAddressesAndBracketedIpv6) {
  const struct {
    const char* text;
    const char* host;
    int port;  // -1: none written
  } cases[] = {{"broker.local", "broker.local", -1}, {"broker.local:1884", "broker.local", 1884},
               {"10.0.0.2:0", "10.0.0.2", 0},        {"[::1]", "::1", -1},
               {"[fe80::1]:8090", "fe80::1", 8090},  {"h:65535", "h", 65535}};
  for (const auto& c : cases) {
    HostPort hp;
    std::string why;
    ASSERT_TRUE(SplitHostPort(c.text, 0, &hp, &why)) << c.text << ": " << why;
    EXPECT_EQ(hp.host, c.host) << c.text;
    EXPECT_EQ(hp.port.value_or(-1), c.port) << c.text;
  }
}

TEST(HostPortTest, RefusesWhatIsNotAHostAndPortSayingWhy) {
  const struct {
    const char* text;
    int min_port;
    const char* why;
  } cases[] = {{"[::1", 0, "closing ']'"},      {"[::1]8090", 0, "':PORT' after ']'"},
               {"::1:8090", 0, "brackets"},     {":8090", 0, "no host"},
               {"host:", 0, "an empty port"},   {"host:65536", 0, "[0, 65535]"},
               {"host:80x", 0, "[0, 65535]"},   {"host:0", 1, "[1, 65535]"},
               {"host:123456", 0, "[0, 65535]"}};
  for (const auto& c : cases) {
    HostPort hp;
    std::string why;
    EXPECT_FALSE(SplitHostPort(c.text, c.min_port, &hp, &why)) << c.text;
    EXPECT_NE(why.find(c.why), std::string::npos) << c.text << ": " << why;
  }
}

}  // namespace
}  // namespace clogscope
