// glTF 2.0 export of a solved scene, as one binary file (.glb) that Blender, Maya, three.js and
// game engines import: every character's skeleton (dynamics/skeleton.h) as a tree of nodes, each
// real body's geometry as a lit mesh in its colour, and one animation, "motion", that keys every
// bone's local rotation (and translation where it varies: roots, prismatic and helical joints)
// at each frame of the animation, linearly interpolated.
//
// Units are metres and seconds, Y up, as in glTF; the animation's time starts at 0 (the scene's
// start time is subtracted). Rotations are unit quaternions kept on one hemisphere from frame to
// frame, so interpolation never turns the long way round. The file is checked by the Khronos
// glTF Validator in the tests.
#pragma once

#include <string>
#include <vector>

#include "core/scene.h"
#include "dynamics/model.h"
#include "solver/animation.h"

namespace spacetime {

// The .glb bytes. models[c] and animation.characters[c] belong to scene.characters[c]; the
// characters share the animation's time grid (sampleAnimation guarantees it).
std::string motionGlb(const Scene& scene, const std::vector<const Model<double>*>& models,
                      const Animation& animation);

}  // namespace spacetime
