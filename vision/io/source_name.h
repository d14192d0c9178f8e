#pragma once

#include <string>

namespace clogscope::vision {

// A source as it may be shown (JSON lines, /status, warnings, errors, the alert command's
// environment): a URL's password replaced by ***, "rtsp://user:pass@cam/s" →
// "rtsp://user:***@cam/s" (a user name alone, which some cameras take as a key:
// "rtsp://***@cam/s"), and the value of a query parameter whose name speaks of a secret (pass, pwd,
// token, secret, key, auth, sig) too: "http://cam/snap.cgi?user=admin&pwd=***". Anything that is
// not a URL (a file, a folder, a device) is shown as it is. The source itself is opened as given:
// this is for showing only.
std::string RedactCredentials(const std::string& source);

}  // namespace clogscope::vision
