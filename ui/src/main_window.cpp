#include "ui/main_window.h"

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDir>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QJsonDocument>
#include <QJsonObject>
#include <QAbstractSpinBox>
#include <QKeyEvent>
#include <QLayout>
#include <QLineEdit>
#include <QLockFile>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QPointer>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QToolBar>
#include <QUuid>

#include "core/atomic_file.h"
#include "core/scene_io.h"
#include "dynamics/build_model.h"
#include "interop/urdf_export.h"
#include "interop/bvh_export.h"
#include "interop/gltf_export.h"
#include "interop/motion_import.h"
#include "interop/outputs.h"
#include "solver/motion_source.h"

namespace spacetime::ui {

namespace {
QString autosaveDirectory() {
  return QStandardPaths::writableLocation(QStandardPaths::AppLocalDataLocation) + "/autosave";
}

bool sameTranscription(const TranscriptionSpec& a, const TranscriptionSpec& b) {
  return a.controlPointsPerSecond == b.controlPointsPerSecond && a.samplesPerSegment == b.samplesPerSegment &&
         a.knots == b.knots && a.legBubbles == b.legBubbles;
}
}  // namespace

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setObjectName("mainWindow");
  setAcceptDrops(true);
  autosaveId_ = QUuid::createUuid().toString(QUuid::WithoutBraces);
  QDir().mkpath(autosaveDirectory());
  autosaveLock_ = std::make_unique<QLockFile>(autosaveDirectory() + "/" + autosaveId_ + ".lock");
  autosaveLock_->tryLock(0);

  viewport_ = new Viewport(&doc_);
  setCentralWidget(viewport_);
  auto dock = [this](const QString& title, const char* name, QWidget* w, Qt::DockWidgetArea area) {
    auto* d = new QDockWidget(title, this);
    d->setObjectName(name);
    d->setWidget(w);
    addDockWidget(area, d);
    return d;
  };
  builder_ = new BuilderPanel(&doc_);
  connect(builder_, &BuilderPanel::said, this, [this](const QString& m) { progress_->setText(m); });
  constraints_ = new ConstraintsPanel(&doc_);
  connect(constraints_, &ConstraintsPanel::said, this, [this](const QString& m) { progress_->setText(m); });
  connect(constraints_, &ConstraintsPanel::pickContactPoint, this, [this](const std::string& term) {
    viewport_->setContactPointTool(term);
    progress_->setText(tr("Click the body where contact '%1' gets a new point").arg(QString::fromStdString(term)));
  });
  connect(viewport_, &Viewport::contactPointToolDone, this, [this](const QString& term, bool added) {
    progress_->setText(added ? tr("Contact '%1': point added (Ctrl+Z removes it)").arg(term)
                             : tr("Contact '%1': the click missed its body, no point added").arg(term));
  });
  timeline_ = new Timeline(&doc_);
  graphs_ = new GraphPanel(&doc_);
  QDockWidget* builderDock = dock(tr("Builder"), "builderDock", builder_, Qt::LeftDockWidgetArea);
  sceneSettings_ = new SceneSettingsPanel(&doc_);
  QDockWidget* sceneDock = dock(tr("Scene"), "sceneDock", sceneSettings_, Qt::LeftDockWidgetArea);
  tabifyDockWidget(builderDock, sceneDock);
  builderDock->raise();
  connect(constraints_, &ConstraintsPanel::showBuilder, builderDock, [builderDock] {
    builderDock->show();
    builderDock->raise();
  });
  QDockWidget* constraintsDock = dock(tr("Constraints"), "constraintsDock", constraints_, Qt::RightDockWidgetArea);
  QDockWidget* timelineDock = dock(tr("Timeline"), "timelineDock", timeline_, Qt::BottomDockWidgetArea);
  QDockWidget* graphDock = dock(tr("Graphs"), "graphDock", graphs_, Qt::BottomDockWidgetArea);
  validity_ = new ValidityPanel(&doc_);
  QDockWidget* validityDock = dock(tr("Validity"), "validityDock", validity_, Qt::RightDockWidgetArea);
  tabifyDockWidget(constraintsDock, validityDock);
  constraintsDock->raise();
  splitDockWidget(timelineDock, graphDock, Qt::Vertical);
  resizeDocks({builderDock, constraintsDock}, {300, 300}, Qt::Horizontal);
  resizeDocks({timelineDock, graphDock}, {100, 330}, Qt::Vertical);

  progress_ = new QLabel(tr("Ready"));
  statusBar()->addPermanentWidget(progress_, 1);
  // While a solve runs: how far the constraint violation has fallen towards the tolerance.
  solveProgress_ = new QProgressBar;
  solveProgress_->setObjectName("solveProgress");
  solveProgress_->setRange(0, 1000);
  solveProgress_->setMinimumWidth(240);
  solveProgress_->setToolTip(tr("The largest constraint violation on a log scale, from the first iterate's to the "
                                "solver tolerance: an estimate of how far the solve has come"));
  solveProgress_->hide();
  statusBar()->addPermanentWidget(solveProgress_);

