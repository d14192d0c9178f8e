#include "apps/watch_http.h"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <microhttpd.h>
#include <netdb.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/ascii.h"
#include "common/atomic_file.h"
#include "common/host_port.h"
#include "common/path_check.h"
#include "watch/frame_jpeg.h"
#include "watch/web_page.h"

namespace clogscope::apps {
namespace {

constexpr const char* kTokenOption = "--http-token-file";
constexpr size_t kMaxHttpTokenFileBytes = 4096;
constexpr int kListenBacklog = 64;
constexpr const char* kPageSecurityPolicy =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src 'self' blob:; connect-src 'self'; base-uri 'none'; form-action 'none'; "
    "frame-ancestors 'none'";

// [HOST:]PORT, [V6]:PORT; no host: 127.0.0.1.
HostPort ParseAddress(const std::string& address) {
  HostPort out;
  std::string why;
  const bool port_alone =
      !address.empty() && address.find_first_not_of("0123456789") == std::string::npos;
  const bool no_host = port_alone || (!address.empty() && address[0] == ':');
  const bool ok =
      SplitHostPort(no_host ? "127.0.0.1" + std::string(port_alone ? ":" : "") + address : address,
                    0, &out, &why);
  if (!ok || !out.port)
    throw std::invalid_argument(
        fmt::format("--http '{}': expected [HOST:]PORT, e.g. 8090 (this machine only) or "
                    "0.0.0.0:8090 (every network)",
                    address));
  return out;
}

// A Host header a browser on this machine sends to a loopback address: an IP literal or localhost,
// with or without a port. (A page elsewhere that points its own name at 127.0.0.1 — DNS
// rebinding — sends its name.) No header at all (HTTP/1.0): not a browser's request.
bool HostIsThisMachine(const char* host_header) {
  if (!host_header) return true;
  HostPort hp;
  std::string why;
  if (!SplitHostPort(host_header, 0, &hp, &why)) return false;
  in_addr v4{};
  in6_addr v6{};
  if (inet_pton(AF_INET, hp.host.c_str(), &v4) == 1 ||
      inet_pton(AF_INET6, hp.host.c_str(), &v6) == 1)
    return true;
  return LowerAscii(hp.host) == "localhost";
}

bool IsLoopback(const sockaddr_storage& a) {
  if (a.ss_family == AF_INET)
    return (ntohl(reinterpret_cast<const sockaddr_in&>(a).sin_addr.s_addr) >> 24) == 127;
  const in6_addr& v6 = reinterpret_cast<const sockaddr_in6&>(a).sin6_addr;
  if (IN6_IS_ADDR_V4MAPPED(&v6)) return v6.s6_addr[12] == 127;
  return IN6_IS_ADDR_LOOPBACK(&v6);
}

// Equal without the time telling where two strings first differ: every byte is compared.
bool SameSecret(const std::string& given, const std::string& secret) {
  volatile unsigned char diff = given.size() != secret.size();
  for (size_t i = 0; i < given.size(); ++i)
    diff = diff | (given[i] ^ (i < secret.size() ? secret[i] : 0));
  return diff == 0;
}

// "Bearer TOKEN" (the scheme in any case, RFC 7235) naming `token`.
bool Authorized(MHD_Connection* c, const std::string& token) {
  const char* value =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
  if (!value) return false;
  const std::string v = value;
  if (v.size() < 7 || strncasecmp(v.c_str(), "Bearer ", 7) != 0) return false;
  const size_t start = v.find_first_not_of(' ', 7);
  return SameSecret(start == std::string::npos ? "" : v.substr(start), token);
}

struct Reply {
  unsigned status = MHD_HTTP_OK;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<const char*, std::string>> headers;
  bool close = false;  // a refused request: its connection is closed after the answer
};

Reply Redirect(const std::string& location) {
  Reply r;
  r.status = MHD_HTTP_FOUND;
  r.body = location + "\n";
  r.headers.emplace_back(MHD_HTTP_HEADER_LOCATION, location);
  return r;
}

Reply Refusal(unsigned status, std::string text) {
  Reply r;
  r.status = status;
  r.body = std::move(text) + "\n";
  r.close = true;
  return r;
}

void FreeBody(void* body) { delete static_cast<std::string*>(body); }

MHD_Result Send(MHD_Connection* c, Reply reply) {
  auto* body = new std::string(std::move(reply.body));
  MHD_Response* r = MHD_create_response_from_buffer_with_free_callback_cls(
      body->size(), body->data(), &FreeBody, body);
  if (!r) {
    delete body;
    return MHD_NO;
  }
  MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, reply.content_type.c_str());
  MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
  MHD_add_response_header(r, "X-Content-Type-Options", "nosniff");
  for (const auto& [name, value] : reply.headers) MHD_add_response_header(r, name, value.c_str());
  if (reply.close) MHD_add_response_header(r, MHD_HTTP_HEADER_CONNECTION, "close");
  const MHD_Result queued = MHD_queue_response(c, reply.status, r);
  MHD_destroy_response(r);
  return queued;
}

void LogFromLibrary(void*, const char* format, va_list args) {
  // What a client did wrong is no news for the operator: debug only, so no client floods the log.
  char line[512];
  std::vsnprintf(line, sizeof line, format, args);
  std::string text = line;
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  spdlog::debug("http: {}", text);
}

}  // namespace

