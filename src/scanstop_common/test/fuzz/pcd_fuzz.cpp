// libFuzzer target: arbitrary bytes as a .pcd file through readPcd (our header check, then PCL's
// reader). It either throws IoError or returns a cloud with a consistent layout.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using scanstop::fuzz::check;
  static const std::string path = scanstop::fuzz::scratchDir() + "/fuzz.pcd";
  scanstop::fuzz::writeBytes(path, data, size);
  try {
    const scanstop::PointCloud cloud = scanstop::readPcd(path);
    check(cloud.layoutProblem().empty(), "consistent cloud layout");
  } catch (const scanstop::IoError& e) {
    check(std::string(e.what()).find(path) == 0, "the error names the file");
  }
  return 0;
}
