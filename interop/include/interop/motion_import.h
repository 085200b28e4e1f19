// Reading a motion file (motion.json, outputs.h's motionJson) back into an Animation, so a
// sampled motion can start a solve when the solver state written beside it is gone (a file
// copied out of its run, a motion another tool wrote in the same contract): the solve re-fits
// the joint splines and forces to it (SpacetimeProblem::initializeFrom, motion_source.h).
#pragma once

#include <optional>
#include <string>

#include "solver/animation.h"

namespace spacetime {

struct MotionLoadResult {
  std::optional<Animation> animation;
  std::string error;  // empty on success: names the file, the field and what is wrong
  // The text has a motion file's shape (looksLikeMotionJson), parsed or not: a caller that may
  // be given either kind tells a malformed motion file from a scene with one parse.
  bool motionFile = false;
};

// Whether `text` is a motion file rather than a scene: a JSON object with `formatVersion` and
// `characters` but no scene `format` field. Lets a caller choose the right reader and error.
bool looksLikeMotionJson(const std::string& text);
MotionLoadResult parseMotionJson(const std::string& text, const std::string& sourceName);
MotionLoadResult loadMotionFile(const std::string& path);

}  // namespace spacetime
