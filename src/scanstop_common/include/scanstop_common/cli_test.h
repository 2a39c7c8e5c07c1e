#pragma once
/// Helpers for tests that run a tool as a user would (the packages' *_cli_test.cpp): runCommand()
/// runs a shell command and returns its exit status with stdout and stderr together; TempDir is a
/// scratch directory under /tmp, removed with everything in it when the object goes.

#include <stdlib.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace scanstop {
namespace test_util {

struct CliRun {
  int status = -1;  ///< exit status; -1 when the command could not be started or did not exit
  std::string out;  ///< stdout and stderr
};

inline CliRun runCommand(const std::string& cmd) {
  CliRun r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "scanstop_test") {
    std::string pattern = "/tmp/" + prefix + "_XXXXXX";
    path = mkdtemp(&pattern[0]) ? pattern : std::string();
  }
  ~TempDir() {
    if (!path.empty() && std::system(("rm -rf '" + path + "'").c_str()) != 0) std::perror("rm");
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return path + "/" + name; }
  std::string path;  ///< empty when it could not be created
};

}  // namespace test_util
}  // namespace scanstop
