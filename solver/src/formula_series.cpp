// Formula series: the formula is compiled once against all contact points of the character
// (a point's force is zero outside its interval, which is what the sampled animation holds).
#include "solver/formula_series.h"

#include "core/expr/tape.h"
#include "dynamics/build_model.h"
#include "dynamics/formula_environment.h"

namespace spacetime {

FormulaSeries evaluateFormulaSeries(const Scene& scene, const CharacterAnimation& animation,
                                    const std::string& expression) {
  FormulaSeries out;
  const CharacterSpec* spec = scene.character(animation.name);
  if (!spec) {
    out.error = "no character '" + animation.name + "' in the scene";
    return out;
  }
  const Model<double> model = buildModel(*spec, scene.gravity);
  if (model.dofNames() != animation.dofs) {
    out.error = "the motion does not match the character (solve again)";
    return out;
  }
  const int forceDims = spec->root == RootKind::Planar ? 2 : 3;
  // One ContactPoints per animation track (the tracks are in term order, point by point).
  std::vector<ContactPoints> contacts;
  for (const ContactTrack& track : animation.contacts) {
    const TermSpec* term = nullptr;
    for (const TermSpec& t : scene.terms)
      if (t.id == track.term) term = &t;
    if (!term || track.pointIndex >= static_cast<int>(term->points.size())) {
      out.error = "the motion does not match the scene's contacts (solve again)";
      return out;
    }
    contacts.push_back({model.bodyIndex(track.link), {term->points[track.pointIndex]}});
  }
  expr::Graph g;
  CharacterFormulaEnvironment env(model, g, contacts, forceDims);
  std::vector<int> touched;  // the tracks are every contact of the character
  for (const ContactPoints& p : contacts) touched.push_back(p.body);
  env.setContactBodies(std::move(touched));
  const expr::FormulaResult parsed = expr::parseFormula(expression, g, env);
  if (!parsed.value) {
    out.error = parsed.error;  // "column N: ..."
    return out;
  }
  const expr::Tape tape = expr::Tape::compile(g, {*parsed.value}, true);
  const int n = model.dofCount();
  std::vector<double> z(3 * n + forceDims * contacts.size()), work;
  for (size_t f = 0; f < animation.times.size(); ++f) {
    const Eigen::Index row = static_cast<Eigen::Index>(f);
    for (int d = 0; d < n; ++d) {
      z[d] = animation.q(row, d);
      z[n + d] = animation.qd(row, d);
      z[2 * n + d] = animation.qdd(row, d);
    }
    for (size_t k = 0; k < contacts.size(); ++k)
      for (int a = 0; a < forceDims; ++a)
        z[3 * n + forceDims * k + a] = animation.contacts[k].force[f](a);
    double value = 0;
    tape.evaluate(z.data(), animation.times[f], &value, work);
    out.values.push_back(value);
  }
  return out;
}

}  // namespace spacetime
