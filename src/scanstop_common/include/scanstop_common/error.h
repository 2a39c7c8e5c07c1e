#pragma once
/// Error types shared by all scanstop core libraries.

#include <stdexcept>
#include <string>

namespace scanstop {

/// A file could not be read or written; what() names the file and the problem.
class IoError : public std::runtime_error {
 public:
  IoError(const std::string& path, const std::string& problem)
      : std::runtime_error(path + ": " + problem), path_(path), problem_(problem) {}
  const std::string& path() const { return path_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string path_;
  std::string problem_;
};

/// A configuration value is missing or out of range; what() names the parameter, value and range.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace scanstop
