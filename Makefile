# sextant — the two README commands (`make demo`, `make test`) and the developer targets.
# Every target that builds installs missing Debian packages first (scripts/install-deps.sh).

JOBS  ?= $(shell nproc)
BUILD ?= build
CMAKE_FLAGS ?=

.PHONY: all deps build test demo install bench asan tsan fuzz spy clean format format-check

all: build

deps:
	@scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

test: build
	@ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS) --timeout 600

demo: build
	@scripts/demo.sh $(BUILD)

# cmake --install (README "Install and link"): PREFIX=/usr/local by default.
PREFIX ?=
install: build
	@cmake --install $(BUILD) $(if $(PREFIX),--prefix $(PREFIX))

bench:
	@SEXTANT_WITH_BENCH=1 scripts/install-deps.sh
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DSEXTANT_BENCH=ON $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)
	@bench/run_all.sh $(BUILD)

# Tests under AddressSanitizer + UndefinedBehaviorSanitizer, and under ThreadSanitizer.  A whole sanitizer build is
# long (15-40 min on two free cores, hours on busy ones); SAN_TARGETS and SAN_TESTS (a ctest -R regex) scope a run to
# what was built, e.g. the daemon's threads and its end-to-end scripts:
#   make tsan SAN_TARGETS="sextantd sextant test_daemon" SAN_TESTS='^(daemon|e2e):'
# (doctest's ctest names are 'daemon:NAME', no space; the e2e scripts are 'e2e: NAME')
# CMAKE_FLAGS reaches their configure step too, e.g. CMAKE_FLAGS=-DCMAKE_CXX_COMPILER_LAUNCHER=ccache.
SAN_TARGETS ?= all
SAN_TESTS ?= .
asan: deps
	@cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSEXTANT_SANITIZE=address,undefined $(CMAKE_FLAGS) >/dev/null
	@cmake --build build-asan -j $(JOBS) --target $(SAN_TARGETS)
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	  ctest --test-dir build-asan -R '$(SAN_TESTS)' --output-on-failure -j $(JOBS) --timeout 1200

tsan: deps
	@cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSEXTANT_SANITIZE=thread $(CMAKE_FLAGS) >/dev/null
	@cmake --build build-tsan -j $(JOBS) --target $(SAN_TARGETS)
	@TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1:suppressions=$(CURDIR)/tests/tsan.supp \
	  ctest --test-dir build-tsan -R '$(SAN_TESTS)' --output-on-failure -j $(JOBS) --timeout 1200

# Fuzz harnesses (tests/fuzz/) as libFuzzer binaries under ASan/UBSan, built with clang in build-fuzz, each run for
# FUZZ_SECONDS (default 60); `make test` replays their corpora and past crash inputs without clang.
FUZZ_SECONDS ?= 60
fuzz:
	@SEXTANT_WITH_FUZZ=1 scripts/install-deps.sh
	@CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSEXTANT_FUZZ=ON \
	  -DSEXTANT_SANITIZE=address,undefined $(CMAKE_FLAGS) >/dev/null
	@cmake --build build-fuzz -j $(JOBS) --target fuzz_all
	@FUZZ_SECONDS=$(FUZZ_SECONDS) scripts/fuzz.sh build-fuzz

# lcm-spy with sextant's message types on the classpath (Debian's lcm-spy wrapper passes a JVM flag
# that Java 17 no longer accepts, so the JVM is started directly).
spy: build
	@CLASSPATH=/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:$(BUILD)/lcmtypes/sextant_types.jar \
	  java -Djava.net.preferIPv4Stack=true -Xmx256m lcm.spy.Spy $(SPY_ARGS)

# The house style (.clang-format): `make format` rewrites every C++ source in place, `make format-check` lists the
# files that differ from it and fails when there is one.
FORMAT_FILES = $(shell git ls-files '*.cpp' '*.hpp' '*.h')
format:
	@command -v clang-format >/dev/null || apt-get install -y -qq clang-format >/dev/null
	@clang-format -i $(FORMAT_FILES)

format-check:
	@command -v clang-format >/dev/null || apt-get install -y -qq clang-format >/dev/null
	@bad=$$(for f in $(FORMAT_FILES); do clang-format $$f | cmp -s - $$f || echo $$f; done); \
	  if [ -n "$$bad" ]; then echo "not formatted (make format):"; echo "$$bad"; exit 1; fi; echo "format: every file as .clang-format says"

clean:
	rm -rf $(BUILD) build-asan build-tsan build-fuzz
