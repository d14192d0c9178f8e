#pragma once

// HTTP over raw sockets for the watch's tests: real connections to a real server on loopback,
// slow or hostile ones included, and nothing in between (no client library decides for the test).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string>

namespace clogscope::apps::testing {

// A TCP connection to 127.0.0.1:port from the loopback address `from` (127.0.0.N: a client of its
// own, as the server counts clients), closed at destruction.
class TestSocket {
 public:
  explicit TestSocket(int port, const std::string& from = "127.0.0.1", int receive_bytes = 0) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (receive_bytes > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_bytes, sizeof(int));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    inet_pton(AF_INET, from.c_str(), &a.sin_addr);
    if (bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return;
    inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
    a.sin_port = htons(static_cast<uint16_t>(port));
    ok_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~TestSocket() {
    if (fd_ >= 0) close(fd_);
  }
  TestSocket(const TestSocket&) = delete;
  TestSocket& operator=(const TestSocket&) = delete;
  TestSocket(TestSocket&& o) noexcept : fd_(o.fd_), ok_(o.ok_) { o.fd_ = -1; }

  bool ok() const { return ok_; }
  // All of `bytes`; false as soon as the server has closed (no SIGPIPE).
  bool Send(const std::string& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }
  // What the server sends until it closes (or resets), or until `timeout_s` passes without an end;
  // *closed says whether it ended.
  std::string ReadUntilClosed(double timeout_s, bool* closed = nullptr) {
    std::string out;
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(timeout_s));
    if (closed) *closed = false;
    char buf[65536];
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return out;
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      const ssize_t n = recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) {
        if (closed) *closed = true;
        return out;
      }
      out.append(buf, static_cast<size_t>(n));
    }
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
};

struct HttpReply {
  int status = 0;  // 0: no answer (closed or reset before one, or timed out)
  std::string head, body;
};

inline HttpReply ParseReply(const std::string& raw) {
  HttpReply r;
  const size_t end = raw.find("\r\n\r\n");
  if (raw.rfind("HTTP/1.", 0) != 0 || end == std::string::npos) return r;
  r.status = std::stoi(raw.substr(9, 3));
  r.head = raw.substr(0, end + 2);
  r.body = raw.substr(end + 4);
  return r;
}

// `request` ("GET /status" and any header lines, each ending in \r\n) sent whole, with
// "Connection: close" and, unless the lines give one, "Host: 127.0.0.1:PORT" (as a browser on this
// machine sends); the reply read until the server closes.
inline HttpReply Request(int port, const std::string& request, double timeout_s = 10,
                         const std::string& from = "127.0.0.1") {
  TestSocket s(port, from);
  const size_t line_end = request.find("\r\n");
  const std::string first = line_end == std::string::npos ? request : request.substr(0, line_end);
  const std::string rest = line_end == std::string::npos ? "" : request.substr(line_end + 2);
  const std::string host =
      rest.rfind("Host:", 0) == 0 || rest.find("\r\nHost:") != std::string::npos
          ? ""
          : "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";
  if (!s.Send(first + " HTTP/1.1\r\n" + host + "Connection: close\r\n" + rest + "\r\n")) return {};
  return ParseReply(s.ReadUntilClosed(timeout_s));
}

inline HttpReply Get(int port, const std::string& path, const std::string& header_lines = "",
                     double timeout_s = 10) {
  return Request(port, "GET " + path + "\r\n" + header_lines, timeout_s);
}

}  // namespace clogscope::apps::testing
