#!/usr/bin/env bash
# Builds the workspace under AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer, part of
# ASan) in build_asan/ and devel_asan/, then runs every package's unit gtests (catkin_add_gtest
# targets; no rostests, no fuzz runs: the fuzzers are sanitized builds of their own) and prints
# PASS/FAIL per test executable. Exits non-zero when the build fails or any test executable fails.
#
# Usage: scripts/sanitize.sh [--no-build] [REGEX]
#   --no-build  run the executables of an earlier build as they are
#   REGEX       run only test executables whose name matches (grep -E), e.g. 'scanstop_common'
# Environment: SCANSTOP_JOBS (default 2) parallel compile jobs; SANITIZE_TEST_TIMEOUT (default 600) s
# per test executable. Reports and gtest XML go to build_asan/sanitize/.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export PATH=/usr/bin:$PATH
export ROS_IP=127.0.0.1 ROS_MASTER_URI=http://127.0.0.1:11311
unset ROS_HOSTNAME

build=1
filter=""
for arg in "$@"; do
  case "$arg" in
    --no-build) build=0 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) filter="$arg" ;;
  esac
done

jobs="${SCANSTOP_JOBS:-2}"
build_dir="$root/build_asan"
devel_dir="$root/devel_asan"
out="$build_dir/sanitize"
# EIGEN_MALLOC_ALREADY_ALIGNED=1: under ASan Eigen switches to its own aligned malloc (it tests
# __SANITIZE_ADDRESS__), while the uninstrumented PCL libraries use plain malloc; without the define an
# Eigen-aligned vector allocated inside libpcl_io and freed in our code is a false heap-buffer-overflow
# (seen in scanstop_slam_bad_input_test via scanstop::writePcd).
san_flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -g1 -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
t0=$(date +%s)

gtest_targets() {  # "<pkg> <name>" of every catkin_add_gtest target (catkin names them _run_tests_<pkg>_gtest_<name>)
  make -C "$build_dir" help 2>/dev/null | sed -n 's/^\.\.\. _run_tests_\(scanstop_[a-z]*\)_gtest_\(.*\)$/\1 \2/p' | sort -u
}

if [[ $build -eq 1 ]]; then
  mkdir -p "$build_dir"
  log="$build_dir/sanitize_build.log"
  echo "sanitize: building the unit tests with ASan + UBSan in build_asan/ (-j$jobs), log in build_asan/sanitize_build.log"
  # Configure (catkin_make runs cmake, then make's "help" target: nothing is compiled yet) ...
  if ! catkin_make --build "$build_dir" -DCATKIN_DEVEL_PREFIX="$devel_dir" -DPYTHON_EXECUTABLE=/usr/bin/python3 \
      -DCMAKE_BUILD_TYPE=Release -DCATKIN_ENABLE_TESTING=ON -DCATKIN_WHITELIST_PACKAGES="" \
      -DCMAKE_CXX_FLAGS="$san_flags" -DCMAKE_C_FLAGS="$san_flags" \
      -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
      -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" help > "$log" 2>&1; then
    tail -30 "$log" >&2
    echo "sanitize: CONFIGURE FAILED (see build_asan/sanitize_build.log)" >&2
    exit 1
  fi
  # ... then build only the unit-test executables and what they link (no nodes, tools, benchmarks, rostests).
  mapfile -t names < <(gtest_targets | cut -d' ' -f2 | grep -v fuzz_run)
  if ! make -C "$build_dir" -j"$jobs" "${names[@]}" >> "$log" 2>&1; then
    grep -E "error|Error" "$log" | head -40 >&2
    echo "sanitize: BUILD FAILED (see build_asan/sanitize_build.log)" >&2
    exit 1
  fi
fi
t_build=$(date +%s)

# The unit gtests are the targets catkin_add_gtest registers as _run_tests_<pkg>_gtest_<name>.
mapfile -t targets < <(gtest_targets)
if [[ ${#targets[@]} -eq 0 ]]; then
  echo "sanitize: no gtest targets found in build_asan (build first)" >&2
  exit 1
fi

mkdir -p "$out"
# Leaks are reported at exit; halt_on_error keeps the first report readable. The suppressions cover
# third-party libraries only (see the file).
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=0:detect_stack_use_after_return=0:strict_string_checks=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
supp="$root/scripts/sanitize_lsan.supp"
[[ -f "$supp" ]] && export LSAN_OPTIONS="suppressions=$supp:print_suppressions=0:${LSAN_OPTIONS:-}"
timeout_s="${SANITIZE_TEST_TIMEOUT:-600}"
passed=0
failed=0
failures=()
for t in "${targets[@]}"; do
  pkg=${t%% *}
  name=${t#* }
  [[ "$name" == *fuzz_run* ]] && continue
  [[ -n "$filter" ]] && ! [[ "$name" =~ $filter ]] && continue
  exe="$devel_dir/lib/$pkg/$name"
  log="$out/$name.log"
  if [[ ! -x "$exe" ]]; then
    echo "FAIL $pkg/$name: executable $exe missing"
    failed=$((failed + 1)); failures+=("$pkg/$name")
    continue
  fi
  s=$(date +%s)
  (
    set +u
    # shellcheck disable=SC1091
    source "$devel_dir/setup.bash"
    cd "$build_dir/$pkg" 2>/dev/null || cd "$build_dir"
    timeout "$timeout_s" "$exe" --gtest_output="xml:$out/$name.xml"
  ) > "$log" 2>&1
  rc=$?
  dt=$(( $(date +%s) - s ))
  if [[ $rc -eq 0 ]] && ! grep -qE "runtime error:|ERROR: (Address|Leak)Sanitizer" "$log"; then
    echo "PASS $pkg/$name (${dt} s)"
    passed=$((passed + 1))
  else
    why="exit $rc"
    [[ $rc -eq 124 ]] && why="timeout after $timeout_s s"
    first=$(grep -m1 -E "runtime error:|ERROR: (Address|Leak)Sanitizer|\[  FAILED  \]" "$log" || true)
    echo "FAIL $pkg/$name (${dt} s, $why): ${first:-see $log}"
    failed=$((failed + 1)); failures+=("$pkg/$name")
  fi
done
t_end=$(date +%s)
echo "sanitize: build $((t_build - t0)) s, tests $((t_end - t_build)) s; executables: $passed passed, $failed failed (logs in build_asan/sanitize/)"
[[ $failed -eq 0 ]]
