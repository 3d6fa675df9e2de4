#!/usr/bin/env python3
"""Probe the `pbcs` binary with hostile inputs, as a new user would type them.

Usage:
    python3 scripts/probe-hostile.py [--bin PATH] [--out CSV] [--only SUBSTR] [--timeout S]
                                     [--keep] [--mem-gb G] [--list]

Each case runs in its own fresh temporary folder (its cwd, holding a copy of the repository's
experiments/), one process at a time, under a per-case timeout (its process group killed past
it) and an address-space limit. Every outcome gets one class:

    panic    exit 101, or "panicked" in stderr
    abort    killed by a signal (SIGABRT, SIGSEGV, SIGKILL by the memory limit, ...), or
             "memory allocation" in stderr
    hang     ran past the timeout
    silent   exit 0 where the case expects a refusal
    refused  nonzero exit with a message (the column names_field says whether it names the
             field the case expects, names_file whether it names the file)
    vague    refused, but the message does not name the expected field (or the line, for the
             TOML structure cases), or is longer than 2 KB
    ok       exit 0 where the case expects success (or accepts either outcome)
    failed   nonzero exit where the case expects success
    nomsg    nonzero exit with nothing on stderr
    wrong    the exit status is fine but the output is not: a file `x` appeared (a shell
             injection through a path), a generated script does not quote a path

The CSV (default /tmp/probe-hostile/report.csv) has one row per case. The summary prints the
counts per class and every case not classed `refused` or `ok`. Exit status 1 if any case is
panic, abort, hang, silent or wrong; 2 if the fixtures could not be built.

Fixtures (a maze-2 PBCS run and its chain, a vanilla run, a phase-1 run, the `smoke` results of
experiments/table.toml, and a results folder with the committed tables of experiments/table.toml)
are built first under /tmp/probe-hostile/fixtures with the binary under test (about 10 s).
Python 3 standard library only.
"""

import argparse
import csv
import os
import random
import re
import resource
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BIN = Path.home() / ".cache/pbcs-rs/target/release/pbcs"
SCRATCH = Path("/tmp/probe-hostile")
FX = SCRATCH / "fixtures"

U64MAX = "18446744073709551615"
I64MAX = "9223372036854775807"
BIG = "100000000000"
TENTH = "1844674407370955162"  # u64::MAX / 10, rounded up: overflows once multiplied by 10

FAILING = {"panic", "abort", "hang", "silent", "wrong"}
MSG_MAX = 2048  # a refusal longer than this is `vague` (a hostile input echoed back)

# bounds (src/validate.rs `bounds`, MAX_MAZE_SIZE, MAX_SEEDS)
EPISODES = 100_000
EPISODE_STEPS = 1_000_000
REPLAY = 100_000_000
WIDTH = 16_384
LAYERS = 16
SAMPLES = 100_000
REPEATS = 1_000_000
MAX_MAZE = 100
MAX_SEEDS = 100_000


# --------------------------------------------------------------------------------------------
# cases


class Case:
    """One probe.

    argv: the command, with {B} (the binary), {T} (the case's folder), {FX} (the fixtures).
    expect: "refuse", "ok" or "either".
    field: substrings, one of which the refusal should contain (the field, the flag, the line).
    file: a substring naming the file (its name) the refusal should contain.
    setup: f(T) preparing the folder.  check: f(ctx) -> None or (class, note), after running.
    """

    def __init__(self, cid, argv, expect="refuse", field=None, file=None, setup=None,
                 check=None, what="", long_ok=False):
        self.cid = cid
        self.argv = argv
        self.expect = expect
        if isinstance(field, str):
            field = [field]
        self.field = field
        self.file = file
        self.setup = setup
        self.check = check
        self.what = what
        self.long_ok = long_ok  # a long refusal is fine (a usage text)


CASES = []
IDS = set()


def add(cid, argv, expect="refuse", **kw):
    if cid in IDS:
        raise SystemExit(f"probe-hostile: duplicate case id {cid}")
    IDS.add(cid)
    CASES.append(Case(cid, argv, expect, **kw))


def write(path, data):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    path.write_bytes(data)


def copy_fixture(name, T, dest=None):
    shutil.copytree(FX / name, Path(T) / (dest or name), symlinks=True)


# ---- TOML text editing (line based: the fixtures' config.toml and the experiment files)


def set_key(text, section, key, value):
    """`text` with `key = value` in `[section]` ("" for the top level): the key's line replaced,
    or added at the end of the section (the section appended if absent). Returns (text, line
    number of the key, 1-based)."""
    lines = text.rstrip("\n").split("\n")
    cur = ""
    found = None
    last = None  # last line of the section
    seen = section == ""
    for i, line in enumerate(lines):
        m = re.match(r"^\s*\[+([^\]]+)\]+\s*(#.*)?$", line)
        if m:
            cur = m.group(1).strip()
            if cur == section:
                seen = True
                last = i
            continue
        if cur == section:
            if re.match(rf"^\s*{re.escape(key)}\s*=", line):
                found = i
            if line.strip():
                last = i
    new = f"{key} = {value}"
    if found is not None:
        lines[found] = new
        at = found
    elif section == "":
        lines.insert(0, new)
        at = 0
    elif seen:
        lines.insert(last + 1, new)
        at = last + 1
    else:
        lines += ["", f"[{section}]", new]
        at = len(lines) - 1
    return "\n".join(lines) + "\n", at + 1


def set_keys(text, changes):
    for section, key, value in changes:
        text, _ = set_key(text, section, key, value)
    return text


def del_key(text, section, key):
    out, cur = [], ""
    for line in text.split("\n"):
        m = re.match(r"^\s*\[+([^\]]+)\]+\s*$", line)
        if m:
            cur = m.group(1).strip()
        elif cur == section and re.match(rf"^\s*{re.escape(key)}\s*=", line):
            continue
        out.append(line)
    return "\n".join(out)


def replace_section(text, section, body):
    """`text` with `[section]`'s lines replaced by `body`."""
    out, cur, skipping = [], "", False
    for line in text.split("\n"):
        m = re.match(r"^\s*\[+([^\]]+)\]+\s*$", line)
        if m:
            cur = m.group(1).strip()
            skipping = cur == section
            if skipping:
                out.append(line)
                out.extend(body.strip("\n").split("\n"))
                continue
        if not skipping:
            out.append(line)
    return "\n".join(out)


def base_text(kind):
    return (FX / kind / "config.toml").read_text()


def table_text():
    return (REPO / "experiments/table.toml").read_text()


def sub1(text, old, new):
    if old not in text:
        raise RuntimeError(f"setup: anchor not found: {old[:80]!r}")
    return text.replace(old, new, 1)


# ---- commands for a job config

OUTS = {
    "run": ["{B}", "run", "--config", "{T}/c.toml", "--quiet", "--out", "{T}/out"],
    "train": ["{B}", "train", "--config", "{T}/c.toml", "--quiet", "--out", "{T}/out"],
    "explore": ["{B}", "explore", "--config", "{T}/c.toml", "--quiet", "--out", "{T}/out"],
}


def config_case(cid, kind, text_fn, expect="refuse", field=None, what="", check=None):
    """A case running `pbcs <kind> --config c.toml`, c.toml being text_fn() (the fixture's
    config.toml changed)."""

    def setup(T):
        write(Path(T) / "c.toml", text_fn())

    add(cid, OUTS[kind], expect, field=field, file="c.toml", setup=setup, check=check, what=what)


def value_cases(kind, section, key, values, expect_of, extra=()):
    """One case per value of `section.key` in the `kind` fixture's config."""
    full = f"{section}.{key}" if section else key
    for v in values:
        exp = expect_of(v)
        cid = f"{kind}.cfg.{full}={v}"
        config_case(cid, kind, (lambda v=v: set_keys(base_text(kind), [(section, key, v)] + list(extra))),
                    exp, field=[key], what=f"c.toml: {full} = {v}"
                    + "".join(f"; {s}.{k} = {x}" for s, k, x in extra))


INT_FULL = ["0", "-1", U64MAX, I64MAX, "1e11", BIG, TENTH, '"many"', "1.5"]
INT_SHORT = ["0", "-1", I64MAX, TENTH, '"many"']
FLOAT_FULL = ["nan", "inf", "-inf", "-1", "0", "1e-300", "1e11", '"many"']
FLOAT_SHORT = ["nan", "inf", "-1", "0"]


def count_expect(zero_ok=False, huge="refuse"):
    """Expectations for a count: 0 refused unless it means off; anything not a whole number in
    range refused; `huge` for an in-u64 value past any sensible bound (a budget: `either`)."""

    def f(v):
        if v == "0":
            return "either" if zero_ok else "refuse"
        if v in (I64MAX, BIG, TENTH) or (v == U64MAX and huge == "either"):
            return huge
        return "refuse"

    return f


def always(e):
    return lambda v: e


def seed_expect(v):
    if v in ("0", I64MAX, BIG, TENTH):
        return "ok"
    if v == U64MAX:
        return "either"  # a valid seed TOML cannot write (its integers are i64)
    return "refuse"


def float_expect(zero_ok=False, big="refuse", tiny="refuse"):
    def f(v):
        if v == "0":
            return "either" if zero_ok else "refuse"
        if v == "1e11":
            return big
        if v == "1e-300":
            return "either" if zero_ok else tiny
        return "refuse"

    return f


