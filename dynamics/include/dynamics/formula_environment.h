// The names a formula can use for one character, built symbolically from the same templated
// kinematics and dynamics the solver runs: q.<dof>, qd.<dof>, qdd.<dof>, tau.<dof>,
// pos(body[, point]), vel(body[, point]), com, force(body), t.
//
// Variables follow the solver's per-sample input layout: q at 0..n-1, qd at n..2n-1, qdd at
// 2n..3n-1, then forceDims components (x, y[, z]) for every contact point in `contacts` order.
#pragma once

#include <memory>
#include <optional>

#include "core/expr/eigen_scalar.h"
#include "core/expr/formula.h"
#include "dynamics/contact_points.h"
#include "dynamics/model.h"

namespace spacetime {

class CharacterFormulaEnvironment : public expr::FormulaEnvironment {
 public:
  CharacterFormulaEnvironment(const Model<double>& model, expr::Graph& graph,
                              std::vector<ContactPoints> contacts = {}, int forceDims = 3);

  std::optional<expr::FormulaValue> name(const std::string& name, std::string* error) override;
  std::optional<expr::Expr> member(const std::string& group, const std::string& member,
                                   std::string* error) override;
  bool isGroup(const std::string& name) const override;
  std::optional<std::array<expr::Expr, 3>> bodyFunction(
      const std::string& function, const std::string& body,
      const std::optional<std::array<double, 3>>& point, std::string* error) override;
  bool isBodyFunction(const std::string& name) const override;

  int variableCount() const;
  // The bodies any contact of the character touches over the whole clip (the contacts above are
  // only those active at one instant). Once set, force(<body>) of another body is an error: it
  // would be zero at every instant, which is never what a formula means.
  void setContactBodies(std::vector<int> bodies) { contactBodies_ = std::move(bodies); }

 private:
  void ensureKinematics();
  void ensureDynamics();
  std::vector<PointForce<expr::Expr>> contactForces();

  const Model<double>& model_;
  expr::Graph& g_;
  std::vector<ContactPoints> contacts_;
  int forceDims_;
  std::vector<expr::Expr> z_;
  std::unique_ptr<Data<expr::Expr>> kinematics_;  // FK with q, qd, qdd
  VecX<expr::Expr> tau_;
  bool haveTau_ = false;
  std::optional<std::vector<int>> contactBodies_;
};

}  // namespace spacetime
