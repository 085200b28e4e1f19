// A task whose constraints truly conflict: the particle scene with a second pin, "clash", at the
// instant of its pin p1 but in another place (5, 5, 5). Both methods must stop and name the pins.
#pragma once

#include "core/scene.h"

namespace spacetime::testing {

// Adds the clashing pin to `scene` (a copy of particle.json) and returns it.
inline TermSpec addClashingPin(Scene& scene) {
  TermSpec clash = scene.terms[1];
  clash.id = "clash";
  clash.position = Eigen::Vector3d(5, 5, 5);  // same time as p1, another place
  scene.terms.push_back(clash);
  return clash;
}

}  // namespace spacetime::testing
