// The longest the interface's event loop waits during a solve: a 5 ms timer ticks while the
// solver job runs, and the largest interval between ticks is the worst stall a user would feel.
// Shared by the editor's Qt Test (which asserts the hidden-window figure) and the editor
// benchmark (which reports the shown-window figures as medians).
#pragma once

#include <QElapsedTimer>
#include <QTimer>
#include <QtTest>
#include <algorithm>

#include "ui/main_window.h"

namespace spacetime::ui {

// How the window is while the event loop is measured.
enum class WindowMode { Hidden, Shown, ShownPlaying };

struct EventLoopGap {
  qint64 worstMs = -1;
  qint64 worstEndedAtMs = -1;  // when the longest wait ended, from the start of the solve
  int iterates = 0;            // solver iterates that reached the interface
  int iteratesBeforeWorst = 0;
};

// Solves the window's scene from its current state and watches the event loop for the first
// `milliseconds` of the solve (or until it ends); then stops the solve. With ShownPlaying the
// timeline plays meanwhile, so every iterate and every frame is drawn.
inline EventLoopGap eventLoopGapDuringSolve(MainWindow& w, WindowMode mode, int milliseconds = 4000) {
  if (mode == WindowMode::ShownPlaying) w.timeline()->play();
  EventLoopGap gap;
  auto counter = QObject::connect(w.solverJob(), &SolverJob::iterate, &w, [&] { ++gap.iterates; });
  w.solve();
  QElapsedTimer clock, sinceTick;
  clock.start();
  sinceTick.start();
  qint64 worst = 0;
  QTimer timer;
  timer.setInterval(5);
  QObject::connect(&timer, &QTimer::timeout, [&] {
    const qint64 waited = sinceTick.restart();
    if (waited > worst) {
      worst = waited;
      gap.worstEndedAtMs = clock.elapsed();
      gap.iteratesBeforeWorst = gap.iterates;
    }
  });
  timer.start();
  while (clock.elapsed() < milliseconds && w.solverJob()->isRunning()) QTest::qWait(20);
  timer.stop();
  w.stopSolve();
  w.solverJob()->waitForFinished(30000);
  if (mode == WindowMode::ShownPlaying) w.timeline()->pause();
  QObject::disconnect(counter);
  gap.worstMs = worst;
  return gap;
}

}  // namespace spacetime::ui
