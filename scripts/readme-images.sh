#!/usr/bin/env bash
# Regenerates every picture of README.md and docs/ (tests/cpu/readme.rs checks they exist):
#
#   docs/images/showcase.png             the showcase example offscreen, 1280x720, 32 frames
#                                        (twice the default settle_frames, as the goldens)
#   docs/images/technique-<name>.png     the headless renderer on one scene, once per technique
#                                        (aaps, image_space, photon_map, volume, reference)
#   docs/images/asset-<Model>.png        each public sample model (tests/gpu/assets.rs) on the
#                                        headless renderer's stage (--stage), default technique
#
# Builds the two examples once, then runs them with no display (the examples render offscreen
# when DISPLAY and WAYLAND_DISPLAY are unset). Needs a Vulkan driver (lavapipe will do: 8 minutes
# on 2 cores, the showcase 3 of them). Settings, all optional:
#
#   SHOWCASE=1 (0: leave the showcase picture as it is)  SHOWCASE_SIZE=1280x720  SHOWCASE_FRAMES=32
#   SCENE=assets/scenes/glass_sphere.gltf  TECH_WIDTH=320  TECH_HEIGHT=240  TECH_FRAMES=24
#   TECH_EV100=13  REFERENCE_PHOTONS=4194304  TECHNIQUES="aaps image_space photon_map volume reference"
#   ASSETS=1 (0: leave the sample-model pictures)  ASSET_DIR=shared/khronos (else ../shared/khronos)
#   ASSET_PHOTONS=1048576  ASSET_MODELS="AttenuationTest TransmissionRoughnessTest SunglassesKhronos
#   DispersionTest GlassTable" (each <Model>/<Model>.glb, or .gltf with its files beside it)
#
# A picture over MAX_BYTES (500 KB) is re-encoded to 256 colours (pngquant or Pillow).
set -euo pipefail
cd "$(dirname "$0")/.."

SHOWCASE=${SHOWCASE:-1}
SHOWCASE_SIZE=${SHOWCASE_SIZE:-1280x720}
SHOWCASE_FRAMES=${SHOWCASE_FRAMES:-32}
SCENE=${SCENE:-assets/scenes/glass_sphere.gltf}
TECH_WIDTH=${TECH_WIDTH:-320}
TECH_HEIGHT=${TECH_HEIGHT:-240}
# Frames measured once the caustics are ready: past the default settle_frames (16).
TECH_FRAMES=${TECH_FRAMES:-24}
# The scenes' sun is 10 000 lux: EV100 13, as the examples' cameras.
TECH_EV100=${TECH_EV100:-13}
# The CPU reference at the Medium preset (2^18 photons) is noisy at 320x240: 2^22.
REFERENCE_PHOTONS=${REFERENCE_PHOTONS:-4194304}
TECHNIQUES=${TECHNIQUES:-aaps image_space photon_map volume reference}
MAX_BYTES=${MAX_BYTES:-512000}
ASSETS=${ASSETS:-1}
if [[ -z ${ASSET_DIR:-} ]]; then
  ASSET_DIR=shared/khronos
  [[ -d $ASSET_DIR ]] || ASSET_DIR=../shared/khronos
fi
# 2^20 photons per light: the stage's sun spreads them over a floor four model radii wide.
ASSET_PHOTONS=${ASSET_PHOTONS:-1048576}
ASSET_MODELS=${ASSET_MODELS:-AttenuationTest TransmissionRoughnessTest SunglassesKhronos DispersionTest GlassTable}
OUT=docs/images

mkdir -p "$OUT"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Offscreen: no window, whatever this shell has.
unset DISPLAY WAYLAND_DISPLAY

elapsed() { echo "$(( $(date +%s) - $1 )) s"; }

# Keep a picture under MAX_BYTES: 256 colours (dithered) with pngquant, else Python's Pillow.
fit() {
  local f=$1 size
  size=$(stat -c %s "$f")
  (( size > MAX_BYTES )) || return 0
  if command -v pngquant >/dev/null; then
    pngquant --force --strip --output "$f.tmp.png" 256 "$f"
  elif python3 -c 'import PIL' 2>/dev/null; then
    python3 - "$f" "$f.tmp.png" <<'PY'
import sys
from PIL import Image
im = Image.open(sys.argv[1]).convert("RGB")
im.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.FLOYDSTEINBERG).save(
    sys.argv[2], optimize=True)
PY
  else
    echo "  $f: $size bytes, over $MAX_BYTES: install pngquant or Pillow to re-encode" >&2
    return 0
  fi
  mv "$f.tmp.png" "$f"
  echo "  $f: $size bytes, re-encoded to $(stat -c %s "$f")"
}

start=$(date +%s)
echo "== building the examples (release)"
cargo build --release --example showcase --example render
echo "   built in $(elapsed "$start")"

if [[ $SHOWCASE == 1 ]]; then
  t=$(date +%s)
  echo "== showcase, ${SHOWCASE_SIZE}, ${SHOWCASE_FRAMES} frames"
  CAUSTICS_EXAMPLE_SIZE=$SHOWCASE_SIZE CAUSTICS_EXAMPLE_FRAMES=$SHOWCASE_FRAMES \
    CAUSTICS_EXAMPLE_OUT=$work cargo run --release --example showcase
  cp "$work/showcase.png" "$OUT/showcase.png"
  fit "$OUT/showcase.png"
  echo "   showcase in $(elapsed "$t")"
fi

for tech in $TECHNIQUES; do
  t=$(date +%s)
  echo "== $tech on $SCENE, ${TECH_WIDTH}x${TECH_HEIGHT}, $TECH_FRAMES frames"
  extra=()
  if [[ $tech == reference ]]; then
    extra=(--photons "$REFERENCE_PHOTONS")
  fi
  cargo run --release --example render -- "$SCENE" --technique "$tech" \
    --width "$TECH_WIDTH" --height "$TECH_HEIGHT" --frames "$TECH_FRAMES" --ev100 "$TECH_EV100" \
    "${extra[@]}" --out-png "$work/technique-$tech.png" --json "$work/technique-$tech.json"
  cp "$work/technique-$tech.png" "$OUT/technique-$tech.png"
  fit "$OUT/technique-$tech.png"
  echo "   $tech in $(elapsed "$t")"
done

if [[ $ASSETS == 1 ]]; then
  for model in $ASSET_MODELS; do
    t=$(date +%s)
    echo "== $model on the stage, aaps, ${TECH_WIDTH}x${TECH_HEIGHT}, $TECH_FRAMES frames"
    file="$ASSET_DIR/$model/$model.glb"
    [[ -f $file ]] || file="$ASSET_DIR/$model/$model.gltf"
    cargo run --release --example render -- "$file" --stage \
      --technique aaps --width "$TECH_WIDTH" --height "$TECH_HEIGHT" --frames "$TECH_FRAMES" \
      --photons "$ASSET_PHOTONS" --out-png "$work/asset-$model.png" --json "$work/asset-$model.json"
    cp "$work/asset-$model.png" "$OUT/asset-$model.png"
    fit "$OUT/asset-$model.png"
    echo "   $model in $(elapsed "$t")"
  done
fi

echo "== done in $(elapsed "$start"): $(ls "$OUT")"
