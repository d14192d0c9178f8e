#!/usr/bin/env bash
# Installs the Debian 12 packages ClogScope builds and runs with. Idempotent: does nothing when every
# package is present. Runs as root, or through sudo when not root. `--clang` adds clang and its
# sanitizer and libFuzzer runtimes, for `make sanitize` and `make fuzz`.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libopencv-dev          # frames and image processing (core, imgproc: only these are linked), drawing
  libceres-dev           # calibration and predictor fits (pulls Eigen)
  libeigen3-dev          # small linear algebra in the edge fitter and the model
  libgtest-dev           # unit tests
  libcli11-dev           # command line
  libspdlog-dev libfmt-dev  # logging and formatting
  nlohmann-json3-dev     # JSON ground truth and tables
  libyaml-cpp-dev        # manifests and parameter files with line numbers in errors
  libavformat-dev libavcodec-dev libavutil-dev libswscale-dev  # video in (straight to luma) and out; TIFF, BMP and PGM/PPM images
  libpng-dev libjpeg-dev # PNG and JPEG images: errors returned, not printed; the JPEG bytes OpenCV wrote (same library and settings)
  libv4l-dev             # V4L2 cameras (`watch /dev/video0`): libv4l2 turns any camera format into YUV, whose luma is measured
  ffmpeg                 # the ffmpeg CLI: camera-like streams and encodes in tests, decode benchmarks
  gnuplot-nox            # plots (optional at run time)
  libmicrohttpd-dev      # `watch --http`: a server made to face a network (epoll, per-client limits); cpp-httplib 0.11 held a thread per slow client
  libmosquitto-dev       # `watch --mqtt`: the Eclipse Mosquitto client library (own network thread, last will, reconnect back-off)
  libcurl4-openssl-dev   # `watch --moonraker/--octoprint`: the printer's HTTP API (timeouts, no redirects, https)
  mosquitto mosquitto-clients  # the MQTT tests: a real broker on localhost and mosquitto_sub to read what was published
  chromium               # the page at / (`watch --http`) tested in a real browser: headless Chromium loads it from a running watch, its DOM and a screenshot are checked against the rendered diameter (tests only; ~360 MB installed)
  prometheus             # the /metrics tests: promtool checks the text and docs/'s alert rules, a real Prometheus on localhost scrapes a watch (its own service may start on :9090; the tests use a free port)
  python3-dev            # the Python module (python/): Debian's Python 3.11 headers
  pybind11-dev           # the Python module's bindings (headers and CMake config)
  python3-numpy          # the Python module: frames in and out as NumPy arrays
  python3-pandas         # the Python module: per-frame and diameter tables as DataFrames
  python3-pytest         # the Python module's tests (python/tests, run by ctest)
  jupyter-nbconvert python3-ipykernel  # a test executes examples/measure_folder.ipynb (~30 MB)
)
if [ "${1:-}" = "--clang" ]; then
  packages+=(clang-14 libclang-rt-14-dev lld-14)  # the sanitizer build (linked by lld); libFuzzer with ASan/UBSan
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: not root and no sudo; install these packages: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
