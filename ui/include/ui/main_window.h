// The main window: the viewport in the middle, dockable builder, constraints, timeline and
// graph panels (layout restored from QSettings), menus and toolbar for everything common with
// shortcuts, and a status bar with the solver's progress. It owns the Document and the solver
// job: Solve (F5) runs in the background and the iterates replace the motion as they arrive;
// Stop (Esc) cancels; Auto-solve re-solves warm-started after every edit. File handling: New,
// Open, recent files, Save/Save As (atomic, with the solution), a prompt before losing changes,
// autosave with recovery after a crash, drag and drop of scene files; exports.
#pragma once

#include <QLabel>
#include <QLockFile>
#include <QMainWindow>
#include <QProgressBar>
#include <QTimer>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ui/builder_panel.h"
#include "ui/constraints_panel.h"
#include "ui/document.h"
#include "ui/graph_panel.h"
#include "ui/scene_settings_panel.h"
#include "ui/validity_panel.h"
#include "ui/solve_progress.h"
#include "ui/solver_job.h"
#include "ui/timeline.h"
#include "ui/viewport.h"

namespace spacetime::ui {

class MainWindow : public QMainWindow {
  Q_OBJECT
 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  Document* document() { return &doc_; }
  SolverJob* solverJob() { return &job_; }
  Viewport* viewport() { return viewport_; }
  Timeline* timeline() { return timeline_; }
  BuilderPanel* builder() { return builder_; }
  SceneSettingsPanel* sceneSettings() { return sceneSettings_; }
  ConstraintsPanel* constraints() { return constraints_; }
  GraphPanel* graphs() { return graphs_; }
  ValidityPanel* validity() { return validity_; }
  QString statusText() const;

  bool openFile(const QString& path, QString* error);  // no prompt
  bool saveFile(const QString& path, QString* error);
  void solve();
  void stopSolve();
  void setAutoSolve(bool on);
  bool autoSolve() const { return autoSolve_; }
  bool solveOnOpen = true;  // solve a scene that has no stored solution as soon as it opens

  // Starts from a motion file (motion.json, as the export below or spacetime-cli write it): its
  // sampled motion and contact forces fitted to the scene's transcription go on show, and the
  // next solve (at once with auto-solve) refines it by the method methodForMotionStart chooses
  // (sqp for a scene whose method is al; witkin-kass warm from estimated multipliers). False
  // with the reason: a malformed file (the field named), a scene that cannot be built, no
  // character in common.
  bool importMotionJson(const QString& path, QString* error);

  // Exports (no dialogs).
  bool exportMotionJson(const QString& path, QString* error);
  bool exportMotionCsv(const QString& path, QString* error);
  bool exportUrdf(const QString& directory, QString* error);
  bool exportBvh(const QString& directory, QString* error);  // <character>.bvh at the display rate
  bool exportGltf(const QString& path, QString* error);       // one .glb: every character, animated
  // frame_0000.png ... at the scene's frame rate, `size` pixels each (invalid: the viewport's).
  bool exportImageSequence(const QString& directory, QString* error, const QSize& size = QSize());

  // Autosave: the file the current document autosaves to, writing it, and the recovery check:
  // the autosaves of windows that are no longer running (their lock is free), newest first.
  QString autosavePath() const;
  bool writeAutosave();
  static QStringList pendingRecoveries();
  static constexpr int kAutosaveDelayMs = 2000;  // after the last edit
  // Opens the scene autosaved in `file` by a session that did not close cleanly, as a modified
  // document without a file (Save asks where). The prompt at start-up calls it.
  bool recoverAutosave(const QString& file, QString* error);

 protected:
  void closeEvent(QCloseEvent* e) override;
  bool eventFilter(QObject* watched, QEvent* event) override;
  void dragEnterEvent(QDragEnterEvent* e) override;
  void dropEvent(QDropEvent* e) override;

 private:
  // Writes <directory>/<character id>.<extension> for every character of the scene, each with
  // text(index, spec, model); creates the directory. False with a reason on the first failure.
  bool writeCharacterFiles(
      const QString& directory, const QString& extension, QString* error,
      const std::function<std::string(size_t, const CharacterSpec&, const Model<double>&)>& text);
  void createActions();
  void updateTitle();
  // The solve's progress bar: its value (per mille) and text, drawn with the next paint.
  void showSolveProgress(int permille, const QString& format);
  bool maybeSave();
  void addRecent(const QString& path);
  void rebuildRecentMenu();
  void offerRecovery();

  Document doc_;
  SolverJob job_;
  Viewport* viewport_;
  Timeline* timeline_;
  BuilderPanel* builder_;
  SceneSettingsPanel* sceneSettings_ = nullptr;
  ConstraintsPanel* constraints_;
  GraphPanel* graphs_;
  ValidityPanel* validity_;
  QLabel* progress_;
  QProgressBar* solveProgress_ = nullptr;
  SolveProgress progressEstimate_{1e-7};
  // The transcription of the last iterate shown: a refinement restarts the estimate.
  std::optional<TranscriptionSpec> progressTranscription_;
  QMenu* recentMenu_ = nullptr;
  QAction* solveAction_ = nullptr;
  QAction* stopAction_ = nullptr;
  QAction* autoSolveAction_ = nullptr;
  QAction* showStoppedAction_ = nullptr;
  bool autoSolve_ = false;
  QTimer autosaveTimer_;
  QTimer autosaveSoon_;  // a few seconds after the last edit: a crash loses only that much
  QTimer resolveTimer_;  // coalesces bursts of edits into one re-solve
  QString autosaveId_;
  // Held while this window lives: another instance's recovery check sees a live autosave, not a
  // crash's leftover (a crashed process's lock is stale and taken over).
  std::unique_ptr<QLockFile> autosaveLock_;
};

}  // namespace spacetime::ui
