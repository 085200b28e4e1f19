// The Document: the scene being edited, its undo stack, its file, the motion on show, the
// current time and the selection. Every change to the scene is an undo command (EditScene, a
// snapshot of the scene before and after, merged while the same drag or field goes on), so
// undo/redo always restores an identical scene. A solver result is not an edit: it replaces the
// motion and leaves the undo stack alone - but every converged motion is remembered as the
// solution of its scene, so undo and redo bring back the motion the user saw without solving,
// and a solve that stops without converging never replaces the last converged motion (the safety
// net: the stopped result is kept aside to inspect or accept). Views observe the signals and
// never call each other.
#pragma once

#include <QObject>
#include <QString>
#include <QUndoCommand>
#include <QUndoStack>
#include <functional>
#include <memory>
#include <optional>

#include "core/scene.h"
#include "dynamics/model.h"
#include "ui/solved_motion.h"

namespace spacetime::ui {

class Document : public QObject {
  Q_OBJECT
 public:
  explicit Document(QObject* parent = nullptr);

  const Scene& scene() const { return scene_; }
  QUndoStack* undoStack() { return &undo_; }

  // Applies `change` to a copy of the scene as one undo command named `text`. Consecutive edits
  // with the same non-zero mergeId become one command (a drag, typing in a field). An edit
  // that changes nothing adds no command.
  void edit(const QString& text, const std::function<void(Scene&)>& change, int mergeId = 0);
  // A drag whose moves merge into one command (mergeId) is under way, from the press to the
  // release (0: none). A refinement adopted meanwhile joins the drag's command (see acceptResult).
  void beginContinuousEdit(int mergeId) { continuousEdit_ = mergeId; }
  void endContinuousEdit() { continuousEdit_ = 0; }

  // Replaces the whole document (New, Open, presets from a file): clears the undo stack. A
  // stored solution that fits the scene becomes the motion on show.
  void reset(const Scene& scene, const QString& filePath);
  // Loads a scene file; false with the loader's message (file, field, what is wrong).
  bool open(const QString& path, QString* error);
  // Saves atomically, with the motion on show as the scene's stored solution.
  bool saveAs(const QString& path, QString* error);
  // The scene as it is saved: with the current motion's solution.
  Scene sceneForSave() const;

  QString filePath() const { return path_; }
  // The file Save writes to (empty: Save asks where); emits filePathChanged when it changes.
  void setFilePath(const QString& path);
  bool isModified() const { return !undo_.isClean(); }
  // Unsaved whatever the undo stack says (a recovered autosave): closing will ask to save.
  void markModified() { undo_.resetClean(); }

  // Models of the scene's characters (empty when the scene cannot be built).
  const std::vector<Model<double>>& models() const { return models_; }

  // The motion on show: null when none fits the scene.
  std::shared_ptr<const SolvedMotion> motion() const { return motion_; }
  void setMotion(std::shared_ptr<const SolvedMotion> motion);
  // A solve's final motion. A converged one goes on show and is remembered as the solution of
  // its scene. One that stopped without converging (stalled, out of time, Stop) goes on show only
  // when there is no converged motion that fits the scene to keep showing; otherwise the last
  // converged motion stays (or comes back, after the live iterates) and the stopped one is kept
  // as stoppedMotion(). A converged motion of this scene on a transcription the solve refined
  // also sets the scene's transcription to it, as one undo command ("Refine the transcription"),
  // and remembers the motion it reached at the scene's own transcription (undo shows it). While
  // a drag goes on that command joins the drag's (one Undo returns to before the drag, as the
  // drag's later moves keep merging) instead of splitting the drag in two.
  // Returns whether `motion` is on show.
  bool acceptResult(std::shared_ptr<const SolvedMotion> motion);
  // The last result that stopped without converging and was not put on show (null when none).
  std::shared_ptr<const SolvedMotion> stoppedMotion() const { return stopped_; }
  // Puts the stopped result on show (to inspect it, or to continue from it).
  void showStoppedMotion();
  // Whether the motion on show is a converged solution of exactly the current scene: a re-solve
  // would find it again.
  bool showsSolutionOfScene() const;
  // Attaches a validity report to the current motion if it is still `motion` (a report that
  // arrives after a newer motion is dropped). Emits validityChanged, not motionChanged: nothing
  // needs redrawing but the validity view.
  void attachValidity(const SolvedMotion* motion, std::shared_ptr<const ValidityReport> report);

