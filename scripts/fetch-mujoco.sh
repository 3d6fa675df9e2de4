#!/usr/bin/env bash
# MuJoCo 3.17.0 for the `mujoco` feature (gymnasium-robotics' PointMaze, src/envs/pointmaze/): the
# library inside the PyPI wheel `mujoco==3.17.0` — the version mujoco-rs 7.0.0 binds, and the
# one gymnasium-robotics runs on in the equality test — put in .mujoco/lib under its soname
# (libmujoco.so.3.17.0, what binaries load) and as libmujoco.so (what the linker looks for).
# .cargo/config.toml points MUJOCO_DYNAMIC_LINK_DIR there and build.rs writes it into the
# binaries' run path. Needs python3 with pip and the package index; nothing is compiled.
set -euo pipefail
cd "$(dirname "$0")/.."
version=3.17.0
dest=.mujoco/lib
if [ -f "$dest/libmujoco.so.$version" ] && [ -L "$dest/libmujoco.so" ]; then
  echo "MuJoCo $version is in $dest"
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 -m pip download --quiet --no-deps --only-binary=:all: "mujoco==$version" -d "$tmp"
mkdir -p "$dest"
python3 - "$tmp" "$dest" "$version" <<'PY'
import glob, os, sys, zipfile
tmp, dest, version = sys.argv[1:]
wheels = glob.glob(os.path.join(tmp, f"mujoco-{version}-*.whl"))
if len(wheels) != 1:
    sys.exit(f"expected one mujoco {version} wheel, pip gave {wheels}")
name = f"mujoco/libmujoco.so.{version}"
with zipfile.ZipFile(wheels[0]) as z:
    data = z.read(name)
part = os.path.join(dest, f"libmujoco.so.{version}.part")
with open(part, "wb") as f:
    f.write(data)
os.replace(part, os.path.join(dest, f"libmujoco.so.{version}"))
PY
ln -sfn "libmujoco.so.$version" "$dest/libmujoco.so"
echo "MuJoCo $version is in $dest: cargo build --release --features mujoco"
