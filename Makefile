# Front door. `make demo` and `make test` each do the whole set-up (Debian
# packages, configure, build) and then their job.
.PHONY: all deps build test test-release test-asan demo clean

BUILD_DIR := build/release
ASAN_DIR := build/asan
GIBENCH := $(BUILD_DIR)/bin/gibench
DEMO_OUT ?= demo-out

all: build

deps:
	@bash scripts/install-deps.sh

build: deps
	cmake --preset release >/dev/null
	cmake --build --preset release

test: test-release test-asan

test-release: build
	ctest --preset release

# The unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
test-asan: deps
	cmake --preset asan >/dev/null
	cmake --build --preset asan
	ctest --preset asan

demo: build
	bash scripts/demo.sh $(GIBENCH) $(DEMO_OUT)

clean:
	rm -rf build $(DEMO_OUT)
