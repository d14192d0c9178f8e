// The watch's HTTP server facing clients that are slow, hostile or without the token: a real
// server on a loopback port the server chose, real sockets, and the server's own count of open
// connections as the signal that they are held (no sleeps).
#include "apps/watch_http.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include "common/atomic_file.h"
#include "tests/apps/http_test_client.h"
#include "tests/scratch_dir.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using testing::Get;
using testing::HttpReply;
using testing::Request;
using testing::TestSocket;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Under AddressSanitizer freed memory waits in a quarantine instead of being reused: resident
// memory then says nothing about what a request keeps.
#if defined(CLOGSCOPE_SANITIZED)
constexpr bool kRssMeansSomething = false;
#else
constexpr bool kRssMeansSomething = true;
#endif

long RssKb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// A partial request: the line and a header begun, never ended.
const std::string kPartialRequest = "GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";

class WatchHttpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // A 720p frame of noise: its JPEG is large (~1 MB), as a worst case for /frame.jpg.
    watch::WatchSnapshot s;
    s.frame = cv::Mat(720, 1280, CV_8UC1);
    cv::randu(s.frame, 0, 255);
    s.counters.source = "test";
    board_.Publish(s);
  }
  std::unique_ptr<WatchHttpServer> Start(const std::string& address = "127.0.0.1:0",
                                         const std::string& token = "") {
    WatchHttpOptions o;
    o.address = address;
    o.token = token;
    return std::make_unique<WatchHttpServer>(o, &board_, std::nullopt);
  }
  // Until the server holds `n` connections (bounded: a server that never does fails the test).
  static bool WaitForConnections(const WatchHttpServer& server, unsigned n) {
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    while (server.connections() < n && Clock::now() < deadline) std::this_thread::yield();
    return server.connections() >= n;
  }
  // `count` connections from `first_address`..: `per_address` from each, each sending a partial
  // request and then nothing.
  static std::vector<TestSocket> SlowClients(int port, int count, int per_address,
                                             int first_address = 2) {
    std::vector<TestSocket> clients;
    for (int i = 0; i < count; ++i) {
      clients.emplace_back(port, "127.0.0." + std::to_string(first_address + i / per_address));
      EXPECT_TRUE(clients.back().ok());
      clients.back().Send(kPartialRequest);
    }
    return clients;
  }
  watch::WatchBoard board_;
};

TEST_F(WatchHttpTest, PortZeroIsTheBoundPortAndAPortAloneIsThisMachineOnly) {
  const auto server = Start("127.0.0.1:0");
  ASSERT_GT(server->port(), 0);
  EXPECT_EQ(server->url(), "http://127.0.0.1:" + std::to_string(server->port()));
  EXPECT_TRUE(server->loopback_only());
  const HttpReply r = Get(server->port(), "/status");
  ASSERT_EQ(r.status, 200) << r.head;
  EXPECT_EQ(nlohmann::json::parse(r.body)["source"], "test");
  const auto alone = Start("0");
  EXPECT_EQ(alone->url(), "http://127.0.0.1:" + std::to_string(alone->port()));
  EXPECT_TRUE(alone->loopback_only());
  EXPECT_FALSE(Start("0.0.0.0:0")->loopback_only());
  for (const std::string bad : {"host:", "127.0.0.1:65536", "127.0.0.1:80x", "[::1", ":-1", ""})
    EXPECT_THROW(Start(bad), std::invalid_argument) << bad;
}

// A loopback watch without a token answers to this machine's own names only: a page elsewhere
// whose name was pointed at 127.0.0.1 (DNS rebinding) sends its name and is refused. With a token,
// the token decides.
TEST_F(WatchHttpTest, ALoopbackWatchWithoutATokenAnswersOnlyToThisMachinesNames) {
  const auto server = Start();
  const int port = server->port();
  const std::string p = ":" + std::to_string(port);
  for (const std::string& host :
       std::vector<std::string>{"127.0.0.1" + p, "localhost" + p, "LocalHost", "[::1]" + p})
    EXPECT_EQ(Get(port, "/status", "Host: " + host + "\r\n").status, 200) << host;
  for (const std::string& host :
       std::vector<std::string>{"attacker.example" + p, "attacker.example", "127.0.0.1.nip.io"})
    for (const std::string path : {"/status", "/frame.jpg", "/history.json", "/", "/metrics"})
      EXPECT_EQ(Get(port, path, "Host: " + host + "\r\n").status, 403) << host << path;
  const std::string token = "0123456789abcdefXYZ+/=";
  const auto guarded = Start("127.0.0.1:0", token);
  EXPECT_EQ(Get(guarded->port(), "/status",
                "Host: printer.lan\r\nAuthorization: Bearer " + token + "\r\n")
                .status,
            200);
}

