# Everyday commands. `make help` lists them.
CARGO ?= cargo
# Runs at a time for `make results` (one core each).
JOBS ?= 2
# A profile of the experiment files (`smoke`); empty: the committed grids.
PROFILE ?=
# The committed grids: every experiment file, one with a [[method]] (the table's DDPG and TD3
# cells give the 1M-step learning curves). A new file joins without an edit here.
EXPERIMENTS ?= $(patsubst experiments/%.toml,%,$(shell grep -l '^\[\[method\]\]' experiments/*.toml))

PROFILE_FLAG = $(if $(PROFILE),--profile $(PROFILE),)
# The results folder; empty: `results`, or `results-<profile>` with a profile.
RESULTS ?=
RESULTS_FLAG = $(if $(RESULTS),--results $(RESULTS),)
# The figures build has polars (aggregation); the other commands do not need it.
PBCS_POLARS = $(CARGO) run --release --locked --features polars --quiet --
# The binary where cargo puts it (CARGO_TARGET_DIR, as .ci/run sets it, or target/); the `bin`
# rule runs cargo every time, so a stale binary never runs.
TARGET_DIR = $(or $(CARGO_TARGET_DIR),target)
PBCS = $(TARGET_DIR)/release/pbcs

.PHONY: help build bin demo test test-slow bench lint ci clean figures results results-parallel cell \
        commands paper check-paper smoke python experiments mujoco test-mujoco pointmaze \
        mujoco-experiments

help:
	@echo "make demo      explore a 10x10 maze and draw it (out/explore/...)"
	@echo "make test      run the test suite (the README's test command)"
	@echo "make test-slow the six slow end-to-end tests it leaves out (CI runs both)"
	@echo "make figures   tables, figures and the report's LaTeX from the committed raw CSVs"
	@echo "               (results/raw -> results/tables, results/figures, paper/generated)"
	@echo "make results   re-run every experiment (resumable; JOBS=2; PROFILE=smoke; RESULTS=DIR);"
	@echo "               an experiment this build cannot run (PointMaze: MuJoCo) is skipped"
	@echo "               with one line saying how to run it (make pointmaze)"
	@echo "make results-parallel   the same through make -j\$$JOBS, one rule per (cell, seed)"
	@echo "make commands  print one command per (cell, seed), for a cluster's job array"
	@echo "make experiments   list the experiment grids (EXPERIMENTS)"
	@echo "make cell EXP=table CELL=pbcs-maze2 [SEED=3]   re-run one table cell and compare"
	@echo "make paper     build paper/report.pdf (needs latexmk + texlive)"
	@echo "make smoke     the whole pipeline on the smoke profile (CI runs it; RESULTS=DIR)"
	@echo "make bench     phase-1 speed, and learner update cost (every kernel, candle, end to end)"
	@echo "make lint      rustfmt and clippy"
	@echo "make python    the Python package into \$$VENV (default .venv) and its tests"
	@echo "make mujoco    MuJoCo 3.17.0 from its PyPI wheel into .mujoco/lib (feature mujoco)"
	@echo "make test-mujoco   our PointMaze's and AntMaze's tests, and the equality tests against"
	@echo "               gymnasium-robotics' own (installed into \$$VENV)"
	@echo "make pointmaze     every experiment with a PointMaze or AntMaze site (MUJOCO_EXPERIMENTS)"
	@echo "               with MuJoCo, then gymnasium-robotics' verdict on every PointMaze chain"
	@echo "               (python/benches/pointmaze_gym.py)"
	@echo "make mujoco-experiments   list them"
	@echo "make ci        what CI runs (.ci/run)"

build:
	$(CARGO) build --release --locked

demo:
	$(CARGO) run --release --locked -- explore --maze 10 --seed 0

test:
	$(CARGO) test --release --locked

test-slow:
	$(CARGO) test --release --locked -- --ignored

bench:
	$(CARGO) bench --locked --bench phase1
	$(CARGO) bench --locked --bench learner

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --release --locked --workspace --all-targets -- -D warnings

ci:
	bash .ci/run

mujoco:
	bash scripts/fetch-mujoco.sh

test-mujoco: mujoco
	$(CARGO) test --release --locked --features mujoco --test pointmaze --test antmaze
	$(CARGO) build --release --locked --features mujoco --example pointmaze_step --example antmaze_step
	test -x $(VENV)/bin/python || python3 -m venv $(VENV)
	$(VENV)/bin/pip install -q "mujoco==3.17.0" "gymnasium-robotics==1.4.2" pytest
	PBCS_POINTMAZE_STEP=$(abspath $(TARGET_DIR))/release/examples/pointmaze_step \
	  PBCS_ANTMAZE_STEP=$(abspath $(TARGET_DIR))/release/examples/antmaze_step \
	  $(VENV)/bin/python -m pytest -q python/tests/test_pointmaze.py python/tests/test_antmaze.py

# Every experiment with a PointMaze or AntMaze site (its `envs = [...]` line names one): the runs
# need MuJoCo, so `make results` skips them in a build without it. Read from the files, as
# EXPERIMENTS is; tests/experiments holds it to what the library says each grid needs.
MUJOCO_EXPERIMENTS ?= $(patsubst experiments/%.toml,%,$(shell grep -lE '^envs *=.*"(pointmaze|antmaze)' \
  $(patsubst %,experiments/%.toml,$(EXPERIMENTS))))

# The MuJoCo grids (MUJOCO_EXPERIMENTS: PointMaze's named maps, held-out seeds, velocity balls,
# learners alone and with HER, a map of one's own, PBCS with SAC skills), then every PBCS chain on
# PointMaze judged by gymnasium-robotics (each run re-made from its job file, its chain played in
# PointMaze_<Map>-v3; an experiment without such a chain has nothing to judge): the rows `make
# figures` then draws. The Python package first: its build rebuilds `pbcs` without MuJoCo.
pointmaze: mujoco python
	$(CARGO) build --release --locked --features mujoco --bin pbcs
	for e in $(MUJOCO_EXPERIMENTS); do $(PBCS) exp run experiments/$$e.toml --jobs $(JOBS) || exit 1; done
	$(VENV)/bin/pip install -q "mujoco==3.17.0" "gymnasium-robotics==1.4.2"
	for e in $(MUJOCO_EXPERIMENTS); do s=gym_cells_$${e#pointmaze_}.csv; [ $$e = pointmaze ] && s=gym_cells.csv; \
	  $(VENV)/bin/python python/benches/pointmaze_gym.py --pbcs $(PBCS) \
	    --raw results/raw/$$e --summary results/pointmaze/$$s || exit 1; done

mujoco-experiments:
	@echo $(MUJOCO_EXPERIMENTS)

# Aggregation with polars, then plotters; trains nothing (27 s measured after the build).
figures:
	$(PBCS_POLARS) aggregate $(PROFILE_FLAG) $(RESULTS_FLAG)
	$(PBCS_POLARS) figures $(PROFILE_FLAG) $(RESULTS_FLAG)

bin:
	$(CARGO) build --release --locked

results: bin
	for e in $(EXPERIMENTS); do $(PBCS) exp run experiments/$$e.toml --jobs $(JOBS) $(PROFILE_FLAG) \
	  $(RESULTS_FLAG) --skip-unavailable || exit 1; done

results-parallel: bin
	mkdir -p $(TARGET_DIR)
	for e in $(EXPERIMENTS); do $(PBCS) exp list experiments/$$e.toml --make $(PROFILE_FLAG) \
	  $(RESULTS_FLAG) --skip-unavailable > $(TARGET_DIR)/runs-$$e.mk || exit 1; \
	  $(MAKE) -f $(TARGET_DIR)/runs-$$e.mk -j$(JOBS) PBCS=$(PBCS) || exit 1; done

experiments:
	@echo $(EXPERIMENTS)

commands: bin
	@for e in $(EXPERIMENTS); do $(PBCS) exp list experiments/$$e.toml $(PROFILE_FLAG) $(RESULTS_FLAG) \
	  --skip-unavailable; done

cell: bin
	@test -n "$(EXP)" -a -n "$(CELL)" || { echo "usage: make cell EXP=table CELL=pbcs-maze2 [SEED=3]"; exit 2; }
	$(PBCS) exp check experiments/$(EXP).toml --cell $(CELL) $(if $(SEED),--seed $(SEED),) --jobs $(JOBS) $(PROFILE_FLAG)

paper:
	@command -v latexmk >/dev/null 2>&1 || { echo "make paper needs latexmk and LaTeX (Debian/Ubuntu: apt install latexmk texlive-latex-recommended texlive-latex-extra texlive-fonts-recommended); nothing was built"; exit 2; }
	$(MAKE) figures
	cd paper && latexmk -pdf -interaction=nonstopmode report.tex

# Every file the report includes exists (CI runs this after `make figures`).
check-paper:
	bash paper/check-includes.sh

smoke:
	$(MAKE) results PROFILE=smoke
	$(MAKE) figures PROFILE=smoke

# The Python package (python/): a virtual environment with maturin, gymnasium, numpy and
# pytest from PyPI, the package built into it, then its tests (they compare with the command,
# so the binary is built first).
VENV ?= .venv
python: bin
	test -x $(VENV)/bin/python || python3 -m venv $(VENV)
	$(VENV)/bin/pip install -q "maturin>=1.7,<2" "gymnasium>=1.0" numpy pytest
	PATH=$(abspath $(VENV))/bin:$$PATH pip install -q --no-build-isolation ./python
	PBCS_BIN=$(abspath $(PBCS)) $(VENV)/bin/python -m pytest -q python/tests

clean:
	rm -rf out results-*