  createActions();
  for (QDockWidget* d : {builderDock, sceneDock, constraintsDock, validityDock, timelineDock, graphDock})
    findChild<QMenu*>("viewMenu")->addAction(d->toggleViewAction());

  connect(&job_, &SolverJob::iterate, this, [this](std::shared_ptr<const SolvedMotion> m) {
    doc_.setMotion(m);
    // The refinement solves again on a finer transcription: the status says so, and the
    // progress towards the tolerance starts again there.
    QString finer;
    if (m->scene) {
      const TranscriptionSpec& t = m->scene->transcription;
      if (progressTranscription_ && !sameTranscription(*progressTranscription_, t))
        progressEstimate_ = SolveProgress(doc_.scene().solver.tolerance);
      progressTranscription_ = t;
      if (!sameTranscription(t, doc_.scene().transcription))
        finer = tr(" · on a finer transcription: %1 segments, s = %2")
                    .arg(std::lround(t.segments(m->scene->startTime, m->scene->endTime)))
                    .arg(t.samplesPerSegment);
    }
    progress_->setText(tr("Solving… iteration %1 · objective %2 · violation %3%4")
                           .arg(m->iterations).arg(m->objective, 0, 'g', 6).arg(m->maxViolation, 0, 'g', 3).arg(finer));
    const double done = progressEstimate_.update(m->maxViolation);
    showSolveProgress(static_cast<int>(std::lround(1000 * done)),
                      tr("%1 % of the way to the tolerance").arg(std::lround(100 * done)));
  });
  connect(&job_, &SolverJob::finished, this, [this](std::shared_ptr<const SolvedMotion> m, const SolverSummary& s) {
    const bool shown = doc_.acceptResult(m);
    progress_->setText(tr("%1 after %2 iterations (%3 s) · objective %4 · violation %5 · %6%7")
                           .arg(s.converged ? tr("Converged") : tr("Stopped"))
                           .arg(s.iterations).arg(s.solveSeconds, 0, 'f', 2)
                           .arg(s.objective, 0, 'g', 6).arg(s.maxViolation, 0, 'g', 3)
                           .arg(QString::fromStdString(s.reason))
                           .arg(shown ? QString() : tr(" · showing the last converged motion (Solve ▸ Show the stopped result)")));
    showStoppedAction_->setEnabled(doc_.stoppedMotion() != nullptr);
    solveAction_->setEnabled(true);
    stopAction_->setEnabled(false);
    solveProgress_->hide();
  });
  connect(&job_, &SolverJob::validated, this,
          [this](std::shared_ptr<const SolvedMotion> m, std::shared_ptr<const ValidityReport> report) {
            doc_.attachValidity(m.get(), std::move(report));
          });
  connect(&job_, &SolverJob::failed, this, [this](const QString& why) {
    progress_->setText(tr("Cannot solve: %1").arg(why));
    solveAction_->setEnabled(true);
    stopAction_->setEnabled(false);
    solveProgress_->hide();
  });
  resolveTimer_.setSingleShot(true);
  resolveTimer_.setInterval(0);
  connect(&resolveTimer_, &QTimer::timeout, this, &MainWindow::solve);
  // Undo and redo to a scene whose converged motion the document remembers show it at once: no
  // re-solve (it would only find the same motion again, or stall where it had converged).
  connect(doc_.undoStack(), &QUndoStack::indexChanged, this, [this] {
    if (autoSolve_ && !doc_.showsSolutionOfScene()) resolveTimer_.start();
  });
  connect(doc_.undoStack(), &QUndoStack::cleanChanged, this, &MainWindow::updateTitle);
  connect(&doc_, &Document::filePathChanged, this, &MainWindow::updateTitle);
  autosaveTimer_.setInterval(30000);
  connect(&autosaveTimer_, &QTimer::timeout, this, &MainWindow::writeAutosave);
  autosaveTimer_.start();
  autosaveSoon_.setSingleShot(true);
  autosaveSoon_.setInterval(kAutosaveDelayMs);
  connect(&autosaveSoon_, &QTimer::timeout, this, &MainWindow::writeAutosave);
  connect(doc_.undoStack(), &QUndoStack::indexChanged, &autosaveSoon_, qOverload<>(&QTimer::start));

  QSettings settings;
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
  resize(settings.contains("window/geometry") ? size() : QSize(1500, 950));
  updateTitle();
  QTimer::singleShot(0, this, &MainWindow::offerRecovery);
  qApp->installEventFilter(this);  // the undo keys in focused fields (eventFilter)
}

namespace {
// `keys` with `more` appended, each once.
QList<QKeySequence> withKeys(QList<QKeySequence> keys, const QList<QKeySequence>& more) {
  for (const QKeySequence& k : more)
    if (!keys.contains(k)) keys.append(k);
  return keys;
}
}  // namespace

