// Inverse and forward dynamics against independent truths: the pendulum and double pendulum from
// their Lagrangians, RNEA = CRBA qdd + bias, ABA(RNEA(qdd)) = qdd, external forces against
// J^T F with a finite-difference point Jacobian, momentum against the centre-of-mass velocity,
// and the power balance d(KE + PE)/dt = qd . tau.
#include <gtest/gtest.h>

#include <cmath>
#include <Eigen/Eigenvalues>
#include <random>

#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"
#include "random_model.h"

namespace spacetime {
namespace {

constexpr double g = 9.81;

BodySpec pointMassLink(const std::string& id, const std::string& parent, double mass,
                       const Eigen::Vector3d& jointOrigin, const Eigen::Vector3d& com) {
  BodySpec b;
  b.id = id;
  b.parent = parent;
  b.joint.id = id + "_joint";
  b.joint.kind = JointKind::Revolute;
  b.joint.axis = Eigen::Vector3d::UnitZ();
  b.joint.origin = jointOrigin;
  b.mass = mass;
  b.com = com;
  b.inertia = Eigen::Matrix3d::Zero();
  return b;
}

CharacterSpec anchored(std::vector<BodySpec> links) {
  CharacterSpec c;
  c.id = "pendulum";
  c.root = RootKind::Fixed;
  BodySpec anchor;
  anchor.id = "anchor";
  anchor.mass = 1.0;
  c.bodies.push_back(anchor);
  for (auto& l : links) c.bodies.push_back(l);
  return c;
}

TEST(Rnea, PendulumMatchesLagrangian) {
  const double m = 1.3, l = 0.7, Izz = 0.05;
  BodySpec arm = pointMassLink("arm", "anchor", m, Eigen::Vector3d::Zero(), {0, -l, 0});
  arm.inertia = Eigen::Vector3d(0.01, 0.02, Izz).asDiagonal();
  const Model<double> model = buildModel(anchored({arm}), {0, -g, 0});
  Data<double> d(model);
  for (double q : {-2.0, -0.3, 0.0, 0.4, 1.9})
    for (double qd : {-1.0, 0.5})
      for (double qdd : {-3.0, 2.0}) {
        rnea(model, d, &q, &qd, &qdd);
        const double expected = (m * l * l + Izz) * qdd + m * g * l * std::sin(q);
        EXPECT_NEAR(d.tau[0], expected, 1e-12);
      }
}

TEST(Rnea, DoublePendulumMatchesLagrangian) {
  const double m1 = 1.1, m2 = 0.6, l1 = 0.8, l2 = 0.5;
  const Model<double> model = buildModel(
      anchored({pointMassLink("a", "anchor", m1, Eigen::Vector3d::Zero(), {0, -l1, 0}),
                pointMassLink("b", "a", m2, {0, -l1, 0}, {0, -l2, 0})}),
      {0, -g, 0});
  Data<double> d(model);
  std::mt19937 rng(5);
  for (int k = 0; k < 30; ++k) {
    const Eigen::VectorXd q = testing::randomVector(rng, 2, 3), qd = testing::randomVector(rng, 2, 2),
                          qdd = testing::randomVector(rng, 2, 4);
    rnea(model, d, q.data(), qd.data(), qdd.data());
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    const double M11 = (m1 + m2) * l1 * l1 + m2 * l2 * l2 + 2 * m2 * l1 * l2 * c2;
    const double M12 = m2 * l2 * l2 + m2 * l1 * l2 * c2, M22 = m2 * l2 * l2;
    const double h1 = -m2 * l1 * l2 * s2 * (2 * qd[0] * qd[1] + qd[1] * qd[1]);
    const double h2 = m2 * l1 * l2 * s2 * qd[0] * qd[0];
    const double g1 = (m1 + m2) * g * l1 * std::sin(q[0]) + m2 * g * l2 * std::sin(q[0] + q[1]);
    const double g2 = m2 * g * l2 * std::sin(q[0] + q[1]);
    EXPECT_NEAR(d.tau[0], M11 * qdd[0] + M12 * qdd[1] + h1 + g1, 1e-12);
    EXPECT_NEAR(d.tau[1], M12 * qdd[0] + M22 * qdd[1] + h2 + g2, 1e-12);
  }
}

class RandomModels : public ::testing::TestWithParam<RootKind> {};

TEST_P(RandomModels, RneaEqualsCrbaTimesQddPlusBias) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0.3, -g, 0.2});
    Data<double> d(model);
    const int n = model.dofCount();
    const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 2);
    const Eigen::VectorXd tau = rnea(model, d, q.data(), qd.data(), qdd.data());
    const Eigen::VectorXd bias = rnea(model, d, q.data(), qd.data(), static_cast<const double*>(nullptr));
    const Eigen::MatrixXd M = crba(model, d, q.data());
    EXPECT_LT((tau - (M * qdd + bias)).norm(), 1e-10 * (1 + tau.norm()));
    EXPECT_LT((M - M.transpose()).norm(), 1e-12);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0);
  }
}

