# The two commands of the README: `make demo` and `make test`. Both install missing Debian packages,
# then build in Release under build/ (the binary is build/bin/clogscope).
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
ARM64_JOBS ?= 1

.PHONY: all deps build test sanitize fuzz demo bench clean format arm64-check

all: build

deps:
	@scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)

# The test suite under ASan + UBSan in its own build directory (any report fails the test), built by
# clang 14: a second compiler on every change (gcc builds Release), and a third less time than gcc
# with these checks (CI's budget holds both builds). -O1 with line tables and assertions on.
SANITIZE_DIR ?= build-asan
sanitize:
	@scripts/install-deps.sh --clang
	@cmake -S . -B $(SANITIZE_DIR) -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DCLOGSCOPE_SANITIZE=ON >/dev/null
	@cmake --build $(SANITIZE_DIR) -j $(JOBS)
	@cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) $(CTEST_ARGS)

# Each libFuzzer target for FUZZ_SECONDS on its committed seeds (fuzz/corpus/<target>); new
# inputs go to build-fuzz/corpus/, findings (crash-*, timeout-*, leak-*) to build-fuzz/.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS = csv manifest calibration extruder frame step lag
fuzz:
	@scripts/install-deps.sh --clang
	@CC=clang-14 CXX=clang++-14 cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DCLOGSCOPE_FUZZ=ON >/dev/null
	@cmake --build $(FUZZ_DIR) -j $(JOBS) --target $(addsuffix _fuzz,$(FUZZ_TARGETS))
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(FUZZ_DIR)/corpus/$$t; \
	  echo "== $$t: $(FUZZ_SECONDS) s"; \
	  (cd $(FUZZ_DIR) && ./bin/$${t}_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 \
	    -rss_limit_mb=2048 -print_final_stats=1 corpus/$$t ../fuzz/corpus/$$t) || exit 1; \
	done

# The arm64 cross-build (Debian 12 arm64 sysroot, aarch64-linux-gnu-g++) and its unit tests under
# qemu-user, in build-arm64/ (docs/arm64.md). Not in .ci/run: ~25 min of emulated tests (-j2).
arm64-check:
	@JOBS=$(ARM64_JOBS) scripts/arm64-check.sh

demo: build
	@scripts/demo.sh $(BUILD_DIR)/bin/clogscope

bench: build
	@$(BUILD_DIR)/bin/clogscope_bench
	@PYTHONPATH=$(BUILD_DIR)/python /usr/bin/python3 bench/python_overhead.py

format:
	@clang-format -i $$(git ls-files '*.h' '*.cc')

clean:
	@rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(FUZZ_DIR) build-arm64