// Ctrl+Z and the redo keys in a focused text or number field undo the scene, not the field's
// text: an edit is committed as soon as it is made, so the field's own undo would only make its
// text disagree with the scene. A text field's ShortcutOverride takes these keys before the
// window's shortcuts; stopped here, unaccepted, the window's Undo and Redo run instead.
bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::ShortcutOverride) {
    auto* widget = qobject_cast<QWidget*>(watched);
    const auto* key = static_cast<QKeyEvent*>(event);
    const QKeySequence pressed(key->keyCombination());
    const bool undoOrRedo = key->matches(QKeySequence::Undo) || key->matches(QKeySequence::Redo) ||
                            pressed == QKeySequence(Qt::CTRL | Qt::Key_Y) ||
                            pressed == QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z);
    if (undoOrRedo && widget && isAncestorOf(widget) &&
        (qobject_cast<QLineEdit*>(widget) || qobject_cast<QAbstractSpinBox*>(widget)))
      return true;
  }
  return QMainWindow::eventFilter(watched, event);
}

MainWindow::~MainWindow() {
  qApp->removeEventFilter(this);
  job_.cancel();
  // C++ destroys the members (the document, the job, the timers) before the QWidget base deletes
  // the child widgets, and those panels and this window's slots use the document. Left to that
  // order, the undo stack's clear() at the document's end ran this window's slots on destroyed
  // timers, and a panel being deleted could edit a destroyed document: heap corruption
  // ("malloc_consolidate(): unaligned fastbin chunk detected") after a test's window closed.
  // So: no signal of the document or the job reaches anything from here on, and the widgets
  // go while the document they show is whole.
  doc_.undoStack()->disconnect();
  doc_.disconnect();
  job_.disconnect();
  autosaveTimer_.stop();
  autosaveSoon_.stop();
  resolveTimer_.stop();
  QList<QPointer<QObject>> children;
  for (QObject* child : this->children())
    if (!qobject_cast<QLayout*>(child)) children.append(child);  // the window's own layout stays
  for (const QPointer<QObject>& child : children) delete child.data();
}

