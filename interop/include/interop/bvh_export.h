// BVH export of a solved motion: the Biovision Hierarchy format that animation packages
// (Blender, MotionBuilder, Maya) import as a skeleton with keyed channels.
//
// One BVH joint per real body of the character (the floating base's virtual links are folded
// into the root's six channels). A joint's OFFSET is its body frame's origin in the parent body's
// frame with every dof at zero; its rotation channels (Zrotation Xrotation Yrotation, degrees,
// so the local rotation is Rz Rx Ry) carry the body's orientation relative to its parent's at
// each frame, read off forward kinematics, so any joint axis and any fixed placement rotation is
// exact. Joints that translate (prismatic, helical) also get position channels. Leaves end in an
// End Site at the far side of their geometry. Units are the scene's (metres), Y up as in BVH.
#pragma once

#include <string>

#include "core/scene.h"
#include "dynamics/model.h"
#include "solver/animation.h"

namespace spacetime {

// The BVH text of one character's animation (frames at animation.times, uniformly spaced).
std::string motionBvh(const Model<double>& model, const CharacterSpec& character,
                      const CharacterAnimation& animation);

}  // namespace spacetime
