// Solve time of every shipped scene (and of the lamp rooted at its head, tests/scenes/) from its
// default initial guess, and the time of one full residual + Jacobian evaluation of the Luxo
// jump. Run a Release build:
//   ./build/tests/benchmarks/solve_benchmark --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
// and read the *_median rows.
#include <benchmark/benchmark.h>

#include <ceres/crs_matrix.h>
#include <ceres/problem.h>

#include "../shipped_scene.h"
#include "core/scene_io.h"
#include "solver/augmented_lagrangian.h"

namespace spacetime {
namespace {

// With samplesPerSegment > 0 the scene's transcription is overridden (2: a coarser transcription,
// which converges but fails the dense-grid check); polish = false runs the augmented Lagrangian
// without its Newton polish, to measure what the polish saves; threads = 2 is what spacetime-cli
// uses on this 2-core machine (the other rows are single-threaded, as the editor's solver).
void BM_Solve(benchmark::State& state, const std::string& name, int samplesPerSegment = 0,
              bool polish = true, int threads = 1) {
  // "test:NAME" is a scene kept for tests only (tests/scenes/).
  Scene scene = name.rfind("test:", 0) == 0 ? testing::testScene(name.substr(5)) : testing::shippedScene(name);
  if (samplesPerSegment > 0) scene.transcription.samplesPerSegment = samplesPerSegment;
  bool converged = true;
  double violation = 0;
  int iterations = 0, newtonSteps = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::string error;
    auto problem = SpacetimeProblem::build(scene, &error);
    state.ResumeTiming();
    SolverOptions options = solverOptionsFor(scene.solver);  // as spacetime-cli uses them
    options.maxSeconds = 120;
    options.newtonPolish = polish;
    options.threads = threads;
    const SolverSummary s = solveSpacetime(*problem, options);
    converged = converged && s.converged;
    violation = std::max(violation, s.maxViolation);
    iterations = s.iterations;
    newtonSteps = s.newtonSteps;
  }
  state.counters["converged"] = converged ? 1 : 0;
  state.counters["max_violation"] = violation;
  state.counters["lm_iterations"] = iterations;
  state.counters["newton_steps"] = newtonSteps;
}

// What the editor does while an animator drags: luxo_jump solved, then its end pose moved 2 cm
// further (base_x 0.60 -> 0.62) and re-solved warm from the previous solution and multipliers
// (the same structure, so SpacetimeProblem::restore). Timed: the warm re-solve only.
void BM_LuxoWarmResolve(benchmark::State& state, bool polish, double move = 0.02) {
  Scene scene = testing::shippedScene("luxo_jump.json");
  std::string error;
  auto first = SpacetimeProblem::build(scene, &error);
  SolverOptions options = solverOptionsFor(scene.solver);
  options.newtonPolish = polish;
  solveSpacetime(*first, options);
  const SolutionState solved = first->state();
  for (TermSpec& t : scene.terms)
    if (t.id == "end_pose")
      for (auto& [dof, value] : t.values)
        if (dof == "base_x") value += move;
  bool converged = true;
  int iterations = 0, newtonSteps = 0;
  double objective = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto moved = SpacetimeProblem::build(scene, &error);
    const bool restored = moved->restore(solved);
    state.ResumeTiming();
    SolverOptions warm = options;
    warm.warmStart = restored;
    const SolverSummary s = solveSpacetime(*moved, warm);
    converged = converged && restored && s.converged;
    iterations = s.iterations;
    newtonSteps = s.newtonSteps;
    objective = s.objective;
  }
  state.counters["converged"] = converged ? 1 : 0;
  state.counters["lm_iterations"] = iterations;
  state.counters["newton_steps"] = newtonSteps;
  state.counters["objective"] = objective;
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
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm, true)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_2cm_without_polish, false)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm, true, 0.10)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoWarmResolve, end_moved_10cm_without_polish, false, 0.10)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LuxoJacobian, fixed_lift_off, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LuxoJacobian, free_lift_off, true)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace spacetime

BENCHMARK_MAIN();
