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

// The scene is Y-up; URDF readers (MuJoCo, Pinocchio, ROS) pull along -Z unless told. zUp
// turns the character +90 degrees about X under a fixed joint from the world link (the scene's
// Y becomes Z), so that their default gravity is the scene's (0, -9.81, 0); the dofs are the
// same. Either way a comment in the file gives the gravity vector in its frame, and MuJoCo's
// extension element (<mujoco><option gravity=.../>) sets it for MuJoCo.
struct UrdfOptions {
  bool zUp = false;
};

UrdfExport exportUrdf(const Model<double>& model, const CharacterSpec& character, const UrdfOptions& options = {});

// The rotation from the scene's Y-up frame to a Z-up URDF's world: +90 degrees about X.
Eigen::Matrix3d yUpToZUp();

}  // namespace spacetime
