// spacetime: the editor.
//
//   spacetime [SCENE.json]                       opens the editor (default: the Luxo jump)
//   spacetime --screenshot FILE [SCENE.json]     solves (within the scene's time budget), renders the window to FILE, exits
//             [--size WxH] [--time T]            window size; the time shown (default: mid-clip)
//             [--panel NAME]                     a tabbed panel to bring to the front (e.g. Scene)
//
// A scene without a stored solution is solved as soon as it opens, and the motion refines
// on screen while the solver runs.
#include <QApplication>
#include <QDockWidget>
#include <QCommandLineParser>
#include <QMessageBox>
#include <QThread>
#include <QTimer>
#include <algorithm>
#include <cstdio>

#include "ui/main_window.h"

int main(int argc, char** argv) {
  spacetime::ui::useOpenGL33CoreByDefault(4);
  QApplication app(argc, argv);
  QApplication::setOrganizationName("Spacetime");
  QApplication::setApplicationName("Spacetime");

  QCommandLineParser parser;
  parser.setApplicationDescription("Spacetime: physically valid character animation by spacetime constraints.");
  parser.addHelpOption();
  QCommandLineOption screenshot("screenshot", "Solve, render the window to FILE (PNG) and exit.", "FILE");
  QCommandLineOption size("size", "Window size for --screenshot, e.g. 1600x1000.", "WxH", "1600x1000");
  QCommandLineOption time("time", "Time shown in the screenshot (default: the middle of the clip).", "T");
  QCommandLineOption panel("panel", "Panel brought to the front for --screenshot (its title, e.g. Scene or Validity).", "NAME");
  parser.addOptions({screenshot, size, time, panel});
  parser.addPositionalArgument("scene", "Scene file to open (default: the Luxo jump example).", "[SCENE.json]");
  parser.process(app);
  const QString scenePath = parser.positionalArguments().value(0, ":/scenes/luxo_jump.json");

  spacetime::ui::MainWindow window;
  QString error;
  if (parser.isSet(screenshot)) {
    window.solveOnOpen = false;
    qputenv("SPACETIME_NO_RECOVERY", "1");
    const QStringList wh = parser.value(size).split('x');
    window.resize(wh.value(0).toInt() > 0 ? wh.value(0).toInt() : 1600, wh.value(1).toInt() > 0 ? wh.value(1).toInt() : 1000);
  }
  if (!window.openFile(scenePath, &error)) {
    std::fprintf(stderr, "spacetime: %s\n", qPrintable(error));
    if (parser.isSet(screenshot)) return 2;
    QMessageBox::warning(nullptr, "Spacetime", error);
  }
  window.show();
  if (!parser.isSet(screenshot)) return app.exec();

  // Screenshot mode: solve (unless the file holds a solution), show the chosen time, grab.
  if (!window.document()->motion() || !window.document()->motion()->solved) {
    window.solve();
    // As long as the scene's time budget allows the solve, and a minute to check and hand over.
    const double budget = window.document()->scene().solver.maxSeconds + 60;
    window.solverJob()->waitForFinished(static_cast<int>(std::min(budget, 2e6) * 1000));
  }
  const spacetime::Scene& s = window.document()->scene();
  window.document()->setCurrentTime(parser.isSet(time) ? parser.value(time).toDouble() : 0.5 * (s.startTime + s.endTime));
  window.document()->selectBody(0, s.characters.empty() || s.characters[0].bodies.size() < 2 ? std::string() : s.characters[0].bodies.back().id);
  window.viewport()->frameAll();
  if (parser.isSet(panel)) {
    QDockWidget* shown = nullptr;
    for (QDockWidget* d : window.findChildren<QDockWidget*>())
      if (d->windowTitle().compare(parser.value(panel), Qt::CaseInsensitive) == 0) shown = d;
    if (!shown) {
      std::fprintf(stderr, "spacetime: no panel '%s'\n", qPrintable(parser.value(panel)));
      return 2;
    }
    shown->show();
    shown->raise();
  }
  for (int i = 0; i < 20; ++i) {
    QApplication::processEvents();
    QThread::msleep(10);
  }
  const QImage image = window.grab().toImage();
  if (!image.save(parser.value(screenshot))) {
    std::fprintf(stderr, "spacetime: cannot write %s\n", qPrintable(parser.value(screenshot)));
    return 1;
  }
  std::fprintf(stderr, "spacetime: wrote %s (%s)\n", qPrintable(parser.value(screenshot)), qPrintable(window.statusText()));
  return 0;
}