TEST_P(RandomModels, AbaInvertsRnea) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 20; ++trial) {
    const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0, -g, 0});
    Data<double> d(model);
    const int n = model.dofCount();
    const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 2);
    std::vector<PointForce<double>> fext = {{model.bodyCount() - 1, testing::randomVec(rng), testing::randomVec(rng)}};
    const Eigen::VectorXd tau = rnea(model, d, q.data(), qd.data(), qdd.data(), fext);
    const Eigen::VectorXd back = aba(model, d, q.data(), qd.data(), tau.data(), fext);
    EXPECT_LT((back - qdd).norm(), 1e-8 * (1 + qdd.norm()));
  }
}

TEST_P(RandomModels, ExternalForceEqualsJacobianTranspose) {
  std::mt19937 rng(13);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 6, GetParam()), {0, -g, 0});
  Data<double> d(model);
  const int n = model.dofCount();
  const int body = model.bodyCount() - 1;
  const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                        qdd = testing::randomVector(rng, n, 2);
  const Eigen::Vector3d pLocal = testing::randomVec(rng), F = testing::randomVec(rng);
  forwardKinematics(model, d, q.data());
  const Eigen::Vector3d pWorld = pointPosition(d, body, pLocal);
  const Eigen::VectorXd tau0 = rnea(model, d, q.data(), qd.data(), qdd.data());
  const Eigen::VectorXd tauF = rnea(model, d, q.data(), qd.data(), qdd.data(), {{body, pWorld, F}});
  // Point Jacobian by central differences.
  Eigen::MatrixXd J(3, n);
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += 1e-6;
    qm[k] -= 1e-6;
    forwardKinematics(model, d, qp.data());
    const Eigen::Vector3d pp = pointPosition(d, body, pLocal);
    forwardKinematics(model, d, qm.data());
    J.col(k) = (pp - pointPosition(d, body, pLocal)) / 2e-6;
  }
  EXPECT_LT((tauF - (tau0 - J.transpose() * F)).norm(), 1e-7);
  // The same Jacobian gives the point velocity.
  forwardKinematics(model, d, q.data(), qd.data(), qdd.data());
  EXPECT_LT((pointVelocity(d, body, pLocal) - J * qd).norm(), 1e-7);
}

// One body's pose along its chain alone equals the whole forward sweep's.
TEST_P(RandomModels, BodyPoseEqualsForwardKinematics) {
  std::mt19937 rng(29);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0, -g, 0});
  Data<double> d(model);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = testing::randomVector(rng, model.dofCount(), 2);
    forwardKinematics(model, d, q.data());
    for (int b = 0; b < model.bodyCount(); ++b) {
      const Transform<double> X = bodyPose(model, q.data(), b);
      EXPECT_LT((X.matrix() - d.X_world[b].matrix()).norm(), 1e-12) << "body " << b;
      const Eigen::Vector3d p = testing::randomVec(rng);
      EXPECT_LT((pointPosition(X, p) - pointPosition(d, b, p)).norm(), 1e-12);
    }
  }
}

// One body's chain swept alone gives it, and each of its ancestors, the pose, velocity and
// acceleration of the whole forward sweep, and leaves the other bodies as they were.
TEST_P(RandomModels, ChainKinematicsEqualsForwardKinematics) {
  std::mt19937 rng(37);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0, -g, 0});
  const int n = model.dofCount();
  Data<double> full(model), chain(model);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 2);
    forwardKinematics(model, full, q.data(), qd.data(), qdd.data());
    for (int b = 0; b < model.bodyCount(); ++b) {
      for (int i = 0; i < model.bodyCount(); ++i) chain.v[i].lin.setConstant(1e300);  // untouched unless swept
      chainKinematics(model, chain, b, q.data(), qd.data(), qdd.data());
      std::vector<bool> onChain(model.bodyCount(), false);
      for (int i = b; i >= 0; i = model.bodies[i].parent) onChain[i] = true;
      for (int i = 0; i < model.bodyCount(); ++i) {
        if (!onChain[i]) {
          EXPECT_EQ(chain.v[i].lin.x(), 1e300) << "body " << i << " swept for " << b;
          continue;
        }
        EXPECT_EQ((chain.X_world[i].matrix() - full.X_world[i].matrix()).norm(), 0.0) << "body " << i;
        EXPECT_EQ((chain.v[i].vector() - full.v[i].vector()).norm(), 0.0) << "body " << i;
        EXPECT_EQ((chain.a[i].vector() - full.a[i].vector()).norm(), 0.0) << "body " << i;
      }
    }
  }
}

