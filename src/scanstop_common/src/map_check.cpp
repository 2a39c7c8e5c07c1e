#include "scanstop_common/map_check.h"

#include <sys/stat.h>

#include <algorithm>

#include "scanstop_common/error.h"

namespace scanstop {

MapDirectory openMapForTool(const std::string& dir, bool skip_bad,
                            const std::function<void(const std::string&)>& warn) {
  struct stat st;
  if (dir.empty() || ::stat(dir.c_str(), &st) != 0) throw IoError(dir, "no such map directory");
  if (!S_ISDIR(st.st_mode)) throw IoError(dir, "not a directory (a map directory holds poses.csv and scans/)");
  std::string root = dir;
  while (root.size() > 1 && root.back() == '/') root.pop_back();
  if (::stat((root + "/poses.csv").c_str(), &st) != 0)
    throw IoError(root + "/poses.csv", "does not exist: not a map directory");
  MapDirectory map(root);
  const auto& problems = map.problems();
  if (!problems.empty() && !skip_bad) {
    // A read-only tool does not repair: the first problem is named (also a line the scan ledger
    // poses_journal.csv holds: icp_slam_node repairs poses.csv when it next starts; --skip-bad loads it
    // from there).
    const MapProblem& first = problems.front();
    const bool ledger = std::any_of(problems.begin(), problems.end(), [](const MapProblem& p) { return p.repaired; });
    throw IoError(first.path, first.withoutSkipNote() + " (" + std::to_string(problems.size()) +
                                  (problems.size() == 1 ? " problem" : " problems") +
                                  " in the map; --skip-bad loads the rest" +
                                  (ledger ? ", with the lines poses_journal.csv restores" : "") + ")");
  }
  for (const MapProblem& p : problems)
    if (warn) warn((p.repaired ? "repaired: " : "skipped: ") + p.message());
  if (map.size() == 0) throw IoError(map.posesPath(), "the map directory holds no loadable scans");
  return map;
}

}  // namespace scanstop
