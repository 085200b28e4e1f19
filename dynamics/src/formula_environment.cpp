// Symbolic names for formulas (see formula_environment.h).
#include "dynamics/formula_environment.h"

#include <algorithm>

#include "dynamics/algorithms.h"

namespace spacetime {

using expr::Expr;

CharacterFormulaEnvironment::CharacterFormulaEnvironment(const Model<double>& model, expr::Graph& graph,
                                                         std::vector<ContactPoints> contacts,
                                                         int forceDims)
    : model_(model), g_(graph), contacts_(std::move(contacts)), forceDims_(forceDims) {
  for (int i = 0; i < variableCount(); ++i) z_.push_back(g_.variable(i));
}

int CharacterFormulaEnvironment::variableCount() const {
  int points = 0;
  for (const auto& c : contacts_) points += static_cast<int>(c.points.size());
  return 3 * model_.dofCount() + forceDims_ * points;
}

void CharacterFormulaEnvironment::ensureKinematics() {
  if (kinematics_) return;
  const int n = model_.dofCount();
  kinematics_ = std::make_unique<Data<Expr>>(model_);
  forwardKinematics(model_, *kinematics_, z_.data(), z_.data() + n, z_.data() + 2 * n);
}

std::vector<PointForce<Expr>> CharacterFormulaEnvironment::contactForces() {
  return contactPointForces(contacts_, z_.data() + 3 * model_.dofCount(), forceDims_);
}

void CharacterFormulaEnvironment::ensureDynamics() {
  if (haveTau_) return;
  const int n = model_.dofCount();
  Data<Expr> data(model_);
  tau_ = rnea(model_, data, z_.data(), z_.data() + n, z_.data() + 2 * n, contactForces());
  haveTau_ = true;
}

bool CharacterFormulaEnvironment::isGroup(const std::string& name) const {
  return name == "q" || name == "qd" || name == "qdd" || name == "tau";
}

bool CharacterFormulaEnvironment::isBodyFunction(const std::string& name) const {
  return name == "pos" || name == "vel" || name == "force";
}

std::optional<expr::FormulaValue> CharacterFormulaEnvironment::name(const std::string& name,
                                                                    std::string* error) {
  expr::FormulaValue v;
  if (name == "t") {
    v.scalar = g_.time();
    return v;
  }
  if (name == "com") {
    ensureKinematics();
    const Vec3<Expr> c = centerOfMass(model_, *kinematics_);
    v.isVector = true;
    v.vector = {c.x(), c.y(), c.z()};
    return v;
  }
  *error = "unknown name '" + name + "'; expected t, com, q.<dof>, qd.<dof>, qdd.<dof>, tau.<dof>, "
           "pos(<body>), vel(<body>) or force(<body>)";
  return std::nullopt;
}

std::optional<Expr> CharacterFormulaEnvironment::member(const std::string& group,
                                                        const std::string& member, std::string* error) {
  const int d = model_.dofIndex(member);
  if (d < 0) {
    std::string list;
    for (const auto& n : model_.dofNames()) list += (list.empty() ? "" : ", ") + n;
    *error = "unknown degree of freedom '" + member + "' of " + model_.name + "; expected one of: " + list;
    return std::nullopt;
  }
  const int n = model_.dofCount();
  if (group == "q") return z_[d];
  if (group == "qd") return z_[n + d];
  if (group == "qdd") return z_[2 * n + d];
  ensureDynamics();
  return tau_[d];
}

std::optional<std::array<Expr, 3>> CharacterFormulaEnvironment::bodyFunction(
    const std::string& function, const std::string& body,
    const std::optional<std::array<double, 3>>& point, std::string* error) {
  const int b = model_.bodyIndex(body);
  if (b < 0 || model_.bodies[b].isVirtual) {
    std::string list;
    for (const auto& bd : model_.bodies)
      if (!bd.isVirtual) list += (list.empty() ? "" : ", ") + bd.name;
    *error = "unknown body '" + body + "' of " + model_.name + "; expected one of: " + list;
    return std::nullopt;
  }
  const Eigen::Vector3d p = point ? Eigen::Vector3d((*point)[0], (*point)[1], (*point)[2])
                                  : Eigen::Vector3d::Zero();
  if (function == "force" && contactBodies_ &&
      std::find(contactBodies_->begin(), contactBodies_->end(), b) == contactBodies_->end()) {
    std::string list;
    for (int k : *contactBodies_)
      if (list.find("'" + model_.bodies[k].name + "'") == std::string::npos)
        list += (list.empty() ? "" : ", ") + ("'" + model_.bodies[k].name + "'");
    *error = "no contact touches body '" + body + "', so force(" + body + ") is zero at every instant; " +
             (list.empty() ? model_.name + " has no contacts" : "bodies with contacts: " + list);
    return std::nullopt;
  }
  if (function == "force") {
    std::array<Expr, 3> sum{Expr(0.0), Expr(0.0), Expr(0.0)};
    for (const PointForce<Expr>& pf : contactForces())
      if (pf.body == b)
        for (int k = 0; k < 3; ++k) sum[k] = sum[k] + pf.forceWorld[k];
    return sum;
  }
  ensureKinematics();
  const Vec3<Expr> v = function == "pos" ? pointPosition(*kinematics_, b, p)
                                         : pointVelocity(*kinematics_, b, p);
  return std::array<Expr, 3>{v.x(), v.y(), v.z()};
}

}  // namespace spacetime
