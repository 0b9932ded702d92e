# bingham -- build, demo, test and install.
#
#   make demo                    build the library, then build and run the C/C++ examples
#   make broad                   the AHRS vs VQF/Madgwick/Mahony on the BROAD trials (BROAD_DIR), then
#                                the simulated-IMU suite with known truth (examples/python/ahrs_suite.py)
#   make bench-compare           the AHRS's time per sample against VQF's at 50 Hz, 100 Hz, 286 Hz, 1 kHz
#                                (BROAD and simulated samples, through the C ABI): the ratio table
#   make cross-aarch64           the library built for aarch64-unknown-linux-gnu with Debian's Rust
#                                packages, and tests run under qemu-user (docs/testing.md)
#   make venv                    the Python package (pip install ./python) in $(TARGET_DIR)/venv
#   make test                    everything CI runs: `deps`, then `quick`, then `slow` (docs/testing.md)
#   make quick                   the quick tier (about 2 min on 2 cores once built): the test lists'
#                                check, format, clippy, rustdoc, header drift, API coverage, unit
#                                tests, the C/C++ API programs
#   make slow                    the slow tier: install test, Python package, sanitizers, the fuzz
#                                run, long runs, totality, the paper reproductions
#   make sanitize                C/C++ tests and examples under ASan + UBSan + LSan (in `slow`)
#   make valgrind                the same programs and the C ABI fuzz harness under valgrind
#   make fuzz                    long reliability runs: 10^7 fuzz cases, 10^6 filter steps
#   make install PREFIX=/opt/x   shared + static library (debug info stripped; STRIP= keeps it), headers,
#                                pkg-config file, CMake package
#   make header                  regenerate include/bingham.h from src/ffi/ (commit the result)
#
# One test binary: cargo test --release --test <name> (the tiers' lists: QUICK_TESTS, SLOW_TESTS).
# Uses cargo's default target directory (target/), or CARGO_TARGET_DIR if set.

SHELL := /bin/bash
.DEFAULT_GOAL := build

CARGO ?= cargo
PYTHON ?= python3
CC ?= cc
CXX ?= c++
PREFIX ?= /usr/local
LIBDIR ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
DESTDIR ?=
# `make install` strips the debug info (the release build keeps line tables, `debug = 1`, for
# profiling and backtraces): the shared library with --strip-unneeded, the static archive with
# --strip-debug. `make install STRIP=` keeps them.
STRIP ?= strip

VERSION := $(shell sed -n 's/^version *= *"\([^"]*\)".*/\1/p' Cargo.toml | head -n 1)
MAJOR := $(firstword $(subst ., ,$(VERSION)))
MINOR := $(word 2,$(subst ., ,$(VERSION)))
# The SONAME's version (build.rs): the major version, before 1.0 `0.<minor>`.
SOVERSION := $(if $(filter 0,$(MAJOR)),$(MAJOR).$(MINOR),$(MAJOR))
TARGET_DIR := $(or $(CARGO_TARGET_DIR),target)
RELEASE := $(TARGET_DIR)/release
DEMO_DIR := $(TARGET_DIR)/demo
# pkg-config file: paths below the prefix are written relative to ${prefix}
PC_LIBDIR := $(patsubst $(PREFIX)/%,$${prefix}/%,$(LIBDIR))
PC_INCLUDEDIR := $(patsubst $(PREFIX)/%,$${prefix}/%,$(INCLUDEDIR))
# CMake package (cmake/*.cmake.in): directories relative to the prefix, which the config finds
# from its own location (<libdir>/cmake/bingham/) -- or absolute if LIBDIR is not below PREFIX
CMAKEDIR := $(LIBDIR)/cmake/bingham
CMAKE_LIBDIR := $(patsubst $(PREFIX)/%,%,$(LIBDIR))
CMAKE_INCLUDEDIR := $(patsubst $(PREFIX)/%,%,$(INCLUDEDIR))
CMAKE_PREFIX := $(if $(filter /%,$(CMAKE_LIBDIR)),$(PREFIX),$${CMAKE_CURRENT_LIST_DIR}/../..$(subst $(subst ,, ),,$(foreach c,$(subst /, ,$(CMAKE_LIBDIR)),/..)))
SIZEOF_VOID_P := $(shell echo $$(( $$(getconf LONG_BIT) / 8 )))
# what a program linking libbingham.a needs besides the archive (Rust's standard library)
STATIC_LIBS := -lpthread -ldl -lm
EIGEN3_INCLUDE_DIR ?= /usr/include/eigen3
# The virtual environment with the Python package (python/) installed, see `venv`
VENV := $(abspath $(TARGET_DIR))/venv
VENV_PYTHON := $(VENV)/bin/python