// RNEA composing only the forced bodies' world poses gives the same generalized forces.
TEST_P(RandomModels, RneaWithoutAllWorldPosesIsTheSame) {
  std::mt19937 rng(31);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0.2, -g, 0});
  Data<double> full(model), lean(model);
  const int n = model.dofCount();
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 2);
    std::vector<PointForce<double>> fext;
    for (int b : {model.bodyCount() - 1, model.bodyCount() - 1, model.bodyCount() / 2}) {
      PointForce<double> pf{b, testing::randomVec(rng), testing::randomVec(rng)};
      pf.pointIsLocal = trial % 2 == 0;
      fext.push_back(pf);
    }
    const Eigen::VectorXd a = rnea(model, full, q.data(), qd.data(), qdd.data(), fext);
    const Eigen::VectorXd b = rnea(model, lean, q.data(), qd.data(), qdd.data(), fext, true, false);
    EXPECT_LT((a - b).norm(), 1e-12 * (1 + a.norm()));
  }
}

// One point force's generalized force along its chain equals the difference it makes to RNEA.
TEST_P(RandomModels, PointForceGeneralizedEqualsRneaDifference) {
  std::mt19937 rng(37);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 7, GetParam()), {0, -g, 0});
  Data<double> d(model);
  const int n = model.dofCount();
  for (int body = 0; body < model.bodyCount(); ++body) {
    const Eigen::VectorXd q = testing::randomVector(rng, n, 2), qd = testing::randomVector(rng, n, 2),
                          qdd = testing::randomVector(rng, n, 2);
    PointForce<double> pf{body, testing::randomVec(rng), testing::randomVec(rng)};
    pf.pointIsLocal = body % 2 == 0;
    const Eigen::VectorXd withForce = rnea(model, d, q.data(), qd.data(), qdd.data(), {pf});
    const Eigen::VectorXd expected = withForce - rnea(model, d, q.data(), qd.data(), qdd.data());
    forwardKinematics(model, d, q.data());
    Eigen::VectorXd tau = Eigen::VectorXd::Zero(n);
    addPointForceGeneralized(model, d, pf, tau.data());
    EXPECT_LT((tau - expected).norm(), 1e-10 * (1 + expected.norm())) << "body " << body;
  }
}

TEST_P(RandomModels, MomentumAndEnergy) {
  std::mt19937 rng(14);
  const Model<double> model = buildModel(testing::randomCharacter(rng, 6, GetParam()), {0, -g, 0});
  Data<double> d(model);
  const int n = model.dofCount();
  const Eigen::VectorXd q = testing::randomVector(rng, n, 1), qd = testing::randomVector(rng, n, 1),
                        qdd = testing::randomVector(rng, n, 1);
  const double h = 1e-6;
  auto state = [&](double t) {
    const Eigen::VectorXd qt = q + qd * t + 0.5 * qdd * t * t, qdt = qd + qdd * t;
    forwardKinematics(model, d, qt.data(), qdt.data(), qdd.data());
    return std::make_tuple(centerOfMass(model, d), kineticEnergy(model, d) + potentialEnergy(model, d));
  };
  const auto [cp, ep] = state(h);
  const auto [cm, em] = state(-h);
  forwardKinematics(model, d, q.data(), qd.data(), qdd.data());
  const Force<double> momentum = spatialMomentum(model, d);
  EXPECT_LT((momentum.lin - model.totalMass() * (cp - cm) / (2 * h)).norm(), 1e-6);
  // Kinetic energy = 1/2 qd^T M qd.
  const Eigen::MatrixXd M = crba(model, d, q.data());
  forwardKinematics(model, d, q.data(), qd.data(), qdd.data());
  EXPECT_NEAR(kineticEnergy(model, d), 0.5 * qd.dot(M * qd), 1e-10);
  // Power balance: d(KE + PE)/dt = qd . tau.
  const Eigen::VectorXd tau = rnea(model, d, q.data(), qd.data(), qdd.data());
  EXPECT_NEAR((ep - em) / (2 * h), qd.dot(tau), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Roots, RandomModels,
                         ::testing::Values(RootKind::Fixed, RootKind::Planar, RootKind::Floating3D));

}  // namespace
}  // namespace spacetime