def build_config_cases():
    # ---------------- run (PbcsJob): every field of the fixture's config.toml
    value_cases("run", "", "seed", INT_FULL, seed_expect)
    value_cases("run", "maze", "size", INT_FULL + ["1", "101", "100000"], count_expect())
    value_cases("run", "maze", "seed", ["-1", U64MAX, '"many"'], seed_expect)
    for k in ("wall_thickness", "target_radius", "max_action"):
        value_cases("run", "maze", k, ["nan", "0", "-1", "0.6"], float_expect())
    value_cases("run", "explore", "bin_side", FLOAT_FULL + ["1.5"], float_expect())
    value_cases("run", "explore", "budget", ["0", "-1", U64MAX, '"many"'], count_expect(huge="either"))
    value_cases("run", "explore", "hold", ["0", "-1", "4294967296"], count_expect())
    # learner
    value_cases("run", "learner", "batch_size", INT_FULL + [str(REPLAY + 1)], count_expect())
    value_cases("run", "learner", "replay_size", INT_FULL + [str(REPLAY + 1)], count_expect())
    for i, v in enumerate(HIDDEN):
        config_case(f"run.cfg.learner.hidden#{i}", "run",
                    lambda v=v: set_keys(base_text("run"), [("learner", "hidden", v)]),
                    field=["hidden"], what=f"c.toml: learner.hidden = {v[:60]}")
    for k in ("actor_lr", "critic_lr"):
        value_cases("run", "learner", k, ["nan", "inf", "-1", "0"], float_expect())
    value_cases("run", "learner", "gamma", ["1", "1.5", "-0.1", "nan", "inf", '"many"'],
                always("refuse"))
    value_cases("run", "learner", "tau", ["0", "1.5", "nan"], always("refuse"))
    value_cases("run", "learner", "argmax_samples", ["0", I64MAX, str(SAMPLES + 1)],
                count_expect())
    for k in ("noise_sigma", "noise_theta"):
        value_cases("run", "learner", k, ["nan", "-1"], always("refuse"))
    for k in ("algo", "noise", "actor_update"):
        value_cases("run", "learner", k, ['"foo"'], always("refuse"))
    value_cases("run", "learner", "n_critics", ["0", "3"], always("refuse"),
                extra=[("learner", "algo", '"td3"')])
    value_cases("run", "learner", "policy_delay", ["0"], always("refuse"),
                extra=[("learner", "algo", '"td3"')])
    value_cases("run", "learner", "target_noise", ["nan", "-1"], always("refuse"),
                extra=[("learner", "algo", '"td3"')])
    # phase2
    value_cases("run", "phase2", "alpha", INT_SHORT + [str(REPEATS + 1)], count_expect())
    value_cases("run", "phase2", "beta", INT_FULL + [str(EPISODES + 1)], count_expect())
    value_cases("run", "phase2", "max_steps", ["0", I64MAX, str(EPISODE_STEPS + 1)],
                count_expect())
    value_cases("run", "phase2", "k_step", INT_SHORT, count_expect())
    value_cases("run", "phase2", "max_rounds", ["0", I64MAX], count_expect(zero_ok=True))
    value_cases("run", "phase2", "dead_walk", ["0", I64MAX], count_expect(zero_ok=True))
    for k in ("restarts", "retargets", "chain_repairs"):
        value_cases("run", "phase2", k, ["0", "-1", I64MAX], count_expect(zero_ok=True))
    for k in ("patience", "lookahead", "test_lanes"):
        value_cases("run", "phase2", k, ["0", I64MAX], count_expect(zero_ok=True))
    value_cases("run", "phase2", "verify_episodes", INT_FULL + [str(EPISODES + 1)],
                count_expect(zero_ok=True))
    value_cases("run", "phase2", "chain_verify_episodes", INT_FULL + [str(EPISODES + 1)],
                count_expect(zero_ok=True))
    value_cases("run", "phase2", "eval_episodes", INT_FULL + [str(EPISODES + 1)],
                count_expect())
    value_cases("run", "phase2", "eval_max_steps", ["0", I64MAX, str(EPISODE_STEPS + 1)],
                count_expect())
    value_cases("run", "phase2", "max_env_steps", INT_FULL, count_expect(huge="either"))
    value_cases("run", "phase2", "epsilon", FLOAT_FULL + ["1.5"], float_expect())
    value_cases("run", "phase2", "test_path_limit", ["nan", "inf", "-1", "1e-300"],
                float_expect(zero_ok=True))
    value_cases("run", "phase2", "path_limit", ["nan", "-1"],
                float_expect(zero_ok=True), extra=[("phase2", "test_path_limit", "0")])
    value_cases("run", "phase2", "velocity_scale", ["nan", "inf", "-1"],
                float_expect(zero_ok=True))
    for k in ("start", "last_goal", "inputs", "first_starts"):
        value_cases("run", "phase2", k, ['"foo"'], always("refuse"))
    value_cases("run", "phase2", "chaining", ['"yes"', "1"], always("refuse"))

    # ---------------- train (TrainJob)
    value_cases("train", "", "seed", ["-1", U64MAX, '"many"'], seed_expect)
    value_cases("train", "maze", "size", ["0", "100000"], count_expect())
    value_cases("train", "learner", "batch_size", INT_FULL, count_expect())
    value_cases("train", "learner", "replay_size", INT_FULL, count_expect())
    for i, v in enumerate(HIDDEN[:3]):
        config_case(f"train.cfg.learner.hidden#{i}", "train",
                    lambda v=v: set_keys(base_text("train"), [("learner", "hidden", v)]),
                    field=["hidden"], what=f"c.toml: learner.hidden = {v[:60]}")
    value_cases("train", "learner", "gamma", ["1", "1.5", "-0.1", "nan"], always("refuse"))
    value_cases("train", "learner", "actor_lr", ["-1", "nan"], always("refuse"))
    value_cases("train", "train", "steps", INT_FULL, count_expect())
    value_cases("train", "train", "max_episode_steps", INT_FULL + [str(EPISODE_STEPS + 1)],
                count_expect())
    value_cases("train", "train", "learning_starts", ["-1", I64MAX, '"many"'], count_expect())
    value_cases("train", "train", "eval_every", ["0", "-1", I64MAX], count_expect(huge="either"))
    value_cases("train", "train", "eval_episodes", INT_FULL + [str(EPISODES + 1)],
                count_expect())
    value_cases("train", "train", "final_eval_episodes", INT_FULL + [str(EPISODES + 1)],
                count_expect(zero_ok=True))
    value_cases("train", "train", "final_eval_max_steps", ["0", I64MAX], count_expect())
    value_cases("train", "train", "visit_bin", FLOAT_FULL, float_expect())
    value_cases("train", "train", "final_eval_epsilon", ["nan", "0"], float_expect())
    value_cases("train", "train", "updates", ['"foo"'], always("refuse"))
    value_cases("train", "train", "stop_at_successes", ["0", "2", I64MAX], always("refuse"))
    value_cases("train", "train.her", "n_sampled_goal", ["-1", I64MAX], always("refuse"))
    value_cases("train", "train.her", "goal_selection_strategy", ['"foo"'], always("refuse"))
    config_case("train.cfg.batch_size=1e8,steps=2000", "train",
                lambda: set_keys(base_text("train"), [("learner", "batch_size", "100000000"),
                                                      ("train", "steps", "2000"),
                                                      ("train", "learning_starts", "1000")]),
                field=["batch_size"], what="c.toml: learner.batch_size = 100000000, train.steps = 2000")
    config_case("train.cfg.batch_size=1e8", "train",
                lambda: set_keys(base_text("train"), [("learner", "batch_size", "100000000")]),
                field=["batch_size"], what="c.toml: learner.batch_size = 100000000 (steps 3000)")
    # SAC
    sac = ('algo = "sac"\nhidden = [64, 64]\nlearning_rate = 0.0003\ngamma = 0.99\ntau = 0.005\n'
           'batch_size = 64\nreplay_size = 100000\nent_coef = "auto"')
    sac_cases = [("learning_rate", "nan"), ("learning_rate", "-1"), ("ent_coef", '"auto_-1"'),
                 ("ent_coef", "-1"), ("ent_coef", '"foo"'), ("ent_coef", "nan"),
                 ("target_entropy", "nan"), ("batch_size", U64MAX), ("batch_size", "0"),
                 ("hidden", "[1000000000, 1000000000]"), ("actor_lr", "0.001")]
    for k, v in sac_cases:
        config_case(f"train.cfg.sac.{k}={v}", "train",
                    lambda k=k, v=v: set_keys(replace_section(base_text("train"), "learner", sac),
                                              [("learner", k, v)]),
                    field=[k], what=f"c.toml: [learner] algo = sac, {k} = {v}")
    config_case("train.cfg.sac.fixed_ent+target_entropy", "train",
                lambda: set_keys(replace_section(base_text("train"), "learner", sac),
                                 [("learner", "ent_coef", "0.1"), ("learner", "target_entropy", "-2")]),
                field=["target_entropy"], what="c.toml: sac ent_coef = 0.1 with target_entropy")

    # ---------------- explore (ExploreJob)
    value_cases("explore", "explore", "bin_side", ["nan", "0", "1e-300", "-1", "inf"],
                float_expect())
    config_case("explore.cfg.explore.bin_side=1e-30", "explore",
                lambda: set_keys(base_text("explore"), [("explore", "bin_side", "1e-30")]),
                "either", field=["bin_side"], what="c.toml: explore.bin_side = 1e-30 (tiny, positive)")
    value_cases("explore", "explore", "budget", ["0", "-1", U64MAX, I64MAX], count_expect(huge="either"))
    value_cases("explore", "explore", "hold", ["0", "-1", "4294967296"], count_expect())
    value_cases("explore", "maze", "size", ["0", "1", "100000"], count_expect())
    config_case("explore.cfg.learner-section", "explore",
                lambda: base_text("explore") + "\n[learner]\nhidden = [64]\n",
                field=["learner"], what="c.toml: a [learner] section (not an explore key)")


HIDDEN = ["[1000000000, 1000000000]", "[0]", "[]", f"[{WIDTH + 1}]",
          "[" + ", ".join(["8"] * (LAYERS + 1)) + "]", "[-1]", '["a"]', "64", "[64.5]",
          f"[{U64MAX}]", "[" + ", ".join(["64"] * 1_000_000) + "]"]


# ---- TOML structure

def deep_array(n=20000):
    return "[" * n + "]" * n


def deep_table(n=20000):
    return "{a = " * n + "1" + "}" * n


def dotted(n=5000):
    return ".".join(["a"] * n)


def short_msg_check(line=None):
    """The refusal must be under MSG_MAX bytes and name `line N`."""

    def check(ctx):
        if ctx["cls"] != "refused":  # vague already says why
            return None
        err = ctx["stderr"]
        if len(err) >= MSG_MAX:
            return ("vague", f"message is {len(err)} bytes")
        if line is not None and f"line {line}" not in err:
            return ("vague", f"message does not name line {line}")
        return None

    return check


def structure_case(cid, kind, make, expect="refuse", field=None, what=""):
    """A config case whose file is make() -> (text, line): the refusal must be short and name
    that line (None: no line asked)."""
    cache = {}

    def made():
        if "v" not in cache:
            cache["v"] = make()
        return cache["v"]

    def setup(T):
        write(Path(T) / "c.toml", made()[0])

    def check(ctx):
        return short_msg_check(made()[1])(ctx)

    add(cid, OUTS[kind], expect, field=field, file="c.toml", setup=setup, check=check, what=what)


SUBSET = {"deep-array-top", "dotted-top", "unknown-top", "unknown-key-in-train",
          "unknown-key-in-explore", "garbage", "10MB-unknown-string", "seed-bool"}


def build_structure_cases():
    rnd = random.Random(7)
    garbage = bytes(rnd.randrange(256) for _ in range(4096))
    for kind in ("run", "train", "explore"):
        sec = {"run": "phase2", "train": "train", "explore": "explore"}[kind]
        b = lambda kind=kind: base_text(kind)

        def deep_in(kind, section, key, value):
            return lambda: set_key(base_text(kind), section, key, value)

        structure_case(f"{kind}.toml.deep-array-top", kind, deep_in(kind, "", "seed", deep_array()),
                       field=["line 1"], what="c.toml: seed = [[[… 20000 deep …]]] on line 1")
        structure_case(f"{kind}.toml.deep-array-last-line", kind,
                       lambda kind=kind: (b(kind).rstrip("\n") + "\nx = " + deep_array() + "\n",
                                          b(kind).rstrip("\n").count("\n") + 2),
                       what="c.toml: x = [[[… 20000 deep …]]] on the last line")
        if kind != "explore":
            structure_case(f"{kind}.toml.deep-array-hidden", kind,
                           deep_in(kind, "learner", "hidden", deep_array()),
                           what="c.toml: learner.hidden = [[[… 20000 deep …]]]")
        structure_case(f"{kind}.toml.deep-inline-table", kind,
                       deep_in(kind, sec, "x", deep_table()),
                       what=f"c.toml: [{sec}] x = {{a = {{a = … 20000 deep …}}}}")
        structure_case(f"{kind}.toml.dotted-top", kind,
                       lambda kind=kind: (dotted() + " = 1\n" + b(kind), 1),
                       what="c.toml: a.a.a…(5000 parts) = 1 on line 1")
        structure_case(f"{kind}.toml.dotted-in-section", kind,
                       deep_in(kind, sec, dotted(), "1"),
                       what=f"c.toml: [{sec}] a.a.a…(5000 parts) = 1")
        structure_case(f"{kind}.toml.dotted-header", kind,
                       lambda kind=kind: (b(kind).rstrip("\n") + "\n[" + dotted() + "]\nx = 1\n",
                                          b(kind).rstrip("\n").count("\n") + 2),
                       what="c.toml: a table header [a.a.a…(5000 parts)]")
        structure_case(f"{kind}.toml.dotted-array-header", kind,
                       lambda kind=kind: (b(kind).rstrip("\n") + "\n[[" + dotted() + "]]\nx = 1\n",
                                          b(kind).rstrip("\n").count("\n") + 2),
                       what="c.toml: an array-of-tables header [[a.a.a…(5000 parts)]]")
        config_case(f"{kind}.toml.unknown-top", kind, lambda kind=kind: "foo = 1\n" + b(kind),
                    field=["foo"], what="c.toml: foo = 1")
        config_case(f"{kind}.toml.unknown-section", kind,
                    lambda kind=kind: b(kind) + "\n[nosuch]\nx = 1\n", field=["nosuch"],
                    what="c.toml: [nosuch] x = 1")
        config_case(f"{kind}.toml.unknown-maze-key", kind,
                    lambda kind=kind: set_keys(b(kind), [("maze", "siz", "7")]), field=["siz"],
                    what="c.toml: [maze] siz = 7")
        config_case(f"{kind}.toml.unknown-key-in-{sec}", kind,
                    lambda kind=kind, sec=sec: set_keys(b(kind), [(sec, "betaa", "50")]),
                    field=["betaa"], what=f"c.toml: [{sec}] betaa = 50")
        config_case(f"{kind}.toml.maze=5", kind,
                    lambda kind=kind: "maze = 5\n" + re.sub(r"(?s)\[maze\].*?(?=\n\[)", "", b(kind)),
                    field=["maze"], what="c.toml: maze = 5 (not a table)")
        config_case(f"{kind}.toml.size-string", kind,
                    lambda kind=kind: set_keys(b(kind), [("maze", "size", '"5"')]), field=["size"],
                    what='c.toml: maze.size = "5"')
        config_case(f"{kind}.toml.seed-bool", kind,
                    lambda kind=kind: set_keys(b(kind), [("", "seed", "true")]), field=["seed"],
                    what="c.toml: seed = true")
        config_case(f"{kind}.toml.seed-date", kind,
                    lambda kind=kind: set_keys(b(kind), [("", "seed", "1979-05-27")]),
                    field=["seed"], what="c.toml: seed = 1979-05-27")
        config_case(f"{kind}.toml.seed-array", kind,
                    lambda kind=kind: set_keys(b(kind), [("", "seed", "[1]")]), field=["seed"],
                    what="c.toml: seed = [1]")
        config_case(f"{kind}.toml.duplicate-key", kind, lambda kind=kind: "seed = 1\n" + b(kind),
                    field=["seed"], what="c.toml: seed given twice")
        config_case(f"{kind}.toml.duplicate-section", kind,
                    lambda kind=kind: b(kind) + "\n[maze]\nsize = 3\n", field=["maze"],
                    what="c.toml: [maze] given twice")
        config_case(f"{kind}.toml.garbage", kind, lambda: garbage,
                    what="c.toml: 4 KB of random bytes")
        config_case(f"{kind}.toml.nul-bytes", kind, lambda kind=kind: b(kind) + "\x00\x00\x00\n",
                    field=["line"], what="c.toml: NUL bytes at the end")
        config_case(f"{kind}.toml.invalid-utf8", kind,
                    lambda kind=kind: b(kind).encode() + b"# \xff\xfe\xfd\n",
                    what="c.toml: a comment of invalid UTF-8")
        config_case(f"{kind}.toml.utf16", kind,
                    lambda kind=kind: b(kind).encode("utf-16"), what="c.toml: UTF-16 with a BOM")
        config_case(f"{kind}.toml.10MB-unknown-string", kind,
                    lambda kind=kind: b(kind) + 'foo = "' + "x" * 10_000_000 + '"\n',
                    field=["foo"], check=short_msg_check(),
                    what='c.toml: foo = "xxx…" (10 MB line)')
        config_case(f"{kind}.toml.10MB-garbage-line", kind,
                    lambda kind=kind: b(kind) + "x" * 10_000_000 + "\n",
                    check=short_msg_check(b(kind).count("\n") + 1),
                    what="c.toml: a 10 MB line of `x`, no `=`")
        config_case(f"{kind}.toml.10MB-key", kind,
                    lambda kind=kind: "x" * 10_000_000 + " = 1\n" + b(kind),
                    check=short_msg_check(), what="c.toml: a 10 MB key")
        config_case(f"{kind}.toml.10MB-number", kind,
                    lambda kind=kind: set_keys(b(kind), [("", "seed", "1" * 10_000_000)]),
                    field=["seed"], check=short_msg_check(), what="c.toml: seed = 111… (10 MB)")
        config_case(f"{kind}.toml.10MB-comment", kind,
                    lambda kind=kind: b(kind) + "# " + "x" * 10_000_000 + "\n", "ok",
                    what="c.toml: a 10 MB comment (valid)")
    # train and explore: a subset (their parser is the same as run's)
    CASES[:] = [c for c in CASES
                if not re.match(r"(train|explore)\.toml\.", c.cid) or c.cid.split(".toml.")[1] in SUBSET]
    # enum values echoed back
    config_case("run.toml.10MB-enum", "run",
                lambda: set_keys(base_text("run"), [("learner", "algo", '"' + "x" * 10_000_000 + '"')]),
                field=["algo"], check=short_msg_check(), what='c.toml: learner.algo = "xxx…" (10 MB)')
    config_case("run.toml.10MB-start", "run",
                lambda: set_keys(base_text("run"), [("phase2", "start", '"' + "x" * 10_000_000 + '"')]),
                field=["start"], check=short_msg_check(), what='c.toml: phase2.start = "xxx…" (10 MB)')
    # empty-ish files (explore: its defaults are cheap with maze 2)
    for name, data in [("empty", ""), ("whitespace", "   \n\n\t\n"), ("comment-only", "# hi\n")]:
        add(f"explore.toml.{name}", ["{B}", "explore", "--config", "{T}/c.toml", "--maze", "2",
                                     "--quiet", "--out", "{T}/out"], "ok",
            setup=lambda T, data=data: write(Path(T) / "c.toml", data),
            what=f"c.toml: {name} (defaults, maze 2)")
    # odd config paths
    for kind in ("run", "train", "explore"):
        add(f"{kind}.config.missing", ["{B}", kind, "--config", "{T}/nosuch.toml", "--quiet",
                                       "--out", "{T}/out"], file="nosuch.toml",
            what="--config a file that does not exist")
        add(f"{kind}.config.dir", ["{B}", kind, "--config", "{T}", "--quiet", "--out", "{T}/out"],
            what="--config the case's folder")
        add(f"{kind}.config.dev-zero", ["{B}", kind, "--config", "/dev/zero", "--quiet", "--out",
                                        "{T}/out"], file="/dev/zero",
            what="--config /dev/zero (endless)")
        add(f"{kind}.config.empty-path", ["{B}", kind, "--config", "", "--quiet", "--out",
                                          "{T}/out"], field=["config"], what="--config ''")
    add("explore.config.dev-null", ["{B}", "explore", "--config", "/dev/null", "--maze", "2",
                                    "--quiet", "--out", "{T}/out"], "ok",
        what="--config /dev/null (empty: defaults, maze 2)")
    add("explore.config.crlf", ["{B}", "explore", "--config", "{T}/c.toml", "--quiet", "--out",
                                "{T}/out"], "ok",
        setup=lambda T: write(Path(T) / "c.toml", base_text("explore").replace("\n", "\r\n")),
        what="c.toml with CRLF line ends (valid)")


