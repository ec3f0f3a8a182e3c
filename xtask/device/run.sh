#!/usr/bin/env bash
# The device check, on the GPU machine (see prepare.sh, which made `.device-kit/` here): every
# figure that needs that machine, in one call of under ten minutes, most wanted first, each step
# under its own time limit so that a slow one cannot take the others' time:
#
# 1. issue 32: `h100` times the GPU crowd at 1,000,000 walkers at full detail and 10,000,000
#    under the distance policy, with GPU memory a walker, and the CPU crowd at 1,000,000, full
#    detail, on every core beside it; then the 10,000,000 again with seams and the foot lock on
#    (`gpu.txt`);
# 2. issue 32 item 3 on real hardware: gpu-crowd's test `cpu_match` (1,000 walkers, 300 frames,
#    both scenes, seams off and on, every joint against the CPU crowd's), run on this GPU
#    (`cpu-match.txt`);
# 3. issue 35 item 2: the per-walker costs by the criterion bench `model_file` on this machine's
#    CPU (a root-only walker-frame at 100,000 and 2,000 walkers on one thread; a root-only and a
#    level-0 clip build, kriging weights and pose) (`per-walker.txt`);
# 4. issue 35 item 1: `xtask frames`, the tables' frame-time rows with their fixed-work control, at
#    100,000 walkers on 1, 2, 4, 8 and 16 threads and 1,000,000 on 8 and 16 (`frames-*.md`);
# 5. issue 35 item 3: `xtask scaling`, the build's time, stages and peak memory at 800 and 10,000
#    cycles on 1, 2, 4, 8 and 16 threads (`scaling.md`, `figures/scaling.svg`).
#
# Everything goes to $OUT (the device tool's folder that comes back; `out/device` elsewhere), with
# the machine and the whole output in `log.txt`; the whole run stays under 560 s. DEVICE_KIT_SMALL=1 runs each step at a size of
# seconds, to try the script on any machine first (lavapipe serves as the GPU there).
set -uo pipefail
cd "$(dirname "$0")/../.."
kit=.device-kit
out=${OUT:-out/device}
mkdir -p "$out"
[ -x "$kit/bin/xtask" ] || { echo "run.sh: no $kit: run xtask/device/prepare.sh first and carry it" >&2; exit 1; }
exec > >(tee -a "$out/log.txt") 2>&1
started=$SECONDS
step() { echo; echo "== $1 (at $((SECONDS - started)) s)"; }
# Seconds a step may take: its own limit, or what is left of the whole run's (DEVICE_KIT_BUDGET_S,
# 560 s: the device tool stops a command at 600 s), whichever is less.
budget=${DEVICE_KIT_BUDGET_S:-560}
limit() {
  local left=$((budget - (SECONDS - started)))
  [ "$left" -lt "$1" ] && echo "$((left > 5 ? left : 5))" || echo "$1"
}
export XTASK_COMMIT
XTASK_COMMIT=$(cat "$kit/COMMIT")
model=$kit/model.mlod
if [ "${DEVICE_KIT_SMALL:-0}" = 1 ]; then
  gpu_args=(--full 2000 --lod 20000 --frames 5)
  frames_small=(--walkers 2000 --threads 1,2 --frames 10) frames_large=(--walkers 5000 --threads 2 --frames 10)
  scaling_args=(--sizes 800 --threads 2)
  bench_args=(--warm-up-time 0.2 --measurement-time 0.5 'root_only$|crowd_root_only_one_thread/2000$')
else
  gpu_args=(--full 1000000 --lod 10000000 --frames 60)
  frames_small=(--walkers 100000 --threads 1,2,4,8,16) frames_large=(--walkers 1000000 --threads 8,16)
  scaling_args=(--sizes 800,10000 --threads 1,2,4,8,16)
  bench_args=(--warm-up-time 1 --measurement-time 3 'root_only|level0_all_joints')
fi

step "machine"
echo "kit of commit $XTASK_COMMIT, model of $(cat "$kit/DATA")"
nproc; free -g | head -2
lscpu | grep -E '^(Model name|CPU family|Model|Thread|Core|Socket|Flags)' | cut -c1-200
nvidia-smi -L 2>/dev/null || echo "no nvidia-smi"

step "Vulkan loader"
if ! ldconfig -p | grep -q 'libvulkan.so.1 '; then
  for f in "$kit"/gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
  echo "unpacked $(ls "$kit"/gl)"
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -e "$icd" ]; then
  export VK_DRIVER_FILES=$icd VK_ICD_FILENAMES=$icd
  echo "VK_DRIVER_FILES=$icd"
fi

step "1. GPU crowd (issue 32)"
timeout "$(limit 240)" "$kit/bin/h100" "$model" "${gpu_args[@]}" | tee "$out/gpu.txt"
echo "h100 exit status ${PIPESTATUS[0]}"

step "2. the GPU crowd against the CPU crowd on this GPU (issue 32, item 3)"
src=$(cat "$kit/SOURCE_ROOT")
if [ "$src" != "$PWD" ] && [ ! -e "$src" ]; then
  mkdir -p "$(dirname "$src")" && ln -s "$PWD" "$src" && echo "linked $src to $PWD (fixtures/)"
fi
MOTION_LOD_REQUIRE_GPU=1 timeout "$(limit 90)" "$kit/bin/cpu_match" --nocapture 2>&1 | tee "$out/cpu-match.txt"
echo "cpu_match exit status ${PIPESTATUS[0]}"

step "3. per-walker costs (issue 35, item 2)"
# The bench, unpacked outside the kit (which must stay small enough to carry) into a folder of the
# working tree (a temporary folder may forbid running programs); its own setup builds both crowds
# (2,000 and 100,000 walkers) whatever the filter; criterion's reports go there too.
bench=$(mktemp -d "$PWD/.device-bench.XXXXXX")
{ gunzip -c "$kit/bin/model_file.gz" 2>/dev/null ||
  python3 -c 'import gzip, sys; sys.stdout.buffer.write(gzip.open(sys.argv[1]).read())' \
    "$kit/bin/model_file.gz"; } >"$bench/model_file" && chmod +x "$bench/model_file"
CRITERION_HOME=$bench/criterion MOTION_LOD_BENCH_MODEL=$model timeout "$(limit 75)" \
  "$bench/model_file" --bench --noplot "${bench_args[@]}" 2>&1 | tee "$out/per-walker.txt"
echo "model_file exit status ${PIPESTATUS[0]}"
rm -rf "$bench"

step "4. frame times (issue 35, item 1)"
timeout "$(limit 100)" "$kit/bin/xtask" frames "$model" "${frames_small[@]}" --quiet --out "$out/frames-small.md"
echo "exit status $?"
timeout "$(limit 120)" "$kit/bin/xtask" frames "$model" "${frames_large[@]}" --quiet --out "$out/frames-large.md"
echo "exit status $?"

step "5. build scaling (issue 35, item 3)"
data=$(mktemp -d)
tar -xzf "$kit/data.tar.gz" -C "$data"
timeout "$(limit 240)" "$kit/bin/xtask" scaling --data "$data/$(cat "$kit/DATA")" "${scaling_args[@]}" \
  --limit-s 120 --out "$out/scaling.md"
echo "exit status $?"
rm -rf "$data"

step "done"
ls -la "$out" "$out/figures" 2>/dev/null
