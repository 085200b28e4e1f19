#include "ui/document.h"

#include <QFile>
#include <algorithm>

#include "core/scene_io.h"
#include "dynamics/build_model.h"
#include "ui/render_scene.h"

namespace spacetime::ui {

namespace {
// Undo keeps whole scenes: compare them by their canonical text.
bool sameScene(const Scene& a, const Scene& b) { return sceneToJson(a) == sceneToJson(b); }

// The canonical text of a scene without its stored solution: what a solution solves.
std::string problemKey(const Scene& scene) {
  // The frame rate is how the motion is shown and exported, not part of the problem.
  Scene bare = scene;
  bare.solution.reset();
  bare.frameRate = Scene{}.frameRate;
  return sceneToJson(bare);
}

// The motion a scene file stored with it, if it still fits the scene's problem; null if not.
std::shared_ptr<const SolvedMotion> restoredMotion(const Scene& scene, const StoredSolution& stored) {
  std::string error;
  auto problem = SpacetimeProblem::build(scene, &error);
  if (!problem || !problem->restore({stored.variables, stored.multipliers, stored.rho, nullptr})) return nullptr;
  auto m = sampleMotion(*problem);
  m->solved = true;
  m->validity = std::make_shared<const ValidityReport>(checkValidity(*problem));
  m->converged = stored.converged;
  m->reason = "loaded with the scene";
  return m;
}
}  // namespace

Document::Document(QObject* parent) : QObject(parent) {
  scene_.name = "untitled";
  rebuildModels();
}

void Document::edit(const QString& text, const std::function<void(Scene&)>& change, int mergeId) {
  Scene after = scene_;
  change(after);
  after.solution.reset();
  if (sameScene(after, scene_)) return;
  undo_.push(new EditScene(this, text, scene_, std::move(after), mergeId));
}

void Document::applyScene(const Scene& scene) {
  scene_ = scene;
  rebuildModels();
  clearPosed();
  // Undo and redo bring back the converged motion of the scene they restore, as it was shown.
  const std::string key = problemKey(scene_);
  const auto known = std::find_if(solutions_.begin(), solutions_.end(), [&](const auto& e) { return e.first == key; });
  if (known != solutions_.end() && known->second != motion_) {
    motion_ = known->second;
    lastGood_ = motion_;
    emit motionChanged();
  } else if (motion_ && !motionFitsScene(*motion_, scene_)) {
    motion_.reset();
    emit motionChanged();
  }
  emit sceneChanged();
}

void Document::remember(const std::shared_ptr<const SolvedMotion>& motion) {
  if (!motion || !motion->converged || !motion->scene) return;
  const std::string key = problemKey(*motion->scene);
  solutions_.erase(std::remove_if(solutions_.begin(), solutions_.end(), [&](const auto& e) { return e.first == key; }),
                   solutions_.end());
  if (solutions_.size() >= kRemembered) solutions_.erase(solutions_.begin());
  solutions_.emplace_back(key, motion);
}

bool Document::acceptResult(std::shared_ptr<const SolvedMotion> motion) {
  if (!motion || !motionFitsScene(*motion, scene_)) return false;  // a result of an older structure
  if (motion->converged && motion->scene && motion->asked && problemKey(*motion->asked) == problemKey(scene_)) {
    // A solve of this very scene that refined its transcription (not of one edited since, whose
    // new rate the refinement's would overwrite): the scene takes the finer transcription, as an
    // edit the user can undo, so that saving keeps the motion with the transcription it fits and
    // the next solve starts there. Remembered first, so the edit shows it as the scene's solution.
    Scene refined = scene_;
    refined.transcription = motion->scene->transcription;
    const std::string key = problemKey(refined);
    if (key == problemKey(*motion->scene) && key != problemKey(scene_)) {
      // The motion at the scene's own transcription is that scene's solution: undo shows it.
      remember(motion->unrefined);
      remember(motion);
      lastGood_ = motion;
      stopped_.reset();
      // The same refinement undone before (a re-solve of the undone scene refined it again): redo
      // it rather than push a copy, which would drop the rest of the redo stack.
      if (undo_.index() < undo_.count()) {
        const auto* next = dynamic_cast<const EditScene*>(undo_.command(undo_.index()));
        if (next && problemKey(next->before()) == problemKey(scene_) && problemKey(next->after()) == key) {
          undo_.redo();
          return true;
        }
      }
      const auto kept = std::find_if(motion->transcriptions.begin(), motion->transcriptions.end(),
                                     [](const TranscriptionAttempt& a) { return a.kept; });
      // The undo view's text says to what; the Undo action's (after the newline) stays short.
      const QString text = kept == motion->transcriptions.end()
                               ? tr("Refine the transcription")
                               : tr("Refine the transcription to %1\nRefine the transcription")
                                     .arg(QString::fromStdString(describeResolution(*kept)));
      // During a drag whose command is the last one, the refinement merges into it: a command
      // of its own would end the merging, and the drag's next moves would start another.
      const int merge = continuousEdit_ != 0 && undo_.index() > 0 && undo_.index() == undo_.count() &&
                                undo_.command(undo_.index() - 1)->id() == continuousEdit_
                            ? continuousEdit_
                            : 0;
      undo_.push(new EditScene(this, text, scene_, std::move(refined), merge));
      return true;
    }
  }
  if (motion->converged || !lastGood_ || !motionFitsScene(*lastGood_, scene_)) {
    if (motion->converged) {
      remember(motion);
      lastGood_ = motion;
    }
    stopped_.reset();
    setMotion(std::move(motion));
    return true;
  }
  stopped_ = std::move(motion);
  setMotion(lastGood_);
  return false;
}

void Document::showStoppedMotion() {
  if (!stopped_) return;
  auto shown = std::move(stopped_);
  stopped_.reset();
  setMotion(std::move(shown));
}

bool Document::showsSolutionOfScene() const {
  return motion_ && motion_->converged && motion_->scene && problemKey(*motion_->scene) == problemKey(scene_);
}

void Document::reset(const Scene& scene, const QString& filePath) {
  undo_.clear();
  scene_ = scene;
  scene_.solution.reset();
  rebuildModels();
  motion_ = scene.solution ? restoredMotion(scene_, *scene.solution) : nullptr;
  solutions_.clear();
  stopped_.reset();
  lastGood_ = motion_ && motion_->converged ? motion_ : nullptr;
  remember(motion_);
  path_ = filePath;
  time_ = scene_.startTime;
  posed_.reset();
  selCharacter_ = scene_.characters.empty() ? -1 : 0;
  selBody_.clear();
  selTerm_.clear();
  undo_.setClean();
  emit filePathChanged(path_);
  emit sceneChanged();
  emit motionChanged();
  emit currentTimeChanged(time_);
  emit selectionChanged();
}

bool Document::open(const QString& path, QString* error) {
  QFile f(path);
  if (!f.open(QIODevice::ReadOnly)) {
    *error = path + ": cannot be read: " + f.errorString();
    return false;
  }
  const SceneLoadResult r = parseScene(f.readAll().toStdString(), path.toStdString());
  if (!r.scene) {
    *error = QString::fromStdString(r.error);
    return false;
  }
  reset(*r.scene, path.startsWith(":/") ? QString() : path);
  return true;
}

Scene Document::sceneForSave() const {
  Scene s = scene_;
  if (motion_ && motion_->solved)
    s.solution = StoredSolution{motion_->state.variables, motion_->state.multipliers,
                                motion_->state.rho, motion_->converged};
  return s;
}

bool Document::saveAs(const QString& path, QString* error) {
  std::string why;
  if (!saveSceneFile(sceneForSave(), path.toStdString(), &why)) {
    *error = QString::fromStdString(why);
    return false;
  }
  undo_.setClean();
  setFilePath(path);
  return true;
}

void Document::setFilePath(const QString& path) {
  if (path == path_) return;
  path_ = path;
  emit filePathChanged(path_);
}

void Document::setMotion(std::shared_ptr<const SolvedMotion> motion) {
  if (motion && !motionFitsScene(*motion, scene_)) return;  // a result of an older structure
  motion_ = std::move(motion);
  emit motionChanged();
}

void Document::attachValidity(const SolvedMotion* motion, std::shared_ptr<const ValidityReport> report) {
  if (!motion_ || motion_.get() != motion) return;
  auto checked = std::make_shared<SolvedMotion>(*motion_);
  checked->validity = std::move(report);
  // The remembered solution and the last good motion carry the report too.
  for (auto& e : solutions_)
    if (e.second == motion_) e.second = checked;
  if (lastGood_ == motion_) lastGood_ = checked;
  motion_ = std::move(checked);
  emit validityChanged();
}

void Document::setCurrentTime(double t) {
  t = std::clamp(t, scene_.startTime, scene_.endTime);
  if (t == time_) return;
  time_ = t;
  clearPosed();
  emit currentTimeChanged(t);
}

void Document::setPosed(int character, const Eigen::VectorXd& q) {
  if (character < 0 || static_cast<size_t>(character) >= models_.size() || q.size() != models_[character].dofCount()) return;
  posed_ = Posed{character, q};
  emit poseChanged();
}

void Document::clearPosed() {
  if (!posed_) return;
  posed_.reset();
  emit poseChanged();
}

std::vector<Eigen::VectorXd> Document::posesNow() const {
  std::vector<Eigen::VectorXd> poses = posesAt(scene_, models_, motion_.get(), time_);
  if (posed_ && static_cast<size_t>(posed_->character) < poses.size()) poses[posed_->character] = posed_->q;
  return poses;
}

void Document::selectBody(int character, const std::string& body) {
  if (character == selCharacter_ && body == selBody_) return;
  selCharacter_ = character;
  selBody_ = body;
  emit selectionChanged();
}

void Document::selectTerm(const std::string& term) {
  if (term == selTerm_) return;
  selTerm_ = term;
  emit selectionChanged();
}

std::string Document::uniqueTermId(const std::string& stem) const {
  for (int i = 1;; ++i) {
    const std::string id = stem + std::to_string(i);
    if (std::none_of(scene_.terms.begin(), scene_.terms.end(),
                     [&](const TermSpec& t) { return t.id == id; }))
      return id;
  }
}

std::string Document::uniqueBodyId(const std::string& stem) const {
  for (int i = 1;; ++i) {
    const std::string id = stem + std::to_string(i);
    bool used = false;
    for (const CharacterSpec& c : scene_.characters)
      used = used || c.body(id) != nullptr || c.id == id;
    if (!used) return id;
  }
}

void Document::rebuildModels() {
  models_.clear();
  for (const CharacterSpec& c : scene_.characters) {
    if (c.bodies.empty()) {
      models_.clear();
      return;
    }
    models_.push_back(buildModel(c, scene_.gravity));
  }
}

EditScene::EditScene(Document* doc, const QString& text, Scene before, Scene after, int mergeId)
    : QUndoCommand(text), doc_(doc), before_(std::move(before)), after_(std::move(after)),
      mergeId_(mergeId == 0 ? -1 : mergeId) {}

void EditScene::undo() { doc_->applyScene(before_); }
void EditScene::redo() { doc_->applyScene(after_); }

bool EditScene::mergeWith(const QUndoCommand* other) {
  if (other->id() != id()) return false;
  after_ = static_cast<const EditScene*>(other)->after_;
  return true;
}

}  // namespace spacetime::ui
