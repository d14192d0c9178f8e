#pragma once

// `watch --http`: the page at / (watch/web/index.html), /status (JSON), /history.json (the
// board's history; ?since_s=T for the points from T on), /metrics (Prometheus text) and /frame.jpg
// (the latest frame with its overlay), served by GNU libmicrohttpd so that it can face a network:
// a few threads poll every connection (a slow client holds a socket, never a thread), each
// client's share is bounded (HttpLimits), only GET and HEAD without a body are answered, and an
// optional bearer token guards everything but /metrics and the page (which holds no data).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "watch/frame_jpeg.h"
#include "watch/live_watch.h"

namespace clogscope::apps {

// What all clients, or one, may take of the server. A connection past a count is closed at once;
// a request past a size is answered 414 or 431 and closed: nothing waits for room.
struct HttpLimits {
  unsigned max_connections = 512;
  unsigned max_connections_per_ip = 64;
  // Per connection: the request line and headers must fit in it, with the read and write buffers.
  size_t connection_max_bytes = 16 * 1024;
  unsigned idle_timeout_s = 10;  // a connection that sends or takes nothing this long is closed
  unsigned threads = 2;          // each polls its share of the connections (epoll)
};

struct WatchHttpOptions {
  // --http: HOST:PORT, [IPv6]:PORT, or PORT alone for 127.0.0.1 (this machine only). Port 0: a free
  // port, told by WatchHttpServer::url().
  std::string address;
  // Not empty: every path but /metrics and / asks for "Authorization: Bearer TOKEN" (401 without
  // it).
  std::string token;
  HttpLimits limits;
};

// The token in --http-token-file PATH: the file's one line, without surrounding blanks. Throws
// std::invalid_argument naming the option and the file when it cannot be read, is empty, holds more
// than one line or characters a bearer token cannot (RFC 6750: letters, digits, -._~+/=), or is
// shorter than kMinHttpTokenChars.
std::string ReadHttpToken(const std::string& path);
inline constexpr size_t kMinHttpTokenChars = 16;

class WatchHttpServer {
 public:
  // Binds at once and serves on its own threads from then on. Throws std::invalid_argument naming
  // --http when the address is malformed, its host unknown, or the port cannot be bound.
  WatchHttpServer(const WatchHttpOptions& options, const watch::WatchBoard* board,
                  std::optional<calib::ScaleCalibration> conversion,
                  std::shared_ptr<watch::OverlayJpegCache> frames = nullptr);
  // A camera of a farm (`watch --config`): its paths /cameras/NAME/… and label printer="NAME".
  using Camera = watch::CameraFeed;
  // Many cameras: /cameras/NAME/ (the page), /cameras/NAME/status, /history.json and /frame.jpg
  // for each; /status, every camera's state by name; /metrics, every camera's series labelled
  // printer="NAME"; / the page of the one camera (a redirect), or a list of the cameras.
  WatchHttpServer(const WatchHttpOptions& options, std::vector<Camera> cameras);
  ~WatchHttpServer();  // closes every connection at once, whatever its client is doing
  WatchHttpServer(const WatchHttpServer&) = delete;
  WatchHttpServer& operator=(const WatchHttpServer&) = delete;

  int port() const;                // the bound port (the real one for port 0)
  const std::string& url() const;  // "http://127.0.0.1:43125"
  bool loopback_only() const;      // bound to a loopback address: unreachable from elsewhere
  unsigned connections() const;    // open now

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace clogscope::apps