std::string ReadHttpToken(const std::string& path) {
  const auto fail = [&](const std::string& problem) {
    return std::invalid_argument(fmt::format("{} {}: {}", kTokenOption, path, problem));
  };
  std::string why;
  if (!CheckInputPath(kTokenOption, path, PathExpect::kFile, &why))
    throw std::invalid_argument(why);
  std::string content;
  if (!TryReadFile(path, &content, &why)) throw fail("cannot read (" + why + ")");
  if (content.size() > kMaxHttpTokenFileBytes)
    throw fail(fmt::format("over {} bytes: not a token", kMaxHttpTokenFileBytes));
  const auto blank = [](unsigned char c) { return c == ' ' || c == '\t' || c == '\r'; };
  const size_t newline = content.find('\n');
  std::string token = content.substr(0, newline);
  if (newline != std::string::npos &&
      !std::all_of(content.begin() + newline + 1, content.end(),
                   [&](unsigned char c) { return blank(c) || c == '\n'; }))
    throw fail("more than one line; the token is the file's one line");
  while (!token.empty() && blank(token.back())) token.pop_back();
  token.erase(0, std::min(token.size(), token.find_first_not_of(" \t")));
  if (token.empty()) throw fail("empty; write a token of at least 16 characters into it");
  if (!std::all_of(token.begin(), token.end(), [](unsigned char c) {
        return std::isalnum(c) || std::strchr("-._~+/=", c) != nullptr;
      }))
    throw fail("not a bearer token (letters, digits and -._~+/= only)");
  if (token.size() < kMinHttpTokenChars)
    throw fail(fmt::format("the token has {} characters, fewer than {}: too easy to guess",
                           token.size(), kMinHttpTokenChars));
  return token;
}

struct WatchHttpServer::Impl {
  std::vector<Camera> cameras;  // each with its pictures
  bool farm = false;  // --config: the cameras' paths under /cameras/NAME/, labelled metrics
  std::string token;
  MHD_Daemon* daemon = nullptr;
  int port = 0;
  std::string url;
  bool loopback_only = false;

  void Start(const WatchHttpOptions& options, std::vector<Camera> feeds, bool farm_paths);

