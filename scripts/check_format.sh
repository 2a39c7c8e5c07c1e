#!/usr/bin/env bash
# The C++ sources follow .clang-format (Google style, 120 columns): exits 1 naming every file that
# clang-format would change (and the first lines it would change), 0 when none. Fix with
#   clang-format -i $(git ls-files '*.cpp' '*.h')
# Part of the test command (scripts/test_all.sh).
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
command -v clang-format >/dev/null || { echo "check_format: clang-format is not installed (Debian package clang-format, scripts/deps.txt)"; exit 1; }
bad=0
total=0
while IFS= read -r f; do
  total=$((total + 1))
  if ! out=$(clang-format --dry-run --Werror "$f" 2>&1); then
    bad=$((bad + 1))
    echo "check_format: $f is not formatted:"
    echo "$out" | head -6 | sed 's/^/  /'
  fi
done < <(git ls-files '*.cpp' '*.h' '*.hpp' '*.cc')
echo "check_format: $total files, $bad not formatted ($(clang-format --version | head -1))"
[[ $bad -eq 0 ]]