void MainWindow::createActions() {
  auto action = [this](QMenu* menu, const QString& text, const QKeySequence& key, auto slot) {
    QAction* a = menu->addAction(text);
    a->setShortcut(key);
    connect(a, &QAction::triggered, this, slot);
    addAction(a);
    return a;
  };
  QMenu* file = menuBar()->addMenu(tr("&File"));
  action(file, tr("&New"), QKeySequence::New, [this] {
    if (!maybeSave()) return;
    job_.cancel();
    Scene s;
    s.name = "untitled";
    // The shipped jumps' starting resolution and budget, not the file format's defaults: a lamp
    // built in the editor failed the dense-grid check at 2 samples per segment (1.04 x weight)
    // and passed every check at 6 (4.8 s).
    s.transcription.samplesPerSegment = 6;
    s.solver.maxOuterIterations = 100;
    doc_.reset(s, {});
    progress_->setText(tr("Ready"));  // not the previous scene's result
    showStoppedAction_->setEnabled(false);
  });
  action(file, tr("&Open…"), QKeySequence::Open, [this] {
    if (!maybeSave()) return;
    const QString path = QFileDialog::getOpenFileName(this, tr("Open scene"), {}, tr("Spacetime scenes (*.json)"));
    QString error;
    if (!path.isEmpty() && !openFile(path, &error)) QMessageBox::warning(this, tr("Open"), error);
  });
  // Every shipped scene, by its name; it opens untitled, so Save asks where to keep the copy.
  QMenu* examples = file->addMenu(tr("Open E&xample"));
  examples->setObjectName("examplesMenu");
  for (const QFileInfo& info : QDir(":/scenes").entryInfoList({"*.json"}, QDir::Files, QDir::Name)) {
    QFile f(info.filePath());
    const QString name = f.open(QIODevice::ReadOnly) ? QJsonDocument::fromJson(f.readAll()).object().value("name").toString() : QString();
    const QString path = info.filePath();
    examples->addAction(name.isEmpty() ? info.baseName() : name, this, [this, path] {
      if (!maybeSave()) return;
      QString error;
      if (!openFile(path, &error)) QMessageBox::warning(this, tr("Open"), error);
    });
  }
  recentMenu_ = file->addMenu(tr("Open &Recent"));
  rebuildRecentMenu();
  auto saveAs = [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Save scene"), doc_.filePath().isEmpty() ? "scene.json" : doc_.filePath(), tr("Spacetime scenes (*.json)"));
    QString error;
    if (!path.isEmpty() && !saveFile(path, &error)) QMessageBox::warning(this, tr("Save"), error);
  };
  action(file, tr("&Save"), QKeySequence::Save, [this, saveAs] {
    if (doc_.filePath().isEmpty()) return saveAs();
    QString error;
    if (!saveFile(doc_.filePath(), &error)) QMessageBox::warning(this, tr("Save"), error);
  });
  QAction* saveAsAction = action(file, tr("Save &As…"), QKeySequence::SaveAs, saveAs);
  // Blender's and most editors' binding, whatever the platform theme maps SaveAs to.
  saveAsAction->setShortcuts(withKeys(QKeySequence::keyBindings(QKeySequence::SaveAs), {QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S)}));
  file->addSeparator();
  QMenu* importMenu = file->addMenu(tr("&Import"));
  action(importMenu, tr("Start from Motion (JSON)…"), QKeySequence(), [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Start from a motion"), QString(), tr("Motion (*.json)"));
    QString error;
    if (!path.isEmpty() && !importMotionJson(path, &error)) QMessageBox::warning(this, tr("Start from a motion"), error);
  });
  QMenu* exportMenu = file->addMenu(tr("&Export"));
  auto exportTo = [this](const QString& title, const QString& name, const QString& filter,
                         bool (MainWindow::*fn)(const QString&, QString*)) {
    return [=, this] {
      const QString path = QFileDialog::getSaveFileName(this, title, name, filter);
      if (path.isEmpty()) return;
      QString error;
      if (!(this->*fn)(path, &error)) QMessageBox::warning(this, title, error);
      else progress_->setText(tr("Exported %1").arg(QDir::toNativeSeparators(path)));
    };
  };
  action(exportMenu, tr("Motion (JSON)…"), QKeySequence(), exportTo(tr("Export motion"), "motion.json", "JSON (*.json)", &MainWindow::exportMotionJson));
  action(exportMenu, tr("Motion (CSV)…"), QKeySequence(), exportTo(tr("Export motion"), "motion.csv", "CSV (*.csv)", &MainWindow::exportMotionCsv));
  auto exportDir = [this](const QString& title, bool (MainWindow::*fn)(const QString&, QString*)) {
    return [=, this] {
      const QString dir = QFileDialog::getExistingDirectory(this, title);
      if (dir.isEmpty()) return;
      QString error;
      if (!(this->*fn)(dir, &error)) QMessageBox::warning(this, title, error);
      else progress_->setText(tr("Exported into %1").arg(QDir::toNativeSeparators(dir)));
    };
  };
  action(exportMenu, tr("Animated scene (glTF)…"), QKeySequence(), exportTo(tr("Export glTF"), "motion.glb", "glTF binary (*.glb)", &MainWindow::exportGltf));
  action(exportMenu, tr("URDF…"), QKeySequence(), exportDir(tr("Export URDF"), &MainWindow::exportUrdf));
  action(exportMenu, tr("Motion (BVH)…"), QKeySequence(), exportDir(tr("Export BVH"), &MainWindow::exportBvh));
  // PNG frames at a resolution picked first: the viewport's, or a video size.
  action(exportMenu, tr("PNG image sequence…"), QKeySequence(), [this] {
    const QSize viewportSize = viewport_->size() * viewport_->devicePixelRatio();
    const QStringList sizes = {tr("Viewport (%1×%2)").arg(viewportSize.width()).arg(viewportSize.height()),
                               "1280×720", "1920×1080", "3840×2160"};
    bool ok = false;
    const QString picked = QInputDialog::getItem(this, tr("Export images"), tr("Resolution"), sizes, 2, false, &ok);
    if (!ok) return;
    const int index = static_cast<int>(sizes.indexOf(picked));
    const QSize size = index <= 0 ? QSize() : QSize(picked.section(QChar(0xD7), 0, 0).toInt(), picked.section(QChar(0xD7), 1, 1).toInt());
    const QString dir = QFileDialog::getExistingDirectory(this, tr("Export images"));
    if (dir.isEmpty()) return;
    QString error;
    if (!exportImageSequence(dir, &error, size)) QMessageBox::warning(this, tr("Export images"), error);
    else progress_->setText(tr("Exported %1 × %2 images into %3")
                                .arg(size.isValid() ? size.width() : viewportSize.width())
                                .arg(size.isValid() ? size.height() : viewportSize.height())
                                .arg(QDir::toNativeSeparators(dir)));
  });
  file->addSeparator();
  action(file, tr("&Quit"), QKeySequence::Quit, [this] { close(); });

  QMenu* edit = menuBar()->addMenu(tr("&Edit"));
  QAction* undo = doc_.undoStack()->createUndoAction(this, tr("&Undo"));
  undo->setShortcut(QKeySequence::Undo);
  QAction* redo = doc_.undoStack()->createRedoAction(this, tr("&Redo"));
  redo->setShortcuts(withKeys(QKeySequence::keyBindings(QKeySequence::Redo),
                              {QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z), QKeySequence(Qt::CTRL | Qt::Key_Y)}));
  edit->addAction(undo);
  edit->addAction(redo);
  edit->addSeparator();
  QAction* pinTool = action(edit, tr("Add &pin by clicking a body"), QKeySequence(Qt::Key_P), [this] { viewport_->setPinTool(true); });
  // The pose tool (R, as Blender's rotate): drags on bodies turn their joints; K keys the pose.
  QAction* poseTool = edit->addAction(tr("Pose: drag a body to tu&rn its joint"));
  poseTool->setObjectName("poseTool");
  poseTool->setCheckable(true);
  poseTool->setShortcut(QKeySequence(Qt::Key_R));
  poseTool->setToolTip(tr("Drag a body around the ring at its joint to turn the joint; K keys the pose, "
                                 "changing the time drops it"));
  connect(poseTool, &QAction::toggled, this, [this](bool on) {
    viewport_->setPoseTool(on);
    if (on) progress_->setText(tr("Pose: drag a body to turn its joint, K keys the pose"));
  });
  action(edit, tr("&Key the current pose"), QKeySequence(Qt::Key_K), [this] { constraints_->keyCurrentPose(); });
  action(edit, tr("&Delete term"), QKeySequence::Delete, [this] { constraints_->removeSelected(); });

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->setObjectName("viewMenu");
  action(view, tr("&Frame all"), QKeySequence(Qt::Key_Home), [this] { viewport_->frameAll(); });
  action(view, tr("Front"), QKeySequence(Qt::KeypadModifier | Qt::Key_1), [this] { viewport_->camera().front(); viewport_->update(); });
  action(view, tr("Side"), QKeySequence(Qt::KeypadModifier | Qt::Key_3), [this] { viewport_->camera().side(); viewport_->update(); });
  action(view, tr("Top"), QKeySequence(Qt::KeypadModifier | Qt::Key_7), [this] { viewport_->camera().top(); viewport_->update(); });
  action(view, tr("Perspective / orthographic"), QKeySequence(Qt::KeypadModifier | Qt::Key_5), [this] {
    viewport_->camera().orthographic = !viewport_->camera().orthographic;
    viewport_->update();
  });
  view->addSeparator();
  auto toggle = [&](const QString& text, bool on, std::function<void(bool)> set) {
    QAction* a = view->addAction(text);
    a->setCheckable(true);
    a->setChecked(on);
    connect(a, &QAction::toggled, this, [this, set](bool v) { set(v); viewport_->invalidate(); });
  };
  toggle(tr("Ghosts"), true, [this](bool v) { viewport_->options().ghosts = v ? 2 : 0; });
  toggle(tr("Motion trail"), true, [this](bool v) { viewport_->options().trail = v; });
  toggle(tr("Centre-of-mass path"), true, [this](bool v) { viewport_->options().centerOfMass = v; });
  toggle(tr("Contact forces"), true, [this](bool v) { viewport_->options().forces = v; });
  QAction* follow = view->addAction(tr("Follow the character"));
  follow->setObjectName("followCharacter");
  follow->setCheckable(true);
  follow->setShortcut(QKeySequence(Qt::Key_F));
  follow->setToolTip(tr("The camera moves with the selected character's centre of mass as the time changes"));
  connect(follow, &QAction::toggled, this, [this](bool on) { viewport_->setFollow(on); });
  view->addSeparator();

  QMenu* play = menuBar()->addMenu(tr("&Playback"));
  action(play, tr("Play / pause"), QKeySequence(Qt::Key_Space), [this] { timeline_->togglePlay(); });
  action(play, tr("Next frame"), QKeySequence(Qt::Key_Right), [this] { timeline_->step(1); });
  action(play, tr("Previous frame"), QKeySequence(Qt::Key_Left), [this] { timeline_->step(-1); });
  action(play, tr("Go to the start"), QKeySequence(Qt::SHIFT | Qt::Key_Left), [this] { doc_.setCurrentTime(doc_.scene().startTime); });
  action(play, tr("Go to the end"), QKeySequence(Qt::SHIFT | Qt::Key_Right), [this] { doc_.setCurrentTime(doc_.scene().endTime); });

  QMenu* solveMenu = menuBar()->addMenu(tr("&Solve"));
  solveAction_ = action(solveMenu, tr("&Solve"), QKeySequence(Qt::Key_F5), [this] { solve(); });
  stopAction_ = action(solveMenu, tr("S&top"), QKeySequence(Qt::Key_Escape), [this] { stopSolve(); });
  stopAction_->setEnabled(false);
  showStoppedAction_ = solveMenu->addAction(tr("Show the stopped &result"));
  showStoppedAction_->setToolTip(tr("A solve that stops without converging keeps the last converged motion on show; "
                                    "this shows the stopped one instead, to inspect it or continue from it"));
  showStoppedAction_->setEnabled(false);
  connect(showStoppedAction_, &QAction::triggered, this, [this] {
    doc_.showStoppedMotion();
    showStoppedAction_->setEnabled(false);
  });
  autoSolveAction_ = solveMenu->addAction(tr("&Auto-solve after every edit"));
  autoSolveAction_->setCheckable(true);
  autoSolveAction_->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_R));
  connect(autoSolveAction_, &QAction::toggled, this, [this](bool on) { setAutoSolve(on); });

  QToolBar* bar = addToolBar(tr("Main"));
  bar->setObjectName("mainToolBar");
  for (QAction* a : {solveAction_, stopAction_, autoSolveAction_}) bar->addAction(a);
  bar->addSeparator();
  bar->addAction(undo);
  bar->addAction(redo);
  bar->addSeparator();
  bar->addAction(pinTool);
  bar->addAction(poseTool);
  pinTool->setCheckable(true);
  connect(viewport_, &Viewport::pinToolUsed, pinTool, [pinTool] { pinTool->setChecked(false); });
}

