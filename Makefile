# The two commands: `make reproduce` (the main job) and `make test` (all tests).
CARGO ?= cargo

.PHONY: setup build reproduce test clean

setup:
	@bash scripts/setup.sh

build: setup
	$(CARGO) build --release

reproduce: build
	@bash scripts/reproduce.sh

test: setup
	$(CARGO) test --release

clean:
	$(CARGO) clean
	rm -rf runs
