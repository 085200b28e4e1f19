#include "ui/solver_job.h"

#include <QCoreApplication>
#include <QElapsedTimer>
#include <QPointer>
#include <QThread>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <thread>

#include "core/scene_io.h"
#include "ui/live_pacing.h"

namespace spacetime::ui {
namespace {

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The CPU time the calling thread has run (the solver's share of the cores, for LivePacing).
double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

struct SolverJob::Run {
  int generation = 0;
  std::atomic<bool> cancel{false};
  // A newer run replaced this one: its results are dropped, so its validity report stops early.
  std::atomic<bool> superseded{false};
  std::thread thread;
};

SolverJob::SolverJob(QObject* parent) : QObject(parent) {
  qRegisterMetaType<std::shared_ptr<const SolvedMotion>>();
  qRegisterMetaType<SolverSummary>();
}

SolverJob::~SolverJob() {
  cancel();
  // Wait for every worker; they post through queued calls guarded by QPointer, so none touches
  // this object after it is gone.
  while (alive_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (current_ && current_->thread.joinable()) current_->thread.join();
}

void SolverJob::cancel() {
  if (current_) current_->cancel = true;
}

bool SolverJob::waitForFinished(int timeoutMs) {
  QElapsedTimer timer;
  timer.start();
  auto delivering = [this] {
    std::lock_guard<std::mutex> lock(mutex_);
    return deliveryQueued_;
  };
  while (running_ > 0 || delivering()) {
    if (timer.elapsed() > timeoutMs) return false;
    QCoreApplication::processEvents(QEventLoop::AllEvents, 5);
    QThread::msleep(1);
  }
  QCoreApplication::processEvents();
  return true;
}

void SolverJob::start(const Scene& sceneIn, std::optional<SolutionState> warmStart,
                      std::shared_ptr<const Scene> warmScene, std::optional<SolverMethod> method) {
  if (current_) {
    current_->cancel = true;
    current_->superseded = true;
    current_->thread.detach();  // it ends on its own; its results carry an old generation
  }
  auto run = std::make_shared<Run>();
  run->generation = ++generation_;
  current_ = run;
  ++running_;
  ++alive_;
  QPointer<SolverJob> self(this);
  const int threadCount = threads, liveInterval = liveIntervalMs, longestLiveInterval = longestLiveIntervalMs;
  run->thread = std::thread([this, self, run, scene = sceneIn, warmStart, warmScene, method, threadCount, liveInterval,
                             longestLiveInterval]() {
    // The solver yields to the interface (and, under Xvfb, to the software renderer): on a
    // 2-core machine an equal-priority solver makes the event loop wait for a time slice.
    // SCHED_IDLE runs it only on otherwise idle time; nice 15 alone was not enough once the
    // Luxo scenes collocated at six points per interval (hidden window, luxo_jump: longest
    // event-loop gap 14-167 ms over 14 runs, 13-17 ms with SCHED_IDLE over 6). Nice stays as the
    // fallback where the policy is refused. Linux applies both per thread.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 15);
    sched_param none{};
    pthread_setschedparam(pthread_self(), SCHED_IDLE, &none);
    auto fail = [&](const std::string& why) {
      const QString reason = QString::fromStdString(why);
      const int gen = run->generation;
      QMetaObject::invokeMethod(
          qApp, [self, reason, gen] { if (self && gen == self->generation_) emit self->failed(reason); },
          Qt::QueuedConnection);
    };
    // The scene is checked exactly as a file would be, so an edit the loader would reject
    // reports the same clear message instead of reaching the dynamics.
    Scene snapshot = scene;
    snapshot.solution.reset();
    const SceneLoadResult checked = parseScene(sceneToJson(snapshot), snapshot.name.empty() ? "scene" : snapshot.name);
    std::string error;
    std::unique_ptr<SpacetimeProblem> problem;
    if (!checked.scene) error = checked.error;
    else problem = SpacetimeProblem::build(*checked.scene, &error);
    std::shared_ptr<const SolvedMotion> result;  // the final motion, handed over below
    if (!problem) {
      fail(error);
    } else {
      SolverOptions options = solverOptionsFor(scene.solver);
      if (method) options.method = *method;
      options.threads = threadCount;
      options.warmStart = warmStart && (warmScene ? problem->warmStartFrom(*warmScene, *warmStart) != SpacetimeProblem::WarmStart::None
                                                  : problem->restore(*warmStart));
      // The starting motion, drawn at once - except for a warm start, where it is the motion
      // already on screen, and redrawing it (a whole window under Xvfb) only delays the re-solve.
      if (!options.warmStart) {
        auto first = sampleMotion(*problem);
        const ProblemMeasures m = measure(*problem);
        first->objective = m.objective;
        first->maxViolation = m.maxViolation;
        post(run, first);
      }
      // The problem whose iterates the live view samples: the scene's, then each finer
      // transcription the refinement solves when a motion fails its checks (solveRefined owns
      // them all, and hands back the one whose motion it kept).
      const SpacetimeProblem* solving = problem.get();
      // The converged motion at the scene's own transcription, kept in case a finer one replaces it.
      std::shared_ptr<SolvedMotion> unrefined;
      int transcriptionsSolved = 0;
      // Live iterates as often as the interface's drawing leaves the solver enough of the CPU.
      LivePacing pacing(liveInterval * 1e-3, longestLiveInterval * 1e-3);
      pacing.start(wallSeconds(), threadCpuSeconds());
      const RefinementOptions refinement = refinementOptionsFor(scene.solver);
      RefinedSolve solved = solveRefined(
          std::move(problem), options, refinement,
          [&](const IterationReport& r) {
            if (!pacing.due(wallSeconds(), threadCpuSeconds())) return !run->cancel.load();
            auto motion = sampleMotion(*solving);
            motion->objective = r.objective;
            motion->maxViolation = r.maxViolation;
            motion->iterations = r.iterations;
            post(run, motion);
            return !run->cancel.load();
          },
          &run->cancel, [&](const SpacetimeProblem& next) { solving = &next; },
          [&](const SpacetimeProblem& p, const TranscriptionAttempt& attempt, const ValidityReport& report) {
            // With no refinement allowed this motion is the result itself: not sampled twice.
            if (transcriptionsSolved++ > 0 || !refinement.refines() || !attempt.converged || attempt.valid) return;
            unrefined = sampleMotion(p);
            unrefined->objective = attempt.objective;
            unrefined->maxViolation = attempt.maxViolation;
            unrefined->iterations = attempt.iterations;
            unrefined->solved = unrefined->converged = true;
            unrefined->reason = "converged at the scene's transcription, before the solve refined it";
            unrefined->transcriptions = {attempt};
            unrefined->transcriptions.front().kept = true;
            unrefined->validity = std::make_shared<const ValidityReport>(report);
          });
      problem = std::move(solved.problem);
      const SolverSummary summary = solved.summary;
      auto final = sampleMotion(*problem);
      final->objective = summary.objective;
      final->maxViolation = summary.maxViolation;
      final->iterations = summary.iterations;
      final->solved = true;
      final->converged = summary.converged;
      final->reason = summary.reason;
      final->violated = summary.violated;
      final->transcriptions = solved.attempts;
      final->asked = std::make_shared<const Scene>(snapshot);
      if (!solved.attempts.empty() && !solved.attempts.front().kept) final->unrefined = std::move(unrefined);
      // The refinement checked the motion it kept; a solve stopped by the user was not (the
      // check stops with it), and is checked below, after the motion is on screen.
      if (!solved.validity.cancelled) final->validity = std::make_shared<const ValidityReport>(std::move(solved.validity));
      const int gen = run->generation;
      result = final;
      {
        // The result supersedes an iterate not yet delivered: drawing that iterate first would
        // cost the interface a whole window repaint (~27 ms under Xvfb) before the result shows.
        std::lock_guard<std::mutex> lock(mutex_);
        if (pendingGeneration_ == gen) pending_.reset();
      }
      QMetaObject::invokeMethod(
          qApp,
          [self, result, summary, gen] {
            if (self && gen == self->generation_) emit self->finished(result, summary);
          },
          Qt::QueuedConnection);
    }
    // The solve is over for the interface. Decrement through the event loop, so waitForFinished
    // sees the result (or the failure) first.
    QMetaObject::invokeMethod(qApp, [self] { if (self) --self->running_; }, Qt::QueuedConnection);
    // A cancelled result is on screen now without its validity report (tens of milliseconds for a
    // jump: the dense grid and a forward simulation of every flight); it follows as `validated`.
    if (result && !result->validity) {
      // Once a newer run has replaced this one the report would be dropped; it stops then, rather
      // than slow the new solve down beside it (dragging the Luxo end pose: each report ran next
      // to the following solve on the 2 cores).
      auto report = std::make_shared<const ValidityReport>(checkValidity(*problem, 10, &run->superseded));
      const int gen = run->generation;
      if (!report->cancelled)
        QMetaObject::invokeMethod(
            qApp,
            [self, result, report, gen] {
              if (self && gen == self->generation_) emit self->validated(result, report);
            },
            Qt::QueuedConnection);
    }
    --alive_;  // after this the thread touches nothing of the job
  });
}

void SolverJob::post(const std::shared_ptr<Run>& run, std::shared_ptr<const SolvedMotion> motion) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_ = std::move(motion);
  pendingGeneration_ = run->generation;
  if (deliveryQueued_) return;  // the queued delivery will take the newest iterate
  deliveryQueued_ = true;
  QPointer<SolverJob> self(this);
  QMetaObject::invokeMethod(qApp, [self] { if (self) self->deliver(); }, Qt::QueuedConnection);
}

void SolverJob::deliver() {
  std::shared_ptr<const SolvedMotion> motion;
  int generation;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    motion = std::move(pending_);
    generation = pendingGeneration_;
    deliveryQueued_ = false;
  }
  if (motion && generation == generation_) emit iterate(motion);
}

}  // namespace spacetime::ui