# ---- command-line flags


def build_flag_cases():
    outs = ["--quiet", "--out", "{T}/out"]
    for cmd in ("run", "train", "explore"):
        extra = ["--config", "{FX}/train-smoke.toml"] if cmd == "train" else []
        for v in ["0", "1", "101", "100000", "-1", U64MAX, "many", "1.5", ""]:
            add(f"{cmd}.flag.--maze={v}", ["{B}", cmd, *extra, f"--maze={v}", *outs],
                field=["--maze", "maze.size"], what="")
        for v in ["-1", "many", "1.5", "0x10"]:
            add(f"{cmd}.flag.--seed={v}", ["{B}", cmd, *extra, "--maze", "2", f"--seed={v}", *outs],
                field=["--seed"])
            add(f"{cmd}.flag.--maze-seed={v}", ["{B}", cmd, *extra, "--maze", "2",
                                                f"--maze-seed={v}", *outs], field=["--maze-seed"])
        add(f"{cmd}.flag.--seed=u64max", ["{B}", cmd, *extra, "--maze", "2", f"--seed={U64MAX}",
                                          *outs], "ok")
        add(f"{cmd}.flag.--maze-seed=u64max", ["{B}", cmd, *extra, "--maze", "3",
                                               f"--maze-seed={U64MAX}", *outs], "ok")
        add(f"{cmd}.flag.--env=foo", ["{B}", cmd, *extra, "--env", "foo", *outs], field=["--env"])
        add(f"{cmd}.flag.--env=rooms+--maze", ["{B}", cmd, *extra, "--env", "rooms", "--maze", "3",
                                               *outs], field=["maze", "rooms"])
        add(f"{cmd}.flag.--map-missing", ["{B}", cmd, *extra, "--env", "pointmaze", "--map",
                                          "{T}/nosuch.txt", *outs], field=["nosuch.txt", "mujoco"])
        add(f"{cmd}.flag.--map-with-maze", ["{B}", cmd, *extra, "--map",
                                            str(REPO / "experiments/maps/pointmaze_own.txt"), *outs],
            field=["map"])
        add(f"{cmd}.flag.unknown", ["{B}", cmd, "--frobnicate", *outs], field=["--frobnicate"])
    # --steps / --gamma / --algo / --actor
    tr = ["{B}", "train", "--config", "{FX}/train-smoke.toml", "--maze", "2"]
    for v in ["0", "-1", "many", "1e11", "1.5", U64MAX, BIG]:
        add(f"train.flag.--steps={v}", [*tr, f"--steps={v}", *outs], field=["--steps", "steps"])
    for cmd, base in (("train", tr), ("run", ["{B}", "run", "--maze", "2"])):
        for v in ["1", "1.5", "-0.1", "nan", "inf", "many", ""]:
            add(f"{cmd}.flag.--gamma={v}", [*base, f"--gamma={v}", *outs], field=["gamma"])
        add(f"{cmd}.flag.--gamma -0.1", [*base, "--gamma", "-0.1", *outs], field=["gamma", "-0.1"])
        add(f"{cmd}.flag.--algo=foo", [*base, "--algo", "foo", *outs], field=["--algo"])
        add(f"{cmd}.flag.--actor=foo", [*base, "--actor", "foo", *outs], field=["--actor"])
    add("run.flag.--preset=foo", ["{B}", "run", "--preset", "foo", *outs], field=["--preset"])
    add("run.flag.--preset+--config", ["{B}", "run", "--preset", "paper", "--config",
                                       "{FX}/run/config.toml", *outs], "either",
        field=["--preset", "--config"])
    # --stop-after
    for v in ["abc", "-1s", "99999999999h", U64MAX + "s", "1e9h", "", "1.5h", "90", "5 parsecs",
              "0s"]:
        exp = "either" if v in ("0s", "90", "1.5h") else "refuse"
        add(f"run.flag.--stop-after={v}", ["{B}", "run", "--maze", "2", f"--stop-after={v}", *outs],
            exp, field=["--stop-after"])
    add("run.flag.--stop-after -1s", ["{B}", "run", "--maze", "2", "--stop-after", "-1s", *outs],
        field=["--stop-after", "-1"])
    for v in ["abc", "-1s", "99999999999h", U64MAX + "s"]:
        add(f"exp-run.flag.--stop-after={v}", ["{B}", "exp", "run", "{T}/experiments/table.toml",
                                               "--profile", "smoke", f"--stop-after={v}"],
            field=["--stop-after"])
    # eval
    ev = ["{B}", "eval", "--chain", "{T}/run/chain", "--out", "{T}/ev"]
    setup_run = lambda T: copy_fixture("run", T)
    for v in ["0", U64MAX, BIG, "-1", "abc", str(EPISODES + 1), "1e3", ""]:
        add(f"eval.flag.--episodes={v}", [*ev, f"--episodes={v}"], field=["--episodes"],
            setup=setup_run)
    add("eval.flag.--episodes=1", [*ev, "--episodes=1"], "ok", setup=setup_run)
    add("eval.flag.--seed=u64max", [*ev, "--episodes=5", f"--seed={U64MAX}"], "ok", setup=setup_run)
    add("eval.flag.--seed=-1", [*ev, "--seed=-1"], field=["--seed"], setup=setup_run)
    add("eval.chain.missing", ["{B}", "eval", "--chain", "{T}/nosuch"], file="nosuch")
    add("eval.chain.file", ["{B}", "eval", "--chain", "{T}/f.txt"], file="f.txt",
        setup=lambda T: write(Path(T) / "f.txt", "hello\n"))
    add("eval.chain.empty-dir", ["{B}", "eval", "--chain", "{T}/d"], field=["manifest"],
        setup=lambda T: (Path(T) / "d").mkdir())
    add("eval.chain.run-folder", ["{B}", "eval", "--chain", "{T}/run", "--episodes", "5"], "either",
        field=["chain"], setup=setup_run, what="--chain the run folder instead of its chain/")
    add("eval.chain.missing-arg", ["{B}", "eval"], field=["--chain"])
    # table
    tb = ["{B}", "table", "--out", "{T}/tab"]
    for v in ["0", str(MAX_SEEDS + 1), U64MAX, "-1", "many", ""]:
        add(f"table.flag.--seeds={v}", [*tb, "--sizes", "2", f"--seeds={v}"], field=["--seeds"])
    for v in ["0", "1", "101", "100000", "2,2", "", "a", "-1", "2,,5", U64MAX]:
        add(f"table.flag.--sizes={v}", [*tb, f"--sizes={v}", "--seeds", "1"],
            field=["--sizes", "maze.size", "mazes"])
    for v in ["0", "100000", "-1"]:
        add(f"table.flag.--jobs={v}", [*tb, "--sizes", "2", "--seeds", "1", f"--jobs={v}"],
            field=["--jobs"])
    add("table.ok", [*tb, "--sizes", "2", "--seeds", "1", "--jobs", "1"], "ok")
    add("table.flag.--config-missing", [*tb, "--config", "{T}/nosuch.toml", "--sizes", "2"],
        file="nosuch.toml")
    add("table.flag.--config-train-job", [*tb, "--config", "{FX}/train/config.toml", "--sizes",
                                          "2", "--seeds", "1"], field=["train"],
        file="config.toml", what="--config a TrainJob")
    # top level
    add("top.no-args", ["{B}"], field=["Usage", "COMMAND"], long_ok=True)
    add("top.unknown-command", ["{B}", "frobnicate"], field=["frobnicate"])
    add("top.help", ["{B}", "--help"], "ok")
    add("top.version", ["{B}", "--version"], "ok")


# ---- output paths


