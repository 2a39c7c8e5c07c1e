#pragma once
/// Strict loading of a map directory for the offline tools (issue #22 class 2): a tool either loads
/// the whole map or refuses it naming the first bad file (and line or scan index); skipping bad
/// scans or lines is what `--skip-bad` asks for, and then every skipped item is warned about.

#include <functional>
#include <string>

#include "scanstop_common/map_dir.h"

namespace scanstop {

/// Opens an existing map directory without creating anything: IoError "no such map directory" when
/// `dir` is not a directory, "no poses.csv: not a map directory" when it has none. Then, unless
/// skip_bad, any problem of the map (problems()) is an IoError naming its file and what was wrong
/// ("<dir>/poses.csv: line 3: ...", "<dir>/scans/scan_0002.pcd: no such file; scan 2 skipped"), with
/// how many problems there are and that --skip-bad loads the rest. With skip_bad each problem goes
/// to `warn` (prefixed "skipped: ") and the good scans are kept; a bad line of poses.csv whose scan
/// the scan ledger (poses_journal.csv) restored is prefixed "repaired: " (that scan is loaded), and
/// the refusal without skip_bad says that the ledger holds such lines. A map without any loadable
/// scan is an IoError either way.
MapDirectory openMapForTool(const std::string& dir, bool skip_bad, const std::function<void(const std::string&)>& warn);

}  // namespace scanstop
