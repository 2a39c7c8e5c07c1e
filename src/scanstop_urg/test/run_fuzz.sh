#!/usr/bin/env bash
# Bounded libFuzzer run of the SCIP parser as a test: run_fuzz.sh FUZZER RUNS MAX_SECONDS RESULT_XML SEED_DIR WORK_DIR
# A fixed number of inputs (RUNS) with a fixed seed: the same inputs on every machine, so a pass here
# is a pass in CI (a time limit would make the number, and so the result, depend on the machine's
# load); MAX_SECONDS caps the time (a capped run tried a prefix of the same inputs). SCIP_FUZZ_RUNS
# overrides RUNS (a longer campaign). Writes a JUnit result (one test case) and fails on any crash,
# sanitizer report, leak or hang.
set -uo pipefail
fuzzer=$1 runs_wanted=${SCIP_FUZZ_RUNS:-$2} seconds=$3 xml=$4 seeds=$5 work=$6
mkdir -p "$(dirname "$xml")" "$work"
log="$work/fuzz.log"
write_xml() {  # ok(0/1) message
  {
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo "<testsuite name=\"fuzz\" tests=\"1\" failures=\"$((1 - $1))\" errors=\"0\">"
    echo "  <testcase classname=\"fuzz\" name=\"scip_parser\">"
    if [[ $1 -eq 0 ]]; then
      echo "    <failure message=\"$2\"><![CDATA["
      tail -c 20000 "$log" 2>/dev/null | sed 's/]]>/]] >/g'
      echo "]]></failure>"
    fi
    echo "  </testcase>"
    echo "</testsuite>"
  } > "$xml"
}
if [[ ! -x "$fuzzer" ]]; then
  echo "fuzz target $fuzzer was not built: install clang and libclang-rt-14-dev (scripts/deps.txt)" > "$log"
  write_xml 0 "fuzz target not built (clang missing)"
  exit 1
fi
corpus="$work/corpus"
rm -rf "$corpus" "$work"/crash-* "$work"/timeout-* "$work"/leak-*
mkdir -p "$corpus"
cp "$seeds"/* "$corpus"/
# Fixed seed: the run is reproducible. -timeout: one input taking over 5 s counts as a hang.
( cd "$work" && timeout $((seconds + 60)) "$fuzzer" -seed=20261129 -runs="$runs_wanted" -max_total_time="$seconds" -timeout=5 \
    -rss_limit_mb=1024 -max_len=4096 -print_final_stats=1 "$corpus" ) > "$log" 2>&1
rc=$?
runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
echo "fuzz: exit $rc, $runs of $runs_wanted inputs (cap ${seconds} s)"
if [[ $rc -ne 0 ]]; then
  write_xml 0 "the fuzzer found a problem (exit $rc); see the log and $work for the input"
  exit 1
fi
if [[ "${runs:-0}" -lt 1000 ]]; then
  write_xml 0 "the fuzzer ran only ${runs:-0} inputs"
  exit 1
fi
write_xml 1 ""