def build_output_cases():
    def with_file(T):
        write(Path(T) / "afile.txt", "not a folder\n")

    def with_file_and_run(T):
        with_file(T)
        copy_fixture("run", T)

    def with_file_and_figs(T):
        with_file(T)
        copy_fixture("figs", T)

    nf = ["not a folder"]
    F = "{T}/afile.txt"
    cases = [
        ("run", ["{B}", "run", "--maze", "2", "--quiet", "--out", F], with_file),
        ("explore", ["{B}", "explore", "--maze", "2", "--quiet", "--out", F], with_file),
        ("train", ["{B}", "train", "--config", "{FX}/train-smoke.toml", "--maze", "2", "--quiet",
                   "--out", F], with_file),
        ("eval", ["{B}", "eval", "--chain", "{T}/run/chain", "--episodes", "5", "--out", F],
         with_file_and_run),
        ("table", ["{B}", "table", "--sizes", "2", "--seeds", "1", "--out", F], with_file),
        ("exp-run", ["{B}", "exp", "run", "{T}/experiments/table.toml", "--profile", "smoke",
                     "--results", F], with_file),
        ("exp-check", ["{B}", "exp", "check", "{T}/experiments/table.toml", "--profile", "smoke",
                       "--cell", "ddpg-maze2", "--results", F], with_file),
        ("figures--results", ["{B}", "figures", "--experiments", "{T}/figs/exps", "--results", F],
         with_file_and_figs),
        ("figures--figures", ["{B}", "figures", "--experiments", "{T}/figs/exps", "--results",
                              "{T}/figs/res", "--figures", F], with_file_and_figs),
        ("figures--tex", ["{B}", "figures", "--experiments", "{T}/figs/exps", "--results",
                          "{T}/figs/res", "--tex", F], with_file_and_figs),
        ("aggregate--results", ["{B}", "aggregate", "--results", F], with_file),
        ("figures--experiments", ["{B}", "figures", "--experiments", F, "--results",
                                  "{T}/figs/res"], with_file_and_figs),
        ("aggregate--experiments", ["{B}", "aggregate", "--experiments", F, "--profile", "smoke"],
         with_file),
    ]
    # folders the command reads (not writes): "no such folder" and the OS's words do as well
    reads = ["not a folder", "not a directory", "no such"]
    for name, argv, setup in cases:
        inp = "--experiments" in name
        add(f"out.file.{name}", argv, field=reads if inp else nf, file="afile.txt", setup=setup,
            what="the output path is an existing file")
        sub = [a if a != F else F + "/sub" for a in argv]
        rd = inp or name in ("figures--results", "aggregate--results", "exp-check")
        add(f"out.under-file.{name}", sub, field=reads if rd else nf, file="afile.txt",
            setup=setup, what="the output path is under an existing file")
    add("out.file.exp-list", ["{B}", "exp", "list", "{T}/experiments/table.toml", "--profile",
                              "smoke", "--results", F], "either", field=nf, file="afile.txt",
        setup=with_file)
    for name, argv in [
        ("run", ["{B}", "run", "--maze", "2", "--quiet", "--out", "/dev/null"]),
        ("explore", ["{B}", "explore", "--maze", "2", "--quiet", "--out", "/dev/null"]),
        ("eval", ["{B}", "eval", "--chain", "{T}/run/chain", "--episodes", "5", "--out",
                  "/dev/null"]),
    ]:
        add(f"out.dev-null.{name}", argv, field=nf, file="/dev/null", setup=setup_run_fx)
    add("out.empty.run", ["{B}", "run", "--maze", "2", "--quiet", "--out", ""], field=["--out"])
    # a sweep's results folder or a cell folder holding rows
    sm = lambda T: copy_fixture("smoke", T)
    R = "{T}/smoke/results-smoke"
    for cmd, extra in (("run", []), ("explore", []),
                       ("train", ["--config", "{FX}/train-smoke.toml"])):
        add(f"out.sweep-folder.{cmd}", ["{B}", cmd, *extra, "--maze", "2", "--quiet", "--out", R],
            field=["results-smoke"], setup=sm)
        add(f"out.cell-folder.{cmd}", ["{B}", cmd, *extra, "--maze", "2", "--quiet", "--out",
                                       R + "/raw/table/pbcs-maze2"], field=["pbcs-maze2"], setup=sm)
        add(f"out.raw-folder.{cmd}", ["{B}", cmd, *extra, "--maze", "2", "--quiet", "--out",
                                      R + "/raw"], field=["raw"], setup=sm)
        add(f"out.other-run.{cmd}", ["{B}", cmd, *extra, "--maze", "3", "--quiet", "--out",
                                     "{T}/run"], field=["config.toml", "run"], setup=setup_run_fx)
    add("out.chain-folder.run", ["{B}", "run", "--maze", "2", "--quiet", "--out",
                                 "{T}/run/chain"], field=["chain"], setup=setup_run_fx)
    add("out.eval-into-sweep", ["{B}", "eval", "--chain", "{T}/run/chain", "--episodes", "5",
                                "--out", R], "either", setup=lambda T: (sm(T), copy_fixture("run", T)))
    add("out.table-into-smoke-raw", ["{B}", "table", "--sizes", "2", "--seeds", "1", "--out",
                                     R + "/raw/table"], field=["raw"], setup=sm)


def setup_run_fx(T):
    copy_fixture("run", T)


# ---- scripts generated by `exp list`: quoting of paths


def script_check(mode, path_fn):
    """After `exp list ... [--slurm|--make]`: run its output with a do-nothing pbcs and check
    that no file `x` appears, and that each command's --results is the path, quoted."""

    def check(ctx):
        T = Path(ctx["T"])
        if ctx["rc"] != 0:
            return None
        path = path_fn(str(T))
        out = ctx["stdout"]
        f = T / "generated.out"
        f.write_text(out)
        if mode == "slurm":
            cmd = ["bash", str(f)]
            env = dict(os.environ, PBCS="/bin/true", SLURM_ARRAY_TASK_ID="0")
        elif mode == "make":
            cmd = ["make", "-s", "-f", str(f), "PBCS=/bin/true"]
            env = dict(os.environ)
        else:
            cmd = ["bash", "-c", f"pbcs() {{ :; }}; source {shlex.quote(str(f))}"]
            env = dict(os.environ)
        try:
            r = subprocess.run(cmd, cwd=T, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               timeout=20, start_new_session=True)
            ran = f"the output run by {cmd[0]}: exit {r.returncode}"
        except subprocess.TimeoutExpired:
            ran = "the output run by bash: timed out"
        if (T / "x").exists():
            return ("wrong", f"file x appeared after running the output ({ran})")
        # the --results argument of every command, as the shell reads it
        seen = 0
        for line in out.splitlines():
            if "exp run" not in line or line.lstrip().startswith("#"):
                continue
            try:
                words = shlex.split(line.replace("$(PBCS)", "pbcs"), comments=True)
            except ValueError:
                continue
            if path is not None and "--results" in words:
                seen += 1
                got = words[words.index("--results") + 1]
                if got != path:
                    return ("wrong", f"--results reads as {got!r}, not {path!r}; {ran}")
        if path is None:
            return None
        if seen == 0 and "\n" not in path:
            return ("wrong", f"no command in the output names --results; {ran}")
        return None

    return check


def build_script_cases():
    hostile = {
        "space": "a b",
        "semicolon": "a b;touch x",
        "quote": "a'b;touch x'",
        "dollar": "$(touch x)",
        "backtick": "`touch x`",
        "newline": "r\ntouch x #",
        "dq": 'a"b;touch x;"',
    }
    for name, leaf in hostile.items():
        pf = lambda T, leaf=leaf: f"{T}/{leaf}"
        base = ["{B}", "exp", "list", "{T}/experiments/table.toml", "--profile", "smoke",
                "--results", "{T}/" + leaf]
        add(f"script.slurm.results-{name}", base + ["--slurm"], "either",
            check=script_check("slurm", pf), what=f"--results {leaf!r} --slurm")
        add(f"script.plain.results-{name}", base, "either",
            check=script_check("plain", pf), what=f"--results {leaf!r}")
        add(f"script.make.results-{name}", base + ["--make"], "refuse", field=["--make"],
            check=script_check("make", pf), what=f"--results {leaf!r} --make")
    # the experiment file's own path
    for name, leaf in (("space", "e x"), ("semicolon", "e x;touch x")):
        def setup(T, leaf=leaf):
            shutil.copytree(REPO / "experiments", Path(T) / leaf)

        argv = ["{B}", "exp", "list", "{T}/" + leaf + "/table.toml", "--profile", "smoke",
                "--results", "{T}/res"]
        pf = lambda T: f"{T}/res"
        add(f"script.slurm.file-{name}", argv + ["--slurm"], "either", setup=setup,
            check=script_check("slurm", pf), what=f"the experiment file in {leaf!r}, --slurm")
        add(f"script.plain.file-{name}", argv, "either", setup=setup,
            check=script_check("plain", pf), what=f"the experiment file in {leaf!r}")
        add(f"script.make.file-{name}", argv + ["--make"], "either", setup=setup,
            check=script_check("make", pf), what=f"the experiment file in {leaf!r}, --make")
    # plain paths: the generated outputs work
    pf = lambda T: f"{T}/res"
    for mode in ("slurm", "make", "plain"):
        flag = {"slurm": ["--slurm"], "make": ["--make"], "plain": []}[mode]
        add(f"script.{mode}.plain-path", ["{B}", "exp", "list", "{T}/experiments/table.toml",
                                          "--profile", "smoke", "--results", "{T}/res", *flag],
            "ok", check=script_check(mode, pf))
    add("script.slurm+make", ["{B}", "exp", "list", "{T}/experiments/table.toml", "--slurm",
                              "--make"], field=["--make", "--slurm"])
    add("script.profile-injection", ["{B}", "exp", "list", "{T}/experiments/table.toml",
                                     "--profile", "smoke;touch x", "--slurm"], field=["profile"])


# ---- experiment files


def exp_case(cid, mutate, cmds=("list", "list-smoke", "run-smoke"), expect="refuse", field=None,
             what="", check=None, name="table"):
    src = (REPO / f"experiments/{name}.toml").read_text()
    """Cases on `experiments/table.toml` changed by mutate(text) (written in the case's copy of
    experiments/ as `name`.toml), run by each command of cmds."""
    argvs = {
        "list": ["{B}", "exp", "list", f"{{T}}/experiments/{name}.toml"],
        "list-smoke": ["{B}", "exp", "list", f"{{T}}/experiments/{name}.toml", "--profile",
                       "smoke"],
        "run-smoke": ["{B}", "exp", "run", f"{{T}}/experiments/{name}.toml", "--profile", "smoke",
                      "--jobs", "1"],
        "run": ["{B}", "exp", "run", f"{{T}}/experiments/{name}.toml", "--jobs", "1"],
        "run-smoke-cell": ["{B}", "exp", "run", f"{{T}}/experiments/{name}.toml", "--profile",
                           "smoke", "--cell", "pbcs_fast-maze2", "--seed", "0"],
        "figures-smoke": ["{B}", "figures", "--experiments", "{T}/experiments", "--profile",
                          "smoke"],
    }
    for c in cmds:
        exp = expect[c] if isinstance(expect, dict) else expect
        add(f"exp.{cid}.{c}", argvs[c], exp, field=field, file=f"{name}.toml",
            setup=lambda T: write(Path(T) / f"experiments/{name}.toml", mutate(src)),
            what=what, check=check)


def top(key, value):
    """Sets a top-level key of an experiment file (before its first table)."""

    def f(text):
        if re.search(rf"(?m)^{key} = .*$", text):
            return re.sub(rf"(?m)^{key} = .*$", lambda m: f"{key} = {value}", text, count=1)
        return sub1(text, "\n[[method]]", f"\n{key} = {value}\n[[method]]")

    return f


DDPG_SET = 'set = { learner.algo = "ddpg", train.steps = 1000000 }'
SMOKE_PBCS = "pbcs = { phase2.max_env_steps = 20000, phase2.eval_episodes = 10 }"
SMOKE_VANILLA = "vanilla = { train.steps = 3000, train.learning_starts = 1000, train.eval_every = 1000 }"


def chain(*fs):
    def f(text):
        for g in fs:
            text = g(text)
        return text

    return f


def rep(old, new):
    return lambda text: sub1(text, old, new)


def plain_grid(text):
    """table.toml without what names its sizes (by_maze, paper_steps, paper_solved), so that
    `mazes` can change alone."""
    text = re.sub(r"(?m)^paper_(steps|solved) = .*\n", "", text)
    return re.sub(r"(?s)\n\[by_maze\]\n.*?\n\n", "\n\n", text)


