// The solver as a background job: a snapshot of the scene (and a warm start) goes to a worker
// thread; every iterate comes back to the interface thread as an immutable SolvedMotion (latest
// wins: iterates the interface has not drawn yet are replaced, never queued); Stop sets an
// atomic flag the solver checks every iteration. Starting a new solve while one runs cancels
// the old one, whose late results are dropped - that is auto-solve while dragging.
// The solve refines its transcription where the motion fails its validity checks, as the
// command line's does (solveRefined, up to the scene's solver.maxRefinements): the result carries the transcriptions it tried and is
// checked already, and the document adopts the finer transcription (Document::acceptResult).
#pragma once

#include <QObject>
#include <QString>
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>

#include "core/scene.h"
#include "solver/augmented_lagrangian.h"
#include "solver/refinement.h"
#include "ui/solved_motion.h"

namespace spacetime::ui {

class SolverJob : public QObject {
  Q_OBJECT
 public:
  explicit SolverJob(QObject* parent = nullptr);
  ~SolverJob() override;  // cancels and waits for the worker

  // Solves `scene` from `warmStart` if it fits the problem (else from the default initial
  // guess). The scene is validated as a file would be; an invalid one ends in failed().
  // Warm start: `warmStart` is restored when the problem has its shape; otherwise, with the
  // scene it was solved for, its motion is re-fitted (SpacetimeProblem::initializeFrom).
  // `method` replaces the scene's solver.method for this solve.
  void start(const Scene& scene, std::optional<SolutionState> warmStart = std::nullopt,
             std::shared_ptr<const Scene> warmScene = nullptr, std::optional<SolverMethod> method = std::nullopt);
  void cancel();
  bool isRunning() const { return running_ > 0; }
  // Blocks (processing events) until no solve runs and its result is delivered; false on
  // timeout. The result's validity report may still be on its way (`validated`).
  bool waitForFinished(int timeoutMs);

  // Ceres evaluation threads. One by default: on a 2-core machine the other core stays with the
  // interface, which must never stall while the solver runs.
  int threads = 1;
  // Shortest time between two live iterates handed to the interface. Drawing one costs whole-
  // window composites; the interval grows up to longestLiveIntervalMs while that starves the
  // solver (LivePacing).
  int liveIntervalMs = 250;
  int longestLiveIntervalMs = 2000;

 signals:
  void iterate(std::shared_ptr<const spacetime::ui::SolvedMotion> motion);
  void finished(std::shared_ptr<const spacetime::ui::SolvedMotion> motion,
                const spacetime::SolverSummary& summary);
  void failed(const QString& reason);
  // The validity report of a motion whose solve was cancelled (Stop), computed after it was
  // handed over (any other result carries its report).
  void validated(std::shared_ptr<const spacetime::ui::SolvedMotion> motion,
                 std::shared_ptr<const spacetime::ValidityReport> report);

 private:
  struct Run;
  void post(const std::shared_ptr<Run>& run, std::shared_ptr<const SolvedMotion> motion);
  void deliver();  // emits the pending iterate, if it belongs to the current solve

  std::shared_ptr<Run> current_;
  std::atomic<int> running_{0};  // solves whose end the interface has not yet seen
  std::atomic<int> alive_{0};    // worker threads still running code
  int generation_ = 0;
  std::mutex mutex_;  // guards the pending iterate below
  std::shared_ptr<const SolvedMotion> pending_;
  int pendingGeneration_ = -1;
  bool deliveryQueued_ = false;
};

}  // namespace spacetime::ui

Q_DECLARE_METATYPE(std::shared_ptr<const spacetime::ui::SolvedMotion>)
Q_DECLARE_METATYPE(spacetime::SolverSummary)
