// Expression tape figures (issue 4): instructions per second of the compiled tape, reverse-mode
// gradient cost relative to one evaluation, and node size. Run a Release build:
//   ./build/tests/benchmarks/expr_benchmark --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "core/expr/graph.h"
#include "core/expr/tape.h"

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

void BM_TapeGradient(benchmark::State& state) {
  Graph g;
  const Tape tape = Tape::compile(g, {buildProgram(g, 4000)}, false);
  std::vector<double> x(8, 0.3), grad(8), work, adjoint;
  for (auto _ : state) {
    tape.gradient(x.data(), 0.0, 0, grad.data(), 8, work, adjoint);
    benchmark::DoNotOptimize(grad.data());
  }
  state.counters["instructions"] = static_cast<double>(tape.length());
}

BENCHMARK(BM_TapeEvaluate)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TapeGradient)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace spacetime::expr

BENCHMARK_MAIN();