// Slow clients hold sockets, not threads: with 200 of them sending half a request, a new client's
// /status is answered at once (cpp-httplib 0.11 answered none within 20 s with 8 of them).
TEST_F(WatchHttpTest, TwoHundredSlowClientsLeaveStatusAnswering) {
  const auto server = Start();
  const auto slow = SlowClients(server->port(), 200, 25);  // 8 addresses, 25 each
  ASSERT_TRUE(WaitForConnections(*server, 200)) << server->connections() << " held";
  const auto t0 = Clock::now();
  const HttpReply r = Get(server->port(), "/status", "", /*timeout_s=*/1.0);
  const double latency_s = SecondsSince(t0);
  EXPECT_EQ(r.status, 200) << "no /status within 1 s while 200 slow clients are held";
  std::cout << "/status with 200 slow clients held: " << latency_s * 1e3 << " ms\n";
  // The slow ones are still held (the probe's own connection may not be closed on the server's
  // side yet: at least 200).
  EXPECT_GE(server->connections(), 200u);
}

// One address cannot take every connection: past its share it is closed at once, others served.
TEST_F(WatchHttpTest, OneAddressGetsNoMoreThanItsShare) {
  const auto server = Start();
  const unsigned share = HttpLimits{}.max_connections_per_ip;
  const auto held = SlowClients(server->port(), share, share, /*first_address=*/10);
  ASSERT_TRUE(WaitForConnections(*server, share));
  TestSocket one_more(server->port(), "127.0.0.10");
  bool closed = false;
  one_more.ReadUntilClosed(5, &closed);
  EXPECT_TRUE(closed) << "the connection past the share was kept";
  EXPECT_EQ(Get(server->port(), "/status", "", 5).status, 200);
}

// No request, however large, is read into memory: each is refused once it passes the connection's
// 16 KB, its body never read; ranges are not served.
TEST_F(WatchHttpTest, HostileRequestsAreRefusedWithinBoundedMemory) {
  const auto server = Start();
  const int port = server->port();
  const size_t k256Mb = size_t{256} << 20;
  const std::string chunk(64 << 10, 'a');
  // Streams `head` then up to `total` bytes of `chunk`; the status of what came back (0: closed
  // without one) and how many bytes went before the server stopped reading.
  const auto flood = [&](const std::string& head, const std::string& piece, size_t total) {
    TestSocket s(port);
    size_t sent = 0;
    if (s.Send(head))
      while (sent < total && s.Send(piece)) sent += piece.size();
    return std::make_pair(testing::ParseReply(s.ReadUntilClosed(5)).status, sent);
  };
  // Once, before measuring: the first picture starts what lasts (OpenCV's and the JPEG coder's
  // buffers, a malloc arena for the server's thread).
  const long cold_kb = RssKb();
  for (int i = 0; i < 2; ++i) ASSERT_EQ(Get(port, "/frame.jpg").status, 200);
  std::cout << "the first pictures took " << RssKb() - cold_kb << " KB\n";
  long worst_kb = 0;
  const long base_kb = RssKb();
  const auto check = [&](const char* what, std::pair<int, size_t> got, std::set<int> statuses) {
    const long grew_kb = RssKb() - base_kb;
    worst_kb = std::max(worst_kb, grew_kb);
    if (kRssMeansSomething) {
      EXPECT_LT(grew_kb, 16 * 1024) << what;
    }
    EXPECT_LT(got.second, size_t{8} << 20) << what << ": the server kept reading";
    EXPECT_TRUE(statuses.count(got.first)) << what << ": " << got.first;
  };
  // 0: the server's refusal may be lost to the reset of a connection closed with data unread.
  check("a 256 MB request line", flood("GET /", chunk, k256Mb), {414, 0});
  check("a 256 MB body",
        flood("POST /status HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 268435456\r\n\r\n",
              chunk, k256Mb),
        {405, 0});
  check("a 256 MB GET body",
        flood("GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 268435456\r\n\r\n", chunk,
              k256Mb),
        {413, 0});
  check("a chunked body",
        flood("GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n\r\n",
              "10000\r\n" + chunk + "\r\n", k256Mb),
        {413, 0});
  check(
      "a gzip body",
      flood("GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Encoding: gzip\r\nContent-Length: "
            "534528\r\n\r\n",
            std::string(1024, '\x1f'), 534528),
      {413, 0});
  std::string header_lines;
  for (int i = 0; i < 2000; ++i) header_lines += "X-H" + std::to_string(i) + ": v\r\n";
  check("200,000 headers",
        flood("GET /status HTTP/1.1\r\n", header_lines, 100 * header_lines.size()), {431, 0});
  // A thousand ranges ask for one picture a thousand times: the picture is sent once, whole.
  std::string ranges = "Range: bytes=0-";
  for (int i = 1; i < 1000; ++i) ranges += ",0-";
  const HttpReply whole = Get(port, "/frame.jpg");
  const HttpReply ranged = Get(port, "/frame.jpg", ranges + "\r\n");
  ASSERT_EQ(whole.status, 200);
  EXPECT_EQ(ranged.status, 200);
  EXPECT_LT(ranged.body.size(), 2 * whole.body.size());
  check("1000 ranges", {ranged.status, 0}, {200});
  std::cout << "RSS grew at most " << worst_kb << " KB over the hostile requests (frame.jpg "
            << whole.body.size() / 1024 << " KB)\n";
}

