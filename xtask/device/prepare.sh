#!/usr/bin/env bash
# The device kit, made here for a session lent a GPU machine (an H100 with 16 CPU cores, reached
# through the workplace's `device` tool): that machine has no Rust toolchain and reaches no network,
# so everything `run.sh` needs is built and gathered here into `.device-kit/` (git-ignored, about
# 42 MB), which the tool carries beside the working tree (64 MiB at most with the tracked files).
#
#   bash xtask/device/prepare.sh [DATA_DIR]   # default ../shared/mocap/bandai-namco-2-walk
#
# Then one device call, from the repository root (the tool's `run`, carry [".device-kit"],
# timeout_s 600):
#
#   bash xtask/device/run.sh
#
# The kit holds:
# - stripped release builds of `xtask`, `gpu-crowd`'s example `h100` and its test `cpu_match`:
#   plain x86-64 (no `-C target-cpu`), dynamically linked to glibc 2.35 or newer only
#   (`objdump -T`);
# - the criterion bench `model_file` (`benches/model_file.rs`: issue 35's two per-walker costs on
#   a model file), gzipped (`model_file.gz`: the kit stays within the tool's 64 MiB);
# - the model built from DATA_DIR, and DATA_DIR itself as `data.tar.gz` (for `xtask scaling`);
# - the Vulkan loader as Debian packages (`gl/`, unpacked on the device where it has none);
# - the commit it was made from (`COMMIT`), the data's name (`DATA`) and the folder it was built in
#   (`SOURCE_ROOT`: `cpu_match` finds `fixtures/` there).
set -euo pipefail
cd "$(dirname "$0")/../.."
data=${1:-../shared/mocap/bandai-namco-2-walk}
kit=.device-kit
[ -d "$data" ] || { echo "prepare.sh: no data folder $data" >&2; exit 1; }
rm -rf "$kit"
mkdir -p "$kit/bin" "$kit/gl"
echo "== release builds (motion-lod, xtask, gpu-crowd's example h100, its test cpu_match, the bench model_file)"
cargo build --release -q -p motion-lod -p xtask
cargo build --release -q -p gpu-crowd --example h100
cargo test -q -p gpu-crowd --release --no-run 2>/dev/null
match=$(cargo test -p gpu-crowd --release --no-run 2>&1 | sed -n 's|.*Executable tests/cpu_match.rs (\(.*\))|\1|p')
[ -x "$match" ] || { echo "prepare.sh: no test binary of gpu-crowd's cpu_match" >&2; exit 1; }
bench=$(cargo bench -p motion-lod-benches --bench model_file --no-run 2>&1 | sed -n 's|.*Executable model_file.rs (\(.*\))|\1|p')
[ -x "$bench" ] || { echo "prepare.sh: no bench binary model_file" >&2; exit 1; }
cp target/release/xtask target/release/examples/h100 "$kit/bin/"
cp "$match" "$kit/bin/cpu_match"
cp "$bench" "$kit/bin/model_file"
strip "$kit/bin/"*
gzip -9 "$kit/bin/model_file"
echo "== the model of $data"
target/release/motion-lod build "$data" -o "$kit/model.mlod" 2>&1 | tail -1
echo "== the data for xtask scaling"
tar -C "$(dirname "$data")" -czf "$kit/data.tar.gz" "$(basename "$data")"
echo "== the Vulkan loader (Debian packages, unpacked on the device only where it has none)"
lists=$(mktemp -d)
mkdir -p "$lists/partial"
apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 "-oDir::State::Lists=$lists")
apt-get "${apt_opts[@]}" update -qq >/dev/null 2>&1
(cd "$kit/gl" && apt-get "${apt_opts[@]}" download -qq libvulkan1 >/dev/null 2>&1)
rm -rf "$lists"
commit=$(git rev-parse --short HEAD)
if [ -n "$(git status --porcelain --untracked-files=no -- . ':(exclude)docs')" ]; then
  commit="$commit with uncommitted changes"
fi
echo "$commit" >"$kit/COMMIT"
echo "$(basename "$data")" >"$kit/DATA"
# cpu_match reads fixtures/ through the path it was compiled at: run.sh links it to the device's copy.
pwd >"$kit/SOURCE_ROOT"
du -sh "$kit"; ls -l "$kit" "$kit/bin"
echo "kit ready: carry .device-kit and run: bash xtask/device/run.sh (capped at 560 s on the device)"