QString MainWindow::statusText() const { return progress_->text(); }

void MainWindow::updateTitle() {
  const QString name = doc_.filePath().isEmpty() ? QString::fromStdString(doc_.scene().name) : QFileInfo(doc_.filePath()).fileName();
  setWindowTitle(QString("%1%2 — Spacetime").arg(name, doc_.isModified() ? "*" : ""));
}

bool MainWindow::openFile(const QString& path, QString* error) {
  job_.cancel();
  if (!doc_.open(path, error)) return false;
  progress_->setText(doc_.motion() ? tr("Opened with its solved motion") : tr("Ready"));
  showStoppedAction_->setEnabled(false);
  if (!path.startsWith(":/")) addRecent(path);
  viewport_->frameAll();
  if (solveOnOpen && !doc_.motion()) solve();
  return true;
}

bool MainWindow::saveFile(const QString& path, QString* error) {
  if (!doc_.saveAs(path, error)) return false;
  addRecent(path);
  QFile::remove(autosavePath());
  updateTitle();
  return true;
}

void MainWindow::solve() {
  std::optional<SolutionState> warm;
  std::shared_ptr<const Scene> warmScene;
  if (doc_.motion()) {
    warm = doc_.motion()->state;
    warmScene = doc_.motion()->scene;
  }
  // A motion fitted to a motion file has no multipliers: its method as methodForMotionStart says.
  std::optional<SolverMethod> method;
  if (doc_.motion() && doc_.motion()->fromMotionFile)
    method = methodForMotionStart(solverOptionsFor(doc_.scene().solver).method);
  job_.start(doc_.scene(), warm, warmScene, method);
  solveAction_->setEnabled(false);
  stopAction_->setEnabled(true);
  progress_->setText(tr("Solving…"));
  progressEstimate_ = SolveProgress(doc_.scene().solver.tolerance);
  progressTranscription_.reset();
  showSolveProgress(0, tr("starting"));
  solveProgress_->show();
}

