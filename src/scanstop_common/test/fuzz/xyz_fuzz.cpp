// libFuzzer target: arbitrary bytes through the XYZ text parser. It either throws IoError or returns a
// non-empty unorganized cloud with one normal per point or none.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using scanstop::fuzz::check;
  try {
    const scanstop::PointCloud cloud =
        scanstop::parseXyz(std::string(reinterpret_cast<const char*>(data), size), "fuzz.xyz");
    check(!cloud.empty(), "an XYZ file that parses has points");
    check(cloud.layoutProblem().empty(), "consistent cloud layout");
    check(!cloud.isOrganized(), "XYZ clouds are unorganized");
  } catch (const scanstop::IoError& e) {
    check(std::string(e.what()).find("fuzz.xyz") == 0, "the error names the file");
  }
  return 0;
}
