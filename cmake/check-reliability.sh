#!/bin/sh
# The reliability checks CI runs after the README's test command (README, "Reliability"):
# 1. the suite again, built with AddressSanitizer and UndefinedBehaviorSanitizer: every test that
#    runs on the host alone, and the GPU tests but those whose cost is their size (below);
# 2. each libFuzzer target for SECONDS (default 60) from the seed corpus in tests/fuzz/corpus.
# New corpus entries and crash reproducers go to a temporary folder, never into the source tree;
# a finding fails the run and prints the reproducer, to be added to tests/fuzz/corpus.
# Each part's time is printed as it ends.
set -eu
seconds="${1:-60}"
cd "$(dirname "$0")/.."
. cmake/timed-steps.sh
jobs="$(nproc)"

# Without the Staging.* reruns: they change which device copies run, in memory the sanitizers do not
# see, not the host code they check (Python.Module.staging still takes that path once).
step "sanitizer build" sh -c "cmake -S . -B build-sanitize -DVKRAY_SANITIZE=ON -DVKRAY_WERROR=ON -DVKRAY_TEST_STAGING=OFF &&
                              cmake --build build-sanitize -j$jobs"
# LeakSanitizer checks the tests that run on the host alone. Where the Vulkan driver is loaded,
# lavapipe and its LLVM keep allocations until exit, and LeakSanitizer cannot unwind
# their stacks (they are built without frame pointers), so suppressions by library cannot hold and
# a leak of ours could not be told from theirs: there AddressSanitizer and UBSan still check every
# access and operation, leaks are not checked.
export UBSAN_OPTIONS=print_stacktrace=1
step "host tests, sanitized" env ASAN_OPTIONS=detect_leaks=1 ctest --test-dir build-sanitize --output-on-failure -j"$jobs" -LE gpu
# Left out here, run by the README's test command: the tests whose cost is their size, not their
# code. The 7680x4320 renders (a stiff case's and the README's commands, 14.7 GB at their peak
# under ASan), the 120 random scenes and the camera inside a million triangles run the host code
# that smaller tests of the same kind run here (the other stiff cases, the CLI tests of every
# command, BvhGpu's other scenes), for most of the sanitized suite's time.
sized_by_scale='image_7680x4320|^RandomScenes[.]|[.]CameraInsideMillionTriangleSphere$|^ReadmeExamplesTest[.]'
step "GPU tests, sanitized" env ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-sanitize --output-on-failure -j"$jobs" -L gpu -E "$sized_by_scale"

step "fuzzer build" sh -c "sh cmake/install-deps.sh cmake/debian-packages-fuzz.txt &&
                           cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DVKRAY_FUZZ=ON -DVKRAY_WERROR=ON &&
                           cmake --build build-fuzz -j$jobs"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for target in scene obj model views manifest; do
  mkdir -p "$work/$target" "$work/findings-$target"
  if ! build-fuzz/tests/fuzz/${target}_fuzzer -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
      -artifact_prefix="$work/findings-$target/" "$work/$target" "tests/fuzz/corpus/$target"; then
    # The log keeps the reproducers (base64): decode one into tests/fuzz/corpus/$target to make it a
    # regression test once fixed.
    for finding in "$work/findings-$target"/*; do
      echo "vkray: the $target fuzzer found a problem; reproducer $(basename "$finding") in base64:"
      base64 "$finding"
    done
    exit 1
  fi
done