void MainWindow::showSolveProgress(int permille, const QString& format) {
  // QProgressBar::setValue repaints at once (a synchronous paint and flush of the whole window,
  // ~20 ms under Xvfb with the OpenGL viewport in it): at every iterate, and at every edit that
  // starts a solve while a pin is dragged. With updates off it only marks itself dirty and is
  // drawn with the window's other changes.
  solveProgress_->setUpdatesEnabled(false);
  solveProgress_->setValue(permille);
  solveProgress_->setFormat(format);
  solveProgress_->setUpdatesEnabled(true);
}

void MainWindow::stopSolve() { job_.cancel(); }

void MainWindow::setAutoSolve(bool on) {
  autoSolve_ = on;
  if (autoSolveAction_->isChecked() != on) autoSolveAction_->setChecked(on);
  // A motion that already solves the scene would only be found again.
  if (on && !doc_.showsSolutionOfScene()) solve();
}

bool MainWindow::importMotionJson(const QString& path, QString* error) {
  const MotionLoadResult loaded = loadMotionFile(path.toStdString());
  if (!loaded.animation) {
    *error = QString::fromStdString(loaded.error);
    return false;
  }
  std::string why;
  std::unique_ptr<SpacetimeProblem> problem = SpacetimeProblem::build(doc_.scene(), &why);
  if (!problem) {
    *error = tr("The scene cannot be solved: %1").arg(QString::fromStdString(why));
    return false;
  }
  if (startFromMotion(*problem, *loaded.animation) == 0) {
    QStringList theirs;
    for (const CharacterAnimation& c : loaded.animation->characters)
      theirs << QString("%1 (%2 dofs)").arg(QString::fromStdString(c.name)).arg(c.q.cols());
    *error = tr("%1 holds no character of this scene (they are matched by id and number of dofs): it has %2")
                 .arg(QDir::toNativeSeparators(path), theirs.join(", "));
    return false;
  }
  // The multipliers of the motion, estimated for a method that reads them (the solve's own state
  // then carries them into its warm start); here on the interface's thread, on one core.
  SolverOptions options = solverOptionsFor(doc_.scene().solver);
  options.method = methodForMotionStart(options.method);
  options.threads = 1;
  multipliersForMotionStart(*problem, options);
  job_.cancel();
  auto fitted = sampleMotion(*problem);
  const ProblemMeasures m = measure(*problem);
  fitted->objective = m.objective;
  fitted->maxViolation = m.maxViolation;
  fitted->fromMotionFile = true;
  doc_.setMotion(fitted);
  progress_->setText(tr("Started from %1: fitted to this scene (largest constraint violation %2); Solve refines it")
                         .arg(QFileInfo(path).fileName())
                         .arg(m.maxViolation, 0, 'g', 3));
  if (autoSolve_) solve();
  return true;
}

bool MainWindow::exportMotionJson(const QString& path, QString* error) {
  if (!doc_.motion()) { *error = tr("Nothing to export: solve first."); return false; }
  std::string why;
  if (writeFileAtomically(path.toStdString(), motionJson(doc_.motion()->animation), &why)) return true;
  *error = QString::fromStdString(why);
  return false;
}

bool MainWindow::exportMotionCsv(const QString& path, QString* error) {
  if (!doc_.motion()) { *error = tr("Nothing to export: solve first."); return false; }
  std::string why;
  if (writeFileAtomically(path.toStdString(), motionCsv(doc_.motion()->animation), &why)) return true;
  *error = QString::fromStdString(why);
  return false;
}

