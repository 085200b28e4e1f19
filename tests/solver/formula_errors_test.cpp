// Formulas that cannot be evaluated are bad input, named, never a silent zero or a pass: a
// formula that is not a finite number on the starting motion fails the build naming its term,
// time and the operation where the NaN or infinity is born; force(<body>) of a body no contact
// touches is refused with the bodies that have contacts; the graphs' formula errors say their
// column once; and the validity report fails a formula whose value is not finite between the
// samples, where `std::max(0.0, NaN)` used to make it pass with value 0.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../shipped_scene.h"
#include "solver/animation.h"
#include "solver/augmented_lagrangian.h"
#include "solver/formula_series.h"
#include "solver/transcription.h"
#include "solver/validity.h"

namespace spacetime {
namespace {

TermSpec formulaTerm(const std::string& id, const std::string& character, const std::string& expression,
                     char relation, double value) {
  TermSpec f;
  f.id = id;
  f.kind = TermKind::Formula;
  f.character = character;
  f.expression = expression;
  f.relation = relation;
  f.value = value;
  f.time = 0.5;
  return f;
}

std::string buildError(const Scene& scene) {
  std::string error;
  EXPECT_FALSE(SpacetimeProblem::build(scene, &error));
  return error;
}

TEST(FormulaErrors, ANumberThatIsNotFiniteNamesTheTermTimeAndOperation) {
  struct Case {
    std::string expression, because;
  };
  // The particle starts at the origin (its first pin): pos(ball).x is 0 at t = 0.
  for (const Case& c : {Case{"1 / pos(ball).x", "a division by zero"},
                        Case{"log(pos(ball).x - 1)", "the logarithm of a number that is not positive"},
                        Case{"sqrt(pos(ball).x - 1)", "the square root of a negative number"}}) {
    Scene scene = testing::shippedScene("particle.json");
    TermSpec f = formulaTerm("bad", "particle", c.expression, '<', 5);
    f.time = 0;
    scene.terms.push_back(f);
    const std::string error = buildError(scene);
    EXPECT_NE(error.find("term 'bad': formula \"" + c.expression + "\""), std::string::npos) << error;
    EXPECT_NE(error.find("t = 0 s"), std::string::npos) << error;
    EXPECT_NE(error.find(c.because), std::string::npos) << error;
  }
  // The same formulas where they are finite build and solve.
  Scene fine = testing::shippedScene("particle.json");
  fine.terms.push_back(formulaTerm("fine", "particle", "log(pos(ball).y + 1)", '<', 5));
  std::string error;
  auto problem = SpacetimeProblem::build(fine, &error);
  ASSERT_TRUE(problem) << error;
  EXPECT_TRUE(solveSpacetime(*problem, SolverOptions{}).converged);
}

TEST(FormulaErrors, ForceOfABodyNoContactTouchesIsRefused) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  scene.terms.push_back(formulaTerm("push", scene.characters[0].id, "force(head).y", '>', 0));
  const std::string error = buildError(scene);
  EXPECT_NE(error.find("term 'push'"), std::string::npos) << error;
  EXPECT_NE(error.find("no contact touches body 'head'"), std::string::npos) << error;
  EXPECT_NE(error.find("bodies with contacts: 'base'"), std::string::npos) << error;
  // The particle has no contacts at all.
  Scene particle = testing::shippedScene("particle.json");
  particle.terms.push_back(formulaTerm("push", "particle", "force(ball).y", '<', 1));
  EXPECT_NE(buildError(particle).find("particle has no contacts"), std::string::npos);
}

TEST(FormulaErrors, TheGraphsSayTheColumnOnce) {
  const Scene scene = testing::shippedScene("particle.json");
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  const Animation a = sampleAnimation(*problem, 30);
  const FormulaSeries s = evaluateFormulaSeries(scene, a.characters[0], "pos(bal).x");
  EXPECT_EQ(s.error.rfind("column 5: unknown body 'bal'", 0), 0u) << s.error;
  EXPECT_EQ(s.error.find("column", 1), std::string::npos) << s.error;
}

// An interval formula 1 / (t - c) >= -1e9 with c an instant of a validity report at another
// density (7) than the one the solver imposes interval formulas on (kDenseGridFactor = 10):
// finite wherever the solve imposes it, +inf at c, where the old check computed
// max(0, -inf) = 0 and passed it.
TEST(FormulaErrors, TheValidityReportFailsAFormulaThatIsNotFiniteBetweenTheSamples) {
  Scene scene = testing::shippedScene("particle.json");
  std::string error;
  auto plain = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(plain) << error;
  constexpr int kOtherDensity = 7;
  const std::vector<double> imposed = plain->transcription().denseGrid(kDenseGridFactor);
  double c = -1;
  for (double t : plain->transcription().denseGrid(kOtherDensity)) {
    bool sample = false;
    for (const Sample& s : plain->transcription().samples) sample = sample || std::abs(s.time - t) < 1e-9;
    for (double d : imposed) sample = sample || std::abs(d - t) < 1e-6;
    if (!sample && t > 0.2 && t < 0.8) {
      c = t;
      break;
    }
  }
  ASSERT_GT(c, 0);
  char expression[64];
  std::snprintf(expression, sizeof expression, "1 / (t - %.17g)", c);
  TermSpec f = formulaTerm("spike", "particle", expression, '>', -1e9);
  f.interval = true;
  f.start = 0;
  f.end = 1;
  scene.terms.push_back(f);
  auto problem = SpacetimeProblem::build(scene, &error);
  ASSERT_TRUE(problem) << error;
  const SolverSummary s = solveSpacetime(*problem, SolverOptions{});
  ASSERT_TRUE(s.converged) << s.reason;
  EXPECT_LE(checkValidity(*problem).maxFormulaViolation, 1e-5);  // where the solve imposed it
  const ValidityReport v = checkValidity(*problem, kOtherDensity);
  ASSERT_EQ(v.formulas.size(), 1u);
  EXPECT_NE(v.formulas[0].error.find("not a finite number"), std::string::npos) << v.formulas[0].error;
  EXPECT_NEAR(v.formulas[0].worstTime, c, 1e-12);
  bool failed = false;
  for (const ValidityCheck& check : validityChecklist(v))
    if (check.name.find("formula 'spike'") != std::string::npos) failed = !check.pass;
  EXPECT_TRUE(failed);
}

}  // namespace
}  // namespace spacetime
