#pragma once
/// Small file helpers: atomic writes and whole-file reads with clear errors.

#include <string>

namespace scanstop {

/// Writes data to path atomically: a temporary file in the same directory, fsync, rename.
/// A reader never sees a half-written file. Throws IoError naming the path.
void writeFileAtomic(const std::string& path, const std::string& data);

/// A temporary file name next to path, unique per process and call (path + ".tmp.<pid>.<n>"), for
/// writers that produce the file themselves and then call commitTemporaryFile.
std::string temporaryPathFor(const std::string& path);

/// Makes a finished temporary file the file at path: fsync, rename over path, fsync the directory (so
/// the rename survives a power loss). Removes tmp and throws IoError naming path on failure.
void commitTemporaryFile(const std::string& tmp, const std::string& path);

/// Why path cannot be read as an input file, or empty: "no such file", "is a directory, not a file",
/// "not a regular file", "cannot open: <errno text>".
std::string inputFileProblem(const std::string& path);

/// Why a file cannot be written at path, or empty: "the directory <dir> does not exist",
/// "<dir> is not a directory".
std::string outputFileProblem(const std::string& path);

/// Creates the directory and any missing parents (mkdir -p); one that exists already is fine, also when
/// another process creates it at the same moment. Throws IoError naming the part that could not be
/// made ("cannot create directory: <errno text>") or a path that exists but is not a directory.
void makeDirectories(const std::string& path);

/// Reads a whole file; throws IoError (inputFileProblem, "read error") naming the path.
std::string readFile(const std::string& path);

/// Lower-case extension without the dot ("ply" for "a/b.PLY"); empty if none.
std::string fileExtension(const std::string& path);

}  // namespace scanstop
