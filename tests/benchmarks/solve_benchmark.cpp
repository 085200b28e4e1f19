// Solve time of every shipped scene (and of the lamp rooted at its head, tests/scenes/) from its
// default initial guess on 1 and 2 threads, the jump ladder's valid rungs as spacetime-cli solves
// them, warm re-solves after an edit, and the time of one full residual + Jacobian evaluation of
// the Luxo jump. Each solve reports its iterations and the time per step by phase (reportSteps). Run a Release build:
//   ./build/tests/benchmarks/solve_benchmark --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
// and read the *_median rows.
#include <benchmark/benchmark.h>

#include <ceres/crs_matrix.h>
#include <ceres/problem.h>

#include <optional>

#include "../../solver/src/program_steps.h"
#include "../../solver/src/raw_rows.h"
#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "solver/augmented_lagrangian.h"
#include "solver/quadratic_program.h"
#include "solver/refinement.h"

namespace spacetime {
namespace {

// Iterations and where a solve's time went, per step: the augmented Lagrangian's
// Levenberg-Marquardt iterations (Ceres: residual and Jacobian evaluation, the linear solver)
// and the Newton polish's steps (the Hessian, the factorisation with its inertia correction,
// the line search's trial points).
void reportSteps(benchmark::State& state, const SolverSummary& s) {
  if (s.method == SolverMethod::InteriorPoint) {  // IPOPT's iterations: evaluation, Hessian, the rest
    state.counters["ip_iterations"] = s.iterations;
    if (s.iterations > 0 && s.solveSeconds > 0) {
      state.counters["ip_ms_per_iteration"] = 1e3 * s.solveSeconds / s.iterations;
      state.counters["ip_evaluation_share"] = s.jacobianSeconds / s.solveSeconds;
      state.counters["ip_hessian_share"] = s.hessianSeconds / s.solveSeconds;
    }
    return;
  }
  // The SQP's steps: the whole phase per step (its polish attempts included) and the part in
  // its quadratic programs (second-order corrections included).
  if (s.method == SolverMethod::Sqp && s.sqpSteps > 0) {
    state.counters["sqp_steps"] = s.sqpSteps;
    state.counters["sqp_ms_per_step"] = 1e3 * s.sqpSeconds / s.sqpSteps;
    state.counters["sqp_program_ms"] = 1e3 * s.qpSeconds / s.sqpSteps;
  }
  state.counters["lm_iterations"] = s.iterations;
  state.counters["newton_steps"] = s.newtonSteps;
  state.counters["newton_solves"] = s.newtonSolves;
  if (s.chordSteps > 0) state.counters["chord_steps"] = s.chordSteps;
  const double lmSeconds = s.solveSeconds - s.polishSeconds;
  if (s.iterations > 0) {
    state.counters["lm_ms_per_iteration"] = 1e3 * lmSeconds / s.iterations;
    state.counters["lm_evaluation_share"] = lmSeconds > 0 ? (s.jacobianSeconds - s.polishEvaluationSeconds) / lmSeconds : 0;
    state.counters["lm_linear_solver_share"] = lmSeconds > 0 ? s.linearSolverSeconds / lmSeconds : 0;
  }
  // Per KKT system solved: the polish's passes that only changed its active set cost nothing
  // and are not steps.
  const int solved = s.newtonSolves;
  if (solved > 0) state.counters["newton_ms_per_step"] = 1e3 * s.polishSeconds / solved;
  // The summary's Hessian, factorisation and line-search times include the SQP's steps' own: the
  // split is the polish's only without them.
  if (solved > 0 && s.sqpSteps == 0) {
    state.counters["newton_hessian_ms"] = 1e3 * s.hessianSeconds / solved;
    state.counters["newton_factorisation_ms"] = 1e3 * s.factorisationSeconds / solved;
    state.counters["newton_line_search_ms"] = 1e3 * s.lineSearchSeconds / solved;
  }
}

// With samplesPerSegment > 0 the scene's transcription is overridden (2: a coarser transcription,
// which converges but fails the dense-grid check); polish = false runs the augmented Lagrangian
// without its Newton polish, to measure what the polish saves; threads = 2 is what spacetime-cli
// uses on this 2-core machine (the other rows are single-threaded, as the editor's solver);
// method: the interior point (IPOPT) and SQP rows compare them with the default.
void BM_Solve(benchmark::State& state, const std::string& name, int samplesPerSegment = 0,
              bool polish = true, int threads = 1, SolverMethod method = SolverMethod::AugmentedLagrangian) {
  // "test:NAME" is a scene kept for tests only (tests/scenes/).
  Scene scene = name.rfind("test:", 0) == 0 ? testing::testScene(name.substr(5)) : testing::shippedScene(name);
  if (samplesPerSegment > 0) scene.transcription.samplesPerSegment = samplesPerSegment;
  bool converged = true;
  double violation = 0;
  SolverSummary last;
  for (auto _ : state) {
    state.PauseTiming();
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    state.ResumeTiming();
    SolverOptions options = solverOptionsFor(scene.solver);  // as spacetime-cli uses them
    options.maxSeconds = 120;
    options.newtonPolish = polish;
    options.threads = threads;
    options.method = method;
    last = solveSpacetime(*problem, options);
    converged = converged && last.converged;
    violation = std::max(violation, last.maxViolation);
  }
  state.counters["converged"] = converged ? 1 : 0;
  state.counters["max_violation"] = violation;
  reportSteps(state, last);
}

// What the editor does while an animator drags: luxo_jump solved, then its end pose moved 2 cm
// further (base_x 0.60 -> 0.62) and re-solved warm from the previous solution and multipliers
// (the same structure, so SpacetimeProblem::restore). Timed: the warm re-solve only. With
// `method` the first solve and the warm one both use that method (its own optimum is edited).
void BM_LuxoWarmResolve(benchmark::State& state, bool polish, double move = 0.02,
                        SolverMethod method = SolverMethod::AugmentedLagrangian, int threads = 1) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto first = SpacetimeProblem::build(scene, &error);
  SolverOptions options = solverOptionsFor(scene.solver);
  options.newtonPolish = polish;
  options.method = method;
  options.threads = threads;
  solveSpacetime(*first, options);
  const SolutionState solved = first->state();
  for (TermSpec& t : scene.terms)
    if (t.id == "end_pose")
      for (auto& [dof, value] : t.values)
        if (dof == "base_x") value += move;
  bool converged = true;
  SolverSummary last;
  for (auto _ : state) {
    state.PauseTiming();
    auto moved = SpacetimeProblem::build(scene, &error);
    const bool restored = moved->restore(solved);
    state.ResumeTiming();
    SolverOptions warm = options;
    warm.warmStart = restored;
    last = solveSpacetime(*moved, warm);
    converged = converged && restored && last.converged;
  }
  state.counters["converged"] = converged ? 1 : 0;
  state.counters["objective"] = last.objective;
  reportSteps(state, last);
}

// A scene kept for tests (tests/scenes/PATH) solved as spacetime-cli solves it: 2 threads,
// refining the transcription until the motion passes the validity report. Reports the clip's
// length and the characters' dofs, which the scaling rows relate the time to. `method`, if given,
// replaces the scene's (spacetime-cli solve --method).
void solveAsTheCli(benchmark::State& state, const std::string& path, double maxSeconds,
                   std::optional<SolverMethod> method = std::nullopt) {
  const Scene scene = testing::testScene(path);
  bool valid = true;
  RefinedSolve last;
  for (auto _ : state) {
    state.PauseTiming();
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    state.ResumeTiming();
    SolverOptions options = solverOptionsFor(scene.solver);
    options.threads = 2;
    options.maxSeconds = maxSeconds;
    if (method) options.method = *method;
    last = solveRefined(std::move(problem), options, RefinementOptions());
    valid = valid && last.valid;
  }
  state.counters["valid"] = valid ? 1 : 0;
  state.counters["transcriptions"] = static_cast<double>(last.attempts.size());
  state.counters["objective"] = last.summary.objective;
  state.counters["clip_seconds"] = scene.endTime - scene.startTime;
  int dofs = 0;
  for (const CharacterSpec& c : scene.characters) dofs += static_cast<int>(c.dofNames().size());
  state.counters["dofs"] = dofs;
  reportSteps(state, last.summary);
}

// A rung of the jump ladder (tests/scenes/ladder/).
void BM_Ladder(benchmark::State& state, const std::string& name) { solveAsTheCli(state, "ladder/" + name, 120); }

// How the cost grows with the clip and with the character (tests/scenes/scaling/): the shipped
// jump repeated as 1, 2 and 3 consecutive hops (clips of 1.2, 2.4 and 3.6 s), and the same jump by
// a lamp whose arms are split into more, shorter links (6, 9, 12 and 15 dofs, the same length and
// mass). scripts/measure.sh fits the exponents of time against clip length and dofs. The
// ScalingSqp rows solve the same scenes by `sqp`, whose step count grows more slowly with the
// clip than the augmented Lagrangian's iterations.
void BM_Scaling(benchmark::State& state, const std::string& name) { solveAsTheCli(state, "scaling/" + name, 300); }
void BM_ScalingSqp(benchmark::State& state, const std::string& name) {
  solveAsTheCli(state, "scaling/" + name, 300, SolverMethod::Sqp);
}

// One full residual + Jacobian evaluation of the jump; with `freeLiftOff`, the take-off's end is
// a variable (its window's residuals rebuild their input maps from it at every evaluation).
void BM_LuxoJacobian(benchmark::State& state, bool freeLiftOff) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  for (TermSpec& t : scene.terms)
    if (t.id == "takeoff") t.freeEnd = freeLiftOff;
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  double cost = 0;
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  for (auto _ : state) {
    problem->ceresProblem().Evaluate(ceres::Problem::EvaluateOptions(), &cost, &residuals, nullptr, &jacobian);
    benchmark::DoNotOptimize(cost);
  }
  state.counters["rows"] = jacobian.num_rows;
  state.counters["cols"] = jacobian.num_cols;
  state.counters["nonzeros"] = static_cast<double>(jacobian.values.size());
}

