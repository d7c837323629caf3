#!/usr/bin/env bash
# Per-pass GPU milliseconds of every caustics technique at 1920x1080 (examples/gpu_timings.rs),
# under 5 minutes on a real GPU (plus the build). ARGS go to the example; `--help` lists them
# (--frames, --no-sweep, --out FILE, ...).
#
#   scripts/gpu-timings.sh [ARGS]           build, run here; the table goes to docs/gpu-timings.md
#   scripts/gpu-timings.sh --pack           for a machine without Rust or network (the lent GPU
#                                           machine): build here, pack the stripped binary and
#                                           the Vulkan loader into target/gpu-timings/ (~22 MB)
#   scripts/gpu-timings.sh --packed [ARGS]  there, with target/gpu-timings carried: run it
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${CARGO_TARGET_DIR:-target}/release/examples/gpu_timings"
pack=target/gpu-timings

# Where the table goes: the value of --out in the arguments, else the example's default.
table_path() {
  local out="docs/gpu-timings.md" prev=""
  for a in "$@"; do
    [[ "$prev" == "--out" ]] && out="$a"
    [[ "$a" == --out=* ]] && out="${a#--out=}"
    prev="$a"
  done
  echo "$out"
}

case "${1:-}" in
  --pack)
    cargo build --release --example gpu_timings
    mkdir -p "$pack/deb" /tmp/amd64/partial
    strip -o "$pack/gpu_timings" "$bin"
    gzip -9f "$pack/gpu_timings"
    # The Vulkan loader and glvnd, as the device notes bring them: wgpu opens libvulkan.so.1 at
    # run time, and the NVIDIA ICD (libGLX_nvidia.so.0) needs glvnd's libGLdispatch.
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    apt-get $o update -qq
    (cd "$pack/deb" && apt-get $o download libvulkan1 libglvnd0 libegl1 libgl1 libglx0 libopengl0 libgles2)
    du -sh "$pack"
    echo "carry $pack; there run: scripts/gpu-timings.sh --packed --out \$OUT/gpu-timings.md"
    ;;
  --packed)
    shift
    # Always: a machine may have the loader but not glvnd (then no adapter is found).
    for f in "$pack"/deb/*.deb; do dpkg -x "$f" /; done
    ldconfig
    icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    if [[ -z "${VK_DRIVER_FILES:-}" && -f "$icd" ]]; then export VK_DRIVER_FILES="$icd"; fi
    gzip -dc "$pack/gpu_timings.gz" >/tmp/gpu_timings
    chmod +x /tmp/gpu_timings
    /tmp/gpu_timings "$@"
    echo "the table is in $(table_path "$@")"
    ;;
  *)
    cargo build --release --example gpu_timings
    "$bin" "$@"
    echo "the table is in $(table_path "$@")"
    ;;
esac
