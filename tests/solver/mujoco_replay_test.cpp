// A solved motion re-checked by MuJoCo from the files spacetime-cli writes, as an outside tool
// would: motion.json (q, qd, qdd, tau, contact points and forces, gravity) and the URDF, nothing
// else of ours. For every frame, mj_inverse on the URDF gives the generalized force the motion
// needs; the ground's push enters as J^T f through mj_applyFT at each contact's world point.
// What is left must be motion.json's tau, every dof (the same dynamics, read by another library
// from our files), and its unactuated entries - force from nowhere on the floating base - must
// stay within the validity report's 1 % of the character's weight at every frame: MuJoCo's own
// verdict that the motion is physical, between the collocation samples too. Then MuJoCo
// simulates the flight forward under the file's actuated torques and must follow the file's q.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../mujoco_dofs.h"
#include "../shipped_scene.h"
#include "solver/augmented_lagrangian.h"
#include "interop/outputs.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

using nlohmann::json;

struct Replay {
  double worstMismatch = 0;    // |tau_mujoco - tau_file| / (1 + |tau_file|_inf), over all frames
  double worstUnactuated = 0;  // |tau_mujoco| of the unactuated dofs / weight, over all frames
  double worstUnactuatedTime = 0;
  int frames = 0;
  int contactFrames = 0;  // frames where some contact force acts
  // The longest stretch of frames without ground force (the flight), simulated forward by
  // MuJoCo (RK4, the frames' step) from its first frame's state under the file's actuated
  // torques alone: the largest |q_sim - q_file| over it (metres or radians).
  double flightStart = 0, flightEnd = 0;
  double worstFlightError = 0;
};

// Replays DIR/motion.json's first character through MuJoCo on DIR/<its urdf>.
Replay replayInMujoco(const std::string& dir) {
  Replay out;
  std::ifstream in(dir + "/motion.json");
  const json motion = json::parse(in);
  const json& c = motion.at("characters").at(0);
  const std::string urdf = dir + "/" + c.at("urdf").get<std::string>();
  char error[1000] = "";
  mjModel* m = mj_loadXML(urdf.c_str(), nullptr, error, sizeof(error));
  EXPECT_NE(m, nullptr) << error;
  if (!m) return out;
  // Contacts, joint limits and passive forces are not MuJoCo's to add: the ground's forces are
  // the file's.
  m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_CONTACT | mjDSBL_PASSIVE;
  const std::vector<double> gravity = c.at("gravity").get<std::vector<double>>();
  for (int k = 0; k < 3; ++k) m->opt.gravity[k] = gravity[k];
  mjData* d = mj_makeData(m);
  const std::vector<std::string> dofs = c.at("dofs").get<std::vector<std::string>>();
  const std::vector<bool> actuated = c.at("actuated").get<std::vector<bool>>();
  EXPECT_EQ(m->nv, static_cast<int>(dofs.size()));
  const testing::MujocoDofs adr = testing::mujocoDofs(m, dofs);
  std::vector<int> contactBody;
  for (const json& ct : c.at("contacts")) {
    contactBody.push_back(mj_name2id(m, mjOBJ_BODY, ct.at("link").get<std::string>().c_str()));
    EXPECT_GE(contactBody.back(), 0) << ct.at("link");
  }
  const double g = std::sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1] + gravity[2] * gravity[2]);
  const double weight = mj_getTotalmass(m) * g;
  const json &times = c.at("times"), &q = c.at("q"), &qd = c.at("qd"), &qdd = c.at("qdd"), &tau = c.at("tau");
  std::vector<mjtNum> pushed(m->nv);
  std::vector<bool> grounded;
  for (size_t f = 0; f < times.size(); ++f) {
    for (size_t k = 0; k < dofs.size(); ++k) {
      d->qpos[adr.pos[k]] = q[f][k].get<double>();
      d->qvel[adr.vel[k]] = qd[f][k].get<double>();
      d->qacc[adr.vel[k]] = qdd[f][k].get<double>();
    }
    mj_inverse(m, d);
    std::fill(pushed.begin(), pushed.end(), 0.0);
    bool anyForce = false;
    for (size_t j = 0; j < contactBody.size(); ++j) {
      const json& ct = c.at("contacts")[j];
      mjtNum force[3], point[3], torque[3] = {0, 0, 0};
      for (int a = 0; a < 3; ++a) {
        force[a] = ct.at("force")[f][a].get<double>();
        point[a] = ct.at("point")[f][a].get<double>();
      }
      if (force[0] == 0 && force[1] == 0 && force[2] == 0) continue;
      anyForce = true;
      mj_applyFT(m, d, force, torque, point, contactBody[j], pushed.data());
    }
    out.contactFrames += anyForce;
    grounded.push_back(anyForce);
    double scale = 1;
    for (size_t k = 0; k < dofs.size(); ++k) scale = std::max(scale, 1 + std::abs(tau[f][k].get<double>()));
    for (size_t k = 0; k < dofs.size(); ++k) {
      // mj_inverse gives the total force the motion needs; the ground supplies J^T f of it.
      const double needed = d->qfrc_inverse[adr.vel[k]] - pushed[adr.vel[k]];
      out.worstMismatch = std::max(out.worstMismatch, std::abs(needed - tau[f][k].get<double>()) / scale);
      if (!actuated[k] && std::abs(needed) / weight > out.worstUnactuated) {
        out.worstUnactuated = std::abs(needed) / weight;
        out.worstUnactuatedTime = times[f].get<double>();
      }
    }
    ++out.frames;
  }
  // The flight: the longest run of frames without ground force.
  size_t first = 0, last = 0;
  for (size_t a = 0; a < grounded.size();) {
    size_t b = a;
    while (b < grounded.size() && !grounded[b]) ++b;
    if (b > a && b - a > last - first) first = a, last = b - 1;
    a = b + 1;
  }
  if (last > first) {
    out.flightStart = times[first].get<double>();
    out.flightEnd = times[last].get<double>();
    // Each frame's step in kSubsteps RK4 steps, each under the torque linearly interpolated to
    // its midpoint: RK4 holds qfrc_applied constant over a step, and the flight is sensitive to
    // it (one 1 ms step per frame under the frame's torque: 0.12 rad off by the landing).
    constexpr int kSubsteps = 4;
    m->opt.timestep = (times[first + 1].get<double>() - times[first].get<double>()) / kSubsteps;
    m->opt.integrator = mjINT_RK4;
    mj_resetData(m, d);
    for (size_t k = 0; k < dofs.size(); ++k) {
      d->qpos[adr.pos[k]] = q[first][k].get<double>();
      d->qvel[adr.vel[k]] = qd[first][k].get<double>();
    }
    for (size_t f = first; f < last; ++f) {
      for (int sub = 0; sub < kSubsteps; ++sub) {
        const double a = (sub + 0.5) / kSubsteps;
        for (size_t k = 0; k < dofs.size(); ++k)
          d->qfrc_applied[adr.vel[k]] =
              actuated[k] ? (1 - a) * tau[f][k].get<double>() + a * tau[f + 1][k].get<double>() : 0.0;
        mj_step(m, d);
      }
      for (size_t k = 0; k < dofs.size(); ++k)
        out.worstFlightError = std::max(
            out.worstFlightError, std::abs(d->qpos[adr.pos[k]] - q[f + 1][k].get<double>()));
    }
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return out;
}