// One evaluation of every raw row with its Jacobian (solver/src/raw_rows.h: what each step of
// the Newton polish, the SQP and Witkin-Kass evaluates) of the jump at its default guess, on
// `threads` threads.
void BM_LuxoRawRows(benchmark::State& state, int threads) {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  const raw::Variables vars(problem->ceresProblem());
  raw::RawEvaluator evaluator(*problem, vars, threads);
  raw::RawRows rows;
  bool finite = true;
  for (auto _ : state) finite = evaluator.evaluate(&rows, true) && finite;
  state.counters["converged"] = finite ? 1 : 0;  // every row finite
  state.counters["rows"] = static_cast<double>(rows.jacobian.rows());
  state.counters["cols"] = static_cast<double>(rows.jacobian.cols());
}

// One quadratic program of a scene's shape solved by the interior point (quadratic_program.h):
// the program of a Gauss-Newton SQP step at the scene's optimum (found once, by the default
// method), with H = J_r^T J_r, every equality row and the inequality rows within 0.05 of their
// bound, as `sqp` holds them. The same program every time, so the interior point takes the
// same iterations, and the time over qp_iterations is the cost of one of them: K's assembly, its
// LDL^T and the predictor's and corrector's solves. The workspace (K's pattern and analysis) is shared
// between the repetitions, as between an SQP's programs.
void BM_ProgramAtOptimum(benchmark::State& state, const std::string& file) {
  const Scene scene = testing::shippedScene(file);
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  SolverOptions options = solverOptionsFor(scene.solver);
  options.threads = 2;
  solveSpacetime(*problem, options);
  const raw::Variables vars(problem->ceresProblem());
  raw::RawEvaluator evaluator(*problem, vars, 2);
  raw::RawRows rows;
  evaluator.evaluate(&rows, true);
  std::vector<int> objective, equality, held;
  for (int r = 0; r < evaluator.rows(); ++r) {
    const RowKind kind = evaluator.kind(r);
    if (kind == RowKind::Objective) objective.push_back(r);
    else if (kind == RowKind::Equality) equality.push_back(r);
    else if (rows.values[r] > -raw::kMargin) held.push_back(r);
  }
  const int n = static_cast<int>(rows.jacobian.cols());
  raw::Triplets t;
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, 1e-6);
  evaluator.appendGaussNewton(rows, &t);
  QuadraticProgram qp;
  qp.hessian.resize(n, n);
  qp.hessian.setFromTriplets(t.begin(), t.end());
  qp.gradient = raw::transposeTimes(rows.jacobian, objective, raw::selectValues(rows.values, objective));
  qp.equalities = raw::selectRows(rows.jacobian, equality);
  qp.equalityTargets = -raw::selectValues(rows.values, equality);
  qp.inequalities = raw::selectRows(rows.jacobian, held);
  qp.inequalityBounds = -raw::selectValues(rows.values, held);
  QpOptions qpOptions;
  qpOptions.convex = true;
  QpWorkspace workspace;
  QpResult result;
  for (auto _ : state) result = solveQuadraticProgram(qp, qpOptions, &workspace);
  state.counters["converged"] = result.converged ? 1 : 0;
  state.counters["qp_iterations"] = result.iterations;
  state.counters["variables"] = n;
  state.counters["equalities"] = static_cast<double>(equality.size());
  state.counters["inequalities"] = static_cast<double>(held.size());
}

