#!/bin/sh
# The reliability checks CI runs after the README's test command (docs/reliability.md):
# 1. the suite again, built with AddressSanitizer and UndefinedBehaviorSanitizer: every test that
#    runs on the host alone, and the GPU tests whose subject is the host's code (below), without the
#    validation layer;
# 2. each libFuzzer target for SECONDS (default 60) from the seed corpus in tests/fuzz/corpus, as
#    many at once as there are cores.
# New corpus entries and crash reproducers go to a temporary folder, never into the source tree;
# a finding fails the run and prints the reproducer, to be added to tests/fuzz/corpus.
# Each part's time is printed as it ends.
set -eu
seconds="${1:-60}"
cd "$(dirname "$0")/.."
. cmake/timed-steps.sh
jobs="$(nproc)"

# Without the Staging.* reruns: they change which device copies run, in memory the sanitizers do not
# see, not the host code they check (Python.Module runs once, through that path). Without the
# validation layer: the suite ran every Vulkan call of these tests under it, and here the subject is
# the host's memory. Of the GPU tests, those of the host's code alone (tests/CMakeLists.txt,
# host_code_gpu_targets and transfer_tests: every upload and readback, the command line, the C API,
# the Python module): the others vary what the device computes over walks, variants and scenes,
# and the host code they reach is these tests' and the host tests'; their targets are not built
# here. Without the tests whose cost is their size, not their code
# (tests/CMakeLists.txt, sized_by_scale_tests: the 7680x4320 renders, 14.7 GB at their peak under
# ASan, the 120 random scenes, the camera inside a million triangles, the commands of the README and
# docs/), nor those whose subject is the device's arithmetic over many variants (arithmetic_tests
# there): the README's test command runs them, and smaller tests of the same kind run their host
# code here.
# A unity build, as every build by default (CMakeLists.txt, CMAKE_UNITY_BUILD). The
# tests' cache is the suite's (build/test-cache, when there): the pipelines it compiled are taken from
# there, not compiled again (tests/CMakeLists.txt, VKRAY_TEST_CACHE_HOME).
cache_home="$PWD/build-sanitize/test-cache"
[ -d build/test-cache ] && cache_home="$PWD/build/test-cache"
step "sanitizer build" sh -c "cmake -S . -B build-sanitize -DVKRAY_SANITIZE=ON -DVKRAY_WERROR=ON -DVKRAY_TEST_STAGING=OFF \
                                -DVKRAY_TEST_VALIDATION=0 -DVKRAY_TEST_SIZED=OFF -DVKRAY_TEST_ARITHMETIC=OFF \
                                -DVKRAY_TEST_DEVICE_VARIANTS=OFF \
                                -DVKRAY_TEST_CACHE_HOME=$cache_home &&
                              cmake --build build-sanitize -j$jobs"
# LeakSanitizer checks the tests that run on the host alone. Where the Vulkan driver is loaded,
# lavapipe and its LLVM keep allocations until exit, and LeakSanitizer cannot unwind
# their stacks (they are built without frame pointers), so suppressions by library cannot hold and
# a leak of ours could not be told from theirs: there AddressSanitizer and UBSan still check every
# access and operation, leaks are not checked.
export UBSAN_OPTIONS=print_stacktrace=1
step "host tests, sanitized" env ASAN_OPTIONS=detect_leaks=1 ctest --test-dir build-sanitize --output-on-failure -j"$jobs" -LE gpu
# The Python module's tests of test_vkray.py alone (168 s sanitized on a slow day), not its other
# files (157 s more): the module is Python, not instrumented; what is, libvkray.so, these reach
# through the C API's functions, every one of which test_vkray.py or CApi.FromC calls (instances,
# masks, first hits, moved vertices: tests/c_api_test.c), and the engine beneath through the C++
# tests of the same features. Without the Python examples of the README and docs/ and the many-views
# runs (89 s and 146 s): the first make the calls the module's own tests make, on the real models;
# the second run the command line killed, resumed and under schedulers, whose views and manifest
# parsers the fuzzers and the host tests check under the sanitizers. The README's test command runs
# them all. Nor the model files' tests (Python.ModelFiles, 120 s a shard sanitized): what they reach
# of the host's code is the OBJ, PLY and glTF loaders, which the host tests and the fuzzers run here.
step "GPU tests, sanitized" env ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-sanitize --output-on-failure -j"$jobs" -L gpu \
                                -E '^Python[.](ManyViews|ModelFiles|Module[.](readme_python|every_hit|masks|moving_vertices|robotics_calls|instances|bench_plot|docs))([.][0-9]+)?$'

step "fuzzer build" sh -c "sh cmake/install-deps.sh cmake/debian-packages-fuzz.txt &&
                           cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DVKRAY_FUZZ=ON -DVKRAY_WERROR=ON &&
                           cmake --build build-fuzz -j$jobs"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# One fuzzer for SECONDS, its output kept in its log and printed once it ends (two run at once).
run_fuzzer() {
  target=$1
  mkdir -p "$work/$target" "$work/findings-$target"
  if build-fuzz/tests/fuzz/${target}_fuzzer -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
      -artifact_prefix="$work/findings-$target/" "$work/$target" "tests/fuzz/corpus/$target" >"$work/$target.log" 2>&1; then
    echo "vkray: the $target fuzzer ran $seconds s: $(grep -c '' "$work/$target.log") lines of log, no finding"
    grep '^stat::number_of_executed_units' "$work/$target.log" || true
    return 0
  fi
  tail -n 40 "$work/$target.log"
  # The log keeps the reproducers (base64): decode one into tests/fuzz/corpus/$target to make it a
  # regression test once fixed.
  for finding in "$work/findings-$target"/*; do
    echo "vkray: the $target fuzzer found a problem; reproducer $(basename "$finding") in base64:"
    base64 "$finding"
  done
  return 1
}
# The fuzzers in as many lanes as there are cores, each lane's one after another: each fuzzer is
# single-threaded, so two cores run two at once in the time of one.
fuzz_all() {
  targets="scene obj model gltf ply_header views manifest"
  pids=""
  lane=0
  while [ "$lane" -lt "$jobs" ]; do
    lane_targets=$(echo $targets | tr ' ' '\n' | awk -v lanes="$jobs" -v lane="$lane" '(NR - 1) % lanes == lane')
    (for target in $lane_targets; do run_fuzzer "$target" || exit 1; done) &
    pids="$pids $!"
    lane=$((lane + 1))
  done
  failed=0
  for pid in $pids; do wait "$pid" || failed=1; done
  return "$failed"
}
step "fuzzers, $seconds s each" fuzz_all