bool MainWindow::exportUrdf(const QString& directory, QString* error) {
  return writeCharacterFiles(directory, "urdf", error, [](size_t, const CharacterSpec& c, const Model<double>& model) {
    return spacetime::exportUrdf(model, c).xml;
  });
}

namespace {
// The solved motion sampled again from its solution (its splines, not an interpolation of the
// display's samples) by `sample`; the display's samples if the solution cannot be rebuilt.
Animation resampled(const SolvedMotion& motion, const std::function<Animation(const SpacetimeProblem&)>& sample) {
  if (motion.scene) {
    std::string why;
    auto problem = SpacetimeProblem::build(*motion.scene, &why);
    if (problem && problem->restore(motion.state)) return sample(*problem);
  }
  return motion.animation;
}
}  // namespace

bool MainWindow::exportBvh(const QString& directory, QString* error) {
  const std::shared_ptr<const SolvedMotion> motion = doc_.motion();
  if (!motion || !motionFitsScene(*motion, doc_.scene())) { *error = tr("Nothing to export: solve first."); return false; }
  // At the timeline's frame rate: a BVH importer (Blender's) makes one scene frame of each BVH
  // frame, so the display's 120 Hz samples played a 1.2 s jump over 6 s at 24 fps. The motion is
  // sampled again from its solution at that rate (its spline, not an interpolation of samples).
  const double rate = doc_.scene().frameRate;
  const Animation animation =
      resampled(*motion, [&](const SpacetimeProblem& p) { return sampleAnimationAt(p, frameTimes(p.scene(), rate)); });
  return writeCharacterFiles(directory, "bvh", error, [&](size_t i, const CharacterSpec& c, const Model<double>& model) {
    return motionBvh(model, c, animation.characters[i]);
  });
}

bool MainWindow::exportGltf(const QString& path, QString* error) {
  const std::shared_ptr<const SolvedMotion> motion = doc_.motion();
  if (!motion || !motionFitsScene(*motion, doc_.scene())) { *error = tr("Nothing to export: solve first."); return false; }
  std::vector<const Model<double>*> models;
  for (const Model<double>& m : doc_.models()) models.push_back(&m);
  // Cubic keys on the scene's frame grid plus the splines' knots (gltfKeyTimes), like the CLI's.
  const double rate = doc_.scene().frameRate;
  const Animation keys =
      resampled(*motion, [&](const SpacetimeProblem& p) { return sampleAnimationAt(p, gltfKeyTimes(p, rate)); });
  std::string why;
  if (writeFileAtomically(path.toStdString(), motionGlb(doc_.scene(), models, keys), &why)) return true;
  *error = QString::fromStdString(why);
  return false;
}

bool MainWindow::writeCharacterFiles(
    const QString& directory, const QString& extension, QString* error,
    const std::function<std::string(size_t, const CharacterSpec&, const Model<double>&)>& text) {
  if (!QDir().mkpath(directory)) { *error = tr("%1: cannot create the folder").arg(directory); return false; }
  const Scene& s = doc_.scene();
  for (size_t i = 0; i < s.characters.size(); ++i) {
    const CharacterSpec& c = s.characters[i];
    std::string why;
    const QString path = directory + "/" + QString::fromStdString(c.id) + "." + extension;
    if (!writeFileAtomically(path.toStdString(), text(i, c, buildModel(c, s.gravity)), &why)) {
      *error = QString::fromStdString(why);
      return false;
    }
  }
  return true;
}

bool MainWindow::exportImageSequence(const QString& directory, QString* error, const QSize& size) {
  if (!QDir().mkpath(directory)) { *error = tr("%1: cannot create the folder").arg(directory); return false; }
  const Scene& s = doc_.scene();
  const double before = doc_.currentTime();
  const double fps = doc_.scene().frameRate;
  const int frames = static_cast<int>(std::floor((s.endTime - s.startTime) * fps + 1e-9)) + 1;
  for (int f = 0; f < frames; ++f) {
    doc_.setCurrentTime(s.startTime + static_cast<double>(f) / fps);
    const QImage image = size.isValid() ? viewport_->renderImage(size) : viewport_->grabFramebuffer();
    const QString path = QString("%1/frame_%2.png").arg(directory).arg(f, 4, 10, QChar('0'));
    if (!image.save(path)) {
      *error = tr("%1: cannot write the image").arg(path);
      doc_.setCurrentTime(before);
      return false;
    }
  }
  doc_.setCurrentTime(before);
  return true;
}

QString MainWindow::autosavePath() const { return autosaveDirectory() + "/" + autosaveId_ + ".json"; }

bool MainWindow::writeAutosave() {
  if (!doc_.isModified()) return false;
  QDir().mkpath(autosaveDirectory());
  std::string why;
  return saveSceneFile(doc_.sceneForSave(), autosavePath().toStdString(), &why);
}

