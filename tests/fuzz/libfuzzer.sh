#!/usr/bin/env bash
# The CANopen fuzz target under libFuzzer (coverage-guided) with ASan + UBSan, clang 14 (Debian:
# clang-14, libclang-rt-14-dev). Builds build/fuzz/co_fuzz_libfuzzer, seeds a corpus from the
# target's own seeds (co_fuzz --write-seeds, from the ctest build) and runs it.
# Usage: tests/fuzz/libfuzzer.sh [libFuzzer options...]   e.g. -max_total_time=600 -jobs=1
set -euo pipefail
cd "$(dirname "$0")/../.."
CC=${CC:-clang-14}
out=build/fuzz
mkdir -p "$out/corpus"
srcs=(tests/fuzz/co_fuzz.c firmware/comms/*.c firmware/app/*.c firmware/control/*.c firmware/estimators/*.c
      firmware/core/*.c hal/host/*.c)
"$CC" -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -DCO_FUZZ_LIBFUZZER \
  -Ifirmware/core/include -Ifirmware/control/include -Ifirmware/estimators/include \
  -Ifirmware/app/include -Ifirmware/comms/include -Ihal/include -Ihal/host/include "${srcs[@]}" -lm -o "$out/co_fuzz_libfuzzer"
seeder=${SEEDER:-build/host/tests/fuzz/co_fuzz}
if [ -x "$seeder" ] && [ -z "$(ls -A "$out/corpus")" ]; then
  "$seeder" --write-seeds "$out/corpus"
fi
exec "$out/co_fuzz_libfuzzer" "$out/corpus" -max_len=2048 "$@"