def build_experiment_cases():
    ALL3 = ("list", "list-smoke", "run-smoke")
    for v in ["[100000]", "[0]", "[1]", "[-1]", "[]", f"[{U64MAX}]", '"many"', "[2.5]", "[2, 2]",
              "[101]"]:
        cmds = ALL3 + ("run",) if v in ("[100000]", "[2, 2]") else ("list",)
        exp_case(f"mazes={v}", chain(plain_grid, top("mazes", v)), cmds,
                 field=["maze", "mazes"],
                 what=f"table.toml: mazes = {v} (by_maze and paper_* removed)")
    exp_case("mazes=[3]-control", chain(plain_grid, top("mazes", "[3]")), ("list",), "ok",
             what="table.toml: mazes = [3] (by_maze and paper_* removed): the control")
    exp_case("profile-mazes=[100000]", rep("mazes = [2]\nvanilla", "mazes = [100000]\nvanilla"),
             ("list-smoke", "run-smoke"), field=["maze", "mazes"],
             what="table.toml: [profile.smoke] mazes = [100000]")
    exp_case("profile-mazes=[2,2]", rep("mazes = [2]\nvanilla", "mazes = [2, 2]\nvanilla"),
             ("list-smoke", "run-smoke"), field=["mazes"],
             what="table.toml: [profile.smoke] mazes = [2, 2]")
    for v in ['"many"', "-1", "0", U64MAX, I64MAX]:
        cmds = ALL3 + ("run",) if v == '"many"' else ALL3
        exp_case(f"ddpg-set-train.steps={v}", rep(DDPG_SET, f'set = {{ learner.algo = "ddpg", train.steps = {v} }}'),
                 cmds, expect={"list": "refuse", "list-smoke": "either", "run-smoke": "either",
                               "run": "refuse"} if v == I64MAX else "refuse",
                 field=["train.steps", "steps"], what=f"table.toml: ddpg's set train.steps = {v}")
    for v in ["-1", "0", '"many"']:
        exp_case(f"by_maze-max_env_steps={v}",
                 rep('"2" = { pbcs = { phase2.max_env_steps = 642000 } }',
                     f'"2" = {{ pbcs = {{ phase2.max_env_steps = {v} }} }}'),
                 ALL3, field=["max_env_steps"],
                 what=f'table.toml: [by_maze] "2" pbcs phase2.max_env_steps = {v}')
        exp_case(f"smoke-max_env_steps={v}",
                 rep(SMOKE_PBCS, f"pbcs = {{ phase2.max_env_steps = {v}, phase2.eval_episodes = 10 }}"),
                 ("list-smoke", "run-smoke"), field=["max_env_steps"],
                 what=f"table.toml: [profile.smoke] pbcs phase2.max_env_steps = {v}")
    for v in ["0", "-1", '"many"']:
        exp_case(f"smoke-train.steps={v}",
                 rep(SMOKE_VANILLA, f"vanilla = {{ train.steps = {v}, train.learning_starts = 1000, train.eval_every = 1000 }}"),
                 ("list-smoke", "run-smoke"), field=["steps"],
                 what=f"table.toml: [profile.smoke] vanilla train.steps = {v}")
    for v in ["0", str(MAX_SEEDS + 1), "-1", U64MAX, '"many"', "1.5"]:
        cmds = ALL3 + ("run",) if v in ("0", str(MAX_SEEDS + 1)) else ("list", "list-smoke")
        exp_case(f"seeds={v}", top("seeds", v), cmds, field=["seeds"],
                 what=f"table.toml: seeds = {v}")
    for v in ["0", str(MAX_SEEDS + 1), "-1"]:
        exp_case(f"smoke-seeds={v}", rep("seeds = 1\nmazes = [2]", f"seeds = {v}\nmazes = [2]"),
                 ("list-smoke", "run-smoke"), field=["seeds"],
                 what=f"table.toml: [profile.smoke] seeds = {v}")
    # first_seed
    exp_case("first_seed=u64max,seeds=1,pictures=[u64max]",
             chain(top("seeds", "1"), top("picture_seeds", f"[{U64MAX}]"), top("first_seed", U64MAX)),
             ("list", "list-smoke"), "ok", field=["first_seed"],
             what=f"table.toml: first_seed = {U64MAX}, seeds = 1, picture_seeds = [{U64MAX}]")
    exp_case("first_seed=u64max,seeds=1,pictures=[]",
             chain(top("seeds", "1"), top("picture_seeds", "[]"), top("first_seed", U64MAX)),
             ("list", "list-smoke"), "ok", field=["first_seed"],
             what=f"table.toml: first_seed = {U64MAX}, seeds = 1, picture_seeds = []")
    exp_case("first_seed=u64max,seeds=1,pictures=[0]",
             chain(top("seeds", "1"), top("first_seed", U64MAX)),
             ("list",), field=["picture_seeds", "first_seed"],
             what=f"table.toml: first_seed = {U64MAX}, seeds = 1, picture_seeds = [0] (not a seed)")
    exp_case("first_seed=u64max,seeds=2",
             chain(top("seeds", "2"), top("picture_seeds", "[]"), top("first_seed", U64MAX)),
             ("list", "list-smoke", "run-smoke"), field=["first_seed"],
             what=f"table.toml: first_seed = {U64MAX}, seeds = 2")
    exp_case("first_seed=i64max,seeds=2",
             chain(top("seeds", "2"), top("picture_seeds", "[]"), top("first_seed", I64MAX)),
             ("list",), "ok", what=f"table.toml: first_seed = {I64MAX}, seeds = 2")
    exp_case("first_seed=-1", top("first_seed", "-1"), ("list",), field=["first_seed"],
             what="table.toml: first_seed = -1")
    exp_case("first_seed=\"many\"", top("first_seed", '"many"'), ("list",), field=["first_seed"],
             what='table.toml: first_seed = "many"')
    # picture_seeds
    exp_case("picture_seeds=[50]", top("picture_seeds", "[50]"), ALL3, field=["picture_seeds"],
             what="table.toml: picture_seeds = [50] (seeds 0..9)")
    exp_case("picture_seeds=[5]-smoke", top("picture_seeds", "[5]"), ("list-smoke", "run-smoke"),
             field=["picture_seeds"],
             what="table.toml: picture_seeds = [5], the smoke profile runs 1 seed")
    exp_case("first_seed=5-smoke-pictures-[0]", top("first_seed", "5"), ("list", "list-smoke"),
             field=["picture_seeds"], what="table.toml: first_seed = 5, picture_seeds = [0]")
    exp_case("profile-picture_seeds=[3]",
             rep("seeds = 1\nmazes = [2]", "seeds = 1\npicture_seeds = [3]\nmazes = [2]"),
             ("list-smoke", "run-smoke"), field=["picture_seeds"],
             what="table.toml: [profile.smoke] picture_seeds = [3] with seeds = 1")
    for v in ["[-1]", '"many"', f"[{U64MAX}]", "[0, 0]"]:
        exp_case(f"picture_seeds={v}", top("picture_seeds", v), ("list",),
                 expect="either" if v == "[0, 0]" else "refuse", field=["picture_seeds"],
                 what=f"table.toml: picture_seeds = {v}")
    # seeds_by_maze
    for v in ['{ "2" = 0 }', '{ "2" = 11 }', '{ "9" = 1 }', '{ "2" = -1 }', '{ "abc" = 1 }']:
        exp_case(f"seeds_by_maze={v}", top("seeds_by_maze", v), ("list",),
                 field=["seeds_by_maze"], what=f"table.toml: seeds_by_maze = {v}")
    # [registered]
    reg = lambda sha, preset="pbcs_fast.toml", date="2026-11-25": (
        lambda text: text + f'\n[registered]\npreset = "{preset}"\nsha256 = "{sha}"\ndate = "{date}"\n')
    # on experiments/heldout.toml, registered for pbcs_fast.toml
    hsha = lambda v: (lambda t: re.sub(r'(?m)^sha256 = .*$', f'sha256 = {v}', t, count=1))
    hpre = lambda v: (lambda t: re.sub(r'(?m)^preset = .*$', f'preset = {v}', t, count=1))
    def warned(ctx):
        # `exp list` may list a grid it would refuse to run, if it says so
        if ctx["rc"] == 0 and "sha256" not in ctx["stderr"]:
            return ("silent", "listed without a word on the hash")
        return None

    lst = {"list": "either", "list-smoke": "either", "run-smoke": "refuse"}
    exp_case("registered-wrong-hash", hsha('"' + "0" * 64 + '"'), ALL3, lst, name="heldout",
             field=["sha256"], check=warned,
             what="heldout.toml: [registered] sha256 = 000…0 (wrong); exp list may warn instead")
    exp_case("registered-bad-hex", hsha('"xyz"'), ("list", "run-smoke"), lst, name="heldout",
             field=["sha256"], check=warned,
             what='heldout.toml: [registered] sha256 = "xyz"; exp list may warn instead')
    exp_case("registered-hash-number", hsha("5"), ("list",), name="heldout",
             field=["sha256"], what="heldout.toml: [registered] sha256 = 5")
    exp_case("registered-missing-preset", hpre('"nosuch.toml"'), ("list", "run-smoke"),
             name="heldout", field=["nosuch.toml", "preset"],
             what="heldout.toml: [registered] preset = nosuch.toml")
    exp_case("registered-escaping-preset", hpre('"../../../../etc/passwd"'), ("list",),
             name="heldout", field=["preset", "passwd"],
             what="heldout.toml: [registered] preset = ../../../../etc/passwd")
    exp_case("registered-unknown-key", rep("[registered]", "[registered]\nfoo = 1"), ("list",),
             name="heldout", field=["foo"], what="heldout.toml: [registered] foo = 1")
    exp_case("registered-on-table", reg("0" * 64), ("list",), field=["registered", "pbcs_paper"],
             what="table.toml: [registered] pbcs_fast.toml, though methods run pbcs_paper.toml")
    # methods
    exp_case("method-kind=foo", rep('kind = "vanilla"', 'kind = "foo"'), ("list",), field=["kind"],
             what='table.toml: ddpg kind = "foo"')
    exp_case("method-base-missing", rep('base = "baseline.toml"', 'base = "nosuch.toml"'),
             ("list", "run-smoke"), field=["nosuch.toml"], what="table.toml: ddpg base = nosuch.toml")
    exp_case("method-base-etc-passwd", rep('base = "baseline.toml"', 'base = "/etc/passwd"'),
             ("list",), field=["passwd"], what="table.toml: ddpg base = /etc/passwd")
    exp_case("method-base-self", rep('base = "baseline.toml"', 'base = "table.toml"'),
             ("list",), field=["table.toml", "title"], what="table.toml: ddpg base = table.toml")
    exp_case("method-base-dir", rep('base = "baseline.toml"', 'base = "maps"'),
             ("list",), field=["maps"], what="table.toml: ddpg base = maps (a folder)")
    exp_case("method-base-empty", rep('base = "baseline.toml"', 'base = ""'),
             ("list",), field=["base"], what='table.toml: ddpg base = ""')
    exp_case("method-base-wrong-kind", rep('base = "baseline.toml"', 'base = "pbcs_fast.toml"'),
             ("list",), field=["pbcs_fast.toml", "phase2", "explore"],
             what="table.toml: vanilla ddpg's base = pbcs_fast.toml")
    exp_case("method-name-duplicate", rep('name = "td3"', 'name = "ddpg"'), ("list",),
             field=["ddpg", "name"], what="table.toml: two methods named ddpg")
    for nm, label in [("", "empty"), ("a b", "space"), ("../x", "dotdot"), ("x/y", "slash"),
                      ("$(touch x)", "dollar"), ("a'b", "quote"), ("x" * 5000, "5000chars"),
                      ("maze2", "maze2"), ("é", "unicode")]:
        cmds = ("list", "list-smoke") + (("run-smoke",) if label == "5000chars" else ())
        exp_case(f"method-name-{label}", rep('name = "td3"', f'name = "{nm}"'),
                 cmds, expect="either" if label in ("unicode", "maze2") else "refuse",
                 field=["name"], what=f"table.toml: td3's name = {nm[:30]!r}",
                 check=short_msg_check())
    add("exp.method-name-dollar.slurm", ["{B}", "exp", "list", "{T}/experiments/table.toml",
                                         "--profile", "smoke", "--slurm"], "either",
        setup=lambda T: write(Path(T) / "experiments/table.toml",
                              sub1(table_text(), 'name = "td3"', 'name = "x$(touch x)"')),
        check=script_check("slurm", lambda T: None), field=["name"],
        what="table.toml: a method named x$(touch x), --slurm")
    exp_case("method-unknown-key", rep('label = "DDPG"', 'label = "DDPG"\nfoo = 1'), ("list",),
             field=["foo"], what="table.toml: ddpg foo = 1")
    exp_case("method-mazes-not-in-grid", rep('label = "DDPG"', 'label = "DDPG"\nmazes = [3]'),
             ("list",), field=["mazes", "3"], what="table.toml: ddpg mazes = [3] (not a maze of the grid)")
    exp_case("no-methods", lambda t: re.sub(r"(?s)\[\[method\]\].*?(?=\n# Twice)", "", t),
             ("list",), field=["method"], what="table.toml: no [[method]]")
    # set tables
    sets = [
        ("hidden-1e9", 'learner.hidden = [1000000000, 1000000000]', ["hidden"]),
        ("seed=-1", "seed = -1", ["seed"]),
        ("maze.size=100000", "maze.size = 100000", ["maze.size", "size"]),
        ("unknown", "frobnicate = 1", ["frobnicate"]),
        ("train.steps=many", 'train.steps = "many"', ["steps"]),
        ("batch=u64max", f"learner.batch_size = {U64MAX}", ["batch_size"]),
        ("replay=0", "learner.replay_size = 0", ["replay_size"]),
        ("eval_episodes=1e11", f"train.eval_episodes = {BIG}", ["eval_episodes"]),
        ("phase2-on-vanilla", "phase2.beta = 0", ["phase2"]),
        ("learner=string", 'learner = "ddpg"', ["learner"]),
    ]
    for label, body, field in sets:
        exp_case(f"ddpg-set-{label}", rep(DDPG_SET, f"set = {{ {body} }}"), ("list", "run-smoke"),
                 field=field, what=f"table.toml: ddpg's set = {{ {body} }}")
    psets = [("beta=0", "phase2.beta = 0", ["beta"]),
             ("verify=u64max", f"phase2.verify_episodes = {U64MAX}", ["verify_episodes"]),
             ("chain_verify=1e11", f"phase2.chain_verify_episodes = {BIG}", ["chain_verify_episodes"]),
             ("epsilon=nan", "phase2.epsilon = nan", ["epsilon"]),
             ("bin_side=1e-300", "explore.bin_side = 1e-300", ["bin_side"]),
             ("train-on-pbcs", "train.steps = 10", ["train"])]
    for label, body, field in psets:
        exp_case(f"pbcs-set-{label}",
                 rep("set = { phase2.chaining = false }", f"set = {{ phase2.chaining = false, {body} }}"),
                 ("list", "run-smoke"), field=field,
                 what=f"table.toml: pbcs_no_chaining's set += {body}")
    # dotted keys and deep nesting inside an experiment file: the message must name the line
    def line_of(text, needle):
        return text[: text.index(needle)].count("\n") + 1

    def dotted_set(t):
        return rep(DDPG_SET, "set = { " + dotted() + " = 1 }")(t)

    for label, fn, needle in [
        ("set-dotted-5000", dotted_set, "set = { a.a"),
        ("profile-dotted-5000", rep(SMOKE_PBCS, "pbcs = { " + dotted() + " = 1 }"), "pbcs = { a.a"),
        ("by_maze-dotted-5000", rep('"2" = { pbcs = { phase2.max_env_steps = 642000 } }',
                                    '"2" = { pbcs = { ' + dotted() + ' = 1 } }'), '"2" = { pbcs = { a.a'),
        ("top-dotted-5000", lambda t: dotted() + " = 1\n" + t, "a.a.a"),
        ("set-deep-array", rep(DDPG_SET, "set = { learner.hidden = " + deep_array() + " }"),
         "set = { learner.hidden = [[["),
        ("mazes-deep-array", top("mazes", deep_array()), "mazes = [[["),
        ("set-deep-table", rep(DDPG_SET, "set = " + deep_table()), "set = {a = {a"),
    ]:
        def mk_check(fn=fn, needle=needle):
            def check(ctx):
                return short_msg_check(line_of(fn(table_text()), needle))(ctx)
            return check

        exp_case(label, fn, ("list", "run-smoke") if "profile" not in label else ("list-smoke", "run-smoke"),
                 field=["line"], check=mk_check(), what=f"table.toml: {label}")
    # structure of the experiment file itself
    rnd = random.Random(11)
    garbage = bytes(rnd.randrange(256) for _ in range(4096)).decode("latin-1")
    exp_case("empty-file", lambda t: "", ("list",), field=["title", "seeds", "method"],
             what="table.toml: empty")
    exp_case("garbage", lambda t: garbage, ("list",), what="table.toml: 4 KB of random bytes")
    exp_case("10MB-line", lambda t: t + "\nfoo = \"" + "x" * 10_000_000 + "\"\n", ("list",),
             field=["foo"], check=short_msg_check(), what="table.toml: a 10 MB line foo = \"xxx…\"")
    exp_case("10MB-title", top("title", '"' + "x" * 10_000_000 + '"'), ("list",), "either",
             check=short_msg_check(), what="table.toml: a 10 MB title (valid)")
    exp_case("no-title", lambda t: re.sub(r"(?m)^title = .*\n", "", t), ("list",), field=["title"],
             what="table.toml: no title")
    exp_case("unknown-top-key", top("frobnicate", "1"), ("list",), field=["frobnicate"],
             what="table.toml: frobnicate = 1")
    exp_case("envs=[maze]", top("envs", '["maze"]'), ("list",), field=["envs", "maze"],
             what='table.toml: envs = ["maze"]')
    exp_case("envs=[nosuch]", top("envs", '["nosuch"]'), ("list",), field=["nosuch", "envs"],
             what='table.toml: envs = ["nosuch"]')
    exp_case("in_progress=yes", top("in_progress", '"yes"'), ("list",), field=["in_progress"],
             what='table.toml: in_progress = "yes"')
    exp_case("by_maze-not-a-maze", rep('"15" = { pbcs', '"3" = { pbcs'), ("list",),
             field=["3", "by_maze"], what='table.toml: by_maze "3" (not a maze of the grid)')
    exp_case("by_maze-abc", rep('"15" = { pbcs', '"abc" = { pbcs'), ("list",),
             field=["abc", "by_maze"], what='table.toml: by_maze "abc"')
    exp_case("paper_steps=-1", rep('paper_steps = { "2" = 1000000, "5"', 'paper_steps = { "2" = -1, "5"'),
             ("list",), field=["paper_steps"], what='table.toml: ddpg paper_steps "2" = -1')
    exp_case("paper_steps-99", rep('paper_steps = { "2" = 1000000, "5"', 'paper_steps = { "99" = 1, "5"'),
             ("list",), field=["paper_steps", "99"], what='table.toml: ddpg paper_steps "99"')
    exp_case("profile-unknown-key", rep("[profile.smoke]", "[profile.smoke]\nfoo = 1"),
             ("list-smoke",), field=["foo"], what="table.toml: [profile.smoke] foo = 1")
    exp_case("figure-kind-foo", rep('kind = "grid"', 'kind = "foo"'), ("list",), field=["kind", "foo"],
             what='table.toml: a figure of kind "foo"')
    exp_case("report-settings-nosuch", rep('settings = { pbcs = "pbcs"', 'settings = { pbcs = "nosuch"'),
             ("list",), field=["nosuch", "settings"], what="table.toml: report settings names no method")

    # flags on the unchanged file
    tt = ["{T}/experiments/table.toml"]
    runsm = ["{B}", "exp", "run", *tt, "--profile", "smoke"]
    for v in ["5", U64MAX, "-1", "many"]:
        add(f"exp.run.--seed={v}", [*runsm, f"--seed={v}"], field=["--seed", "seed"])
    add("exp.run.--seed=1-full-grid-cell", ["{B}", "exp", "run", *tt, "--cell", "ddpg-maze2",
                                            "--seed", "10"], field=["--seed", "seed"])
    for v in ["nope-maze2", "", "pbcs-maze5", "../../etc", "ddpg-maze2 ", "DDPG-maze2"]:
        add(f"exp.run.--cell={v!r}", [*runsm, f"--cell={v}"], field=["--cell", "cell"])
        add(f"exp.check.--cell={v!r}", ["{B}", "exp", "check", *tt, "--profile", "smoke",
                                        f"--cell={v}"], field=["--cell", "cell"])
    for v in ["0", "100000", "-1", U64MAX]:
        add(f"exp.run.--jobs={v}", [*runsm, f"--jobs={v}"], field=["--jobs"])
    add("exp.check.--jobs=0", ["{B}", "exp", "check", *tt, "--profile", "smoke", "--cell",
                               "ddpg-maze2", "--jobs=0"], field=["--jobs"])
    add("exp.check.--seed=5", ["{B}", "exp", "check", *tt, "--profile", "smoke", "--cell",
                               "ddpg-maze2", "--seed=5"], field=["--seed", "seed"])
    for cmd in ("run", "list"):
        add(f"exp.{cmd}.--profile=nosuch", ["{B}", "exp", cmd, *tt, "--profile", "nosuch"],
            field=["nosuch", "profile"])
        add(f"exp.{cmd}.file-missing", ["{B}", "exp", cmd, "{T}/experiments/nosuch.toml"],
            file="nosuch.toml")
        add(f"exp.{cmd}.file-dir", ["{B}", "exp", cmd, "{T}/experiments"], file="experiments")
        add(f"exp.{cmd}.file-dev-null", ["{B}", "exp", cmd, "/dev/null"], file="null")
        add(f"exp.{cmd}.file-dev-zero", ["{B}", "exp", cmd, "/dev/zero"], file="zero")
        add(f"exp.{cmd}.job-file", ["{B}", "exp", cmd, "{T}/experiments/pbcs_fast.toml"],
            file="pbcs_fast.toml", what="a job file given as an experiment file")
        add(f"exp.{cmd}.settings-file", ["{B}", "exp", cmd, "{T}/experiments/settings.toml"],
            file="settings.toml", what="experiments/settings.toml given as an experiment file")
    add("exp.list.ok", ["{B}", "exp", "list", *tt], "ok")
    add("exp.list.smoke-ok", ["{B}", "exp", "list", *tt, "--profile", "smoke"], "ok")
    add("exp.run.smoke-ok", [*runsm, "--jobs", "1"], "ok")
    add("exp.run.smoke-cell-ok", [*runsm, "--cell", "pbcs_fast-maze2", "--seed", "0"], "ok")
    add("exp.list.all-committed", ["{B}", "exp", "list", "{T}/experiments/rooms.toml", "--profile",
                                   "smoke"], "either")