  double currentTime() const { return time_; }
  void setCurrentTime(double t);  // drops an unkeyed pose

  // An unkeyed pose of one character at the current time (the viewport's rotate gizmo makes
  // it): shown instead of the motion there, and what K keys, until the time or the scene changes
  // (as in Blender, a pose not keyed is gone when the frame changes).
  struct Posed {
    int character = -1;
    Eigen::VectorXd q;
  };
  const std::optional<Posed>& posed() const { return posed_; }
  void setPosed(int character, const Eigen::VectorXd& q);
  void clearPosed();
  // Each character's pose at the current time: the unkeyed pose, else the motion's (the zero
  // pose without a motion).
  std::vector<Eigen::VectorXd> posesNow() const;

  // Selection: a body of a character, and/or a term.
  int selectedCharacter() const { return selCharacter_; }
  const std::string& selectedBody() const { return selBody_; }
  const std::string& selectedTerm() const { return selTerm_; }
  void selectBody(int character, const std::string& body);
  void selectTerm(const std::string& term);

  // Applied by EditScene only: sets the scene without touching the undo stack.
  void applyScene(const Scene& scene);

  // A unique id for a new term or body ("pin1", "pin2", ...).
  std::string uniqueTermId(const std::string& stem) const;
  std::string uniqueBodyId(const std::string& stem) const;

 signals:
  void sceneChanged();
  void motionChanged();
  void validityChanged();
  void currentTimeChanged(double t);
  void poseChanged();
  void selectionChanged();
  void filePathChanged(const QString& path);

 private:
  void rebuildModels();

  Scene scene_;
  QUndoStack undo_;
  QString path_;
  std::vector<Model<double>> models_;
  std::shared_ptr<const SolvedMotion> motion_;
  // Converged motions by the canonical text of the scene they solve (at most kRemembered, the
  // oldest dropped first), the last converged motion put on show, and the stopped result aside.
  static constexpr size_t kRemembered = 64;
  std::vector<std::pair<std::string, std::shared_ptr<const SolvedMotion>>> solutions_;
  std::shared_ptr<const SolvedMotion> lastGood_, stopped_;
  int continuousEdit_ = 0;  // the merge id of the drag under way, or 0
  void remember(const std::shared_ptr<const SolvedMotion>& motion);
  double time_ = 0;
  std::optional<Posed> posed_;
  int selCharacter_ = -1;
  std::string selBody_, selTerm_;
};

// The one undo command of the document: the scene before and after an edit.
class EditScene : public QUndoCommand {
 public:
  EditScene(Document* doc, const QString& text, Scene before, Scene after, int mergeId);
  void undo() override;
  void redo() override;
  int id() const override { return mergeId_; }
  bool mergeWith(const QUndoCommand* other) override;
  const Scene& before() const { return before_; }
  const Scene& after() const { return after_; }

 private:
  Document* doc_;
  Scene before_, after_;
  int mergeId_;
};

// Merge ids of continuous edits: a kind in the high bits, a field or handle index below.
enum MergeKind : int {
  kMergePinDrag = 1 << 20,
  kMergeContactDrag = 2 << 20,
  kMergeBodyField = 3 << 20,
  kMergeTermField = 4 << 20,
  kMergeSceneField = 5 << 20,
  kMergeFrameRate = 6 << 20,
};

}  // namespace spacetime::ui