TEST_F(WatchHttpTest, OnlyGetAndHeadWithoutABodyAreAnswered) {
  const auto server = Start();
  const int port = server->port();
  const HttpReply post = Request(port, "POST /status\r\nContent-Length: 3\r\n\r\nabc");
  EXPECT_EQ(post.status, 405);
  EXPECT_NE(post.head.find("Allow: GET, HEAD"), std::string::npos) << post.head;
  EXPECT_EQ(Request(port, "DELETE /status").status, 405);
  EXPECT_EQ(Request(port, "GET /status\r\nContent-Length: 5\r\n\r\nhello").status, 413);
  const HttpReply head = Request(port, "HEAD /status");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
  EXPECT_EQ(Get(port, "/../etc/passwd").status, 404);
  EXPECT_EQ(Get(port, "/metrics").status, 200);
}

TEST_F(WatchHttpTest, ABearerTokenGuardsEverythingButMetricsAndThePage) {
  const std::string token = "0123456789abcdefXYZ+/=";
  const auto server = Start("127.0.0.1:0", token);
  const int port = server->port();
  const HttpReply none = Get(port, "/status");
  EXPECT_EQ(none.status, 401);
  EXPECT_NE(none.head.find("WWW-Authenticate: Bearer"), std::string::npos) << none.head;
  EXPECT_EQ(Get(port, "/status", "Authorization: Bearer " + token + "x\r\n").status, 401);
  EXPECT_EQ(Get(port, "/status", "Authorization: Bearer " + token.substr(1) + "\r\n").status, 401);
  EXPECT_EQ(Get(port, "/status", "Authorization: Basic " + token + "\r\n").status, 401);
  EXPECT_EQ(Get(port, "/frame.jpg").status, 401);
  EXPECT_EQ(Get(port, "/history.json").status, 401);
  EXPECT_EQ(Get(port, "/history.json?since_s=0").status, 401);
  EXPECT_EQ(Get(port, "/status", "Authorization: Bearer " + token + "\r\n").status, 200);
  EXPECT_EQ(Get(port, "/history.json", "Authorization: Bearer " + token + "\r\n").status, 200);
  EXPECT_EQ(Get(port, "/frame.jpg", "Authorization: bearer " + token + "\r\n").status, 200);
  EXPECT_EQ(Get(port, "/metrics").status, 200);  // a scraper needs no token
  // The page holds no data: it is served without the token, and asks for the data with it.
  const HttpReply page = Get(port, "/");
  EXPECT_EQ(page.status, 200);
  EXPECT_NE(page.head.find("Content-Type: text/html; charset=utf-8"), std::string::npos);
  EXPECT_EQ(page.body.find(token), std::string::npos);
  // The page is watch/web/index.html byte for byte: embedded at build time, no file read now.
  EXPECT_EQ(
      page.body,
      ReadFile((fs::path(CLOGSCOPE_TESTDATA_DIR).parent_path() / "watch/web/index.html").string()));
}

