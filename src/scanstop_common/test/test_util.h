#pragma once
// Helpers for scanstop_common tests: temporary directories and expected-error checks.

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "scanstop_common/error.h"

namespace scanstop {
namespace test {

/// A fresh directory under /tmp, removed with its files at the end of the test.
class TempDir {
 public:
  TempDir() {
    char pattern[] = "/tmp/scanstop_test_XXXXXX";
    path_ = mkdtemp(pattern);
  }
  ~TempDir() {
    const std::string cmd = "rm -rf '" + path_ + "'";
    if (std::system(cmd.c_str()) != 0) std::perror("rm");
  }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  std::string write(const std::string& name, const std::string& data) const {
    std::ofstream(file(name), std::ios::binary) << data;
    return file(name);
  }

 private:
  std::string path_;
};

/// Runs f, expects an IoError whose message contains both the file name and `problem`.
template <typename F>
void expectIoError(F f, const std::string& path, const std::string& problem) {
  try {
    f();
    ADD_FAILURE() << "expected an IoError about '" << problem << "' for " << path;
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  }
}

}  // namespace test
}  // namespace scanstop