# ---- results folders read back


def edit_csv(path, fn):
    path = Path(path)
    rows = list(csv.reader(path.read_text().splitlines()))
    rows = fn(rows)
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def set_col(col, value, row=1):
    def fn(rows):
        i = rows[0].index(col)
        rows[row][i] = value
        return rows

    return fn


def build_results_cases():
    FIG = ["{B}", "figures", "--experiments", "{T}/figs/exps", "--results", "{T}/figs/res"]
    TAB = "figs/res/tables/table.csv"

    def figs(edit=None):
        def setup(T):
            copy_fixture("figs", T)
            if edit:
                edit(Path(T))

        return setup

    add("results.figures.ok", FIG, "ok", setup=figs())
    table_edits = [
        ("successes>n", set_col("successes", "11"), ["successes"]),
        ("successes=-1", set_col("successes", "-1"), ["successes"]),
        ("n=0", set_col("n", "0"), ["n"]),
        ("n=-1", set_col("n", "-1"), ["n"]),
        ("n=u64max", set_col("n", U64MAX), ["n"]),
        ("success_rate=NaN", set_col("success_rate", "NaN"), ["success_rate"]),
        ("success_rate=inf", set_col("success_rate", "inf"), ["success_rate"]),
        ("success_rate=2", set_col("success_rate", "2"), ["success_rate"]),
        ("success_rate-mismatch", set_col("success_rate", "0.9"), ["success_rate"]),
        ("wilson_lo>hi", set_col("wilson_lo", "0.99"), ["wilson"]),
        ("wilson=NaN", set_col("wilson_hi", "NaN"), ["wilson"]),
        ("steps_median=abc", set_col("steps_median", "abc"), ["steps_median"]),
        ("steps_median=NaN", set_col("steps_median", "NaN"), ["steps"]),
        ("steps_median=-1", set_col("steps_median", "-1"), ["steps"]),
        ("cell-unknown", set_col("cell", "nope-maze2"), ["nope-maze2", "cell"]),
        ("maze=100000", set_col("maze", "100000"), ["maze"]),
        ("duplicate-row", lambda rows: rows[:2] + rows[1:], ["ddpg-maze2", "duplicate", "twice"]),
        ("row-missing", lambda rows: rows[:1] + rows[2:], ["ddpg-maze2", "missing"]),
        ("column-missing", lambda rows: [r[:6] + r[7:] for r in rows], ["successes"]),
        ("short-row", lambda rows: rows[:1] + [rows[1][:5]] + rows[2:], ["line 2", "line: 2"]),
        ("header-only", lambda rows: rows[:1], ["table"]),
    ]
    for label, fn, field in table_edits:
        add(f"results.figures.table-{label}", FIG, field=field, file="table.csv",
            setup=figs(lambda T, fn=fn: edit_csv(T / TAB, fn)), what=f"tables/table.csv: {label}")
    for label, data in [("empty", ""), ("garbage", bytes(range(256)) * 4),
                        ("10MB-line", "x" * 10_000_000 + "\n")]:
        add(f"results.figures.table-{label}", FIG, file="table.csv",
            setup=figs(lambda T, data=data: write(T / TAB, data)), check=short_msg_check(),
            what=f"tables/table.csv: {label}")
    ROW = "figs/res/raw/table/pbcs_fast-maze2/s0"

    def solved_no_eval(T):
        edit_csv(T / (ROW + ".csv"), set_col("solved", "true"))
        (T / (ROW + ".evaluation.csv")).unlink()

    raw_edits = [
        ("solved-no-evaluation", solved_no_eval, ["evaluation"]),
        ("evaluation-deleted", lambda T: (T / (ROW + ".evaluation.csv")).unlink(), ["evaluation"]),
        ("success_rate=NaN", lambda T: edit_csv(T / (ROW + ".csv"), set_col("success_rate", "NaN")),
         ["success_rate"]),
        ("success_rate=2", lambda T: edit_csv(T / (ROW + ".csv"), set_col("success_rate", "2")),
         ["success_rate"]),
        ("solved=maybe", lambda T: edit_csv(T / (ROW + ".csv"), set_col("solved", "maybe")),
         ["solved"]),
        ("env_steps=-1", lambda T: edit_csv(T / (ROW + ".csv"), set_col("env_steps", "-1")),
         ["env_steps"]),
        ("seed-mismatch", lambda T: edit_csv(T / (ROW + ".csv"), set_col("seed", "5")), ["seed"]),
        ("cell-mismatch", lambda T: edit_csv(T / (ROW + ".csv"), set_col("cell", "pbcs-maze2")),
         ["cell"]),
        ("empty-row", lambda T: write(T / (ROW + ".csv"), ""), ["s0.csv"]),
        ("row-garbage", lambda T: write(T / (ROW + ".csv"), bytes(range(256))), ["s0.csv"]),
        ("config-maze=100000", lambda T: write(T / (ROW + ".toml"), set_keys(
            (T / (ROW + ".toml")).read_text(), [("maze", "size", "100000")])), ["maze", "size"]),
        ("evaluation-garbage", lambda T: write(T / (ROW + ".evaluation.csv"), "a,b\n1,2\n"),
         ["evaluation"]),
    ]
    for label, fn, field in raw_edits:
        add(f"results.figures.raw-{label}", FIG, field=field, file="s0",
            setup=figs(fn), what=f"raw/table/pbcs_fast-maze2/s0: {label}")
    PIC = "figs/res/raw/table/pbcs-maze2/s0.picture.csv"  # drawn by the `mazes` figure
    for label, data in [("garbage", "x\n"), ("empty", ""), ("nan", None)]:
        def fn(T, data=data):
            if data is None:
                rows = (T / PIC).read_text().splitlines()
                data = "\n".join([rows[0]] + [re.sub(r"[-0-9.]+", "NaN", r, count=1) for r in rows[1:]]) + "\n"
            write(T / PIC, data)

        add(f"results.figures.picture-{label}", FIG, field=["picture"], file="picture",
            setup=figs(fn), what=f"raw/table/pbcs-maze2/s0.picture.csv: {label}")
    # aggregate over the committed rows of the table (no profile)
    AGGF = ["{B}", "aggregate", "--experiments", "{T}/figs/exps", "--results", "{T}/figs/res"]
    for label, fn, field in raw_edits[:3]:
        add(f"results.aggregate.committed-{label}", AGGF, field=field, file="s0", setup=figs(fn),
            what=f"aggregate: raw/table/pbcs_fast-maze2/s0: {label}")
    # figures flags
    add("results.figures.--profile=nosuch", [*FIG, "--profile", "nosuch"], field=["nosuch"],
        setup=figs())
    add("results.figures.results-missing", ["{B}", "figures", "--experiments", "{T}/figs/exps",
                                            "--results", "{T}/nosuch"], file="nosuch", setup=figs())
    add("results.figures.no-tables", ["{B}", "figures", "--experiments", "{T}/experiments",
                                      "--profile", "smoke", "--results", "{T}/smoke/results-smoke"],
        field=["aggregate"], setup=lambda T: copy_fixture("smoke", T))
    # aggregate on the smoke results
    AGG = ["{B}", "aggregate", "--experiments", "{T}/smoke/experiments", "--results",
           "{T}/smoke/results-smoke"]
    SROW = "smoke/results-smoke/raw/table/pbcs-maze2/s0"

    def smoke(edit=None):
        def setup(T):
            copy_fixture("smoke", T)
            if edit:
                edit(Path(T))

        return setup

    def smoke_solved_no_eval(T):
        edit_csv(T / (SROW + ".csv"), set_col("solved", "true"))
        ev = T / (SROW + ".evaluation.csv")
        if ev.exists():
            ev.unlink()

    add("results.aggregate.smoke-no-profile", AGG, field=["--profile"], setup=smoke(),
        what="aggregate on smoke results without --profile: a hint naming --profile expected")
    add("results.aggregate.smoke-default-folder", ["{B}", "aggregate", "--experiments",
                                                   "{T}/smoke/experiments"],
        field=["--profile", "results"], setup=smoke(), what="aggregate with no results/ folder")
    add("results.aggregate.smoke-profile", [*AGG, "--profile", "smoke"], "either",
        setup=smoke(), what="aggregate --profile smoke (refused only where the build lacks polars)")
    for label, fn, field in [
        ("solved-no-evaluation", smoke_solved_no_eval, ["evaluation", "solved"]),
        ("success_rate=NaN", lambda T: edit_csv(T / (SROW + ".csv"), set_col("success_rate", "NaN")),
         ["success_rate"]),
        ("row-garbage", lambda T: write(T / (SROW + ".csv"), bytes(range(256))), ["s0.csv"]),
        ("config-edited", lambda T: write(T / (SROW + ".toml"), set_keys(
            (T / (SROW + ".toml")).read_text(), [("phase2", "beta", "0")])), ["s0.toml", "config"]),
    ]:
        add(f"results.aggregate.raw-{label}", [*AGG, "--profile", "smoke"], field=field, file="s0",
            setup=smoke(fn), what=f"smoke raw/table/pbcs-maze2/s0: {label}")
        add(f"results.exp-list.raw-{label}", ["{B}", "exp", "list", "{T}/smoke/experiments/table.toml",
                                              "--profile", "smoke", "--results",
                                              "{T}/smoke/results-smoke"], "either", field=field,
            file="s0", setup=smoke(fn), what=f"exp list over smoke rows: {label}")
    add("results.aggregate.--profile=nosuch", [*AGG, "--profile", "nosuch"], field=["nosuch"],
        setup=smoke())
    # exp run over a sweep whose rows were edited
    add("results.exp-run.row-edited", ["{B}", "exp", "run", "{T}/smoke/experiments/table.toml",
                                       "--profile", "smoke", "--results", "{T}/smoke/results-smoke"],
        "either", field=["s0"], setup=smoke(lambda T: edit_csv(T / (SROW + ".csv"),
                                                              set_col("success_rate", "NaN"))),
        what="exp run over smoke rows with a NaN success_rate")


