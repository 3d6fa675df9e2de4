# Everyday commands. `make help` lists them.
CARGO ?= cargo

.PHONY: help build demo test bench lint ci clean

help:
	@echo "make demo   explore a 10x10 maze and draw it (out/explore/...)"
	@echo "make test   run the test suite (the README's test command)"
	@echo "make bench  phase-1 speed, and learner update cost (fused vs candle)"
	@echo "make lint   rustfmt and clippy"
	@echo "make ci     what CI runs (.ci/run)"

build:
	$(CARGO) build --release --locked

demo:
	$(CARGO) run --release --locked -- explore --maze 10 --seed 0

test:
	$(CARGO) test --release --locked

bench:
	$(CARGO) bench --locked --bench phase1
	$(CARGO) bench --locked --bench learner

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --release --locked --all-targets -- -D warnings

ci:
	bash .ci/run

clean:
	rm -rf out