// Building the jump's problem from its scene: what every edit pays before its solve (the editor
// and spacetime-cli build a problem per solve; LuxoWarmResolve leaves it out of its time).
void BM_LuxoProblemBuild(benchmark::State& state) {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  size_t residuals = 0;
  for (auto _ : state) {
    auto problem = SpacetimeProblem::build(scene, &error);
    residuals = problem ? problem->residuals().size() : 0;
  }
  state.counters["converged"] = residuals > 0 ? 1 : 0;  // built
  state.counters["residuals"] = static_cast<double>(residuals);
}

BENCHMARK(BM_LuxoProblemBuild)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Solve, particle, std::string("particle.json"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Solve, particle_gravity, std::string("particle_gravity.json"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Solve, luxo_jump, std::string("luxo_jump.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_jump_2_threads, std::string("luxo_jump.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_jump_without_polish, std::string("luxo_jump.json"), 0, false)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_hurdle, std::string("luxo_hurdle.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_heavy, std::string("luxo_heavy.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_power_formula, std::string("luxo_power_formula.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_jump_2_samples, std::string("luxo_jump.json"), 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_3d, std::string("luxo_3d.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
// The same lamp rooted at its head: its contacts are on a leaf body, so no held stance applies.
BENCHMARK_CAPTURE(BM_Solve, luxo_head_root_2_threads, std::string("test:luxo_head_root.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, particle_ipopt, std::string("particle.json"), 0, true, 1, SolverMethod::InteriorPoint)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_Solve, luxo_jump_sqp_2_threads, std::string("luxo_jump.json"), 0, true, 2, SolverMethod::Sqp)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_jump_ipopt_2_threads, std::string("luxo_jump.json"), 0, true, 2, SolverMethod::InteriorPoint)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_hurdle_ipopt_2_threads, std::string("luxo_hurdle.json"), 0, true, 2, SolverMethod::InteriorPoint)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm, true)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm_without_polish, false)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm, true, 0.10)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm_without_polish, false, 0.10)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm_sqp, true, 0.02, SolverMethod::Sqp)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm_sqp, true, 0.10, SolverMethod::Sqp)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
// Two threads, as spacetime-cli solves (the single-threaded rows above are the editor's).
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm_2_threads, true, 0.02, SolverMethod::AugmentedLagrangian, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm_2_threads, true, 0.10, SolverMethod::AugmentedLagrangian, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_hurdle_2_threads, std::string("luxo_hurdle.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_3d_2_threads, std::string("luxo_3d.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_power_formula_2_threads, std::string("luxo_power_formula.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, luxo_heavy_2_threads, std::string("luxo_heavy.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, biped_jump_2_threads, std::string("biped_jump.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, humanoid_jump_2_threads, std::string("humanoid_jump.json"), 0, true, 2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
// The ladder's rungs that end valid (the longer ones stall for about a minute: scripts/measure.sh
// runs them through the CLI).
BENCHMARK_CAPTURE(BM_Ladder, jump_0_3m, std::string("luxo_jump_0.3m.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Ladder, jump_0_6m, std::string("luxo_jump_0.6m.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Ladder, jump_0_9m, std::string("luxo_jump_0.9m.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Ladder, jump_1_2m, std::string("luxo_jump_1.2m.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Ladder, hurdle_double, std::string("luxo_hurdle_double.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, hops_1, std::string("luxo_hops_1.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, hops_2, std::string("luxo_hops_2.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, hops_3, std::string("luxo_hops_3.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, chain_6, std::string("luxo_chain_6.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, chain_9, std::string("luxo_chain_9.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, chain_12, std::string("luxo_chain_12.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_Scaling, chain_15, std::string("luxo_chain_15.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, hops_1, std::string("luxo_hops_1.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, hops_2, std::string("luxo_hops_2.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, hops_3, std::string("luxo_hops_3.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, chain_6, std::string("luxo_chain_6.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, chain_9, std::string("luxo_chain_9.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, chain_12, std::string("luxo_chain_12.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_ScalingSqp, chain_15, std::string("luxo_chain_15.json"))->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoJacobian, fixed_lift_off, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LuxoJacobian, free_lift_off, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LuxoRawRows, 1_thread, 1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_LuxoRawRows, 2_threads, 2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_ProgramAtOptimum, luxo_jump, std::string("luxo_jump.json"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_ProgramAtOptimum, luxo_3d, std::string("luxo_3d.json"))->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace spacetime

BENCHMARK_MAIN();
