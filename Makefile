# The two commands: `make reproduce` (the main job) and `make test` (all tests).
CARGO ?= cargo
# The LIGGGHTS callback shim is built when LIGGGHTS' headers are installed (after setup).
FEATURES = $$(test -f /usr/include/liggghts/fix_external.h && echo --features liggghts-shim)

.PHONY: setup build reproduce test clean

setup:
	@bash scripts/setup.sh

build: setup
	$(CARGO) build --release $(FEATURES)

reproduce: build
	@bash scripts/reproduce.sh

test: setup
	$(CARGO) test --release $(FEATURES)

clean:
	$(CARGO) clean
	rm -rf runs
