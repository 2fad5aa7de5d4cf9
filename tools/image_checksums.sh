#!/usr/bin/env bash
# Image checksums of every built-in scene and the scene files in scenes/,
# each in every transport, at a fixed seed and a small size: the check that a
# refactoring left every image bit-identical.
#
#   tools/image_checksums.sh FSPEC_BINARY > checksums.txt
#   diff before.txt after.txt      # empty: bit-identical
#
# The film is the default of `fspec render` (splat; sample for --transport
# cv) but in the line that pins `--film sample`; checksums taken before the
# default became splat differ from later ones in every other non-cv line.
#
# The EXR outputs are hashed (the linear float image, no 8-bit rounding that
# could hide a change in the last bits).
set -euo pipefail
fspec=${1:?usage: tools/image_checksums.sh FSPEC_BINARY}
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

transports=(
  "--coeffs 4"
  "--coeffs 12"
  "--coeffs 12 --film sample"
  "--coeffs 12 --to-color series"
  "--coeffs 12 --to-color lut"
  "--coeffs 12 --to-color mese"
  "--coeffs 12 --buffer rgb"
  "--coeffs 16 --filter box"
  "--coeffs 32"
  "--transport sampled --wavelengths 1 --sampling uniform"
  "--transport sampled --wavelengths 4 --sampling stratified"
  "--transport sampled --wavelengths 4 --sampling hero"
  "--transport sampled --wavelengths 8 --sampling visible"
  "--transport sampled --wavelengths 32"
  "--transport cv --wavelengths 8 --coeffs 4"
  "--transport cv --wavelengths 12 --coeffs 12 --cv-alpha-per-pixel"
)
scenes=$("$fspec" scenes | awk 'NF {print $1}' | grep -E '^[a-z][a-z0-9-]*$' || true)
scenes="$scenes $(ls scenes/*.toml)"
for scene in $scenes; do
  for t in "${transports[@]}"; do
    # shellcheck disable=SC2086 # the options are meant to split
    if "$fspec" render "$scene" --width 24 --height 16 --spp 4 --max-depth 6 \
         --seed 7 --threads 2 --quiet $t --out "$work/i.exr" >"$work/log" 2>&1; then
      sum=$(sha256sum "$work/i.exr" | cut -c1-16)
    else
      sum="error:$(tail -1 "$work/log")"
    fi
    printf '%s | %s | %s\n' "$scene" "$t" "$sum"
  done
done
