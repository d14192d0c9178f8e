#pragma once

// A real mosquitto broker for the watch's MQTT tests, started on a free localhost port, and
// mosquitto_sub reading what it delivers (each message with its time, retained flag and topic).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/spawn.h"
#include "tests/apps/external_process.h"

namespace clogscope::apps::mqtt_testing {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

inline Clock::time_point Deadline(double s) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

inline double UnixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

inline std::string MosquittoBinary() {
  for (const std::string& p : {FindOnPath("mosquitto"), std::string("/usr/sbin/mosquitto")})
    if (!p.empty() && access(p.c_str(), X_OK) == 0) return p;
  return "";
}

inline bool Accepts(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  close(fd);
  return ok;
}

inline void Stop(pid_t* pid, int signal = SIGTERM) {
  if (*pid <= 0) return;
  kill(*pid, signal);
  waitpid(*pid, nullptr, 0);
  *pid = -1;
}

// A file another process writes, read as it grows.
class GrowingFile {
 public:
  explicit GrowingFile(fs::path path) : path_(std::move(path)) {}
  const std::string& Text() {
    std::ifstream in(path_, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(text_.size()));
    text_.append(std::istreambuf_iterator<char>(in), {});
    return text_;
  }
  // Until pred(text so far) holds, for at most timeout_s.
  bool WaitFor(const std::function<bool(const std::string&)>& pred, double timeout_s) {
    const auto deadline = Deadline(timeout_s);
    while (!pred(Text())) {
      if (Clock::now() > deadline) return false;
      std::this_thread::yield();
    }
    return true;
  }

 private:
  fs::path path_;
  std::string text_;
};

// mosquitto on 127.0.0.1:port, its configuration and log in `dir`.
class Broker {
 public:
  Broker(const fs::path& dir, int port, const std::string& auth = "allow_anonymous true\n")
      : port_(port) {
    const fs::path conf = dir / ("mosquitto_" + std::to_string(port) + ".conf");
    // Run as root, mosquitto would become the user "mosquitto" and no longer read the test's
    // files: it stays who it is.
    const passwd* me = getpwuid(getuid());
    std::ofstream(conf) << "listener " << port << " 127.0.0.1\npersistence false\nuser "
                        << (me ? me->pw_name : "root") << "\n"
                        << auth;
    SpawnOptions run;
    run.argv = {MosquittoBinary(), "-c", conf.string()};
    run.stdout_path = run.stderr_path =
        (dir / ("mosquitto_" + std::to_string(port) + ".log")).string();
    std::string why;
    pid_ = Spawn(run, &why);
  }
  ~Broker() { Stop(&pid_, paused_ ? SIGKILL : SIGTERM); }
  // Stops answering, its connections left open (SIGSTOP): a broker that hangs.
  void Pause() {
    kill(pid_, SIGSTOP);
    paused_ = true;
  }
  // Accepting connections within timeout_s (it binds soon after it starts).
  bool WaitReady(double timeout_s) {
    const auto deadline = Deadline(timeout_s);
    while (pid_ > 0 && Clock::now() < deadline) {
      if (Accepts(port_)) return true;
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) pid_ = -1;  // it failed to start
      std::this_thread::yield();
    }
    return false;
  }
  int port() const { return port_; }

 private:
  int port_;
  pid_t pid_ = -1;
  bool paused_ = false;
};

struct Received {
  double unix_s = 0;  // when mosquitto_sub had it
  bool retained = false;
  std::string topic, payload;
};

// mosquitto_sub on `topics`, one line per message: time, retained flag, topic, payload in hex.
class Subscriber {
 public:
  Subscriber(const fs::path& dir, const std::string& name, int port,
             const std::vector<std::string>& topics, const std::vector<std::string>& extra = {},
             const std::vector<std::string>& login = {})
      : port_(port), login_(login), out_(dir / (name + ".sub")) {
    const fs::path out = dir / (name + ".sub");
    SpawnOptions run;
    run.argv = {"mosquitto_sub",      "-h", "127.0.0.1",  "-p",
                std::to_string(port), "-F", "%U %r %t %x"};
    for (const std::string& t : topics) run.argv.insert(run.argv.end(), {"-t", t});
    run.argv.insert(run.argv.end(), extra.begin(), extra.end());
    run.argv.insert(run.argv.end(), login.begin(), login.end());
    run.stdout_path = out.string();
    run.stderr_path = (dir / (name + ".sub.err")).string();
    std::string why;
    pid_ = Spawn(run, &why);
  }
  ~Subscriber() { Stop(&pid_); }

  // The messages received so far.
  std::vector<Received> Messages() { return Parse(out_.Text()); }
  bool WaitFor(const std::function<bool(const std::vector<Received>&)>& pred, double timeout_s) {
    return out_.WaitFor([&](const std::string& text) { return pred(Parse(text)); }, timeout_s);
  }
  // Subscribed: a probe published to `topic` comes back (sent again until it does).
  bool WaitSubscribed(const std::string& topic, double timeout_s) {
    const auto deadline = Deadline(timeout_s);
    while (Clock::now() < deadline) {
      SpawnOptions pub;
      pub.argv = {"mosquitto_pub", "-h", "127.0.0.1", "-p", std::to_string(port_), "-t",
                  topic,           "-m", "probe"};
      pub.argv.insert(pub.argv.end(), login_.begin(), login_.end());
      std::string why;
      const pid_t pid = Spawn(pub, &why);
      if (pid < 0 || !WaitForExit(pid, &why)) return false;
      if (WaitFor(Has(topic, "probe"), 0.5)) return true;
    }
    return false;
  }
  static std::function<bool(const std::vector<Received>&)> Has(const std::string& topic,
                                                               const std::string& payload) {
    return [=](const std::vector<Received>& all) {
      for (const Received& m : all)
        if (m.topic == topic && m.payload == payload) return true;
      return false;
    };
  }

 private:
  static std::vector<Received> Parse(const std::string& text) {
    std::vector<Received> out;
    size_t at = 0;
    for (size_t end; (end = text.find('\n', at)) != std::string::npos; at = end + 1) {
      std::istringstream line(text.substr(at, end - at));
      Received m;
      std::string hex;
      int retained = 0;
      line >> m.unix_s >> retained >> m.topic >> hex;
      m.retained = retained != 0;
      for (size_t i = 0; i + 1 < hex.size(); i += 2)
        m.payload.push_back(static_cast<char>(std::stoi(hex.substr(i, 2), nullptr, 16)));
      out.push_back(std::move(m));
    }
    return out;
  }
  int port_;
  std::vector<std::string> login_;  // -u USER -P PASSWORD, or none
  GrowingFile out_;
  pid_t pid_ = -1;
};

inline std::vector<Received> On(const std::vector<Received>& all, const std::string& topic) {
  std::vector<Received> out;
  for (const Received& m : all)
    if (m.topic == topic) out.push_back(m);
  return out;
}

}  // namespace clogscope::apps::mqtt_testing
