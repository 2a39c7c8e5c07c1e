#pragma once
// Shared by the libFuzzer targets of scanstop_common: a scratch directory for targets that read files,
// and the contract every reader keeps (an IoError for bad input, never another exception or a crash).
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace scanstop {
namespace fuzz {

/// A per-process scratch directory (on /dev/shm when it exists: the targets write a file per input),
/// removed at exit.
inline const std::string& scratchDir() {
  static const std::string dir = [] {
    struct stat st;
    std::string pattern = (::stat("/dev/shm", &st) == 0 && S_ISDIR(st.st_mode) && ::access("/dev/shm", W_OK) == 0)
                              ? "/dev/shm/scanstop_fuzz_XXXXXX"
                              : "/tmp/scanstop_fuzz_XXXXXX";
    if (!::mkdtemp(&pattern[0])) std::abort();
    static std::string removed;
    removed = pattern;
    std::atexit([] {
      const std::string cmd = "rm -rf '" + removed + "'";
      if (std::system(cmd.c_str()) != 0) std::perror("rm");
    });
    return pattern;
  }();
  return dir;
}

inline void writeBytes(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) std::abort();
}

/// Aborts (a finding for libFuzzer) when a condition the readers promise does not hold.
inline void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
    std::abort();
  }
}

}  // namespace fuzz
}  // namespace scanstop
