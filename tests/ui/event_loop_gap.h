// The longest the interface's event loop waits during a solve: a 5 ms timer ticks while the
// solver job runs, and the largest interval between ticks is the worst stall a user would feel.
// Shared by the editor's Qt Test (which asserts the hidden-window figure) and the editor
// benchmark (which reports the shown-window figures as medians). WindowPaintCounter counts the
// paints of a whole window, for the test that an iterate is drawn without forced paints.
#pragma once

#include <QElapsedTimer>
#include <QEventLoop>
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

// Counts the UpdateRequests a window receives: each is a paint and flush of the whole window.
struct WindowPaintCounter : QObject {
  int count = 0;
  bool eventFilter(QObject*, QEvent* e) override {
    if (e->type() == QEvent::UpdateRequest) ++count;
    return false;
  }
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
  // A real event loop, as the editor's: it sleeps in poll() until the next event. QTest::qWait
  // would not do: between its passes it sleeps 10 ms with the loop stopped, which adds up to
  // 10 ms to every measured wait and lets timers, iterates and repaints pile up.
  QEventLoop loop;
  QTimer watch;
  watch.setInterval(20);
  QObject::connect(&watch, &QTimer::timeout, [&] {
    if (clock.elapsed() >= milliseconds || !w.solverJob()->isRunning()) loop.quit();
  });
  timer.start();
  watch.start();
  loop.exec();
  watch.stop();
  timer.stop();
  w.stopSolve();
  w.solverJob()->waitForFinished(30000);
  if (mode == WindowMode::ShownPlaying) w.timeline()->pause();
  QObject::disconnect(counter);
  gap.worstMs = worst;
  return gap;
}

}  // namespace spacetime::ui
