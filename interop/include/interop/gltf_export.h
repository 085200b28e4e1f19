// glTF 2.0 export of a solved scene, as one binary file (.glb) that Blender, Maya, three.js and
// game engines import: every character's skeleton (dynamics/skeleton.h) as a tree of nodes, each
// real body's geometry as a lit mesh in its colour, and one animation, "motion", that keys every
// bone's local rotation (and translation where it varies: roots, prismatic and helical joints)
// at each frame of the animation. When the animation has velocities (a solved motion) the keys
// are CUBICSPLINE with the motion's exact tangents - the pose's derivative along q-dot, the
// in-tangent from just before the key (a touch-down's impact) - so the animation is right between
// keys at any rate (30 Hz: within 1e-4 m of forward kinematics); without them, LINEAR.
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

// Key times for a solved motion's glTF: the uniform grid at rateHz (both ends), each interval
// split further where a dof moves fast. A cubic Hermite interval over which a joint turns by
// theta = h |q-dot|max is off by about theta^4 / 384 (per metre of lever), so intervals are split
// until theta <= kMaxKeyTurn: 30 Hz stays 30 Hz where the motion is slow and gets denser in a
// push-off's whip.
constexpr double kMaxKeyTurn = 0.3;
std::vector<double> gltfKeyTimes(const SpacetimeProblem& problem, double rateHz);

}  // namespace spacetime
