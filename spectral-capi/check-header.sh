#!/usr/bin/env bash
# Regenerates include/fspec.h from the crate with cbindgen into a temporary
# file and fails if the committed header differs (the header is generated,
# never edited by hand). `--write` updates the committed header instead.
# Needs cbindgen (`cargo install cbindgen --locked`).
set -euo pipefail
cd "$(dirname "$0")"

generated="$(mktemp)"
trap 'rm -f "$generated"' EXIT
# cbindgen reports skipped private items on stderr; only failures matter.
cbindgen --quiet --config cbindgen.toml --crate spectral-capi --output "$generated" .

if [[ "${1:-}" == "--write" ]]; then
  cp "$generated" include/fspec.h
  echo "include/fspec.h updated"
elif ! diff -u include/fspec.h "$generated"; then
  echo "include/fspec.h is out of date: run spectral-capi/check-header.sh --write" >&2
  exit 1
else
  echo "include/fspec.h is up to date"
fi
