#pragma once
/// Location of the project's shared real data (../shared/data beside the workspace), for tests
/// and benchmarks. The environment variable SCANSTOP_SHARED_DATA overrides the compiled default.

#include <cstdlib>
#include <string>

namespace scanstop {

inline std::string sharedDataDir() {
  if (const char* env = std::getenv("SCANSTOP_SHARED_DATA")) return env;
#ifdef SCANSTOP_SHARED_DATA_DIR
  return SCANSTOP_SHARED_DATA_DIR;
#else
  return "../shared/data";
#endif
}

/// sharedDataDir() + "/" + relative.
inline std::string sharedDataPath(const std::string& relative) { return sharedDataDir() + "/" + relative; }

}  // namespace scanstop