.PHONY: build header demo demo-programs broad bench-compare cross-aarch64 venv test quick slow deps tiers fmt-check clippy doc quick-build \
        api-test unit-test c-test slow-test rust-test python-test install install-test uninstall clean \
        sanitize valgrind fuzz long

build:
	$(CARGO) build --release --lib

header:
	BINGHAM_WRITE_HEADER=1 $(CARGO) test --release --test header

# The example programs, each rebuilt only when its source, the headers or the static library
# changed (a rerun of `make demo` on an unchanged tree compiles nothing).
DEMO_C := $(wildcard examples/c/*.c)
DEMO_CXX11 := $(wildcard examples/c/*.cpp)
DEMO_CXX17 := $(wildcard examples/cpp/*.cpp)
DEMO_SRCS := $(DEMO_C) $(DEMO_CXX11) $(DEMO_CXX17)
DEMO_HEADERS := $(wildcard include/*.h include/*.hpp)

$(DEMO_DIR)/%: examples/c/%.c $(RELEASE)/libbingham.a $(DEMO_HEADERS)
	@mkdir -p $(DEMO_DIR)
	$(CC) -std=c99 -O2 -Wall -Wextra -Werror -pedantic -Iinclude $< $(RELEASE)/libbingham.a $(STATIC_LIBS) -o $@
$(DEMO_DIR)/%: examples/c/%.cpp $(RELEASE)/libbingham.a $(DEMO_HEADERS)
	@mkdir -p $(DEMO_DIR)
	$(CXX) -std=c++11 -O2 -Wall -Wextra -Werror -pedantic -Iinclude $< $(RELEASE)/libbingham.a $(STATIC_LIBS) -o $@
$(DEMO_DIR)/%: examples/cpp/%.cpp $(RELEASE)/libbingham.a $(DEMO_HEADERS)
	@mkdir -p $(DEMO_DIR)
	$(CXX) -std=c++17 -O2 -Wall -Wextra -Werror -pedantic -Iinclude -isystem $(EIGEN3_INCLUDE_DIR) $< \
	  $(RELEASE)/libbingham.a $(STATIC_LIBS) -o $@

# `build` (cargo) may refresh the archive; the programs are made after it.
demo-programs: build
	@$(MAKE) -s --no-print-directory $(foreach src,$(DEMO_SRCS),$(DEMO_DIR)/$(basename $(notdir $(src))))

demo: deps build venv demo-programs
	@set -e; for src in $(DEMO_SRCS); do \
	  echo "==== $$src"; $(DEMO_DIR)/$$(basename "$${src%.*}"); echo; \
	done
	@echo "==== plot of one run of examples/c/axis_tracking.c (truth, Bingham mode with 95 % interval, Kalman)"
	@$(DEMO_DIR)/axis_tracking $(DEMO_DIR)/axis_tracking_run.csv > /dev/null
	$(PYTHON) scripts/plot_run.py $(DEMO_DIR)/axis_tracking_run.csv $(DEMO_DIR)/axis_tracking_run.svg
	@echo; echo "==== examples/python/track_quaternion.py (20 runs, the package installed by \`make venv\`)"
	@$(VENV_PYTHON) examples/python/track_quaternion.py 20
	@echo; echo "==== examples/python/nonlinear.py (nonlinear rate law + pinhole camera)"
	@$(VENV_PYTHON) examples/python/nonlinear.py
	@echo; echo "==== examples/python/spin_bank.py (spin filter vs a bank of 12, as examples/c/spin_bank.c)"
	@$(VENV_PYTHON) examples/python/spin_bank.py

# Orientation accuracy on real IMU data (BROAD, CC BY 4.0): our AHRS against VQF, Madgwick and
# Mahony (the peers need the Python packages vqf and ahrs: `make deps`); plot of trial 07. Then
# the simulated-IMU suite (examples/python/ahrs_suite.py, known truth): the AHRS, VQF and Madgwick
# on the same simulated samples (about 25 s), all numbers in $(TARGET_DIR)/ahrs_suite.json.
BROAD_DIR ?= ../shared/data/broad

broad: venv
	$(VENV_PYTHON) examples/python/broad.py $(BROAD_DIR) \
	  --plot $(TARGET_DIR)/broad_trial07.svg
	@echo
	$(VENV_PYTHON) examples/python/ahrs_suite.py --json $(TARGET_DIR)/ahrs_suite.json

# The AHRS against VQF on the same samples, time per sample at 50 Hz, 100 Hz, 286 Hz and 1 kHz
# (examples/python/bench_compare.py: the nine BROAD trials, native and decimated, and simulated
# runs; both batch calls, interleaved, BENCH_REPEATS rounds, medians; figures: docs/speed.md).
# Not part of `make test`. BENCH_COMPARE_ARGS passes more options (e.g. --kernel portable).
BENCH_REPEATS ?= 5
BENCH_COMPARE_ARGS ?=

bench-compare: deps venv
	$(VENV_PYTHON) examples/python/bench_compare.py $(BROAD_DIR) --repeats $(BENCH_REPEATS) \
	  --json $(TARGET_DIR)/bench_compare.json $(BENCH_COMPARE_ARGS)

# The library for aarch64-unknown-linux-gnu (scripts/cross-aarch64.sh: Debian's rustc-web and its
# arm64 standard library unpacked into $(TARGET_DIR)/aarch64-toolchain, the host's cargo, the
# gcc-aarch64-linux-gnu linker), then AARCH64_TESTS under qemu-user (the portable kernel path:
# the one an aarch64 CPU runs). Skipped there: the dispatch test that runs its own binary again
# as a child process (qemu-user emulates one process; without a binfmt_misc handler the child
# cannot be started). Not part of `make test`; docs/testing.md.
AARCH64_TESTS ?= dispatch normalization special q4 saddlepoint mle deterministic filter ahrs \
                 observation spin
AARCH64_SKIP ?= the_environment_variable_forces_the_path

cross-aarch64:
	CARGO="$(CARGO)" TARGET_DIR="$(TARGET_DIR)" AARCH64_TESTS="$(AARCH64_TESTS)" \
	  AARCH64_SKIP="$(AARCH64_SKIP)" scripts/cross-aarch64.sh

# --- tests ---------------------------------------------------------------------------------
#
# `make test` = `make quick` then `make slow` (docs/testing.md: the steps, their times, how to run
# one tier or one test). Every integration test binary (tests/<name>.rs, tests/<name>/main.rs)
# is named in exactly one of the lists below; `make tiers` (the first step of `quick`) fails
# otherwise, so a new test file cannot escape both tiers.

# Run first in the quick tier: the header drift check, the API coverage test (every export
# against its mirrors) and the documented paths and versions.
API_TESTS := header api_mirrors doc_paths
# The quick tier's other binaries (with the library's unit tests, `--lib`), then the C/C++
# programs (c_tests, last: it compiles C++ with Eigen when its sources or headers changed).
UNIT_TESTS := ahrs ahrs_latency ahrs_timing deterministic dispatch distribution filter filter_alloc \
              filter_health general_d layering mle nonlinear normalization observation q4 \
              saddlepoint smoother special speed_figures spin threads world
C_TESTS := c_tests
QUICK_TESTS := $(API_TESTS) $(UNIT_TESTS) $(C_TESTS)
# The slow tier's binaries: the C ABI fuzz run, the long runs, the totality sweep, the paper
# reproductions, issue 21's acceptance run (10^6 importance draws per problem).
SLOW_TESTS := fuzz_ffi long_run totality glover_composition_kl glover_spin glover_spin_failures \
              glover_table1 nonlinear_trust
# `cargo test` with a list of binaries; --no-fail-fast: a failing binary does not hide the others.
CARGO_TEST := $(CARGO) test --release --no-fail-fast

test: deps quick slow
	@echo "make test: all passed"

# The quick tier (about 2 min on 2 cores once built, docs/testing.md): the tier lists, format,
# clippy, rustdoc, the header drift and API coverage tests, the unit tests, the C/C++ programs.
quick: deps tiers fmt-check clippy doc quick-build api-test unit-test c-test
	@echo "make quick: all passed"

# The slow tier, shortest step first: the install test, the Python package, the C/C++ programs
# under the sanitizers, the slow Rust tests.
slow: build install-test python-test sanitize slow-test
	@echo "make slow: all passed"

# Installs what the tests need when it is missing (Debian/Ubuntu): a C++ compiler, Eigen,
# pkg-config, binutils, python3-venv, and NumPy/pytest for the Python package.
deps:
	@PYTHON="$(PYTHON)" CXX="$(CXX)" scripts/install-deps.sh

tiers:
	@scripts/check-tiers.sh "$(QUICK_TESTS)" "$(SLOW_TESTS)"

fmt-check:
	$(CARGO) fmt --all --check

clippy:
	$(CARGO) clippy --workspace --all-targets -- -D warnings

# The API documentation with rustdoc's warnings (broken intra-doc links, bad HTML, ...) as errors.
doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps

# Builds every binary of the quick tier in one cargo run (cargo compiles the library and its
# unit tests in parallel), so the steps below only run tests.
quick-build:
	$(CARGO) test --release --no-run --lib $(addprefix --test ,$(QUICK_TESTS))

api-test:
	$(CARGO_TEST) $(addprefix --test ,$(API_TESTS))

# The library's unit tests, its doc tests and the quick integration binaries.
unit-test:
	$(CARGO_TEST) --lib $(addprefix --test ,$(UNIT_TESTS))
	$(CARGO_TEST) --doc

# The C/C++ programs of c_tests/ against the library (tests/c_tests.rs).
c-test:
	$(CARGO_TEST) $(addprefix --test ,$(C_TESTS))

slow-test:
	$(CARGO_TEST) $(addprefix --test ,$(SLOW_TESTS))

# Every Rust test in one cargo run (both tiers' binaries, unit and doc tests), without the
# other steps.
rust-test:
	$(CARGO_TEST)

# The pytest suite (python/tests/) run by the venv's Python against the INSTALLED package (from
# python/tests/, so the checkout's python/bingham/ is not on the path; BINGHAM_LIB unset, so the
# bundled library is loaded): fails when the package does not build or install.
# Then the package's type annotations: mypy --strict on python/bingham (mypy installed into the
# venv when missing).
python-test: venv
	@$(VENV_PYTHON) -c 'import pytest' 2>/dev/null || $(VENV_PYTHON) -m pip install pytest
	cd python/tests && env -u BINGHAM_LIB $(VENV_PYTHON) -m pytest -q -p no:cacheprovider
	@$(VENV_PYTHON) -c 'import mypy' 2>/dev/null || \
	  $(VENV_PYTHON) -m pip install --disable-pip-version-check --progress-bar off mypy
	$(VENV_PYTHON) -m mypy --strict --no-incremental python/bingham

# The Python package in a virtual environment ($(TARGET_DIR)/venv), for python-test, demo and
# broad: `pip install ./python` with BINGHAM_PREBUILT_LIB ships the libbingham.so that `build`
# made (debug info stripped) instead of compiling the crate again through setuptools-rust, so
# one build serves the C library and the Python package. --system-site-packages reuses NumPy,
# pytest, vqf and ahrs of the system Python (`make deps`). Reinstalled when the library or a file
# of the package changed (the stamp $(VENV)/.installed).
venv: build
	@$(MAKE) -s --no-print-directory $(VENV)/.installed
	@$(VENV_PYTHON) -c 'import bingham; print("bingham", bingham.__version__, "loads", bingham.library_path())'

# (re)installed when the library or a file of the package changed
$(VENV)/.installed: $(RELEASE)/libbingham.so $(shell find python -path python/build -prune -o -type f \( -name '*.py' -o -name '*.toml' -o -name '*.cfg' -o -name 'py.typed' \) -not -path '*/tests/*' -print 2>/dev/null)
	@test -x $(VENV_PYTHON) || $(PYTHON) -m venv --system-site-packages $(VENV)
	BINGHAM_PREBUILT_LIB=$(abspath $(RELEASE)/libbingham.so) \
	  $(VENV_PYTHON) -m pip install --disable-pip-version-check --progress-bar off ./python
	@touch $@

# Installs into a temporary prefix and builds/runs a C++11 program against it via pkg-config.
install-test: build
	MAKE="$(MAKE)" CXX="$(CXX)" CC="$(CC)" scripts/install-test.sh

# --- reliability ---------------------------------------------------------------------------

# The C/C++ tests and examples built with -fsanitize=address,undefined against libbingham.a and
# run with leak detection; fails if ASan is not really linked (about 2.5 min on 2 cores).
sanitize: build
	CARGO="$(CARGO)" CC="$(CC)" CXX="$(CXX)" scripts/sanitize.sh

# The same programs, and tests/fuzz_ffi/ with exactly-sized buffers, under valgrind memcheck
# (about 15 min on 2 cores; installs valgrind when missing).
valgrind: build
	CARGO="$(CARGO)" CC="$(CC)" CXX="$(CXX)" scripts/valgrind.sh

FUZZ_CASES ?= 10000000
LONG_STEPS ?= 1000000

# Long runs: the C ABI fuzz harness with FUZZ_CASES cases (seed: BINGHAM_FUZZ_SEED, default 0)
# and the filter's long runs with LONG_STEPS steps per scenario (`cargo test` runs 250000 cases
# and 10^4 steps).
fuzz: long
	BINGHAM_FUZZ_CASES=$(FUZZ_CASES) BINGHAM_FUZZ_STATS=1 $(CARGO) test --release --test fuzz_ffi -- --nocapture

long:
	BINGHAM_LONG_STEPS=$(LONG_STEPS) $(CARGO) test --release --test long_run -- --nocapture --test-threads=1

# --- install -------------------------------------------------------------------------------

install:
	@test -f $(RELEASE)/libbingham.so -a -f $(RELEASE)/libbingham.a || $(MAKE) --no-print-directory build
	install -d $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(INCLUDEDIR) $(DESTDIR)$(CMAKEDIR)
	install -m 644 include/bingham.h include/bingham.hpp include/bingham_eigen.hpp $(DESTDIR)$(INCLUDEDIR)/
	install -m 644 $(RELEASE)/libbingham.a $(DESTDIR)$(LIBDIR)/libbingham.a
	install -m 755 $(RELEASE)/libbingham.so $(DESTDIR)$(LIBDIR)/libbingham.so.$(VERSION)
	ln -sf libbingham.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libbingham.so.$(SOVERSION)
	ln -sf libbingham.so.$(SOVERSION) $(DESTDIR)$(LIBDIR)/libbingham.so
	$(if $(STRIP),$(STRIP) --strip-unneeded $(DESTDIR)$(LIBDIR)/libbingham.so.$(VERSION))
	$(if $(STRIP),$(STRIP) --strip-debug $(DESTDIR)$(LIBDIR)/libbingham.a)
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBDIR@|$(PC_LIBDIR)|g' \
	    -e 's|@INCLUDEDIR@|$(PC_INCLUDEDIR)|g' -e 's|@VERSION@|$(VERSION)|g' \
	    bingham.pc.in > $(DESTDIR)$(LIBDIR)/pkgconfig/bingham.pc
	set -e; for f in binghamConfig binghamConfigVersion; do \
	  sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@MAJOR@|$(MAJOR)|g' -e 's|@MINOR@|$(MINOR)|g' \
	      -e 's|@SOVERSION@|$(SOVERSION)|g' \
	      -e 's|@CMAKE_PREFIX@|$(CMAKE_PREFIX)|g' -e 's|@CMAKE_LIBDIR@|$(CMAKE_LIBDIR)|g' \
	      -e 's|@CMAKE_INCLUDEDIR@|$(CMAKE_INCLUDEDIR)|g' -e 's|@SIZEOF_VOID_P@|$(SIZEOF_VOID_P)|g' \
	      cmake/$$f.cmake.in > $(DESTDIR)$(CMAKEDIR)/$$f.cmake; \
	done
	@echo "installed bingham $(VERSION) into $(DESTDIR)$(PREFIX)"

uninstall:
	rm -f $(DESTDIR)$(INCLUDEDIR)/bingham.h $(DESTDIR)$(INCLUDEDIR)/bingham.hpp \
	      $(DESTDIR)$(INCLUDEDIR)/bingham_eigen.hpp $(DESTDIR)$(LIBDIR)/libbingham.a \
	      $(DESTDIR)$(LIBDIR)/libbingham.so $(DESTDIR)$(LIBDIR)/libbingham.so.$(SOVERSION) \
	      $(DESTDIR)$(LIBDIR)/libbingham.so.$(VERSION) $(DESTDIR)$(LIBDIR)/pkgconfig/bingham.pc \
	      $(DESTDIR)$(CMAKEDIR)/binghamConfig.cmake $(DESTDIR)$(CMAKEDIR)/binghamConfigVersion.cmake
	-rmdir $(DESTDIR)$(CMAKEDIR) 2>/dev/null

clean:
	$(CARGO) clean
