// The rigid-motion structure of a contact's points (dynamics/contact_points.h): which of the
// body's rotations move them, and which points' heights decide the others'. The solver keeps a
// contact still with one row per independent motion (ContactPointMotionKernel, ImpactKernel),
// counts those rows when it lays out leg bubbles, and puts a contact on the ground with one
// height row per independent point (ContactAnchorKernel).
#include "dynamics/contact_points.h"

#include <algorithm>

#include <Eigen/SVD>

namespace spacetime {

double contactReach(const ContactPoints& contact) {
  double reach = 0;
  for (const Eigen::Vector3d& p : contact.points) reach = std::max(reach, (p - contact.points.front()).norm());
  return reach;
}

std::vector<Eigen::Vector3d> contactTurns(const ContactPoints& contact, bool planar) {
  std::vector<Eigen::Vector3d> turns;
  const double reach = contactReach(contact);
  if (!(reach > 1e-9)) return turns;
  if (planar) {  // the turn about z moves a point off the first one's (x, y), never along z alone
    for (const Eigen::Vector3d& p : contact.points)
      if ((p - contact.points.front()).head<2>().norm() > 1e-9) return {Eigen::Vector3d::UnitZ()};
    return turns;
  }
  // w x (p_i - p_0) = -[p_i - p_0]x w: the turns w that move some point span the row space.
  Eigen::MatrixXd cross(3 * contact.points.size(), 3);
  for (size_t i = 0; i < contact.points.size(); ++i) {
    const Eigen::Vector3d d = contact.points[i] - contact.points.front();
    cross.block<3, 3>(3 * i, 0) << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(cross, Eigen::ComputeFullV);
  for (int k = 0; k < 3; ++k)
    if (svd.singularValues()[k] > 1e-9 * reach) turns.push_back(svd.matrixV().col(k));
  return turns;
}

std::vector<int> heightPoints(const ContactPoints& contact, bool planar) {
  std::vector<int> points;
  if (contact.points.empty()) return points;
  points.push_back(0);
  const double reach = contactReach(contact);
  std::vector<Eigen::Vector3d> basis;  // orthonormal, spanning the offsets taken
  for (size_t i = 1; i < contact.points.size(); ++i) {
    Eigen::Vector3d d = contact.points[i] - contact.points.front();
    if (planar) d.z() = 0;  // a turn about z moves a point's height by its x and y only
    for (const Eigen::Vector3d& e : basis) d -= e.dot(d) * e;
    if (d.norm() > 1e-9 * reach) {
      basis.push_back(d.normalized());
      points.push_back(static_cast<int>(i));
    }
  }
  return points;
}

}  // namespace spacetime