  Reply Route(MHD_Connection* c, const std::string& path, const std::string& method) const {
    if (method != MHD_HTTP_METHOD_GET && method != MHD_HTTP_METHOD_HEAD) {
      Reply r = Refusal(MHD_HTTP_METHOD_NOT_ALLOWED, "only GET and HEAD");
      r.headers.emplace_back("Allow", "GET, HEAD");
      return r;
    }
    // Every path takes no body: one announced is refused before a byte of it is read.
    const char* length = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
    if ((length && std::strcmp(length, "0") != 0) ||
        MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Transfer-Encoding"))
      return Refusal(MHD_HTTP_CONTENT_TOO_LARGE, "request bodies are refused");
    // A loopback watch without a token answers only to this machine's own names: a web page
    // elsewhere cannot read it through a name of its own pointed at 127.0.0.1.
    if (token.empty() && loopback_only &&
        !HostIsThisMachine(MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Host")))
      return Refusal(MHD_HTTP_FORBIDDEN,
                     "this watch answers to 127.0.0.1, [::1] or localhost only (a guard against "
                     "DNS rebinding; --http-token-file lets other names in)");
    // A farm's camera: /cameras/NAME/PATH is that camera's PATH.
    const Camera* camera = farm ? nullptr : &cameras.front();
    std::string inner = path;
    const std::string under = "/cameras/";
    if (farm && path.rfind(under, 0) == 0) {
      const size_t slash = path.find('/', under.size());
      const std::string name = path.substr(under.size(), slash - under.size());
      for (const Camera& f : cameras)
        if (f.name == name) camera = &f;
      if (!camera) return Refusal(MHD_HTTP_NOT_FOUND, "no camera named '" + name + "'");
      // The page asks for status, history.json and frame.jpg beside itself: it needs the slash.
      if (slash == std::string::npos) return Redirect(path + "/");
      inner = path.substr(slash);
    }
    // /metrics stays open: a Prometheus scraper without the token still sees the level. So does
    // the page at /, which holds no data: it asks for the rest with the token it was given.
    if (!token.empty() && inner != "/metrics" && inner != "/" && !Authorized(c, token)) {
      Reply r = Refusal(MHD_HTTP_UNAUTHORIZED, "a bearer token is required (--http-token-file)");
      r.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"clogscope watch\"");
      return r;
    }
    if (!camera) return FarmRoute(path);
    return CameraRoute(c, *camera, inner);
  }

  // The farm's own paths: every camera's state and metrics, and where the pages are.
  Reply FarmRoute(const std::string& path) const {
    Reply r;
    if (path == "/status") {
      // Names are [A-Za-z0-9_-]: JSON keys as they are.
      r.content_type = "application/json";
      r.body = "{\"cameras\":{";
      for (const Camera& f : cameras) {
        const watch::WatchSnapshot s = f.board->Read();
        r.body += (&f == &cameras.front() ? "\"" : ",\"") + f.name +
                  "\":" + watch::StatusJson(s.status, s.clog, s.counters, "status");
      }
      r.body += "}}\n";
    } else if (path == "/metrics") {
      std::vector<watch::PrometheusCamera> all;
      for (const Camera& f : cameras) {
        const watch::WatchSnapshot s = f.board->Read();
        all.push_back({f.name, s.status, s.clog, s.counters});
      }
      r.content_type = "text/plain; version=0.0.4; charset=utf-8";
      r.body = watch::PrometheusText(all);
    } else if (path == "/" && cameras.size() == 1) {
      return Redirect("/cameras/" + cameras.front().name + "/");
    } else if (path == "/") {
      // The list holds the names only: the pages ask for the rest (with the token, if any).
      r.content_type = "text/html; charset=utf-8";
      r.body =
          "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>clogscope watch</title>"
          "</head><body><h1>Cameras</h1><ul>";
      for (const Camera& f : cameras)
        r.body += fmt::format("<li><a href=\"cameras/{0}/\">{0}</a></li>", f.name);
      // A list opened as /#token=T hands its fragment on to each page, which reads the token
      // there (the fragment never reaches the server).
      r.body +=
          "</ul><script>for (const a of document.querySelectorAll('a')) a.href += "
          "location.hash;</script></body></html>\n";
      r.headers.emplace_back("Content-Security-Policy", kPageSecurityPolicy);
      r.headers.emplace_back("Referrer-Policy", "no-referrer");
    } else {
      return Refusal(MHD_HTTP_NOT_FOUND,
                     "not found: / /status /metrics /cameras/NAME/ /cameras/NAME/status "
                     "/cameras/NAME/history.json /cameras/NAME/frame.jpg");
    }
    return r;
  }

  // One camera's paths (all of a single watch's).
  Reply CameraRoute(MHD_Connection* c, const Camera& camera, const std::string& path) const {
    const watch::WatchBoard* board = camera.board;
    Reply r;
    if (path == "/status") {
      const watch::WatchSnapshot s = board->Read();
      r.content_type = "application/json";
      r.body = watch::StatusJson(s.status, s.clog, s.counters, "status") + "\n";
    } else if (path == "/metrics" && !farm) {
      const watch::WatchSnapshot s = board->Read();
      r.content_type = "text/plain; version=0.0.4; charset=utf-8";
      r.body = watch::PrometheusText(s.status, s.clog, s.counters);
    } else if (path == "/frame.jpg") {
      // Drawn on request, once a frame: the measuring thread never pays for a picture nobody
      // looks at. Ranges are not served: the whole picture or nothing.
      const auto jpeg = camera.frames->Latest();
      if (!jpeg) return Refusal(MHD_HTTP_SERVICE_UNAVAILABLE, "no frame yet");
      r.content_type = "image/jpeg";
      r.body.assign(jpeg->begin(), jpeg->end());
    } else if (path == "/history.json") {
      double since_s = -std::numeric_limits<double>::infinity();
      if (const char* since = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "since_s")) {
        char* end = nullptr;
        since_s = std::strtod(since, &end);
        if (*since == '\0' || *end != '\0' || !std::isfinite(since_s))
          return Refusal(MHD_HTTP_BAD_REQUEST,
                         "since_s: expected a time in seconds of the watch's clock, e.g. 120");
      }
      r.content_type = "application/json";
      r.body = watch::HistoryJson(board->History(since_s), board->history_options(),
                                  camera.conversion.has_value()) +
               "\n";
    } else if (path == "/") {
      r.content_type = "text/html; charset=utf-8";
      r.body = watch::WatchPageHtml();
      // Nothing but the watch itself: no script, style or picture from elsewhere, and nowhere
      // else to send the token to.
      r.headers.emplace_back("Content-Security-Policy", kPageSecurityPolicy);
      r.headers.emplace_back("Referrer-Policy", "no-referrer");
    } else if (farm) {
      return Refusal(MHD_HTTP_NOT_FOUND,
                     "not found: /cameras/NAME/, status, history.json, frame.jpg under it");
    } else {
      return Refusal(MHD_HTTP_NOT_FOUND, "not found: / /status /history.json /metrics /frame.jpg");
    }
    return r;
  }

  static MHD_Result Answer(void* cls, MHD_Connection* c, const char* url, const char* method,
                           const char* /*version*/, const char* /*upload_data*/,
                           size_t* upload_data_size, void** request) {
    // Called once the headers are in: answered then, so a body is never read (MHD closes the
    // connection after the answer rather than read one).
    if (*request != nullptr) {
      *upload_data_size = 0;
      return MHD_YES;
    }
    *request = cls;
    try {
      return Send(c, static_cast<const Impl*>(cls)->Route(c, url, method));
    } catch (const std::exception& e) {
      spdlog::warn("http {}: {}", url, e.what());
      return Send(c, Refusal(MHD_HTTP_INTERNAL_SERVER_ERROR, "internal error"));
    }
  }
};

WatchHttpServer::WatchHttpServer(const WatchHttpOptions& options, const watch::WatchBoard* board,
                                 std::optional<calib::ScaleCalibration> conversion,
                                 std::shared_ptr<watch::OverlayJpegCache> frames)
    : impl_(std::make_unique<Impl>()) {
  impl_->Start(options, {Camera{"", board, std::move(conversion), std::move(frames)}},
               /*farm=*/false);
}

WatchHttpServer::WatchHttpServer(const WatchHttpOptions& options, std::vector<Camera> cameras)
    : impl_(std::make_unique<Impl>()) {
  if (cameras.empty()) throw std::invalid_argument("--http: no camera to serve");
  impl_->Start(options, std::move(cameras), /*farm=*/true);
}

// Set up before the daemon starts: its threads read all this without a lock.
void WatchHttpServer::Impl::Start(const WatchHttpOptions& options, std::vector<Camera> feeds,
                                  bool farm_paths) {
  Impl& d = *this;
  d.farm = farm_paths;
  for (Camera& c : feeds) {
    if (!c.frames) c.frames = std::make_shared<watch::OverlayJpegCache>(c.board, c.conversion);
    d.cameras.push_back(std::move(c));
  }
  d.token = options.token;
  const HostPort hp = ParseAddress(options.address);
  const auto cannot = [&](const std::string& why) {
    return std::invalid_argument(fmt::format("--http {}: {}", options.address, why));
  };
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (const int err =
          getaddrinfo(hp.host.c_str(), std::to_string(*hp.port).c_str(), &hints, &found);
      err != 0)
    throw cannot(fmt::format("unknown host {} ({})", hp.host, gai_strerror(err)));
  sockaddr_storage addr{};
  std::memcpy(&addr, found->ai_addr, found->ai_addrlen);
  const socklen_t addr_len = found->ai_addrlen;
  freeaddrinfo(found);
  // Close-on-exec from its birth: no child (--on-alert) inherits the port or a client.
  const int fd = socket(addr.ss_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) throw cannot(fmt::format("cannot make a socket ({})", std::strerror(errno)));
  const int on = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), addr_len) != 0 ||
      listen(fd, kListenBacklog) != 0) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw cannot("cannot listen there (" + why + ")");
  }
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  char numeric[NI_MAXHOST] = "";
  getnameinfo(reinterpret_cast<const sockaddr*>(&addr), len, numeric, sizeof numeric, nullptr, 0,
              NI_NUMERICHOST);
  d.port = ntohs(addr.ss_family == AF_INET ? reinterpret_cast<sockaddr_in&>(addr).sin_port
                                           : reinterpret_cast<sockaddr_in6&>(addr).sin6_port);
  d.url =
      fmt::format(addr.ss_family == AF_INET6 ? "http://[{}]:{}" : "http://{}:{}", numeric, d.port);
  d.loopback_only = IsLoopback(addr);

  const HttpLimits& l = options.limits;
  unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL | MHD_USE_ERROR_LOG;
  if (addr.ss_family == AF_INET6) flags |= MHD_USE_IPv6;
  d.daemon = MHD_start_daemon(
      flags, 0, nullptr, nullptr, &Impl::Answer, this, MHD_OPTION_EXTERNAL_LOGGER, &LogFromLibrary,
      nullptr, MHD_OPTION_LISTEN_SOCKET, fd, MHD_OPTION_THREAD_POOL_SIZE, l.threads,
      MHD_OPTION_CONNECTION_LIMIT, l.max_connections, MHD_OPTION_PER_IP_CONNECTION_LIMIT,
      l.max_connections_per_ip, MHD_OPTION_CONNECTION_MEMORY_LIMIT, l.connection_max_bytes,
      MHD_OPTION_CONNECTION_TIMEOUT, l.idle_timeout_s, MHD_OPTION_END);
  // From here the daemon owns the socket and closes it when stopped. Should it fail to start, the
  // socket is left open rather than risk closing a descriptor it already closed: the watch ends.
  if (!d.daemon) throw cannot("the HTTP server did not start (libmicrohttpd refused its options)");
}

WatchHttpServer::~WatchHttpServer() {
  if (impl_->daemon) MHD_stop_daemon(impl_->daemon);
}

int WatchHttpServer::port() const { return impl_->port; }
const std::string& WatchHttpServer::url() const { return impl_->url; }
bool WatchHttpServer::loopback_only() const { return impl_->loopback_only; }

unsigned WatchHttpServer::connections() const {
  const MHD_DaemonInfo* info =
      MHD_get_daemon_info(impl_->daemon, MHD_DAEMON_INFO_CURRENT_CONNECTIONS);
  return info ? info->num_connections : 0;
}

}  // namespace clogscope::apps
