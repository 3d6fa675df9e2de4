"""Where the `pbcs` command is: $PBCS_BIN, else cargo's target folder ($CARGO_TARGET_DIR or
target/). Tests that compare with the command need it (CI sets PBCS_BIN)."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def pbcs_bin():
    candidates = [os.environ.get("PBCS_BIN")]
    target = os.environ.get("CARGO_TARGET_DIR")
    candidates += [str(Path(target) / "release" / "pbcs") if target else None]
    candidates += [str(ROOT / "target" / "release" / "pbcs")]
    for c in candidates:
        if c and Path(c).is_file():
            return c
    if os.environ.get("PBCS_BIN"):
        pytest.fail(f"PBCS_BIN={os.environ['PBCS_BIN']} is not a file")
    pytest.skip("the pbcs command is not built (cargo build --release, or set PBCS_BIN)")
