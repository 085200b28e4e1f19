// Atomic file writing: write a sibling temporary file, flush it, then rename it over the target,
// so a crash or a full disk never leaves a half-written scene or output behind.
#pragma once

#include <string>

namespace spacetime {

// Returns true on success; otherwise false with a one-line reason in *error.
bool writeFileAtomically(const std::string& path, const std::string& contents,
                         std::string* error);

// Reads a whole file; false with a reason if it cannot be read.
bool readWholeFile(const std::string& path, std::string* contents, std::string* error);

}  // namespace spacetime
