// RenderScene: everything the viewport draws, as plain values built from the scene, the
// characters' Models and the motion at a time - outside any GL code, so it is testable
// without a display (as MuJoCo's mjv_updateScene feeds mjr_render). The GL widget only draws it.
//
// Solids are the unit meshes of core/shape_mesh.h placed by a 4x4 matrix that includes the
// scale (a capsule is a cylinder and two spheres).
#pragma once

#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/scene.h"
#include "core/shape_mesh.h"
#include "dynamics/model.h"
#include "ui/solved_motion.h"

namespace spacetime::ui {

using Mesh = UnitShape;  // the unit meshes of core/shape_mesh.h

struct Solid {
  Mesh mesh = Mesh::Cube;
  glm::mat4 transform{1.0f};  // unit mesh -> world
  glm::vec4 color{0.8f, 0.8f, 0.8f, 1.0f};
  int character = -1;  // -1: not a body (arrows)
  std::string body;
  bool ghost = false;  // onion skin: drawn translucent, not pickable
};

struct Polyline {
  std::vector<glm::vec3> points;
  glm::vec4 color{1.0f};
};

struct Handle {  // a pin target the user can drag
  glm::vec3 position{0.0f};
  glm::vec3 bodyPoint{0.0f};  // where the pinned point is now (drawn as a line to the target)
  std::string term;
  bool selected = false;
};

// What a clearance term keeps a body point out of, drawn as translucent boxes: the term's box,
// or for a height clearance a block from the ground up to the height under the point's path
// over the term's interval (the hurdle the point must pass over).
struct Obstacle {
  std::string term;
  std::vector<Solid> boxes;  // unit cubes placed and scaled; never picked
};

struct RenderScene {
  std::vector<Solid> solids;
  std::vector<Obstacle> obstacles;
  std::vector<Polyline> lines;
  std::vector<Handle> handles;
  bool ground = true;
  float groundHeight = 0;
  glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};  // of the characters over the whole clip
};

// How far a preview's bodies (an unsolved iterate) are washed towards grey.
inline constexpr float kPreviewWash = 0.65f;

struct RenderOptions {
  double time = 0;
  int ghosts = 2;             // onion-skin frames on each side of the current time
  double ghostSpacing = 0.15; // seconds between ghost frames
  bool trail = true;         // motion trail of the selected body's origin (or every root)
  bool centerOfMass = true;  // the COM trajectory of each character
  bool forces = true;        // contact-force arrows
  double forceScale = 0.02;  // metres per newton ... per unit of weight-relative force x weight
  int selectedCharacter = -1;
  std::string selectedBody;
  std::string selectedTerm;
  // An unkeyed pose of one character, shown at `time` instead of the motion's (not in ghosts).
  int posedCharacter = -1;
  Eigen::VectorXd posedQ;
  // The pose tool is on: a ring around the selected body's joint, in the plane it turns in.
  bool poseGizmo = false;
};

RenderScene buildRenderScene(const Scene& scene, const std::vector<Model<double>>& models,
                             const SolvedMotion* motion, const RenderOptions& options);

// The pose of each character at time t: the motion's, or the zero pose without one.
std::vector<Eigen::VectorXd> posesAt(const Scene& scene, const std::vector<Model<double>>& models,
                                     const SolvedMotion* motion, double t);

// A world point or direction in the renderer's single precision.
glm::vec3 toGlm(const Eigen::Vector3d& v);

// The joint the pose gizmo turns when a body is dragged: the body's own revolute joint (for a
// root, the last joint of its chain: a planar root's rotation). Its dof, the pivot (the body's
// origin) and the unit axis in world at pose q; nullopt for a fixed or sliding joint.
struct PoseJoint {
  int dof = -1;
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero(), axis = Eigen::Vector3d::UnitZ();
};
std::optional<PoseJoint> poseJoint(const Model<double>& model, const Eigen::VectorXd& q, int body);

// The nearest solid (not a ghost) hit by the ray origin + s * direction; the hit in world.
struct Pick {
  int solid = -1;
  float distance = 0;
  glm::vec3 point{0.0f};
};
std::optional<Pick> pickSolid(const RenderScene& scene, const glm::vec3& origin,
                              const glm::vec3& direction);

// A world point expressed in a body's frame at a pose (for "pin the clicked point").
Eigen::Vector3d worldToBody(const Model<double>& model, const Eigen::VectorXd& q, int body,
                            const Eigen::Vector3d& world);
Eigen::Vector3d bodyToWorld(const Model<double>& model, const Eigen::VectorXd& q, int body,
                            const Eigen::Vector3d& local);

}  // namespace spacetime::ui