// /history.json: the board's points as JSON, from a time on with ?since_s; a bad time is one line.
TEST_F(WatchHttpTest, HistoryIsServedFromTheBoardAndSinceSelectsItsTail) {
  watch::WatchState state({}, std::nullopt);
  for (int i = 0; i < 100; ++i) {  // 4 s at 25 frames/s of a 50 px strand
    state.Add(i / 25.0, watch::FrameView::kStrand, 50.0 + 0.1 * (i % 2));
    watch::WatchSnapshot s;
    s.status = state.status();
    board_.Publish(s);
  }
  const auto server = Start();
  const int port = server->port();
  const HttpReply all = Get(port, "/history.json");
  ASSERT_EQ(all.status, 200) << all.body;
  EXPECT_NE(all.head.find("application/json"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(all.body);
  ASSERT_EQ(j["points"].size(), 4u);
  EXPECT_EQ(j["unit"], "px");
  EXPECT_NEAR(j["points"][3]["diameter_px"].get<double>(), 50.05, 0.01);
  EXPECT_EQ(j["points"][3]["time_s"], 3.96);
  const nlohmann::json tail = nlohmann::json::parse(Get(port, "/history.json?since_s=2").body);
  ASSERT_EQ(tail["points"].size(), 2u);
  EXPECT_EQ(tail["points"][0]["time_s"], 2.96);
  for (const std::string bad : {"", "abc", "1x", "nan", "inf"}) {
    const HttpReply r = Get(port, "/history.json?since_s=" + bad);
    EXPECT_EQ(r.status, 400) << bad;
    EXPECT_EQ(r.body, "since_s: expected a time in seconds of the watch's clock, e.g. 120\n");
  }
  const HttpReply missing = Get(port, "/nothing");
  EXPECT_EQ(missing.status, 404);
  EXPECT_EQ(missing.body, "not found: / /status /history.json /metrics /frame.jpg\n");
}

// The sockets of this process whose local port is `port`: the server's listening and accepted
// ones (a client's local port is its own).
std::vector<int> SocketsOnLocalPort(int port) {
  std::set<std::string> inodes;
  std::ifstream tcp("/proc/net/tcp");
  std::string line;
  std::getline(tcp, line);
  char want[8];
  std::snprintf(want, sizeof want, ":%04X", port);
  while (std::getline(tcp, line)) {
    std::istringstream f(line);
    std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout, inode;
    f >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >> timeout >>
        inode;
    if (local.size() > 5 && local.substr(local.size() - 5) == want) inodes.insert(inode);
  }
  std::vector<int> fds;
  for (const auto& e : fs::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    const std::string target = fs::read_symlink(e.path(), ec).string();
    if (target.rfind("socket:[", 0) == 0 && inodes.count(target.substr(8, target.size() - 9)))
      fds.push_back(std::stoi(e.path().filename().string()));
  }
  return fds;
}

// No child (--on-alert) inherits the port or a client's connection.
TEST_F(WatchHttpTest, TheListeningAndAcceptedSocketsAreClosedOnExec) {
  const auto server = Start();
  TestSocket client(server->port());
  client.Send(kPartialRequest);
  ASSERT_TRUE(WaitForConnections(*server, 1));
  const std::vector<int> fds = SocketsOnLocalPort(server->port());
  EXPECT_GE(fds.size(), 2u) << "the listening socket and the accepted one";
  for (const int fd : fds) EXPECT_TRUE(fcntl(fd, F_GETFD) & FD_CLOEXEC) << "socket fd " << fd;
}

// Stopping closes every connection at once, whatever its client is doing: half a request sent,
// or a picture asked for and never read.
TEST_F(WatchHttpTest, StoppingClosesEveryConnectionAtOnce) {
  auto server = Start();
  const int port = server->port();
  auto slow = SlowClients(port, 50, 25);
  TestSocket reader(port, "127.0.0.1", /*receive_bytes=*/4096);
  reader.Send("GET /frame.jpg HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  ASSERT_TRUE(WaitForConnections(*server, 51));
  const auto t0 = Clock::now();
  server.reset();
  const double stop_s = SecondsSince(t0);
  std::cout << "stopped with 51 clients held in " << stop_s * 1e3 << " ms\n";
  EXPECT_LT(stop_s, 2.0);
  bool closed = false;
  slow.front().ReadUntilClosed(5, &closed);
  EXPECT_TRUE(closed);
}

class HttpTokenFileTest : public ::testing::Test {
 protected:
  fs::path Write(const std::string& name, const std::string& content) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  // The one line ReadHttpToken throws for `path`, which must name the option and the file.
  static std::string Refusal(const fs::path& path) {
    try {
      ReadHttpToken(path.string());
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--http-token-file " + path.string()), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      return what;
    }
    ADD_FAILURE() << path << " was taken";
    return "";
  }
  fs::path dir_ = testutil::FreshDir("clogscope_http_token_" + std::to_string(getpid()));
};

TEST_F(HttpTokenFileTest, TheTokenIsTheFilesOneLine) {
  EXPECT_EQ(ReadHttpToken(Write("t", "  0123456789abcdefghij \r\n\n").string()),
            "0123456789abcdefghij");
  EXPECT_NE(Refusal(dir_ / "missing").find("no such file"), std::string::npos);
  EXPECT_NE(Refusal(Write("empty", "\n")).find("empty"), std::string::npos);
  EXPECT_NE(Refusal(Write("short", "abc\n")).find("fewer than 16"), std::string::npos);
  EXPECT_NE(Refusal(Write("two", "0123456789abcdefghij\nsecond\n")).find("more than one line"),
            std::string::npos);
  EXPECT_NE(Refusal(Write("odd", "0123456789abcdef ghij\n")).find("not a bearer token"),
            std::string::npos);
  EXPECT_NE(Refusal(Write("big", std::string(5000, 'a'))).find("over 4096 bytes"),
            std::string::npos);
  EXPECT_NE(Refusal(dir_).find("--http-token-file"), std::string::npos);  // a directory
}

}  // namespace
}  // namespace clogscope::apps