class MujocoReplay : public ::testing::TestWithParam<const char*> {};

TEST_P(MujocoReplay, SolvedMotionFilesReplayInMujoco) {
  const Scene scene = testing::shippedScene(GetParam());
  std::string error;
  const std::unique_ptr<SpacetimeProblem> problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  const SolverSummary summary = solveSpacetime(*problem, options);
  ASSERT_TRUE(summary.converged) << summary.reason;
  const std::string dir = ::testing::TempDir() + "/replay_" + std::string(GetParam());
  std::filesystem::remove_all(dir);
  std::string warning;
  ASSERT_TRUE(writeSolveOutputs(*problem, summary, checkValidity(*problem), OutputOptions{4000}, dir, &error, &warning)) << error;

  const Replay r = replayInMujoco(dir);
  EXPECT_GT(r.frames, 1000);
  EXPECT_GT(r.contactFrames, r.frames / 2);  // the take-off and the landing, two thirds of the clip
  EXPECT_LT(r.worstMismatch, 1e-9);
  EXPECT_LE(r.worstUnactuated, 0.01) << "at t = " << r.worstUnactuatedTime;
  // The flight is the gap between the scene's take-off contacts (ending first) and its landing
  // contacts (starting last).
  double liftOff = scene.endTime, touchDown = scene.startTime;
  for (const TermSpec& t : scene.terms)
    if (t.kind == TermKind::Contact) {
      if (t.start <= scene.startTime) liftOff = std::min(liftOff, t.end);
      else touchDown = std::max(touchDown, t.start);
    }
  EXPECT_NEAR(r.flightStart, liftOff, 0.002);
  EXPECT_NEAR(r.flightEnd, touchDown, 0.002);
  // The validity report's limit for its own simulation (ABA on the spline's continuous torque).
  // MuJoCo integrates the file's sampled torque, so the frames are written at 4 kHz: there it
  // follows within 6e-4 (jump), 7e-4 (3D lamp) and 1.8e-4 (biped); from 1 ms frames, 0.010 and 0.012 since the
  // lamp's head grazes the floor at the landing (0.003-0.004 before bodies were kept above it).
  EXPECT_LE(r.worstFlightError, 0.01);
  std::printf("%s in MuJoCo: %d frames (%d with ground forces), tau agrees to %.2g relative, unactuated force "
              "at most %.4f x weight (t = %.3f s); flight %.3f-%.3f s simulated by MuJoCo's RK4 within %.2g\n",
              GetParam(), r.frames, r.contactFrames, r.worstMismatch, r.worstUnactuated, r.worstUnactuatedTime,
              r.flightStart, r.flightEnd, r.worstFlightError);
}

INSTANTIATE_TEST_SUITE_P(Scenes, MujocoReplay, ::testing::Values("luxo_jump.json", "luxo_3d.json", "biped_jump.json"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string name = info.param;
                           return name.substr(0, name.find('.'));
                         });

}  // namespace
}  // namespace spacetime