# ---- chain manifests


def manifest_parts(text):
    head, *skills = re.split(r"(?m)^(?=\[\[skills\]\])", text)
    return head, skills


def build_manifest_cases():
    EV = ["{B}", "eval", "--chain", "{T}/run/chain", "--episodes", "10", "--out", "{T}/ev"]
    M = "run/chain/manifest.toml"

    def man(fn):
        def setup(T):
            copy_fixture("run", T)
            p = Path(T) / M
            p.write_text(fn(p.read_text()))

        return setup

    def cut_last(t):
        h, s = manifest_parts(t)
        return h + "".join(s[:-1])

    def cut_last_count(t):
        h, s = manifest_parts(t)
        h = re.sub(r"(?m)^skill_count = .*$", f"skill_count = {len(s) - 1}", h)
        return h + "".join(s[:-1])

    def cut_first_count(t):
        h, s = manifest_parts(t)
        h = re.sub(r"(?m)^skill_count = .*$", f"skill_count = {len(s) - 1}", h)
        return h + "".join(s[1:])

    def reorder(t):
        h, s = manifest_parts(t)
        s = [x if x.endswith("\n\n") else x.rstrip("\n") + "\n\n" for x in s]
        return h + "".join(reversed(s))

    def dup_first(t, count=True):
        h, s = manifest_parts(t)
        s = [x if x.endswith("\n\n") else x.rstrip("\n") + "\n\n" for x in s]
        if count:
            h = re.sub(r"(?m)^skill_count = .*$", f"skill_count = {len(s) + 1}", h)
        return h + s[0] + "".join(s)

    def dup_replace(t):
        h, s = manifest_parts(t)
        s = [x if x.endswith("\n\n") else x.rstrip("\n") + "\n\n" for x in s]
        return h + s[0] + s[0]

    def last_skill(key, value):
        def f(t):
            h, s = manifest_parts(t)
            s[-1] = re.sub(rf"(?m)^{key} = .*$", f"{key} = {value}", s[-1])
            return h + "".join(s)

        return f

    def first_skill(key, value):
        def f(t):
            h, s = manifest_parts(t)
            s[0] = re.sub(rf"(?m)^{key} = .*$", f"{key} = {value}", s[0])
            return h + "".join(s)

        return f

    def head(key, value):
        return lambda t: re.sub(rf"(?m)^{key} = .*$", f"{key} = {value}", t, count=1)

    edits = [
        ("cut-last-skill", cut_last, ["skill_count", "skills"]),
        ("cut-last-skill-count-fixed", cut_last_count, ["target", "skill", "τ", "end"]),
        ("cut-first-skill-count-fixed", cut_first_count, ["start", "skill"]),
        ("reordered", reorder, ["start_index", "order", "skill"]),
        ("duplicated-skill", dup_first, ["start_index", "skill"]),
        ("duplicated-skill-count-unchanged", lambda t: dup_first(t, False), ["skill_count", "start_index"]),
        ("skill1-replaced-by-skill0", dup_replace, ["start_index", "target_index", "skill"]),
        ("target_index=u64max", last_skill("target_index", U64MAX), ["target_index"]),
        ("target_index=i64max", last_skill("target_index", I64MAX), ["target_index"]),
        ("target_index=100000", last_skill("target_index", "100000"), ["target_index"]),
        ("target_index=past-end", last_skill("target_index", "70"), ["target_index"]),
        ("target_index=-1", last_skill("target_index", "-1"), ["target_index"]),
        ("target<start", first_skill("target_index", "0"), ["target_index", "start_index"]),
        ("start_index=u64max", last_skill("start_index", U64MAX), ["start_index"]),
        ("start_index=gap", last_skill("start_index", "13"), ["start_index"]),
        ("skill_count=0", head("skill_count", "0"), ["skill_count"]),
        ("skill_count=u64max", head("skill_count", U64MAX), ["skill_count"]),
        ("skill_count=i64max", head("skill_count", I64MAX), ["skill_count"]),
        ("skill_count=-1", head("skill_count", "-1"), ["skill_count"]),
        ("no-skills", lambda t: manifest_parts(t)[0], ["skill"]),
        ("sha256-wrong", first_skill("sha256", '"' + "0" * 64 + '"'), ["sha256"]),
        ("job_sha256-wrong", head("job_sha256", '"' + "0" * 64 + '"'), ["job_sha256", "run.toml"]),
        ("file-missing", first_skill("file", '"nosuch.safetensors"'), ["nosuch.safetensors"]),
        ("file-escape", first_skill("file", '"../../../../etc/passwd"'), ["passwd", "file"]),
        ("file-absolute", first_skill("file", '"/etc/passwd"'), ["passwd", "file"]),
        ("job_file-missing", head("job_file", '"nosuch.toml"'), ["nosuch.toml"]),
        ("policy=foo", first_skill("policy", '"foo"'), ["policy"]),
        ("sizes-huge", first_skill("sizes", "[2, 1000000000, 1000000000, 2]"), ["sizes"]),
        ("sizes-mismatch", first_skill("sizes", "[2, 32, 32, 2]"), ["sizes", "skill0"]),
        ("sizes-empty", first_skill("sizes", "[]"), ["sizes"]),
        ("sizes-zero", first_skill("sizes", "[2, 0, 64, 2]"), ["sizes"]),
        ("action_bounds-short", first_skill("action_bounds", "[1.0]"), ["action_bounds"]),
        ("action_bounds-nan", first_skill("action_bounds", "[nan, 1.0]"), ["action_bounds"]),
        ("radius=nan", first_skill("radius", "nan"), ["radius"]),
        ("radius=-1", first_skill("radius", "-1.0"), ["radius"]),
        ("radius=0", first_skill("radius", "0.0"), ["radius"]),
        ("radius=inf", first_skill("radius", "inf"), ["radius"]),
        ("center-short", first_skill("center", "[0.5]"), ["center"]),
        ("center-nan", first_skill("center", "[nan, 0.5]"), ["center"]),
        ("origin-inf", first_skill("origin", "[inf, 1.0]"), ["origin"]),
        ("action_scale-nan", first_skill("action_scale", "[nan, 0.1]"), ["action_scale"]),
        ("unknown-key", lambda t: "foo = 1\n" + t, ["foo"]),
        ("empty", lambda t: "", ["skill_count", "skills", "manifest"]),
        ("garbage", lambda t: bytes(range(256)).decode("latin-1"), ["manifest"]),
        ("deep-array", lambda t: t.rstrip("\n") + "\nx = " + deep_array() + "\n", ["line"]),
        ("10MB-line", lambda t: t + 'foo = "' + "x" * 10_000_000 + '"\n', ["foo"]),
    ]
    for label, fn, field in edits:
        add(f"manifest.{label}", EV, field=field, file="manifest", setup=man(fn),
            check=short_msg_check(), what=f"chain/manifest.toml: {label}")

    def chain_setup(fn):
        def setup(T):
            copy_fixture("run", T)
            fn(Path(T) / "run/chain")

        return setup

    files = [
        ("manifest-deleted", lambda c: (c / "manifest.toml").unlink(), ["manifest"], "manifest"),
        ("run.toml-deleted", lambda c: (c / "run.toml").unlink(), ["run.toml"], "run.toml"),
        ("run.toml-maze=100000", lambda c: write(c / "run.toml", set_keys(
            (c / "run.toml").read_text(), [("maze", "size", "100000")])), ["run.toml", "job_sha256"],
         "run.toml"),
        ("skill-truncated", lambda c: write(c / "skill0.safetensors",
                                            (c / "skill0.safetensors").read_bytes()[:100]),
         ["skill0", "sha256"], "skill0"),
        ("skill-garbage", lambda c: write(c / "skill0.safetensors", bytes(range(256)) * 8),
         ["skill0", "sha256"], "skill0"),
        ("skill-deleted", lambda c: (c / "skill1.safetensors").unlink(), ["skill1"], "skill1"),
        ("skills-swapped", lambda c: (
            (c / "skill0.safetensors").rename(c / "tmp"),
            (c / "skill1.safetensors").rename(c / "skill0.safetensors"),
            (c / "tmp").rename(c / "skill1.safetensors")), ["sha256", "skill"], "skill"),
        ("manifest-is-dir", lambda c: ((c / "manifest.toml").unlink(), (c / "manifest.toml").mkdir()),
         ["manifest"], "manifest"),
    ]
    for label, fn, field, file in files:
        add(f"chain.{label}", EV, field=field, file=file, setup=chain_setup(fn),
            what=f"chain/: {label}")
    add("chain.ok", EV, "ok", setup=setup_run_fx)


