#pragma once
/// Small file helpers: atomic writes and whole-file reads with clear errors.

#include <string>

namespace scanstop {

/// Writes data to path atomically: a temporary file in the same directory, fsync, rename.
/// A reader never sees a half-written file. Throws IoError naming the path.
void writeFileAtomic(const std::string& path, const std::string& data);

/// Reads a whole file; throws IoError ("no such file", "cannot read") naming the path.
std::string readFile(const std::string& path);

/// Lower-case extension without the dot ("ply" for "a/b.PLY"); empty if none.
std::string fileExtension(const std::string& path);

}  // namespace scanstop
