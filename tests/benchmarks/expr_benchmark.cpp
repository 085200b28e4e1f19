// Expression tape figures: instructions per second of the compiled tape, node size, and the
// lamp's RNEA as a tape against native code. Run a Release build:
//   ./build/tests/benchmarks/expr_benchmark --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "../shipped_scene.h"
#include "core/expr/eigen_scalar.h"
#include "core/expr/graph.h"
#include "core/expr/tape.h"
#include "core/scene_io.h"
#include "dynamics/algorithms.h"
#include "dynamics/build_model.h"

namespace spacetime::expr {
namespace {

// A random chain of arithmetic and transcendental steps over 8 variables.
Expr buildProgram(Graph& g, int steps) {
  std::mt19937 rng(7);
  std::vector<Expr> pool;
  for (int i = 0; i < 8; ++i) pool.push_back(g.variable(i));
  for (int s = 0; s < steps; ++s) {
    const Expr a = pool[rng() % pool.size()], b = pool[rng() % pool.size()];
    switch (rng() % 6) {
      case 0: pool.push_back(a + b); break;
      case 1: pool.push_back(a * b); break;
      case 2: pool.push_back(a - b * 0.5); break;
      case 3: pool.push_back(sin(a)); break;
      case 4: pool.push_back(a / (b * b + 1.0)); break;
      default: pool.push_back(a * 1.01 + 0.3); break;
    }
  }
  Expr sum = pool.back();
  for (size_t i = pool.size() - 64; i + 1 < pool.size(); ++i) sum = sum + pool[i];
  return sum;
}

void BM_TapeEvaluate(benchmark::State& state) {
  Graph g;
  const Tape tape = Tape::compile(g, {buildProgram(g, 4000)}, true);
  std::vector<double> x(8, 0.3), work;
  double out = 0;
  for (auto _ : state) {
    tape.evaluate(x.data(), 0.0, &out, work);
    benchmark::DoNotOptimize(out);
  }
  state.counters["instructions"] = static_cast<double>(tape.length());
  state.counters["slots"] = static_cast<double>(tape.slotCount());
  state.counters["instr_per_s"] = benchmark::Counter(static_cast<double>(tape.length()) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["bytes_per_node"] = sizeof(Node);
}

Model<double> luxo() {
  const Scene scene = testing::shippedScene("luxo_jump.json");
  return buildModel(scene.characters[0], scene.gravity);
}

// The Luxo lamp's RNEA built symbolically and compiled; compare with BM_NativeRnea.
void BM_SymbolicRneaTape(benchmark::State& state) {
  const Model<double> model = luxo();
  const int n = model.dofCount();
  Graph g;
  std::vector<Expr> z;
  for (int i = 0; i < 3 * n; ++i) z.push_back(g.variable(i));
  Data<Expr> data(model);
  const VecX<Expr> tau = rnea(model, data, z.data(), z.data() + n, z.data() + 2 * n);
  std::vector<Expr> outputs(tau.data(), tau.data() + n);
  const Tape tape = Tape::compile(g, outputs, true);
  std::vector<double> x(3 * n, 0.4), work, out(n);
  for (auto _ : state) {
    tape.evaluate(x.data(), 0.0, out.data(), work);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["nodes"] = static_cast<double>(g.size());
  state.counters["bytes_per_node"] = static_cast<double>(sizeof(Node));
  state.counters["arena_bytes"] = static_cast<double>(g.size() * sizeof(Node));
  state.counters["index_bytes"] = static_cast<double>(g.indexBytes());
  state.counters["tape_length"] = static_cast<double>(tape.length());
}

void BM_NativeRnea(benchmark::State& state) {
  const Model<double> model = luxo();
  const int n = model.dofCount();
  Data<double> data(model);
  std::vector<double> x(3 * n, 0.4);
  for (auto _ : state) {
    const VecX<double>& tau = rnea(model, data, x.data(), x.data() + n, x.data() + 2 * n);
    benchmark::DoNotOptimize(tau.data());
  }
}

BENCHMARK(BM_SymbolicRneaTape)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_NativeRnea)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_TapeEvaluate)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace spacetime::expr

BENCHMARK_MAIN();
