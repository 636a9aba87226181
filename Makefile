# Front door. `make demo` and `make test` each do the whole set-up (Debian
# packages, configure, build) and then their job.
.PHONY: all deps build test test-release test-asan demo results clean

BUILD_DIR := build/release
ASAN_DIR := build/asan
GIBENCH := $(BUILD_DIR)/bin/gibench
DEMO_OUT ?= demo-out

all: build

deps:
	@bash scripts/install-deps.sh

# Bash completion of commands, methods and parameters, generated from the
# build's own `gibench methods --json` into the user's completion folder.
COMPLETION_DIR ?= $(or $(XDG_DATA_HOME),$(HOME)/.local/share)/bash-completion/completions

build: deps
	cmake --preset release >/dev/null
	cmake --build --preset release
	@mkdir -p $(COMPLETION_DIR) && python3 scripts/gen-completion.py $(GIBENCH) $(COMPLETION_DIR)/gibench \
	  || echo "make: bash completion not installed (scripts/gen-completion.py failed)"

test: test-release test-asan

test-release: build
	ctest --preset release

# The unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
test-asan: deps
	cmake --preset asan >/dev/null
	cmake --build --preset asan
	ctest --preset asan

# The demo study: the Cornell box, every installed method with a small sweep,
# the path-traced references and convergence curve; report in $(DEMO_OUT)/.
demo: build
	$(GIBENCH) study harness/studies/demo.json --out $(DEMO_OUT)
	@echo "demo: report in $(DEMO_OUT)/report.md and $(DEMO_OUT)/index.html"

# Every committed study under results/ afresh, with its tables (hours on
# llvmpipe; scripts/regenerate_results.sh STUDY... for one).
results: build
	@bash scripts/install-deps.sh --sources
	GIBENCH=$(GIBENCH) scripts/regenerate_results.sh

clean:
	rm -rf build $(DEMO_OUT)
