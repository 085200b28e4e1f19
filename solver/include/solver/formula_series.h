// A formula (core/expr/formula.h) evaluated at every frame of a sampled animation: the graph
// widget's "typed formula" series. The formula sees the character's q, qd, qdd, tau, body
// positions and velocities, the centre of mass, the contact forces and t, exactly as formula
// constraints in the solver do.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/scene.h"
#include "solver/animation.h"

namespace spacetime {

struct FormulaSeries {
  std::vector<double> values;  // one per frame of the character's animation
  std::string error;           // non-empty when the formula does not parse
};

FormulaSeries evaluateFormulaSeries(const Scene& scene, const CharacterAnimation& animation,
                                    const std::string& expression);

}  // namespace spacetime
