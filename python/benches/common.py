"""What the benchmark scripts here share."""

import os
import tempfile


def write_atomic(path, text):
    """Writes `text` to `path` (its folder made if needed) through a temporary file in the same
    folder, renamed into place: a reader sees the old file or the whole new one."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False, suffix=".tmp") as f:
        f.write(text)
    os.replace(f.name, path)