# --------------------------------------------------------------------------------------------
# fixtures


def build_fixtures(binary):
    if FX.exists():
        shutil.rmtree(FX)
    FX.mkdir(parents=True)
    write(FX / "train-smoke.toml",
          "[train]\nsteps = 3000\nlearning_starts = 1000\neval_every = 1000\n")

    def run(argv, cwd=FX):
        r = subprocess.run(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=300)
        if r.returncode != 0:
            raise SystemExit(f"probe-hostile: fixture command failed ({r.returncode}): "
                             f"{shlex.join(argv)}\n{r.stderr.decode(errors='replace')[-2000:]}")

    b = str(binary)
    run([b, "run", "--maze", "2", "--seed", "0", "--quiet", "--out", str(FX / "run")])
    run([b, "train", "--config", str(FX / "train-smoke.toml"), "--maze", "2", "--seed", "0",
         "--quiet", "--out", str(FX / "train")])
    run([b, "explore", "--maze", "2", "--seed", "0", "--quiet", "--out", str(FX / "explore")])
    smoke = FX / "smoke"
    smoke.mkdir()
    shutil.copytree(REPO / "experiments", smoke / "experiments")
    run([b, "exp", "run", "experiments/table.toml", "--profile", "smoke", "--jobs", "1"], cwd=smoke)
    # the committed tables and rows of experiments/table.toml, and the files `figures` reads
    figs = FX / "figs"
    (figs / "res/tables").mkdir(parents=True)
    (figs / "exps").mkdir()
    for f in (REPO / "results/tables").glob("table*.csv"):
        shutil.copy(f, figs / "res/tables")
    shutil.copytree(REPO / "results/raw/table", figs / "res/raw/table")
    shutil.copy(REPO / "results/raw/legacy_without_evaluation.txt", figs / "res/raw")
    for name in ("table", "baseline", "pbcs_paper", "pbcs_fast", "settings", "departures"):
        shutil.copy(REPO / f"experiments/{name}.toml", figs / "exps")
    claims = (REPO / "experiments/claims.toml").read_text()
    head, *parts = re.split(r"(?m)^(?=\[\[claim\]\])", claims)
    keep = [p for p in parts
            if re.search(r'(?m)^experiment = "table"', p) and "than_experiment" not in p]
    (figs / "exps/claims.toml").write_text(head + "".join(keep))
    check = figs.parent / "figs-check"
    shutil.copytree(figs, check)
    run([b, "figures", "--experiments", str(check / "exps"), "--results", str(check / "res")])
    shutil.rmtree(check)


# --------------------------------------------------------------------------------------------
# running


def limits(mem_gb):
    def f():
        gb = int(mem_gb * (1 << 30))
        resource.setrlimit(resource.RLIMIT_AS, (gb, gb))
        fs = 4 << 30
        resource.setrlimit(resource.RLIMIT_FSIZE, (fs, fs))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    return f


def subst(s, T, binary):
    return s.replace("{B}", str(binary)).replace("{T}", str(T)).replace("{FX}", str(FX))


def show(argv):
    """The command as one shell line, $T standing for the case's folder."""
    words = []
    for a in argv:
        a = a.replace("{B}", "pbcs").replace("{FX}", "$FX").replace("{T}", "$T")
        if len(a) > 120:
            a = a[:100] + f"…({len(a)} chars)"
        if re.fullmatch(r"[\w@%+=:,./$-]+", a):
            words.append(a)
        else:
            q = re.sub(r'([\\"`])', r"\\\1", a).replace("$", "\\$")
            q = q.replace("\\$T", "$T").replace("\\$FX", "$FX").replace("\n", "\\n")
            words.append(f'"{q}"')
    return " ".join(words)


def read_cut(path, n=1 << 20):
    with open(path, "rb") as f:
        data = f.read(n)
    return data.decode("utf-8", errors="replace")


def run_case(case, binary, timeout, mem_gb, keep):
    work = SCRATCH / "work"
    work.mkdir(parents=True, exist_ok=True)
    T = Path(tempfile.mkdtemp(prefix="case-", dir=work))
    note = ""
    try:
        shutil.copytree(REPO / "experiments", T / "experiments")
        if case.setup:
            case.setup(str(T))
    except Exception as e:  # the script's own fault
        return {"rc": "", "seconds": 0.0, "cls": "setup-error", "stderr": f"setup: {e!r}",
                "stdout": "", "note": "", "names_field": "", "names_file": "", "T": str(T)}
    argv = [subst(a, T, binary) for a in case.argv]
    env = {k: v for k, v in os.environ.items() if not k.startswith("PBCS")}
    env["NO_COLOR"] = "1"
    env["RUST_BACKTRACE"] = "0"
    out_p, err_p = T / ".probe.stdout", T / ".probe.stderr"
    t0 = time.monotonic()
    timed_out = False
    with open(out_p, "wb") as so, open(err_p, "wb") as se:
        try:
            p = subprocess.Popen(argv, cwd=T, stdin=subprocess.DEVNULL, stdout=so, stderr=se,
                                 env=env, start_new_session=True, preexec_fn=limits(mem_gb))
        except OSError as e:
            return {"rc": "", "seconds": 0.0, "cls": "setup-error", "stderr": f"spawn: {e!r}",
                    "stdout": "", "note": "", "names_field": "", "names_file": "", "T": str(T)}
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            rc = p.wait()
        # anything the command left running in its group goes too
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    seconds = time.monotonic() - t0
    stderr = read_cut(err_p)
    stdout = read_cut(out_p, 4 << 20)
    stderr_len = err_p.stat().st_size
    if rc < 0:
        try:
            rc_s = "SIG" + signal.Signals(-rc).name.removeprefix("SIG")
        except ValueError:
            rc_s = f"signal {-rc}"
    else:
        rc_s = str(rc)
    names_field = ""
    names_file = ""
    if timed_out:
        cls = "hang"
    elif rc < 0:
        cls = "abort"
    elif rc == 101 or "panicked" in stderr:
        cls = "panic"
    elif "memory allocation" in stderr:
        cls = "abort"
    elif rc == 0:
        cls = "silent" if case.expect == "refuse" else "ok"
    elif not stderr.strip():
        cls = "nomsg"
    elif case.expect == "ok":
        cls = "failed"
    else:
        cls = "refused"
    if cls in ("refused", "failed", "nomsg"):
        low = stderr.lower()
        if case.field:
            hit = any(f.lower() in low for f in case.field)
            names_field = "true" if hit else "false"
            if not hit and cls == "refused":
                cls = "vague"
                note = "names none of: " + ", ".join(case.field)
        if case.file:
            names_file = "true" if case.file.lower() in low else "false"
        if cls == "refused" and stderr_len >= MSG_MAX and not case.long_ok:
            cls = "vague"
            note = f"message is {stderr_len} bytes"
    ctx = {"T": str(T), "rc": rc, "stdout": stdout, "stderr": stderr, "cls": cls}
    if case.check and cls not in ("hang", "abort", "panic"):
        r = case.check(ctx)
        if r:
            cls, extra = r
            note = (note + "; " if note else "") + extra
    if cls not in ("wrong",) and (T / "x").exists():
        cls, note = "wrong", (note + "; " if note else "") + "file x appeared in the case folder"
    res = {"rc": rc_s, "seconds": round(seconds, 2), "cls": cls, "stderr": stderr,
           "stderr_len": stderr_len, "stdout": stdout, "note": note, "names_field": names_field,
           "names_file": names_file, "T": str(T)}
    if not keep:
        shutil.rmtree(T, ignore_errors=True)
    return res


def build_all():
    build_config_cases()
    build_structure_cases()
    build_flag_cases()
    build_output_cases()
    build_script_cases()
    build_experiment_cases()
    build_results_cases()
    build_manifest_cases()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=str(DEFAULT_BIN), help="the pbcs binary (default: %(default)s)")
    ap.add_argument("--out", default=str(SCRATCH / "report.csv"), help="the CSV (default: %(default)s)")
    ap.add_argument("--only", default=None, help="only the cases whose id contains this")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per case (default 30)")
    ap.add_argument("--mem-gb", type=float, default=6.0,
                    help="address-space limit of each case, GiB (default 6)")
    ap.add_argument("--keep", action="store_true", help="keep each case's folder")
    ap.add_argument("--list", action="store_true", help="list the case ids and exit")
    args = ap.parse_args()

    binary = Path(args.bin)
    if not os.access(binary, os.X_OK):
        print(f"probe-hostile: {binary} is not an executable", file=sys.stderr)
        return 2
    SCRATCH.mkdir(parents=True, exist_ok=True)
    if not (args.list and (FX / "run/config.toml").exists()):
        print(f"probe-hostile: building fixtures with {binary} ...", flush=True)
        build_fixtures(binary)
    build_all()
    cases = [c for c in CASES if args.only is None or args.only in c.cid]
    if args.list:
        for c in cases:
            print(c.cid, "|", c.expect, "|", show(c.argv), "|", c.what)
        print(f"{len(cases)} cases")
        return 0
    print(f"probe-hostile: {len(cases)} cases, timeout {args.timeout:g} s each", flush=True)
    results = []
    t_all = time.monotonic()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["id", "command", "input", "expect", "exit", "seconds", "class", "names_field",
                    "names_file", "stderr_bytes", "stderr", "note"])
        for i, c in enumerate(cases, 1):
            r = run_case(c, binary, args.timeout, args.mem_gb, args.keep)
            results.append((c, r))
            w.writerow([c.cid, show(c.argv), c.what, c.expect, r["rc"], r["seconds"], r["cls"],
                        r["names_field"], r["names_file"], r.get("stderr_len", ""),
                        r["stderr"][:200], r["note"]])
            f.flush()
            mark = "" if r["cls"] in ("ok", "refused") else f"  <-- {r['cls']}"
            print(f"[{i}/{len(cases)}] {r['cls']:8} {r['rc']:>7} {r['seconds']:6.2f}s {c.cid}{mark}",
                  flush=True)
    counts = {}
    for _, r in results:
        counts[r["cls"]] = counts.get(r["cls"], 0) + 1
    print(f"\n== {len(results)} cases in {time.monotonic() - t_all:.0f} s; CSV: {args.out}")
    for k in sorted(counts, key=lambda k: (-counts[k], k)):
        print(f"  {k:12} {counts[k]}")
    nofile = sum(1 for c, r in results if r["names_file"] == "false")
    print(f"  (refusals whose message does not name the expected file: {nofile})")
    odd = [(c, r) for c, r in results if r["cls"] not in ("ok", "refused")]
    if odd:
        print("\n== cases not classed refused or ok")
        for c, r in odd:
            print(f"\n[{r['cls']}] {c.cid}  (exit {r['rc']}, {r['seconds']} s)")
            print(f"  $ {show(c.argv)}")
            if c.what:
                print(f"  input: {c.what}")
            if r["note"]:
                print(f"  note: {r['note']}")
            err = r["stderr"][:300].replace("\n", "\n    ")
            print(f"  stderr: {err}")
    return 1 if any(r["cls"] in FAILING for _, r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
