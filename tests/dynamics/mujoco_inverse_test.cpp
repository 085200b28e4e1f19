// Our inverse dynamics against MuJoCo's mj_inverse on the URDF we export, for random states:
// the independent check that the dynamics, the Model built from a scene and the URDF writer
// all agree with another library's reading of the same character.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <fstream>
#include <random>

#include "../mujoco_dofs.h"
#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "interop/urdf_export.h"
#include "random_model.h"

namespace spacetime {
namespace {

// Loads the URDF into MuJoCo, compares mj_inverse with our RNEA; returns the worst relative
// error over `states` random states.
// MuJoCo takes the gravity from the file (<mujoco><option gravity/>): nothing is set here. With
// zUp the file is the Z-up export.
double worstRelativeError(const CharacterSpec& character, const Eigen::Vector3d& gravity,
                          int states, unsigned seed, bool zUp = false) {
  const Model<double> model = buildModel(character, gravity);
  const UrdfExport urdf = exportUrdf(model, character, UrdfOptions{zUp});
  // One file per test and variant: ctest runs the tests in parallel processes.
  const std::string path = ::testing::TempDir() + "/" + ::testing::UnitTest::GetInstance()->current_test_info()->name() +
                           "_" + character.id + std::to_string(seed) + (zUp ? "_z_up" : "") + ".urdf";
  std::ofstream(path) << urdf.xml;
  char error[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  EXPECT_NE(m, nullptr) << error;
  if (!m) return 1e9;
  m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_CONTACT | mjDSBL_PASSIVE;
  const Eigen::Vector3d expected = zUp ? Eigen::Vector3d(yUpToZUp() * gravity) : gravity;
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(m->opt.gravity[k], expected[k], 1e-12);
  mjData* d = mj_makeData(m);
  EXPECT_EQ(m->nv, model.dofCount());
  const testing::MujocoDofs adr = testing::mujocoDofs(m, model.dofNames());
  std::mt19937 rng(seed);
  Data<double> data(model);
  double worst = 0;
  const int n = model.dofCount();
  for (int s = 0; s < states; ++s) {
    const Eigen::VectorXd q = testing::randomVector(rng, n, 1.5), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 3);
    for (int k = 0; k < n; ++k) {
      d->qpos[adr.pos[k]] = q[k];
      d->qvel[adr.vel[k]] = qd[k];
      d->qacc[adr.vel[k]] = qdd[k];
    }
    mj_inverse(m, d);
    const Eigen::VectorXd tau = rnea(model, data, q.data(), qd.data(), qdd.data());
    for (int k = 0; k < n; ++k)
      worst = std::max(worst, std::abs(d->qfrc_inverse[adr.vel[k]] - tau[k]) / (1 + tau.cwiseAbs().maxCoeff()));
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return worst;
}

TEST(MujocoInverse, ShippedCharactersAgree) {
  for (const char* scene : {"luxo_jump.json", "luxo_heavy.json", "luxo_3d.json", "particle_gravity.json"}) {
    const Scene s = testing::shippedScene(scene);
    EXPECT_LT(worstRelativeError(s.characters[0], s.gravity, 50, 7), 1e-9) << scene;
  }
}

// The Z-up export: MuJoCo reproduces our inverse dynamics under the scene's (0, -9.81, 0) with
// the gravity along -Z that is its default. Both files say their gravity in a comment.
TEST(MujocoInverse, ZUpExportNeedsNoGravitySetting) {
  for (const char* scene : {"luxo_jump.json", "luxo_3d.json"}) {
    const Scene s = testing::shippedScene(scene);
    ASSERT_EQ(s.gravity, Eigen::Vector3d(0, -9.81, 0));
    const Model<double> model = buildModel(s.characters[0], s.gravity);
    const std::string yUp = exportUrdf(model, s.characters[0]).xml;
    EXPECT_NE(yUp.find("gravity is (0 -9.81 0)"), std::string::npos) << yUp.substr(0, 400);
    EXPECT_NE(exportUrdf(model, s.characters[0], UrdfOptions{true}).xml.find("gravity is (0 0 -9.81)"), std::string::npos);
    EXPECT_LT(worstRelativeError(s.characters[0], s.gravity, 50, 7, /*zUp=*/true), 1e-9) << scene;
  }
}

// Random trees use principal-axis inertias and no fixed joints: MuJoCo re-diagonalises rotated
// and fused (fixed-joint) inertias with an iterative eigen-solver, which alone costs it ~1e-8.
TEST(MujocoInverse, RandomTreesAgree) {
  std::mt19937 rng(21);
  for (RootKind root : {RootKind::Fixed, RootKind::Planar, RootKind::Floating3D}) {
    for (int trial = 0; trial < 5; ++trial) {
      const CharacterSpec c = testing::randomCharacter(rng, 6, root, /*allowHelical=*/false, /*rotatedInertia=*/false,
                                                     /*allowFixed=*/false);
      EXPECT_LT(worstRelativeError(c, {0.5, -9.81, 0.3}, 20, trial), 1e-9) << toString(root);
    }
  }
}

}  // namespace
}  // namespace spacetime
