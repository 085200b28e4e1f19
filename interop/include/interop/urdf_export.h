// URDF export of a character: one link per body, one joint per degree of freedom, in the same
// order and with the same names as the Model, so outside tools (MuJoCo, Pinocchio, ROS) can
// re-check a motion. A floating base becomes its chain of virtual prismatic/revolute joints on
// massless links, hung from a fixed "<character>_world" link at the scene's world frame.
#pragma once

#include <string>

#include "core/scene.h"
#include "dynamics/model.h"

namespace spacetime {

struct UrdfExport {
  std::string xml;
  std::string warning;  // non-empty when something could not be expressed exactly
};

UrdfExport exportUrdf(const Model<double>& model, const CharacterSpec& character);

}  // namespace spacetime
