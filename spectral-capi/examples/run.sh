#!/usr/bin/env bash
# Builds the C11 and C++17 examples with the system compilers against the
# static library of spectral-capi, runs them, and compares every number
# they print with the same scene computed by spectral-core directly
# (`cargo run --example reference_xyz`), within a relative tolerance. Then
# builds the library without `std` (its own panic handler, profile
# `release-nostd`) and runs the C example against that too. Called by .ci/run.
set -euo pipefail
cd "$(dirname "$0")/../.."
target="${CARGO_TARGET_DIR:-target}"
out="$target/capi-examples"
mkdir -p "$out"
examples=spectral-capi/examples
c_flags=(-std=c11 -Wall -Wextra -Werror -pedantic -Ispectral-capi/include)
cpp_flags=(-std=c++17 -Wall -Wextra -Werror -pedantic -Ispectral-capi/include)
# What a Rust staticlib that links std needs from the system.
std_libs=(-lm -lpthread -ldl)

compare() { # compare REFERENCE OUTPUT: same labels, numbers within tolerance
  python3 - "$1" "$2" <<'PY'
import sys
# f64 results run the same code in both (equal up to printing); the 8-lane
# f32 results too. The tolerance only absorbs the 10 printed digits.
RELATIVE = 1e-8
reference, output = (open(p).read().split("\n") for p in sys.argv[1:3])
reference = [l.split() for l in reference if l.strip()]
output = [l.split() for l in output if l.strip()]
if [r[0] for r in reference] != [o[0] for o in output]:
    sys.exit(f"labels differ: {[r[0] for r in reference]} vs {[o[0] for o in output]}")
for r, o in zip(reference, output):
    if len(r) != len(o):
        sys.exit(f"{r[0]}: {len(o) - 1} numbers, expected {len(r) - 1}")
    for a, b in zip(map(float, r[1:]), map(float, o[1:])):
        if abs(a - b) > RELATIVE * max(abs(a), abs(b)):
            sys.exit(f"{r[0]}: {b} differs from the reference {a}")
print(f"  {len(output)} lines agree with the reference")
PY
}

echo "-- reference (spectral-core directly)"
cargo run --release -q -p spectral-capi --example reference_xyz > "$out/reference.txt"

echo "-- C11 and C++17 examples against libspectral_capi.a (std)"
cargo build --release -q -p spectral-capi
lib="$target/release/libspectral_capi.a"
cc "${c_flags[@]}" "$examples/c/lamp_reflectance.c" "$lib" "${std_libs[@]}" -o "$out/c_example"
c++ "${cpp_flags[@]}" "$examples/cpp/lamp_reflectance.cpp" "$lib" "${std_libs[@]}" -o "$out/cpp_example"
"$out/c_example" > "$out/c.txt"
compare "$out/reference.txt" "$out/c.txt"
"$out/cpp_example" > "$out/cpp.txt"
compare "$out/reference.txt" "$out/cpp.txt"

echo "-- C11 example against libspectral_capi.a without std (panic-handler, release-nostd)"
cargo build --profile release-nostd -q -p spectral-capi --no-default-features --features panic-handler
nostd_lib="$target/release-nostd/libspectral_capi.a"
# Without std the library needs only libm (and libc's memcpy and friends).
# --gc-sections drops the unwinding tables of the precompiled `core`, which
# is built for unwinding and names a personality routine that an
# abort-on-panic library without std does not define.
cc "${c_flags[@]}" "$examples/c/lamp_reflectance.c" "$nostd_lib" -lm -Wl,--gc-sections \
  -o "$out/c_example_nostd"
"$out/c_example_nostd" > "$out/c_nostd.txt"
compare "$out/reference.txt" "$out/c_nostd.txt"
