# The two commands: `make reproduce` (the main job) and `make test` (all tests).
CARGO ?= cargo
# The LIGGGHTS callback shim is built when LIGGGHTS' headers are installed (after setup).
FEATURES = $$(test -f /usr/include/liggghts/fix_external.h && echo --features liggghts-shim)

.PHONY: setup build reproduce test lint clean

setup:
	@bash scripts/setup.sh

# One build serves both targets. `cargo build` resolves dependency features without the
# dev-dependencies, `cargo test` with them (criterion and tempfile turn on bitflags/std,
# either/use_std and zerocopy/derive: compare `cargo tree -e features -e normal,build` with
# `-e normal,build,dev`), so the 35 crates above those (polars, faer, hdf5, rayon among them)
# got different hashes and the second command rebuilt them. `cargo test --no-run` builds
# target/release/magdem too (cargo builds the binaries for the integration tests, which run it)
# with the test resolution, so `make test`
# after `make build` (or the other way round) compiles nothing new. The price: `make build`
# also compiles the test binaries. The extra features add trait impls and derives, no code
# the solver runs, so the binary computes the same results either way.
build: setup
	$(CARGO) test --release --no-run $(FEATURES)

reproduce: build
	@bash scripts/reproduce.sh

test: setup
	$(CARGO) test --release $(FEATURES)

# Formatting and lints (CI runs this before the tests): rustfmt.toml's layout, clippy's
# warnings as errors.
lint: setup
	$(CARGO) fmt --check
	$(CARGO) clippy --release --all-targets $(FEATURES) -- -D warnings

clean:
	$(CARGO) clean
	rm -rf runs
