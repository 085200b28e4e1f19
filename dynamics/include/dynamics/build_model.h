// Compiling a scene character into a dynamics Model (a pure function of plain values).
// Root kinds expand into chains of virtual joints on massless bodies; see model.h.
#pragma once

#include "core/scene.h"
#include "dynamics/model.h"

namespace spacetime {

Model<double> buildModel(const CharacterSpec& character, const Eigen::Vector3d& gravity);

// Parent -> joint frame placement from a URDF-style origin and roll-pitch-yaw.
Transform<double> placement(const Eigen::Vector3d& origin, const Eigen::Vector3d& rpy);

}  // namespace spacetime