QStringList MainWindow::pendingRecoveries() {
  QDir dir(autosaveDirectory());
  QStringList out;
  for (const QString& name : dir.entryList({"*.json"}, QDir::Files, QDir::Time)) {
    // A live window holds its lock; a crashed one's lock is stale and taken over here.
    QLockFile lock(dir.filePath(QFileInfo(name).completeBaseName() + ".lock"));
    if (!lock.tryLock(0)) continue;
    lock.unlock();
    out << dir.filePath(name);
  }
  return out;
}

void MainWindow::offerRecovery() {
  // Files left by windows that did not close cleanly (ours are removed on close), newest first.
  // Each is offered by itself: recovered (into this window, or a new one once this one holds a
  // recovered scene), discarded, or kept for the next start. Only what the user recovered or
  // discarded is deleted.
  static bool offered = false;  // once per process: windows opened by the recovery do not ask again
  if (offered || qEnvironmentVariableIsSet("SPACETIME_NO_RECOVERY")) return;
  offered = true;
  QStringList files = pendingRecoveries();
  files.removeAll(autosavePath());
  bool recoveredHere = false;
  for (const QString& file : files) {
    const SceneLoadResult peek = loadSceneFile(file.toStdString());
    const QString name = peek.scene ? QString::fromStdString(peek.scene->name) : QFileInfo(file).fileName();
    const auto answer = QMessageBox::question(
        this, tr("Recover"),
        tr("Spacetime did not close cleanly. Recover the unsaved scene \"%1\", autosaved at %2?\n\n"
           "No keeps it for the next start; Discard deletes it.")
            .arg(name, QFileInfo(file).lastModified().toString()),
        QMessageBox::Yes | QMessageBox::No | QMessageBox::Discard);
    if (answer == QMessageBox::No) continue;
    if (answer == QMessageBox::Yes) {
      MainWindow* target = this;
      if (recoveredHere) {
        target = new MainWindow;
        target->setAttribute(Qt::WA_DeleteOnClose);
        target->show();
      }
      QString error;
      if (!target->recoverAutosave(file, &error)) {
        QMessageBox::warning(this, tr("Recover"), error);
        continue;  // kept: it may be read by a later version
      }
      recoveredHere = true;
      target->writeAutosave();  // under the recovering window's own name before the old goes
    }
    QFile::remove(file);
  }
}

bool MainWindow::recoverAutosave(const QString& file, QString* error) {
  if (!doc_.open(file, error)) return false;
  // A recovered scene has no file yet (Save asks where) and is unsaved work.
  doc_.setFilePath({});
  doc_.markModified();
  return true;
}

bool MainWindow::maybeSave() {
  if (!doc_.isModified()) return true;
  const auto answer = QMessageBox::warning(this, tr("Unsaved changes"), tr("The scene has unsaved changes. Save them?"),
                                           QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel);
  if (answer == QMessageBox::Cancel) return false;
  if (answer == QMessageBox::Discard) return true;
  QString path = doc_.filePath();
  if (path.isEmpty()) path = QFileDialog::getSaveFileName(this, tr("Save scene"), "scene.json", tr("Spacetime scenes (*.json)"));
  if (path.isEmpty()) return false;
  QString error;
  if (!saveFile(path, &error)) {
    QMessageBox::warning(this, tr("Save"), error);
    return false;
  }
  return true;
}

void MainWindow::addRecent(const QString& path) {
  QSettings settings;
  // One entry per file, however its path was spelled (relative, with "." or "..", through a
  // symbolic link): the list used to keep the spelling it removed and add the absolute one.
  auto canonical = [](const QString& p) {
    const QFileInfo info(p);
    const QString real = info.canonicalFilePath();
    return real.isEmpty() ? QDir::cleanPath(info.absoluteFilePath()) : real;
  };
  const QString file = canonical(path);
  QStringList recent;
  for (const QString& p : settings.value("recentFiles").toStringList())
    if (const QString other = canonical(p); other != file && !recent.contains(other)) recent.append(other);
  recent.prepend(file);
  while (recent.size() > 10) recent.removeLast();
  settings.setValue("recentFiles", recent);
  rebuildRecentMenu();
}

void MainWindow::rebuildRecentMenu() {
  recentMenu_->clear();
  for (const QString& path : QSettings().value("recentFiles").toStringList())
    recentMenu_->addAction(path, this, [this, path] {
      if (!maybeSave()) return;
      QString error;
      if (!openFile(path, &error)) QMessageBox::warning(this, tr("Open"), error);
    });
  recentMenu_->setEnabled(!recentMenu_->isEmpty());
}

void MainWindow::closeEvent(QCloseEvent* e) {
  if (!maybeSave()) {
    e->ignore();
    return;
  }
  job_.cancel();
  QSettings settings;
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  QFile::remove(autosavePath());
  e->accept();
}

void MainWindow::dragEnterEvent(QDragEnterEvent* e) {
  if (e->mimeData()->hasUrls() && e->mimeData()->urls().front().toLocalFile().endsWith(".json")) e->acceptProposedAction();
}

void MainWindow::dropEvent(QDropEvent* e) {
  const QString path = e->mimeData()->urls().front().toLocalFile();
  if (!maybeSave()) return;
  QString error;
  if (!openFile(path, &error)) QMessageBox::warning(this, tr("Open"), error);
}

}  // namespace spacetime::ui
