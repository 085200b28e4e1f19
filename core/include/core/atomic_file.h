// Atomic file writing: write a sibling temporary file, flush it, then rename it over the target,
// so a crash or a full disk never leaves a half-written scene or output behind. Temporaries a
// killed process left (PATH.tmp-PID of a PID no longer running) are removed at the next write.
#pragma once

#include <string>

namespace spacetime {

// Returns true on success; otherwise false with a one-line reason in *error.
bool writeFileAtomically(const std::string& path, const std::string& contents,
                         std::string* error);

// Whether a process with this id is running (a temporary's owner).
bool processIsAlive(long pid);

// Removes the entries of `dir` named PREFIX<pid> (PREFIX ends in "tmp-" or the like) whose
// process is no longer running: the temporaries of killed writers.
void removeStaleTemporaries(const std::string& dir, const std::string& prefix);

// Reads a whole file; false with a reason if it cannot be read.
bool readWholeFile(const std::string& path, std::string* contents, std::string* error);

}  // namespace spacetime
