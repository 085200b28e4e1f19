// Qt Test suite of the editor, run under xvfb-run (a QOpenGLWidget needs a real X server).
// It drives the panels as a user does - their commands and form editors - and checks what the
// user would check: the motion meets the pin, undo/redo restores identical documents, saving
// loses nothing, the interface never stalls while the solver runs, Stop leaves a consistent
// document, and the viewport draws the lamp in its colours.
#include <QChart>
#include <QCheckBox>
#include <QComboBox>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QLineEdit>
#include <QSettings>
#include <QWheelEvent>
#include <QStandardPaths>
#include <QFile>
#include <QFileInfo>
#include <QJsonDocument>
#include <QJsonObject>
#include <QLineSeries>
#include <QMenu>
#include <QRegularExpression>
#include <QSpinBox>
#include <QTemporaryDir>
#include <QTimer>
#include <QToolButton>
#include <QProgressBar>
#include <QPushButton>
#include <QtTest>
#include <cstring>
#include <iterator>
#include <map>
#include <set>
#include <QChartView>
#include <QValueAxis>
#include <cmath>

#include "core/scene_io.h"
#include "core/shape_mesh.h"
#include "dynamics/algorithms.h"
#include "solver/augmented_lagrangian.h"
#include "solver/interior_point.h"
#include "solver/spacetime_problem.h"
#include "ui/live_pacing.h"
#include "ui/main_window.h"
#include "ui/render_scene.h"
#include "ui/solved_motion.h"
#include "event_loop_gap.h"

using namespace spacetime;
using namespace spacetime::ui;

namespace {

std::string json(const Document& d) { return sceneToJson(d.scene()); }

// A wait for a solve or a timer, stretched in an instrumented build (SPACETIME_TIME_SCALE, set
// by the sanitizer presets), as the solves' own budgets are.
int scaled(int ms) { return static_cast<int>(ms * instrumentedTimeScale()); }

void setSpin(QWidget* vectorEditor, const char* axis, double value) {
  auto* spin = vectorEditor->findChild<QDoubleSpinBox*>(axis);
  QVERIFY(spin);
  spin->setValue(value);
}

// Opens a shipped scene in a window that does not solve on its own; shown at `size` when given.
bool openScene(MainWindow& w, const QString& path, std::optional<QSize> size = std::nullopt) {
  w.solveOnOpen = false;
  if (size) {
    w.resize(*size);
    w.show();
    if (!QTest::qWaitForWindowExposed(&w)) return false;
  }
  QString error;
  if (w.openFile(path, &error)) return true;
  qWarning("%s", qPrintable(error));
  return false;
}

bool openLuxo(MainWindow& w, std::optional<QSize> size = std::nullopt) {
  return openScene(w, ":/scenes/luxo_jump.json", size);
}

// A converged result of a solve asked to solve `asked` that refined its transcription to split
// knots (24 segments, one split, s = 8); the default guess stands in for the solve, as only the
// scenes matter to the document. Null if the split scene does not build.
std::shared_ptr<SolvedMotion> refinedResultOf(const Scene& asked) {
  Scene split = asked;
  for (int k = 1; k < 24; ++k) split.transcription.knots.push_back(k / 20.0);
  split.transcription.knots.insert(split.transcription.knots.begin() + 8, 0.425);
  split.transcription.samplesPerSegment = 8;
  std::string why;
  const auto problem = SpacetimeProblem::build(split, &why);
  if (!problem) return nullptr;
  auto result = sampleMotion(*problem);
  result->solved = result->converged = true;
  result->asked = std::make_shared<const Scene>(asked);
  return result;
}

// Where a press on the centre of `body`'s solid lands: the pixel, the hit, and the hit point in
// the body's frame at the pose on show.
struct BodyGrab {
  QPointF pixel;
  glm::vec3 point{0.0f};
  Eigen::Vector3d local = Eigen::Vector3d::Zero();
  bool ok = false;
};
BodyGrab grabBody(MainWindow& w, const std::string& body) {
  BodyGrab g;
  glm::vec3 centre(0.0f);
  for (const Solid& s : w.viewport()->renderScene().solids)
    if (s.body == body && !s.ghost) centre = glm::vec3(s.transform[3]);
  g.pixel = w.viewport()->toPixel(centre);
  glm::vec3 o, dir;
  w.viewport()->camera().ray(g.pixel.x(), g.pixel.y(), static_cast<float>(w.viewport()->width()),
                             static_cast<float>(w.viewport()->height()), &o, &dir);
  const std::optional<Pick> hit = pickSolid(w.viewport()->renderScene(), o, dir);
  if (!hit || w.viewport()->renderScene().solids[hit->solid].body != body) return g;
  const Model<double>& model = w.document()->models()[0];
  g.point = hit->point;
  g.local = worldToBody(model, w.document()->posesNow()[0], model.bodyIndex(body),
                        Eigen::Vector3d(hit->point.x, hit->point.y, hit->point.z));
  g.ok = true;
  return g;
}

// A Shift+drag in the viewport from p0 to p1 in eight moves.
void shiftDrag(MainWindow& w, QPointF p0, QPoint p1) {
  QTest::mousePress(w.viewport(), Qt::LeftButton, Qt::ShiftModifier, p0.toPoint());
  for (int k = 1; k <= 8; ++k) {
    const QPointF p = p0 + (QPointF(p1) - p0) * k / 8.0;
    QMouseEvent move(QEvent::MouseMove, p, w.viewport()->mapToGlobal(p), Qt::NoButton, Qt::LeftButton, Qt::ShiftModifier);
    QApplication::sendEvent(w.viewport(), &move);
  }
  QTest::mouseRelease(w.viewport(), Qt::LeftButton, Qt::ShiftModifier, p1);
}

// Opens the particle and solves it to the end.
bool solvedParticle(MainWindow& w) {
  if (!openScene(w, ":/scenes/particle.json")) return false;
  w.solve();
  return w.solverJob()->waitForFinished(scaled(60000));
}

Scene emptyScene() {
  Scene s;
  s.name = "two_body";
  s.startTime = 0;
  s.endTime = 1;
  return s;
}

}  // namespace

class EditorTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() { QStandardPaths::setTestModeEnabled(true); qputenv("SPACETIME_NO_RECOVERY", "1"); }

  void builderTwoBodyCharacterMeetsItsPin() {
    MainWindow w;
    w.solveOnOpen = false;
    Document& doc = *w.document();
    doc.reset(emptyScene(), {});
    BuilderPanel& builder = *w.builder();
    builder.addCharacter();
    doc.selectBody(0, {});
    auto* root = qobject_cast<QComboBox*>(builder.form()->editor("Root"));
    QVERIFY(root);
    root->setCurrentIndex(0);  // fixed: an arm bolted to the world
    QVERIFY(doc.scene().characters[0].root == RootKind::Fixed);
    doc.selectBody(0, doc.scene().characters[0].bodies[0].id);
    builder.addBody();
    QCOMPARE(doc.scene().characters[0].bodies.size(), size_t(2));
    const std::string link = doc.scene().characters[0].bodies[1].id;
    QVERIFY(doc.selectedBody() == link);
    // The new character's box stands on the ground, and the new link on the box's top.
    const BodySpec base = doc.scene().characters[0].bodies[0];
    QCOMPARE(lowestHeight(base.geometry, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()), 0.0);
    const double shoulder = doc.scene().characters[0].bodies[1].joint.origin.y();
    QCOMPARE(shoulder, base.geometry.size.y());
    auto* mass = qobject_cast<QDoubleSpinBox*>(builder.form()->editor("Mass"));
    QVERIFY(mass);
    mass->setValue(0.8);
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, 0.8);

    // Pin the link's tip at t = 0.5 where the joint angle is asin(0.6): the tip is at
    // (-0.12, shoulder + 0.16), which the form's spin boxes hold exactly. A new pin holds the
    // body's tip (the capsule's end, 0.2 along it), not its joint.
    doc.setCurrentTime(0.5);
    const std::string pin = w.constraints()->addPin();
    QVERIFY(!pin.empty());
    PropertyForm* form = w.constraints()->form();
    QVERIFY(form->editor("Body point"));
    QCOMPARE(doc.scene().terms.back().point.y(), 0.2);
    const double angle = std::asin(0.6);
    const Eigen::Vector3d target(-0.2 * std::sin(angle), shoulder + 0.2 * std::cos(angle), 0);
    setSpin(form->editor("Target"), "x", target.x());
    setSpin(form->editor("Target"), "y", target.y());
    const TermSpec& term = doc.scene().terms.back();
    QCOMPARE(term.point.y(), 0.2);
    QVERIFY((term.position - target).norm() < 1e-9);

    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    QVERIFY2(doc.motion() && doc.motion()->converged, qPrintable(w.statusText()));
    const Model<double>& model = doc.models()[0];
    const Eigen::VectorXd q = poseAt(doc.motion()->animation.characters[0], 0.5);
    const Eigen::Vector3d tip = bodyToWorld(model, q, model.bodyIndex(link), Eigen::Vector3d(0, 0.2, 0));
    QVERIFY2((tip - target).norm() < 1e-5, qPrintable(QString("tip misses the pin by %1 m").arg((tip - target).norm())));
    QVERIFY(std::abs(q[0] - angle) < 1e-4);

    // A contact under the box holds its two bottom corners once the character floats (planar):
    // one point would leave it pivoting.
    doc.selectBody(0, {});
    root = qobject_cast<QComboBox*>(builder.form()->editor("Root"));  // the form was rebuilt
    QVERIFY(root);
    root->setCurrentIndex(1);  // planar floating
    QVERIFY(doc.scene().characters[0].root == RootKind::Planar);
    doc.selectBody(0, base.id);
    QVERIFY(!w.constraints()->addContact().empty());
    const TermSpec& contact = doc.scene().terms.back();
    QCOMPARE(contact.points.size(), size_t(2));
    QCOMPARE(contact.points[0], Eigen::Vector3d(-0.1, 0, 0));
    QCOMPARE(contact.points[1], Eigen::Vector3d(0.1, 0, 0));
  }

  void undoRedoRestoresIdenticalDocumentsForEveryKindOfEdit() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1400, 900)));
    Document& doc = *w.document();
    std::vector<std::string> states{json(doc)};
    auto step = [&](const char* what) {
      QVERIFY2(json(doc) != states.back(), what);  // every step is an edit
      states.push_back(json(doc));
    };
    BuilderPanel& b = *w.builder();
    ConstraintsPanel& c = *w.constraints();
    doc.selectBody(0, "head");
    b.addBody();                                                     step("add body");
    auto* name = qobject_cast<QLineEdit*>(b.form()->editor("Body"));
    name->setText("antenna");
    emit name->editingFinished();                                    step("rename body");
    QTest::qWait(1);
    doc.selectBody(0, "antenna");
    setSpin(b.form()->editor("Axis"), "x", 1.0);                     step("joint axis");
    qobject_cast<QComboBox*>(b.form()->editor("Geometry"))->setCurrentIndex(1);  step("geometry");
    qobject_cast<QDoubleSpinBox*>(b.form()->editor("Mass"))->setValue(0.05);     step("mass");
    b.removeBody();                                                  step("remove body");
    doc.selectBody(0, "upper_arm");
    doc.setCurrentTime(0.6);
    c.addPin();                                                      step("add pin");
    setSpin(c.form()->editor("Target"), "y", 0.5);                   step("move pin target");
    c.keyCurrentPose();                                              step("key pose");
    c.addRest();                                                     step("add rest");
    c.addContact();                                                  step("add contact");
    c.addClearance();                                                step("add clearance");
    c.addFormula();                                                  step("add formula");
    c.setEnabled("takeoff", false);                                  step("disable");
    doc.selectTerm("start_rest");
    c.removeSelected();                                              step("delete");
    // Drag the landing contact bar 0.1 s earlier on the timeline: one merged command.
    TimelineBar* bar = w.timeline()->bar();
    const QRectF r = bar->contactBar("landing");
    QVERIFY(!r.isEmpty());
    const QPoint from = r.center().toPoint();
    const QPoint to = from - QPoint(static_cast<int>(bar->xAt(0.1) - bar->xAt(0.0)), 0);
    QTest::mousePress(bar, Qt::LeftButton, {}, from);
    for (int k = 1; k <= 5; ++k) {
      QMouseEvent move(QEvent::MouseMove, QPointF(from + (to - from) * k / 5), bar->mapToGlobal(QPointF(from + (to - from) * k / 5)),
                       Qt::NoButton, Qt::LeftButton, Qt::NoModifier);
      QApplication::sendEvent(bar, &move);
    }
    QTest::mouseRelease(bar, Qt::LeftButton, {}, to);               step("drag contact");
    const int commands = doc.undoStack()->count();
    QCOMPARE(commands, static_cast<int>(states.size()) - 1);  // the drag merged into one
    b.applyPreset(":/scenes/particle.json");                         step("preset");

    for (int i = static_cast<int>(states.size()) - 2; i >= 0; --i) {
      doc.undoStack()->undo();
      QVERIFY2(json(doc) == states[i], qPrintable(QString("undo to state %1 differs").arg(i)));
    }
    QVERIFY(!doc.isModified());
    for (size_t i = 1; i < states.size(); ++i) {
      doc.undoStack()->redo();
      QVERIFY2(json(doc) == states[i], qPrintable(QString("redo to state %1 differs").arg(i)));
    }
  }

  void saveThenLoadIsIdenticalWithTheSolution() {
    QTemporaryDir dir;
    MainWindow w;
    QVERIFY(solvedParticle(w));
    QVERIFY(w.document()->motion() && w.document()->motion()->converged);
    QString error;
    const QString path = dir.filePath("particle_saved.json");
    QVERIFY2(w.saveFile(path, &error), qPrintable(error));
    QVERIFY(!w.document()->isModified());

    Document loaded;
    QVERIFY2(loaded.open(path, &error), qPrintable(error));
    QCOMPARE(sceneToJson(loaded.sceneForSave()), sceneToJson(w.document()->sceneForSave()));
    QVERIFY(loaded.motion() && loaded.motion()->solved);
    const Eigen::MatrixXd& a = w.document()->motion()->animation.characters[0].q;
    const Eigen::MatrixXd& b = loaded.motion()->animation.characters[0].q;
    QCOMPARE(a.rows(), b.rows());
    QCOMPARE((a - b).cwiseAbs().maxCoeff(), 0.0);  // the same variables give the same motion
  }

  // File > Import > Start from Motion: the jump's motion exported by one window (its 120 Hz
  // display samples) starts another window's scene near the same motion - fitted, within 1e-4 of
  // every displayed q - and its solve, sqp since the file has no multipliers, ends at the same
  // objective in a few steps. A malformed file and a motion of another character are refused
  // with the reason, the motion on show unchanged. A scene solved by witkin-kass keeps its method,
  // warm from the multipliers the import estimates.
  void aMotionFileStartsTheSolveAtItsOptimum() {
    QTemporaryDir dir;
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/luxo_jump.json"));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    QVERIFY(w.document()->motion() && w.document()->motion()->converged);
    const double objective = w.document()->motion()->objective;
    QString error;
    QVERIFY2(w.exportMotionJson(dir.filePath("motion.json"), &error), qPrintable(error));

    MainWindow v;
    QVERIFY(openScene(v, ":/scenes/luxo_jump.json"));
    v.setAutoSolve(false);
    QVERIFY2(v.importMotionJson(dir.filePath("motion.json"), &error), qPrintable(error));
    const std::shared_ptr<const SolvedMotion> fitted = v.document()->motion();
    QVERIFY(fitted && fitted->fromMotionFile && !fitted->solved);
    const Eigen::MatrixXd& a = w.document()->motion()->animation.characters[0].q;
    const Eigen::MatrixXd& b = fitted->animation.characters[0].q;
    QCOMPARE(a.rows(), b.rows());
    QVERIFY2((a - b).cwiseAbs().maxCoeff() < 1e-4, qPrintable(QString::number((a - b).cwiseAbs().maxCoeff())));
    QVERIFY(v.statusText().contains("Started from motion.json"));
    v.solve();
    QVERIFY(v.solverJob()->waitForFinished(scaled(120000)));
    const std::shared_ptr<const SolvedMotion> solved = v.document()->motion();
    QVERIFY(solved && solved->converged && !solved->fromMotionFile);
    QVERIFY2(QString::fromStdString(solved->reason).contains(QRegularExpression("after [1-3] SQP steps")),
             solved->reason.c_str());
    QVERIFY2(std::abs(solved->objective - objective) < 1e-6 * objective,
             qPrintable(QString("%1 against %2").arg(solved->objective, 0, 'g', 12).arg(objective, 0, 'g', 12)));

    // A scene solved by witkin-kass keeps its method: the import estimates the multipliers its
    // warm start reads, and Newton steps alone end at the same optimum.
    {
      QFile shipped(":/scenes/luxo_jump.json");
      QVERIFY(shipped.open(QIODevice::ReadOnly));
      QJsonObject json = QJsonDocument::fromJson(shipped.readAll()).object();
      QJsonObject solver = json["solver"].toObject();
      solver["method"] = "witkin-kass";
      json["solver"] = solver;
      QFile edited(dir.filePath("witkin_kass.json"));
      QVERIFY(edited.open(QIODevice::WriteOnly));
      edited.write(QJsonDocument(json).toJson());
      edited.close();
      MainWindow k;
      QVERIFY(openScene(k, edited.fileName()));
      k.setAutoSolve(false);
      QVERIFY2(k.importMotionJson(dir.filePath("motion.json"), &error), qPrintable(error));
      k.solve();
      QVERIFY(k.solverJob()->waitForFinished(scaled(120000)));
      const std::shared_ptr<const SolvedMotion> projected = k.document()->motion();
      QVERIFY(projected && projected->converged);
      QVERIFY2(QString::fromStdString(projected->reason).contains(QRegularExpression("after [1-9] Newton steps")),
               projected->reason.c_str());
      QVERIFY2(std::abs(projected->objective - objective) < 1e-6 * objective,
               qPrintable(QString("%1 against %2").arg(projected->objective, 0, 'g', 12).arg(objective, 0, 'g', 12)));
    }

    QFile bad(dir.filePath("bad.json"));
    QVERIFY(bad.open(QIODevice::WriteOnly));
    bad.write("{\"formatVersion\": 1, \"characters\": [{\"name\": \"luxo\"}]}");
    bad.close();
    QVERIFY(!v.importMotionJson(dir.filePath("bad.json"), &error));
    QVERIFY2(error.contains("field 'characters[0].dofs': missing required field"), qPrintable(error));
    MainWindow particle;
    QVERIFY(solvedParticle(particle));
    QVERIFY2(particle.exportMotionJson(dir.filePath("particle.json"), &error), qPrintable(error));
    QVERIFY(!v.importMotionJson(dir.filePath("particle.json"), &error));
    QVERIFY2(error.contains("holds no character of this scene"), qPrintable(error));
    QCOMPARE(v.document()->motion(), solved);
  }

  // Every export of a solved motion writes its file: motion JSON and CSV, URDF, glTF, and a BVH
  // with one frame per displayed sample.
  void exportsWriteEveryFormat() {
    QTemporaryDir dir;
    MainWindow before;
    QVERIFY(openScene(before, ":/scenes/particle.json"));
    QString error;
    QVERIFY(!before.exportBvh(dir.filePath("none"), &error));  // nothing solved yet: a clear error
    QVERIFY(error.contains("solve first"));
    MainWindow w;
    QVERIFY(solvedParticle(w));
    QVERIFY2(w.exportMotionJson(dir.filePath("motion.json"), &error), qPrintable(error));
    QVERIFY2(w.exportMotionCsv(dir.filePath("motion.csv"), &error), qPrintable(error));
    QVERIFY2(w.exportUrdf(dir.filePath("urdf"), &error), qPrintable(error));
    QVERIFY2(w.exportBvh(dir.filePath("bvh"), &error), qPrintable(error));
    QVERIFY2(w.exportGltf(dir.filePath("motion.glb"), &error), qPrintable(error));
    for (const char* name : {"motion.json", "motion.csv", "urdf/particle.urdf", "bvh/particle.bvh", "motion.glb"})
      QVERIFY2(QFileInfo(dir.filePath(name)).size() > 0, name);
    QFile bvh(dir.filePath("bvh/particle.bvh"));
    QVERIFY(bvh.open(QIODevice::ReadOnly));
    const QString text = QString::fromUtf8(bvh.readAll());
    QVERIFY(text.startsWith("HIERARCHY\nROOT "));
    // At the scene's frame rate (the timeline's fps field; 24 by default), whatever the display
    // samples: the particle's 1 s clip is 25 frames of 1/24 s.
    QCOMPARE(w.timeline()->framesPerSecond(), 24);
    QVERIFY2(text.contains("Frames: 25\n"), qPrintable(text.left(400)));
    const QRegularExpressionMatch frameTime = QRegularExpression("Frame Time: ([0-9.eE+-]+)").match(text);
    QVERIFY(frameTime.hasMatch());
    QVERIFY(std::abs(frameTime.captured(1).toDouble() - 1.0 / 24) < 1e-9);
    // And at 30 fps: 31 frames.
    auto* fps = w.timeline()->findChild<QSpinBox*>();
    QVERIFY(fps);
    fps->setValue(30);
    QVERIFY2(w.exportBvh(dir.filePath("bvh30"), &error), qPrintable(error));
    QFile bvh30(dir.filePath("bvh30/particle.bvh"));
    QVERIFY(bvh30.open(QIODevice::ReadOnly));
    const QString text30 = QString::fromUtf8(bvh30.readAll());
    QVERIFY2(text30.contains("Frames: 31\n"), qPrintable(text30.left(400)));
    // The rate is the scene's (saved with it, one undo step); the solved motion still fits it.
    QCOMPARE(w.document()->scene().frameRate, 30.0);
    QVERIFY(w.document()->showsSolutionOfScene());
    w.document()->undoStack()->undo();
    QCOMPARE(w.document()->scene().frameRate, 24.0);
    QCOMPARE(fps->value(), 24);
  }

  // PNG frames at the scene's frame rate, at a resolution other than the viewport's (rendered
  // offscreen), each showing the scene: the lamp's colours, not a blank or black frame.
  void pngFramesAtAChosenResolution() {
    QTemporaryDir dir;
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1000, 700)));
    w.viewport()->frameAll();
    QString error;
    QVERIFY2(w.exportImageSequence(dir.filePath("png"), &error, QSize(640, 360)), qPrintable(error));
    const QStringList frames = QDir(dir.filePath("png")).entryList({"frame_*.png"}, QDir::Files, QDir::Name);
    QCOMPARE(frames.size(), 29);  // 1.2 s at 24 fps, both ends
    for (const QString& name : {frames.front(), frames.back()}) {
      const QImage image(dir.filePath("png/" + name));
      QCOMPARE(image.size(), QSize(640, 360));
      std::set<QRgb> colours;
      int yellowish = 0;  // the lamp's head (0.95, 0.85, 0.4), lit
      for (int y = 0; y < image.height(); y += 2)
        for (int x = 0; x < image.width(); x += 2) {
          const QColor c = image.pixelColor(x, y);
          colours.insert(c.rgb());
          yellowish += c.red() > 120 && c.green() > 100 && c.blue() < 0.7 * c.green();
        }
      QVERIFY2(colours.size() > 50, qPrintable(QString::number(colours.size())));
      QVERIFY2(yellowish > 100, qPrintable(QString::number(yellowish)));
    }
  }

  // The dock layout survives a restart: closing saves it to QSettings, the next window restores
  // it (a hidden panel stays hidden, a moved one stays where it was put).
  void dockLayoutIsRestoredFromSettings() {
    QSettings().clear();
    {
      MainWindow w;
      w.resize(1200, 800);
      w.show();
      QVERIFY(QTest::qWaitForWindowExposed(&w));
      w.findChild<QDockWidget*>("graphDock")->hide();
      w.addDockWidget(Qt::RightDockWidgetArea, w.findChild<QDockWidget*>("builderDock"));
      QVERIFY(w.close());
    }
    MainWindow restored;
    restored.show();
    QVERIFY(QTest::qWaitForWindowExposed(&restored));
    auto* graphs = restored.findChild<QDockWidget*>("graphDock");
    auto* builder = restored.findChild<QDockWidget*>("builderDock");
    QVERIFY(graphs && builder);
    QVERIFY(graphs->isHidden());
    QVERIFY(!builder->isHidden());
    QCOMPARE(restored.dockWidgetArea(builder), Qt::RightDockWidgetArea);
    QCOMPARE(restored.size(), QSize(1200, 800));
    QSettings().clear();
  }

  // A session that dies leaves its autosave behind; the next session finds it and recovers the
  // unsaved scene exactly, as a modified document without a file. A clean close removes the
  // session's own autosave.
  void autosaveIsRecoveredAfterACrash() {
    for (const QString& f : MainWindow::pendingRecoveries()) QFile::remove(f);
    auto* crashed = new MainWindow;
    QVERIFY(openScene(*crashed, ":/scenes/particle.json"));
    crashed->document()->edit("Move pin", [](Scene& s) {
      for (TermSpec& t : s.terms)
        if (t.kind == TermKind::Pin) t.position.y() += 0.25;
    });
    QVERIFY(crashed->writeAutosave());
    const QString autosave = crashed->autosavePath();
    const std::string unsaved = sceneToJson(crashed->document()->sceneForSave());
    delete crashed;  // no closeEvent: as if the process had died
    QVERIFY(MainWindow::pendingRecoveries().contains(autosave));

    MainWindow w;
    QString error;
    QVERIFY2(w.recoverAutosave(autosave, &error), qPrintable(error));
    QCOMPARE(sceneToJson(w.document()->sceneForSave()), unsaved);
    QVERIFY(w.document()->isModified());
    QVERIFY(w.document()->filePath().isEmpty());
    QVERIFY(QFile::remove(autosave));

    QVERIFY(w.writeAutosave());
    QVERIFY(QFile::exists(w.autosavePath()));
    QTemporaryDir dir;
    QVERIFY2(w.saveFile(dir.filePath("recovered.json"), &error), qPrintable(error));
    QVERIFY(w.close());  // saved, so no prompt
    QVERIFY(!QFile::exists(w.autosavePath()));
  }

  // A live window's autosave is never taken for a crash's leftover (its lock is held), and an
  // edit is autosaved a few seconds after it, not only every 30 s.
  void aLiveWindowsAutosaveIsNotRecoveredAndEditsAreSavedSoon() {
    for (const QString& f : MainWindow::pendingRecoveries()) QFile::remove(f);
    auto* first = new MainWindow;
    QVERIFY(openScene(*first, ":/scenes/particle.json"));
    first->document()->edit("Move pin", [](Scene& s) {
      for (TermSpec& t : s.terms)
        if (t.kind == TermKind::Pin) t.position.y() += 0.25;
    });
    QElapsedTimer clock;
    clock.start();
    QTRY_VERIFY_WITH_TIMEOUT(QFile::exists(first->autosavePath()), scaled(3 * MainWindow::kAutosaveDelayMs));
    QVERIFY(clock.elapsed() < 3 * MainWindow::kAutosaveDelayMs);
    const QString path = first->autosavePath();
    MainWindow second;  // another editor instance starting up
    QVERIFY(!MainWindow::pendingRecoveries().contains(path));
    QVERIFY(QFile::exists(path));
    delete first;  // no closeEvent: as if the process had died
    QVERIFY(MainWindow::pendingRecoveries().contains(path));
    QVERIFY(QFile::remove(path));
  }

  // The longest event-loop gap in the first 4 s of a Luxo solve from the default guess, and the
  // iterates that reached the interface.
  // In an instrumented build (SPACETIME_TIME_SCALE > 1) the window is stretched like the solve.
  static EventLoopGap luxoSolveGap(WindowMode mode) {
    MainWindow w;
    if (!openLuxo(w, mode == WindowMode::Hidden ? std::nullopt : std::optional<QSize>(QSize(1400, 900)))) return {};
    return eventLoopGapDuringSolve(w, mode, scaled(4000));
  }

  void luxoSolveKeepsTheEventLoopResponsive() {
    // The solve runs on a worker thread and hands iterates over latest-wins, so the interface
    // thread only swaps a pointer, updates the plots and draws. The issue's target: no gap over
    // 50 ms. Hidden, the interface thread's own work is measured: 6 ms on this 2-core machine,
    // so it is asserted - with the suite run alone (RUN_SERIAL in tests/CMakeLists.txt): next to
    // another solver test under `ctest -j2` CI once measured 78 ms, the scheduler's share of two
    // cores among three busy threads rather than the editor's work.
    // Shown, each iterate's one repaint composites the whole window in Mesa's software renderer
    // (~30 ms): 26-44 ms (every iterate drawn) and 26-42 ms (timeline playing too) on an idle
    // machine, more when another process loads the second core - reported here and as medians
    // by the editor benchmark, not asserted.
    const EventLoopGap hidden = luxoSolveGap(WindowMode::Hidden);
    qInfo("window hidden: longest event-loop gap %lld ms (ending %lld ms into the solve, after %d iterates), "
          "%d iterates delivered", hidden.worstMs, hidden.worstEndedAtMs, hidden.iteratesBeforeWorst, hidden.iterates);
    // Live refinement: iterates reached the interface. The hidden solve takes 0.6-0.9 s today and
    // live iterates come at most every 250 ms, so 2 or 3 arrive (3 of 3 runs, then 2: asking for
    // 3 failed at random); 2 still means a live iterate after the starting motion.
    QVERIFY(hidden.iterates >= 2);
    // The 50 ms bound is a property of the Release build: under a sanitizer the interface
    // thread's own work is tens of times slower, so there the test only drives the hand-over.
    if (instrumentedTimeScale() == 1)
      QVERIFY2(hidden.worstMs >= 0 && hidden.worstMs <= 50, qPrintable(QString("event loop stalled %1 ms").arg(hidden.worstMs)));
    const EventLoopGap shown = luxoSolveGap(WindowMode::Shown);
    qInfo("window shown: longest event-loop gap %lld ms, %d iterates drawn", shown.worstMs, shown.iterates);
    // Drawn iterates: the solve now takes ~1.3 s and live iterates come at most every 250 ms,
    // latest-wins, so a busy interface thread (playing, another test loading the other core)
    // draws as few as 2 (measured: 2 while playing under `ctest -j2`). At least one live iterate
    // after the starting motion still proves the refinement is shown while it runs.
    QVERIFY(shown.iterates >= 2);
    const EventLoopGap playing = luxoSolveGap(WindowMode::ShownPlaying);
    qInfo("window shown and playing: longest event-loop gap %lld ms, %d iterates drawn", playing.worstMs, playing.iterates);
    QVERIFY(playing.iterates >= 2);
  }

  // The safety net: a re-solve that stops without converging (here: Stop during the re-solve
  // after a 27 cm drag of the landing) leaves the last converged motion on show, and one undo
  // brings back exactly the motion of the scene it restores (the same q, byte for byte) without
  // solving, auto-solve on. The stopped result stays at hand (Solve > Show the stopped result).
  void aStoppedSolveKeepsTheLastGoodMotionAndUndoRestoresIt() {
    MainWindow w;
    QVERIFY(openLuxo(w));
    w.setAutoSolve(true);
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    const auto good = w.document()->motion();
    QVERIFY2(good && good->converged, qPrintable(w.statusText()));
    QVERIFY(w.document()->showsSolutionOfScene());
    const Eigen::MatrixXd q = good->animation.characters[0].q;

    w.document()->edit("Drag the landing", [](Scene& s) {
      for (TermSpec& t : s.terms)
        if (t.id == "end_pose")
          for (auto& [dof, value] : t.values)
            if (dof == "base_x") value += 0.27;
    }, kMergeTermField);
    QTRY_VERIFY_WITH_TIMEOUT(w.solverJob()->isRunning(), scaled(5000));
    QTRY_VERIFY_WITH_TIMEOUT(w.document()->motion() != good, scaled(20000));  // a live iterate
    w.stopSolve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(10000)));
    QTRY_VERIFY(w.document()->stoppedMotion() != nullptr);
    QVERIFY(!w.document()->stoppedMotion()->converged);
    QCOMPARE(w.document()->motion()->animation.characters[0].q, q);
    QVERIFY2(w.statusText().contains("showing the last converged motion"), qPrintable(w.statusText()));

    w.document()->undoStack()->undo();
    QTest::qWait(200);
    QVERIFY(!w.solverJob()->isRunning());
    QVERIFY(w.document()->showsSolutionOfScene());
    const Eigen::MatrixXd& back = w.document()->motion()->animation.characters[0].q;
    QCOMPARE(back.rows(), q.rows());
    QVERIFY(std::memcmp(back.data(), q.data(), sizeof(double) * q.size()) == 0);

    // Redo returns to the dragged scene, whose re-solve had not converged: it solves again.
    w.document()->undoStack()->redo();
    QTRY_VERIFY_WITH_TIMEOUT(w.solverJob()->isRunning(), scaled(5000));
    w.stopSolve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(10000)));
    QTRY_VERIFY(w.document()->stoppedMotion() != nullptr);
    const auto stopped = w.document()->stoppedMotion();
    QAction* show = nullptr;
    for (QAction* a : w.findChildren<QAction*>())
      if (a->text().contains("stopped")) show = a;
    QVERIFY(show && show->isEnabled());
    show->trigger();
    QCOMPARE(w.document()->motion(), stopped);
    QVERIFY(!show->isEnabled());
  }

  // The wheel over an unfocused field of a form scrolls; it never edits the scene. K keys the
  // pose at the current time (it was bound twice, and Qt ran neither).
  void wheelNeverEditsAndKKeysThePose() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1280, 800)));
    Document& doc = *w.document();
    doc.selectBody(0, doc.scene().characters[0].bodies[1].id);
    auto* mass = qobject_cast<QDoubleSpinBox*>(w.builder()->form()->editor("Mass"));
    QVERIFY(mass);
    QVERIFY(!mass->hasFocus());
    const std::string before = json(doc);
    const int commands = doc.undoStack()->count();
    const QPointF at = QPointF(mass->rect().center());
    for (int i = 0; i < 3; ++i) {
      QWheelEvent wheel(at, mass->mapToGlobal(at), QPoint(), QPoint(0, 120), Qt::NoButton, Qt::NoModifier,
                        Qt::NoScrollPhase, false);
      QApplication::sendEvent(mass, &wheel);
    }
    QCOMPARE(json(doc), before);
    QCOMPARE(doc.undoStack()->count(), commands);

    doc.setCurrentTime(0.3);
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    QTest::keyClick(QApplication::focusWidget() ? QApplication::focusWidget() : &w, Qt::Key_K);
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    const TermSpec& key = doc.scene().terms.back();
    QVERIFY(key.kind == TermKind::Keyframe);
    QCOMPARE(key.time, 0.3);
    QCOMPARE(key.values.size(), doc.scene().characters[0].dofNames().size());
  }

  // Blender-like keys: Ctrl+Z in a focused number field undoes the scene edit (not the field's
  // text), Ctrl+Y and Ctrl+Shift+Z redo it, Shift+Left and Shift+Right go to the clip's start
  // and end, Ctrl+Shift+S is Save As.
  void undoKeysInAFocusedFieldUndoTheScene() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1280, 800)));
    Document& doc = *w.document();
    w.setAutoSolve(false);
    doc.selectBody(0, doc.scene().characters[0].bodies[1].id);
    auto* mass = qobject_cast<QDoubleSpinBox*>(w.builder()->form()->editor("Mass"));
    QVERIFY(mass);
    const double before = *doc.scene().characters[0].bodies[1].mass;
    mass->setValue(before + 0.5);
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, before + 0.5);
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    mass->setFocus();
    QTRY_VERIFY(mass->hasFocus());
    QTest::keyClick(mass, Qt::Key_Z, Qt::ControlModifier);
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, before);
    QCOMPARE(mass->value(), before);  // the field shows the scene's value again
    QTest::keyClick(mass, Qt::Key_Y, Qt::ControlModifier);
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, before + 0.5);
    QTest::keyClick(mass, Qt::Key_Z, Qt::ControlModifier);
    QTest::keyClick(mass, Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, before + 0.5);

    doc.setCurrentTime(0.4);
    QTest::keyClick(&w, Qt::Key_Right, Qt::ShiftModifier);
    QCOMPARE(doc.currentTime(), doc.scene().endTime);
    QTest::keyClick(&w, Qt::Key_Left, Qt::ShiftModifier);
    QCOMPARE(doc.currentTime(), doc.scene().startTime);
    QAction* saveAs = nullptr;
    for (QAction* a : w.findChildren<QAction*>())
      if (a->text().startsWith("Save &As")) saveAs = a;
    QVERIFY(saveAs && saveAs->shortcuts().contains(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S)));
  }

  // A typed value below a field's smallest is refused with a message under the form and the
  // field shows the scene's value again: -1 kg used to become +1 kg, and 0 was ignored silently.
  void typedValuesBelowTheSmallestAreRefusedWithAMessage() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1280, 800)));
    Document& doc = *w.document();
    w.setAutoSolve(false);
    doc.selectBody(0, doc.scene().characters[0].bodies[1].id);
    PropertyForm* form = w.builder()->form();
    auto* mass = qobject_cast<QDoubleSpinBox*>(form->editor("Mass"));
    QVERIFY(mass);
    const double before = *doc.scene().characters[0].bodies[1].mass;
    const int commands = doc.undoStack()->count();
    auto type = [&](const char* text) {
      mass->setFocus();
      mass->selectAll();
      QTest::keyClicks(mass, text);
      QTest::keyClick(mass, Qt::Key_Return);
    };
    for (const char* bad : {"-1", "0"}) {
      type(bad);
      QCOMPARE(*doc.scene().characters[0].bodies[1].mass, before);
      QCOMPARE(doc.undoStack()->count(), commands);
      QVERIFY2(form->message().contains("Mass must be at least 0.001 kg"), qPrintable(form->message()));
      QCOMPARE(mass->value(), before);
    }
    type("2");
    QCOMPARE(*doc.scene().characters[0].bodies[1].mass, 2.0);
    QVERIFY(form->message().isEmpty());
  }

  // Removing a body with a subtree says what went with it; one undo brings it all back.
  void removingABodySaysWhatWentWithIt() {
    MainWindow w;
    QVERIFY(openLuxo(w));
    w.setAutoSolve(false);
    Document& doc = *w.document();
    const std::string before = json(doc);
    doc.selectBody(0, "lower_arm");
    w.builder()->removeBody();
    QCOMPARE(doc.scene().characters[0].bodies.size(), size_t(1));
    QVERIFY2(w.statusText().contains("Removed 'lower_arm', 2 bodies under it"), qPrintable(w.statusText()));
    QVERIFY2(w.statusText().contains("Ctrl+Z"), qPrintable(w.statusText()));
    doc.undoStack()->undo();
    QCOMPARE(json(doc), before);
  }

  // Open Recent lists a file once however its path was spelled.
  void openRecentListsAFileOnce() {
    QTemporaryDir dir;
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/particle.json"));
    QString error;
    const QString path = dir.filePath("recent.json");
    QVERIFY2(w.saveFile(path, &error), qPrintable(error));
    QVERIFY2(w.saveFile(dir.path() + "/./recent.json", &error), qPrintable(error));
    QVERIFY2(w.openFile(path, &error), qPrintable(error));
    QMenu* recent = nullptr;
    for (QMenu* m : w.findChildren<QMenu*>())
      if (m->title().contains("Recent")) recent = m;
    QVERIFY(recent);
    int entries = 0;
    for (QAction* a : recent->actions())
      if (QFileInfo(a->text()).fileName() == "recent.json") ++entries;
    QCOMPARE(entries, 1);
  }

  // File > New starts from a clean status: not the previous scene's solve result.
  void newSceneClearsThePreviousResult() {
    MainWindow w;
    QVERIFY(solvedParticle(w));
    QVERIFY2(w.statusText().contains("Converged"), qPrintable(w.statusText()));
    QAction* fresh = nullptr;
    for (QAction* a : w.findChildren<QAction*>())
      if (a->text() == "&New") fresh = a;
    QVERIFY(fresh);
    fresh->trigger();
    QCOMPARE(w.statusText(), QString("Ready"));
    QVERIFY(!w.document()->motion());
  }

  // The Scene panel reaches the scene-wide fields a new character needs (clip, gravity, ground,
  // objective, resolution), each edit one undo command; a clip end before its start is kept
  // after it.
  void sceneSettingsEditTheSceneUndoably() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/particle.json"));
    Document& doc = *w.document();
    PropertyForm* form = w.sceneSettings()->form();
    const int commands = doc.undoStack()->count();
    auto* end = qobject_cast<QDoubleSpinBox*>(form->editor("Clip end"));
    QVERIFY(end);
    end->setValue(2.5);
    QCOMPARE(doc.scene().endTime, 2.5);
    setSpin(form->editor("Gravity"), "y", -1.62);
    QCOMPARE(doc.scene().gravity.y(), -1.62);
    auto* ground = qobject_cast<QCheckBox*>(form->editor("Ground"));
    QVERIFY(ground);
    QVERIFY(!doc.scene().groundEnabled);
    ground->setChecked(true);
    QVERIFY(doc.scene().groundEnabled);
    auto* height = qobject_cast<QDoubleSpinBox*>(form->editor("Ground height"));
    QVERIFY(height);
    height->setValue(-1);  // under the particle's lowest pin (at y = 0 a pin would hold the ball in it)
    QCOMPARE(doc.scene().groundHeight, -1.0);
    auto* rate = qobject_cast<QDoubleSpinBox*>(form->editor("Control points per second"));
    QVERIFY(rate);
    rate->setValue(30);
    QCOMPARE(doc.scene().transcription.controlPointsPerSecond, 30.0);
    auto* samples = qobject_cast<QComboBox*>(form->editor("Samples per segment"));
    QVERIFY(samples);
    samples->setCurrentIndex(3);
    QCOMPARE(doc.scene().transcription.samplesPerSegment, 4);
    auto* legs = qobject_cast<QCheckBox*>(form->editor("Leg bubbles"));
    QVERIFY(legs);
    legs->setChecked(true);
    QVERIFY(doc.scene().transcription.legBubbles);
    auto* method = qobject_cast<QComboBox*>(form->editor("Solver method"));
    QVERIFY(method);
    QCOMPARE(method->count(), static_cast<int>(std::size(SolverSpec::kMethods)));  // one entry per method
    method->setCurrentIndex(1);
    QCOMPARE(doc.scene().solver.method, std::string("ipopt"));
    QCOMPARE(doc.undoStack()->count(), commands + 8);
    end->setValue(-5);  // before the start: kept after it
    QVERIFY(doc.scene().endTime > doc.scene().startTime);
    QCOMPARE(end->value(), doc.scene().endTime);
    doc.undoStack()->undo();
    QCOMPARE(doc.scene().endTime, 2.5);
    // The edited scene solves (the particle over 2.5 s under moon gravity), with the method chosen.
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(60000)));
    QVERIFY2(doc.motion() && doc.motion()->converged, qPrintable(w.statusText()));
    if (interiorPointAvailable()) QVERIFY2(w.statusText().contains("interior-point"), qPrintable(w.statusText()));
    while (doc.undoStack()->canUndo() && doc.undoStack()->index() > commands) doc.undoStack()->undo();
    QCOMPARE(doc.scene().endTime, 1.0);
    QCOMPARE(end->value(), 1.0);
  }

  // At 1280x720 a docked form shows every vector component whole: the fields wrap under their
  // labels instead of running off the panel (the gravity's z needed sideways scrolling).
  void vectorFieldsFitTheDockedPanel() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1280, 720)));
    for (QDockWidget* d : w.findChildren<QDockWidget*>())
      if (d->windowTitle() == "Scene") d->raise();
    QTest::qWait(50);
    QWidget* gravity = w.sceneSettings()->form()->editor("Gravity");
    QVERIFY(gravity && gravity->isVisible());
    QWidget* panel = w.sceneSettings();
    for (QDoubleSpinBox* s : gravity->findChildren<QDoubleSpinBox*>()) {
      const int needed = s->fontMetrics().horizontalAdvance(s->text()) + 4;
      QVERIFY2(s->width() >= needed, qPrintable(QString("%1: %2 px for %3 px of text").arg(s->objectName()).arg(s->width()).arg(needed)));
      const QPoint right = s->mapTo(panel, QPoint(s->width(), 0));
      QVERIFY2(right.x() <= panel->width(), qPrintable(QString("%1 ends at %2 of %3").arg(s->objectName()).arg(right.x()).arg(panel->width())));
    }
  }

  void stopLeavesAConsistentDocument() {
    MainWindow w;
    QVERIFY(openLuxo(w));
    const std::string before = json(*w.document());
    const int commands = w.document()->undoStack()->count();
    // Stop as soon as the first live iterate arrives: the Luxo solve takes about a second now,
    // so a fixed wait could see it finish.
    const auto initial = w.document()->motion();
    w.solve();
    QTRY_VERIFY_WITH_TIMEOUT(w.document()->motion() != initial, scaled(20000));
    QElapsedTimer clock;
    clock.start();
    w.stopSolve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(10000)));
    qInfo("stopped %lld ms after Stop: %s", clock.elapsed(), qPrintable(w.statusText()));
    QCOMPARE(json(*w.document()), before);
    QCOMPARE(w.document()->undoStack()->count(), commands);
    QVERIFY(!w.document()->isModified());
    auto motion = w.document()->motion();
    QVERIFY(motion);
    QVERIFY(motionFitsScene(*motion, w.document()->scene()));
    QVERIFY(!motion->converged);
    QVERIFY(motion->animation.characters[0].q.allFinite());
    QVERIFY(w.statusText().contains("Stopped"));
    // The stopped motion is checked too (the report follows the motion), and fails: physics
    // does not hold yet.
    QTRY_VERIFY(w.document()->motion()->validity);
    QVERIFY2(w.validity()->verdict().contains("fail"), qPrintable(w.validity()->verdict()));
    // Clicking the dense-grid row takes the timeline to where the residual is worst.
    QTreeWidget* checks = w.validity()->list();
    QTreeWidgetItem* dense = nullptr;
    for (int i = 0; i < checks->topLevelItemCount(); ++i)
      if (checks->topLevelItem(i)->text(0).contains("residual on the dense grid")) dense = checks->topLevelItem(i);
    QVERIFY(dense);
    emit checks->itemClicked(dense, 0);
    QCOMPARE(w.document()->currentTime(), w.document()->motion()->validity->worstDenseTime);
    QVERIFY(w.document()->currentTime() > 0);
    // Solving again continues from where Stop left it.
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(300000)));
    QVERIFY2(w.document()->motion()->converged, qPrintable(w.statusText()));
  }

  // A motion that fails between the samples is refined in the editor as on the command line
  // (solveRefined). The shipped lamp at three samples per segment converges with 18 % of its
  // weight unexplained between the samples; the solve splits the segments where it is, the live
  // view follows the finer transcription, and the scene takes that transcription as one undo
  // command. The status bar, the validity panel and the Scene panel say what was refined;
  // saving keeps the motion with the knots it fits; undo returns to the scene's own
  // transcription.
  void aSolveRefinesTheTranscriptionAndTheSceneTakesIt() {
    MainWindow w;
    QVERIFY(openLuxo(w));
    Document& doc = *w.document();
    doc.edit("Three samples per segment", [](Scene& s) { s.transcription.samplesPerSegment = 3; });
    const std::string coarse = json(doc);
    const int commands = doc.undoStack()->count();
    // An iterate of the refined transcription is shown while it runs, and the status says so.
    bool liveOnKnots = false;
    QString statusOnKnots;
    connect(w.solverJob(), &SolverJob::iterate, this, [&](std::shared_ptr<const SolvedMotion> m) {
      if (!m->scene || m->scene->transcription.knots.empty()) return;
      liveOnKnots = true;
      statusOnKnots = w.statusText();
    });
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(300000)));
    const auto motion = doc.motion();
    QVERIFY2(motion && motion->converged, qPrintable(w.statusText()));
    QVERIFY2(motion->transcriptions.size() >= 2, qPrintable(w.statusText()));
    QVERIFY(motion->transcriptions.front().converged && !motion->transcriptions.front().valid);
    QVERIFY(motion->transcriptions.back().kept && motion->transcriptions.back().valid);
    QVERIFY(liveOnKnots);

    // The scene is the refined one, as one undo command, and the motion on show is its solution.
    const TranscriptionSpec& refined = doc.scene().transcription;
    QVERIFY(!refined.knots.empty());
    QCOMPARE(refined.samplesPerSegment, RefinementOptions::kMaxRefinedSamples);
    QVERIFY2(statusOnKnots.contains(QString("on a finer transcription: %1 segments, s = 8").arg(refined.knots.size() + 1)),
             qPrintable(statusOnKnots));
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    QCOMPARE(doc.undoStack()->undoText(), QString("Refine the transcription"));
    QVERIFY2(doc.undoStack()->text(commands).contains("segments split from 20 control points per second"),
             qPrintable(doc.undoStack()->text(commands)));
    QVERIFY(doc.showsSolutionOfScene());
    QVERIFY(doc.isModified());

    // What was refined, where the user looks.
    QVERIFY2(w.statusText().contains("finer transcription tried"), qPrintable(w.statusText()));
    QVERIFY(motion->validity);
    QVERIFY2(w.validity()->verdict().startsWith("Physically valid"), qPrintable(w.validity()->verdict()));
    QVERIFY2(w.validity()->verdict().contains("refined the transcription once, because the motion at 20 control "
                                              "points per second, s = 3 failed"),
             qPrintable(w.validity()->verdict()));
    auto* segments = w.sceneSettings()->findChild<QLabel*>("segments");
    QVERIFY(segments);
    QVERIFY2(segments->text().startsWith(QString::number(refined.knots.size() + 1) + ", split"), qPrintable(segments->text()));

    // Saved and opened again: the motion comes back on its knots without a solve.
    QTemporaryDir dir;
    QString error;
    const QString path = dir.filePath("refined.json");
    QVERIFY2(w.saveFile(path, &error), qPrintable(error));
    MainWindow reopened;
    QVERIFY(openScene(reopened, path));
    QVERIFY(reopened.document()->motion() && reopened.document()->motion()->converged);
    // Exactly the solved variables: a state has its held stances settled (their copies of the
    // stance pose, their zero velocities) as restoring it does, so nothing moves on reopening.
    const std::vector<double>& back = reopened.document()->motion()->state.variables;
    QCOMPARE(back.size(), motion->state.variables.size());
    for (size_t i = 0; i < back.size(); ++i) QVERIFY(std::abs(back[i] - motion->state.variables[i]) < 1e-12);

    // Undo returns to the scene's own transcription and shows the motion the solve reached there,
    // with its failed report: that scene's solution, so auto-solve does not solve it again (it
    // would refine again and drop the redo). Redo brings the refined solution back.
    w.setAutoSolve(true);
    doc.undoStack()->undo();
    QCOMPARE(json(doc), coarse);
    QCOMPARE(segments->text(), QString("24, uniform"));
    QVERIFY(motion->unrefined);
    QCOMPARE(doc.motion(), motion->unrefined);
    QVERIFY(doc.showsSolutionOfScene());
    QCOMPARE(doc.motion()->scene->transcription.samplesPerSegment, 3);
    QCOMPARE(doc.motion()->objective, motion->transcriptions.front().objective);
    QVERIFY2(w.validity()->verdict().contains("fail"), qPrintable(w.validity()->verdict()));
    QTest::qWait(50);
    QVERIFY(!w.solverJob()->isRunning());
    QVERIFY(doc.undoStack()->canRedo());
    doc.undoStack()->redo();
    QVERIFY(doc.showsSolutionOfScene());
    QCOMPARE(doc.motion(), motion);
    w.setAutoSolve(false);

    // With "Most refinements" at 0 the scene's own transcription is the last word: the solve
    // ends on it, not valid, and the scene stays as it is.
    doc.undoStack()->undo();
    auto* most = qobject_cast<QDoubleSpinBox*>(w.sceneSettings()->form()->editor("Most refinements"));
    QVERIFY(most);
    most->setValue(0);
    QCOMPARE(doc.scene().solver.maxRefinements, 0);
    const std::string unrefined = json(doc);
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(300000)));
    QVERIFY2(doc.motion()->converged, qPrintable(w.statusText()));
    QCOMPARE(doc.motion()->transcriptions.size(), size_t(1));
    QVERIFY(!doc.motion()->transcriptions.front().valid);
    QCOMPARE(json(doc), unrefined);
    QVERIFY2(w.validity()->verdict().contains("fail"), qPrintable(w.validity()->verdict()));
  }

  // The refined transcription goes only to the scene the solve was asked to solve: a rate typed
  // while a solve ran (auto-solve off) is not overwritten by the refinement's when it ends.
  void aRefinedResultIsAdoptedOnlyByTheSceneItSolved() {
    Document doc;
    QString error;
    QVERIFY2(doc.open(":/scenes/luxo_jump.json", &error), qPrintable(error));
    const Scene asked = doc.scene();
    const auto result = refinedResultOf(asked);
    QVERIFY(result);
    const Scene& split = *result->scene;

    doc.edit("Rate", [](Scene& s) { s.transcription.controlPointsPerSecond = 25; });
    const int commands = doc.undoStack()->count();
    QVERIFY(doc.acceptResult(result));
    QCOMPARE(doc.undoStack()->count(), commands);
    QCOMPARE(doc.scene().transcription.controlPointsPerSecond, 25.0);
    QVERIFY(doc.scene().transcription.knots.empty());

    doc.undoStack()->undo();  // the scene the solve was asked to solve
    QVERIFY(doc.acceptResult(result));
    QCOMPARE(doc.scene().transcription.knots, split.transcription.knots);
    QCOMPARE(doc.scene().transcription.samplesPerSegment, 8);
    QCOMPARE(doc.undoStack()->undoText(), QString("Refine the transcription"));
    QVERIFY(doc.showsSolutionOfScene());

    // The same refinement again after undoing it and an edit made on it (a re-solve of the undone
    // scene): it is redone, and the edit stays on the redo stack.
    doc.edit("Gravity", [](Scene& s) { s.gravity.y() = -9.7; });
    const int after = doc.undoStack()->count();
    doc.undoStack()->undo();
    doc.undoStack()->undo();
    QCOMPARE(doc.scene().transcription.samplesPerSegment, asked.transcription.samplesPerSegment);
    QVERIFY(doc.acceptResult(result));
    QCOMPARE(doc.undoStack()->count(), after);
    QCOMPARE(doc.undoStack()->index(), after - 1);
    QCOMPARE(doc.scene().transcription.knots, split.transcription.knots);
    QCOMPARE(doc.undoStack()->redoText(), QString("Gravity"));
    QCOMPARE(doc.motion(), std::shared_ptr<const SolvedMotion>(result));
  }

  // A refinement adopted while a drag goes on (a live solve that refined the transcription,
  // whose result arrives between two moves) joins the drag's command: the drag stays one undo
  // command, its later moves keep the finer transcription, and one Undo returns to before it.
  // After the release a refinement is its own command again.
  void aRefinementDuringADragJoinsTheDragsCommand() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1400, 900)));
    Document& doc = *w.document();
    const std::string original = json(doc);
    const int commands = doc.undoStack()->count();
    // Drag the landing contact's bar to the left on the timeline, the result arriving mid-drag.
    TimelineBar* bar = w.timeline()->bar();
    const QRectF r = bar->contactBar("landing");
    QVERIFY(!r.isEmpty());
    const QPoint from = r.center().toPoint();
    const QPoint to = from - QPoint(static_cast<int>(bar->xAt(0.05) - bar->xAt(0.0)), 0);
    auto moveTo = [&](int k) {
      const QPointF p = from + QPointF(to - from) * k / 6.0;
      QMouseEvent move(QEvent::MouseMove, p, bar->mapToGlobal(p), Qt::NoButton, Qt::LeftButton, Qt::NoModifier);
      QApplication::sendEvent(bar, &move);
    };
    QTest::mousePress(bar, Qt::LeftButton, {}, from);
    for (int k = 1; k <= 3; ++k) moveTo(k);
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    const auto result = refinedResultOf(doc.scene());
    QVERIFY(result);
    QVERIFY(doc.acceptResult(result));
    QCOMPARE(doc.scene().transcription.knots, result->scene->transcription.knots);
    QVERIFY(doc.showsSolutionOfScene());
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    QCOMPARE(doc.undoStack()->undoText(), QString("Move contact"));
    for (int k = 4; k <= 6; ++k) moveTo(k);
    QTest::mouseRelease(bar, Qt::LeftButton, {}, to);
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    QCOMPARE(doc.scene().transcription.knots, result->scene->transcription.knots);
    const auto landing = std::find_if(doc.scene().terms.begin(), doc.scene().terms.end(),
                                      [](const TermSpec& t) { return t.id == "landing"; });
    QVERIFY(landing != doc.scene().terms.end() && landing->start < 0.8 - 0.04);
    const std::string dragged = json(doc);
    doc.undoStack()->undo();
    QCOMPARE(json(doc), original);
    doc.undoStack()->redo();
    QCOMPARE(json(doc), dragged);

    // After the release: the same kind of result is a command of its own.
    doc.undoStack()->undo();
    QTest::mousePress(bar, Qt::LeftButton, {}, from);
    for (int k = 1; k <= 6; ++k) moveTo(k);
    QTest::mouseRelease(bar, Qt::LeftButton, {}, to);
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    QVERIFY(doc.scene().transcription.knots.empty());
    QVERIFY(doc.acceptResult(refinedResultOf(doc.scene())));
    QCOMPARE(doc.undoStack()->count(), commands + 2);
    QCOMPARE(doc.undoStack()->undoText(), QString("Refine the transcription"));
  }

  // When the finer transcription's solve ran out of time, the motion kept is the coarser one, and
  // the validity panel says so instead of naming the finer transcription.
  void validityPanelSaysWhichTranscriptionsMotionIsShown() {
    Document doc;
    QString error;
    QVERIFY2(doc.open(":/scenes/luxo_jump.json", &error), qPrintable(error));
    std::string why;
    const auto problem = SpacetimeProblem::build(doc.scene(), &why);
    QVERIFY2(problem, why.c_str());
    auto result = sampleMotion(*problem);
    result->solved = result->converged = true;
    result->validity = std::make_shared<const ValidityReport>(checkValidity(*problem));
    TranscriptionAttempt coarse, finer;
    coarse.controlPointsPerSecond = finer.controlPointsPerSecond = 20;
    coarse.samplesPerSegment = 6;
    coarse.segments = 24;
    coarse.converged = true;
    coarse.kept = true;
    finer.samplesPerSegment = 8;
    finer.segments = 30;
    finer.nonUniform = true;
    finer.status = SolveStatus::TimeLimit;
    finer.why = "the motion at 20 control points per second, s = 6 failed the dense grid";
    result->transcriptions = {coarse, finer};
    ValidityPanel panel(&doc);
    QVERIFY(doc.acceptResult(result));
    QVERIFY2(panel.verdict().contains("refined the transcription once, because the motion at 20 control points per "
                                      "second, s = 6 failed the dense grid; the solve at 30 segments split from 20 "
                                      "control points per second, s = 8 stopped (time limit), so this motion is the "
                                      "one at 20 control points per second, s = 6."),
             qPrintable(panel.verdict()));
  }

  // The graphs plot what the physics says they must: in flight the plotted centre of mass falls
  // at g (its second difference on the 120 Hz frames), a body's plotted velocity is the
  // derivative of its plotted position, the plotted ground forces change the centre of mass's
  // momentum as Newton says, and the physics residual stays within the validity report's 1 % of
  // weight. The value axis is labelled at round numbers.
  // A series keeps its colour when another is added, no two plotted series share one, and a
  // left click in the plot moves the time there.
  void graphColoursAreStableAndAClickSetsTheTime() {
    MainWindow w;
    w.resize(1400, 900);
    w.show();
    QVERIFY(solvedParticle(w));
    GraphPanel* graphs = w.graphs();
    const std::vector<std::string> dofs = w.document()->scene().characters[0].dofNames();
    QVERIFY(dofs.size() >= 3);
    auto key = [&](const char* what, int d) { return QString("%1/0/%2").arg(what, QString::fromStdString(dofs[d])); };
    auto colours = [&] {
      std::map<QString, QColor> out;
      for (QAbstractSeries* s : graphs->view()->chart()->series())
        out[s->name()] = static_cast<QLineSeries*>(s)->color();
      return out;
    };
    graphs->setChecked(key("q", 0), true);
    graphs->setChecked(key("q", 1), true);
    const auto before = colours();
    QVERIFY(before.size() >= 2);
    graphs->setChecked(key("q", 2), true);
    graphs->setChecked(key("qd", 0), true);
    const auto after = colours();
    QCOMPARE(after.size(), before.size() + 2);
    for (const auto& [name, colour] : before) QCOMPARE(after.at(name), colour);
    std::set<QRgb> distinct;
    for (const auto& entry : after) distinct.insert(entry.second.rgb());
    QCOMPARE(distinct.size(), after.size());

    GraphView* view = graphs->view();
    QChart* chart = view->chart();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    const QPointF at = chart->mapToPosition(QPointF(0.7, 0), chart->series().front());
    QTest::mouseClick(view->viewport(), Qt::LeftButton, Qt::NoModifier, view->mapFromScene(at));
    QVERIFY2(std::abs(w.document()->currentTime() - 0.7) < 0.01, qPrintable(QString::number(w.document()->currentTime())));
  }

  void graphsPlotTheSolvedLampsPhysics() {
    QCOMPARE(niceTickInterval(28.6), 5.0);
    QCOMPARE(niceTickInterval(1.0), 0.2);
    QVERIFY(std::abs(niceTickInterval(0.013) - 0.002) < 1e-15);
    QCOMPARE(niceTickInterval(0.0), 1.0);
    // Every value axis has a handful of ticks: flat series (zero, or a constant 1000), wide ones,
    // empty data.
    for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{
             {0, 0}, {1000, 1000}, {-1e-12, 1e-12}, {-3, 250}, {0.2, 0.2000001}, {1, -1}}) {
      const ValueAxisRange r = valueAxisRange(lo, hi);
      const double ticks = (r.max - r.min) / r.tickInterval;
      QVERIFY2(ticks >= 2 && ticks <= 20, qPrintable(QString("[%1, %2]: %3 ticks").arg(lo).arg(hi).arg(ticks)));
      if (lo <= hi) QVERIFY(r.min < lo && r.max > hi);
    }
    MainWindow w;
    QVERIFY(openLuxo(w));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(300000)));
    QVERIFY2(w.document()->motion()->converged, qPrintable(w.statusText()));
    const Document& doc = *w.document();
    auto series = [&](const char* key) {
      PlotSeries s;
      QString error;
      if (!computeSeries(doc, key, &s, &error)) qWarning("%s: %s", key, qPrintable(error));
      return s;
    };
    const PlotSeries com = series("com/0/y");
    QVERIFY(com.times.size() > 100);
    const double h = com.times[1] - com.times[0];
    int flightFrames = 0;
    for (size_t f = 1; f + 1 < com.times.size(); ++f) {
      if (com.times[f] < 0.45 || com.times[f] > 0.75) continue;  // the flight is 0.4-0.8 s
      const double accel = (com.values[f + 1] - 2 * com.values[f] + com.values[f - 1]) / (h * h);
      QVERIFY2(std::abs(accel + 9.81) < 0.05, qPrintable(QString("com accel %1 at %2 s").arg(accel).arg(com.times[f])));
      ++flightFrames;
    }
    QVERIFY(flightFrames > 30);
    // The touch-down at 0.8 s is an impact: the velocity jumps there, so the difference across
    // it is no derivative. Elsewhere the central difference's truncation error at 120 Hz is up
    // to 1.4 % of the peak velocity (in the push-off).
    const PlotSeries pos = series("pos/0/head/x"), vel = series("vel/0/head/x");
    double worst = 0, peak = 0;
    for (size_t f = 1; f + 1 < pos.times.size(); ++f) {
      if (std::abs(pos.times[f] - 0.8) <= h) continue;
      worst = std::max(worst, std::abs((pos.values[f + 1] - pos.values[f - 1]) / (2 * h) - vel.values[f]));
      peak = std::max(peak, std::abs(vel.values[f]));
    }
    qInfo("velocity vs derivative of position: %g of peak %g", worst, peak);
    QVERIFY2(worst < 0.03 * peak, qPrintable(QString("velocity vs derivative of position: %1 of peak %2").arg(worst).arg(peak)));
    // Newton's second law for the whole lamp on the ground, in impulse form: over each stance the
    // plotted ground force less the weight, integrated, is the change of the plotted centre of
    // mass's momentum. (A second difference of the 120 Hz frames is too coarse for the push-off,
    // 0.1 × weight off at 0.3 s, and so is a first difference in its last 50 ms, 1.2 %.)
    const double mass = doc.models()[0].totalMass(), weight = mass * 9.81;
    const PlotSeries takeoff = series("force/takeoff/y"), landing = series("force/landing/y");
    QCOMPARE(takeoff.values.size(), com.values.size());
    QCOMPARE(landing.values.size(), com.values.size());
    auto frameAt = [&](double t) { return static_cast<size_t>(std::lround((t - com.times[0]) / h)); };
    auto comVelocity = [&](size_t f) { return (com.values[f + 1] - com.values[f - 1]) / (2 * h); };
    for (const auto& [a, b] : {std::pair{0.05, 0.3}, std::pair{0.85, 1.15}}) {
      const size_t fa = frameAt(a), fb = frameAt(b);
      double impulse = 0;
      for (size_t f = fa; f < fb; ++f)
        impulse += 0.5 * h * (takeoff.values[f] + landing.values[f] + takeoff.values[f + 1] + landing.values[f + 1] - 2 * weight);
      const double momentum = mass * (comVelocity(fb) - comVelocity(fa));
      qInfo("stance %g-%g s: impulse %g N s, momentum change %g N s", a, b, impulse, momentum);
      QVERIFY(std::abs(impulse - momentum) < 0.002 * weight * (b - a));
    }
    const PlotSeries residual = series("residual/0");
    QVERIFY(!residual.values.empty());
    QVERIFY(*std::max_element(residual.values.begin(), residual.values.end()) < 0.01);
    // Plotted in the panel: the value axis steps by 1, 2 or 5 times a power of ten.
    w.graphs()->setChecked("com/0/y", true);
    auto* chart = w.graphs()->findChild<QChartView*>()->chart();
    auto* axis = qobject_cast<QValueAxis*>(chart->axes(Qt::Vertical).value(0));
    QVERIFY(axis);
    QCOMPARE(axis->tickType(), QValueAxis::TicksDynamic);
    const double step = axis->tickInterval(), mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
    QVERIFY2(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 || std::abs(mantissa - 5) < 1e-9,
             qPrintable(QString("tick interval %1").arg(step)));
    // One y axis per unit: the centre of mass's height on metres beside the default joint
    // torques on newton-metres, each axis spanning its own series only (on one shared axis the
    // 0.1-0.5 m height was a flat line under torques of 20 N m).
    QCOMPARE(chart->axes(Qt::Vertical).size(), 2);
    int torques = 0;
    for (QAbstractSeries* line : chart->series()) {
      QValueAxis* y = nullptr;
      for (QAbstractAxis* a : line->attachedAxes())
        if (a->orientation() == Qt::Vertical) y = qobject_cast<QValueAxis*>(a);
      QVERIFY(y);
      if (line->name() == "com.y") {
        QCOMPARE(y->titleText(), QString("m"));
        QVERIFY2(y->max() < 1.0, qPrintable(QString::number(y->max())));
      } else {
        QVERIFY2(line->name().startsWith("tau."), qPrintable(line->name()));
        QCOMPARE(y->titleText(), QString("N·m"));
        QVERIFY(y->max() > 5);
        ++torques;
      }
    }
    QCOMPARE(torques, 3);
  }

  // The validity panel shows the engine's checklist for the solved motion: before a solve it
  // asks for one; the solved particle (exact physics, pins met) passes every check, one row per
  // check with the report's values; after an edit it says the checks are of the solved scene.
  void validityPanelChecksTheSolvedMotion() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/particle.json"));
    QVERIFY2(w.validity()->verdict().contains("Solve"), qPrintable(w.validity()->verdict()));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(60000)));
    QTRY_VERIFY(w.document()->motion() && w.document()->motion()->validity);
    const auto motion = w.document()->motion();
    const std::vector<ValidityCheck> checks = validityChecklist(*motion->validity);
    QCOMPARE(w.validity()->list()->topLevelItemCount(), static_cast<int>(checks.size()));
    QVERIFY2(w.validity()->verdict().startsWith("Physically valid"), qPrintable(w.validity()->verdict()));
    QVERIFY(w.validity()->list()->topLevelItem(0)->text(0).contains("residual"));
    w.document()->edit("Move pin", [](Scene& s) { s.terms.front().position.x() += 0.1; });
    QVERIFY2(w.validity()->verdict().contains("scene changed"), qPrintable(w.validity()->verdict()));
  }

  // Two pins at one instant in two places: the solve stops at the stall, and the validity panel
  // names the two pins on top, as what to change.
  void conflictingPinsAreNamedInTheValidityPanel() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/particle.json"));
    w.document()->edit("Add a clashing pin", [](Scene& s) {
      TermSpec clash = s.terms[1];
      clash.id = "clash";
      clash.position = Eigen::Vector3d(5, 5, 5);
      s.terms.push_back(clash);
    });
    const std::string pinned = w.document()->scene().terms[1].id;
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(60000)));
    QTRY_VERIFY(w.document()->motion() && w.document()->motion()->validity);
    QVERIFY(!w.document()->motion()->converged);
    QVERIFY2(w.validity()->verdict().contains("unmet"), qPrintable(w.validity()->verdict()));
    // Never "valid" above unmet rows, even where every check of the motion itself passes.
    QVERIFY2(w.validity()->verdict().startsWith("Not valid"), qPrintable(w.validity()->verdict()));
    QVERIFY2(!w.validity()->verdict().contains("Physically valid"), qPrintable(w.validity()->verdict()));
    QTreeWidget* rows = w.validity()->list();
    QVERIFY(rows->topLevelItemCount() > 2);
    QStringList top{rows->topLevelItem(0)->text(0), rows->topLevelItem(1)->text(0)};
    top.sort();
    QVERIFY2(top[0].startsWith("unmet: pin 'clash'"), qPrintable(top.join(" | ")));
    QVERIFY2(top[1].startsWith(QString("unmet: pin '%1'").arg(QString::fromStdString(pinned))), qPrintable(top.join(" | ")));
    QVERIFY(!rows->topLevelItem(2)->text(0).startsWith("unmet"));
    QVERIFY2(w.statusText().contains("conflict"), qPrintable(w.statusText()));
  }

  void viewportDrawsTheLampInItsColours() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.viewport()->frameAll();
    const QImage image = w.viewport()->grabFramebuffer();
    QVERIFY(!image.isNull());
    // The head's colour (0.95, 0.85, 0.4), lit: a saturated yellow-orange hue. The background:
    // (0.16, 0.17, 0.19). Count both.
    int head = 0, background = 0;
    const QColor bg = QColor::fromRgbF(0.16f, 0.17f, 0.19f);
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        const QColor c = image.pixelColor(x, y);
        if (c.hsvHueF() > 35.0 / 360 && c.hsvHueF() < 60.0 / 360 && c.hsvSaturationF() > 0.4 && c.valueF() > 0.3) ++head;
        if (std::abs(c.red() - bg.red()) <= 2 && std::abs(c.green() - bg.green()) <= 2 && std::abs(c.blue() - bg.blue()) <= 2) ++background;
      }
    const int total = image.width() * image.height();
    qInfo("%dx%d: %d head pixels, %d background pixels", image.width(), image.height(), head, background);
    QVERIFY(head > 200);
    QVERIFY(background > total / 4);
    QVERIFY(background < total);
  }

  // A preview (the starting guess, an iterate) is drawn washed towards grey; the solved motion
  // in the bodies' own colours.
  void previewsAreDrawnWashedOut() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/luxo_jump.json"));
    const Scene scene = w.document()->scene();
    std::string error;
    const std::unique_ptr<SpacetimeProblem> problem = SpacetimeProblem::build(scene, &error);
    QVERIFY2(problem, error.c_str());
    const std::shared_ptr<SolvedMotion> preview = sampleMotion(*problem);
    QVERIFY(!preview->solved);
    auto result = std::make_shared<SolvedMotion>(*preview);
    result->solved = true;
    const RenderScene washed = buildRenderScene(scene, w.document()->models(), preview.get(), RenderOptions());
    const RenderScene own = buildRenderScene(scene, w.document()->models(), result.get(), RenderOptions());
    QCOMPARE(washed.solids.size(), own.solids.size());
    int compared = 0;
    for (size_t i = 0; i < own.solids.size(); ++i) {
      if (own.solids[i].ghost || own.solids[i].character < 0) continue;
      // Chroma (max - min of r, g, b) shrinks by exactly 1 - kPreviewWash towards grey.
      auto chroma = [](const glm::vec4& c) { return std::max({c.r, c.g, c.b}) - std::min({c.r, c.g, c.b}); };
      QVERIFY(std::abs(chroma(washed.solids[i].color) - (1 - kPreviewWash) * chroma(own.solids[i].color)) < 1e-5);
      if (chroma(own.solids[i].color) > 0.3) ++compared;  // a coloured body (the head)
    }
    QVERIFY(compared >= 1);
  }

  // The hurdle's clearances are drawn as blocks from the ground up to their height, under the
  // cleared point's path over their interval; a clearance at the ground adds nothing, a box
  // clearance is its box, and the selected term is drawn in the selection colour.
  void clearancesAreDrawnWhereThePointMustPass() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/luxo_hurdle.json"));
    Scene scene = w.document()->scene();
    const std::vector<Model<double>>& models = w.document()->models();
    std::string error;
    const std::unique_ptr<SpacetimeProblem> problem = SpacetimeProblem::build(scene, &error);
    QVERIFY2(problem, error.c_str());
    const std::shared_ptr<SolvedMotion> guess = sampleMotion(*problem);  // the lamp moves forward
    RenderOptions options;
    options.selectedTerm = "hurdle_toe";
    const RenderScene rs = buildRenderScene(scene, models, guess.get(), options);
    std::vector<std::string> drawn;
    for (const Obstacle& o : rs.obstacles) drawn.push_back(o.term);
    QCOMPARE(drawn, (std::vector<std::string>{"hurdle_heel", "hurdle_toe"}));  // not heel_above_ground

    const TermSpec* heel = nullptr;
    for (const TermSpec& t : scene.terms)
      if (t.id == "hurdle_heel") heel = &t;
    QVERIFY(heel);
    float xMin = 1e9f, xMax = -1e9f;
    for (const Solid& box : rs.obstacles[0].boxes) {
      QVERIFY(box.ghost && box.character < 0);  // translucent, never picked
      QVERIFY(box.color.r > 0.8f && box.color.g < 0.4f);
      for (float sx : {-0.5f, 0.5f})
        for (float sy : {-0.5f, 0.5f}) {
          const glm::vec3 corner = glm::vec3(box.transform * glm::vec4(sx, sy, 0.0f, 1.0f));
          QVERIFY(std::abs(corner.y - (sy > 0 ? heel->height : scene.groundHeight)) < 1e-6);
          xMin = std::min(xMin, corner.x);
          xMax = std::max(xMax, corner.x);
        }
    }
    const int base = models[0].bodyIndex("base");
    for (double t : {heel->start, 0.5 * (heel->start + heel->end), heel->end}) {
      const double x = bodyToWorld(models[0], poseAt(guess->animation.characters[0], t), base, heel->point).x();
      QVERIFY2(x >= xMin - 1e-4 && x <= xMax + 1e-4, qPrintable(QString("x %1 outside [%2, %3]").arg(x).arg(xMin).arg(xMax)));
    }
    QVERIFY(xMax - xMin > 0.02);  // the path, not a marker
    QVERIFY(rs.obstacles[1].boxes.front().color.g > 0.5f);  // selected: orange

    for (TermSpec& t : scene.terms)
      if (t.id == "hurdle_heel") {
        t.box = true;
        t.boxMin = Eigen::Vector3d(0.1, 0.0, -0.2);
        t.boxMax = Eigen::Vector3d(0.3, 0.15, 0.2);
      }
    const RenderScene withBox = buildRenderScene(scene, models, guess.get(), RenderOptions{});
    QCOMPARE(withBox.obstacles[0].boxes.size(), size_t(1));
    const glm::mat4& m = withBox.obstacles[0].boxes[0].transform;
    const glm::vec3 lo = glm::vec3(m * glm::vec4(-0.5f, -0.5f, -0.5f, 1.0f)), hi = glm::vec3(m * glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
    QVERIFY(glm::length(lo - glm::vec3(0.1f, 0.0f, -0.2f)) < 1e-6f && glm::length(hi - glm::vec3(0.3f, 0.15f, 0.2f)) < 1e-6f);
  }

  // A builder preset, chosen from its menu on an empty scene, solves in the editor to a motion
  // the Validity panel calls physically valid.
  void presetSolvesValid(const QString& name, size_t bodies) {
    MainWindow w;
    w.solveOnOpen = false;
    w.document()->reset(emptyScene(), {});
    QAction* preset = nullptr;
    for (QToolButton* button : w.builder()->findChildren<QToolButton*>())
      if (button->text() == "Presets" && button->menu())
        for (QAction* a : button->menu()->actions())
          if (a->text() == name) preset = a;
    QVERIFY(preset);
    preset->trigger();
    const Scene& scene = w.document()->scene();
    QCOMPARE(scene.characters.size(), size_t(1));
    QCOMPARE(scene.characters[0].bodies.size(), bodies);
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(240000)));
    QTRY_VERIFY_WITH_TIMEOUT(w.document()->motion() && w.document()->motion()->validity, scaled(5000));
    QVERIFY2(w.document()->motion()->converged, qPrintable(w.statusText()));
    QVERIFY2(w.validity()->verdict().startsWith("Physically valid"), qPrintable(w.validity()->verdict()));
  }

  // The Planar biped: a 9-dof character standing on two feet with two-point contacts, which no
  // lamp preset exercises.
  void bipedPresetSolvesValid() { presetSolvesValid("Planar biped", 7); }

  // The Planar quadruped: front and hind legs on point feet, a hop that needs leg bubbles (its
  // scene asks for them; solver/leg_bubbles.cpp).
  void quadrupedPresetSolvesValid() { presetSolvesValid("Planar quadruped", 5); }

  // The 3D humanoid: a floating root with six dofs, head, arms and legs (10 bodies, 14 dofs),
  // heavy enough that the augmented Lagrangian's starting penalty must follow its objective.
  void humanoidPresetSolvesValid() { presetSolvesValid("3D humanoid", 10); }

  // A jumping creature made only through the editor's panels, as a user would, no JSON: File >
  // New; the Scene panel's clip end; the builder's character, three links added on each other's
  // tips with their sizes, masses and limits typed in; K at both ends with the key values typed
  // in the constraints form; rests and two-point contacts from Add. F5 then solves it to a jump
  // that passes every validity check, from the default guess.
  void aCreatureBuiltInThePanelsJumpsValid() {
    MainWindow w;
    w.resize(1400, 900);
    w.show();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    QAction* fileNew = nullptr;
    for (QAction* a : w.findChildren<QAction*>())
      if (a->text() == "&New") fileNew = a;
    QVERIFY(fileNew);
    fileNew->trigger();
    Document& doc = *w.document();
    QVERIFY(doc.scene().characters.empty());
    auto setDouble = [](PropertyForm* form, const char* label, double v) {
      auto* spin = qobject_cast<QDoubleSpinBox*>(form->editor(label));
      QVERIFY2(spin, label);
      spin->setValue(v);
    };
    // Each component through the editor the form shows then: an edit may rebuild the form.
    auto setVector = [](PropertyForm* form, const char* label, const Eigen::Vector3d& v) {
      for (int a = 0; a < 3; ++a) {
        QWidget* editor = form->editor(label);
        QVERIFY2(editor, label);
        setSpin(editor, QByteArray(1, "xyz"[a]).constData(), v[a]);
      }
    };
    auto setBool = [](PropertyForm* form, const char* label, bool v) {
      auto* box = qobject_cast<QCheckBox*>(form->editor(label));
      QVERIFY2(box, label);
      box->setChecked(v);
    };
    setDouble(w.sceneSettings()->form(), "Clip end", 1.2);
    QCOMPARE(doc.scene().endTime, 1.2);

    BuilderPanel& builder = *w.builder();
    builder.addCharacter();
    PropertyForm* body = builder.form();
    setVector(body, "Size", {0.3, 0.04, 0.16});
    setVector(body, "Shape offset", {0, 0.02, 0});
    struct Link {
      double length, mass, lower, upper;
      bool sphere;
    };
    for (const Link& l : {Link{0.25, 0.2, -1.4, 1.6, false}, Link{0.25, 0.2, -2.8, 0.4, false}, Link{0.06, 0.3, -2.2, 1.6, true}}) {
      builder.addBody();  // on the selected body's tip
      if (l.sphere) {
        auto* geometry = qobject_cast<QComboBox*>(body->editor("Geometry"));
        QVERIFY(geometry);
        geometry->setCurrentIndex(2);
        setVector(body, "Size", {l.length, 0, 0});
        setVector(body, "Shape offset", {0, l.length, 0});
      } else {
        setVector(body, "Size", {0.015, l.length, 0});
        setVector(body, "Shape offset", {0, l.length / 2, 0});
      }
      setDouble(body, "Mass", l.mass);
      setBool(body, "Limits", true);
      setDouble(body, "Lower", l.lower);
      setDouble(body, "Upper", l.upper);
    }
    const CharacterSpec& ch = doc.scene().characters.at(0);
    QCOMPARE(ch.bodies.size(), size_t(4));
    QVERIFY2((ch.bodies[2].joint.origin - Eigen::Vector3d(0, 0.25, 0)).norm() < 1e-12,  // on the first link's tip
             qPrintable(QString("%1 %2 %3 / %4 %5").arg(ch.bodies[2].joint.origin.y()).arg(ch.bodies[1].geometry.size.y()).arg(ch.bodies[1].geometry.offset.y()).arg(ch.bodies[1].joint.origin.y()).arg(ch.bodies[1].geometry.size.x())));
    const std::string root = ch.bodies[0].id;

    // Keys at both ends, their values typed into the constraints form.
    ConstraintsPanel& terms = *w.constraints();
    const std::vector<std::string> dofs = ch.dofNames();
    for (double t : {0.0, 1.2}) {
      doc.selectBody(0, root);
      doc.setCurrentTime(t);
      QVERIFY(!terms.keyCurrentPose().empty());
      setDouble(terms.form(), dofs[0].c_str(), t == 0 ? 0.0 : 0.6);  // the root's x: 0.6 m ahead
      setDouble(terms.form(), "j1", 0.4);
      setDouble(terms.form(), "j2", -1.2);
      setDouble(terms.form(), "j3", -0.5);
      QVERIFY(!terms.addRest().empty());
    }
    // Two-point contacts under the base: take-off 0-0.4 s, landing 0.8-1.2 s.
    for (const auto& [start, end] : {std::pair{0.0, 0.4}, std::pair{0.8, 1.2}}) {
      doc.selectBody(0, root);
      doc.setCurrentTime((start + end) / 2);
      QVERIFY(!terms.addContact().empty());
      setDouble(terms.form(), "Start", start);
      setDouble(terms.form(), "End", end);
    }
    int contacts = 0;
    for (const TermSpec& t : doc.scene().terms)
      if (t.kind == TermKind::Contact) {
        ++contacts;
        QCOMPARE(t.points.size(), size_t(2));
      }
    QCOMPARE(contacts, 2);

    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(240000)));
    QTRY_VERIFY(doc.motion() && doc.motion()->validity);
    QVERIFY2(doc.motion()->converged, qPrintable(w.statusText()));
    QVERIFY2(w.validity()->verdict().startsWith("Physically valid"), qPrintable(w.validity()->verdict()));
    QVERIFY(!doc.motion()->validity->flights.empty());
    QVERIFY(doc.motion()->validity->flights[0].maxRootLift >= 0.05);
  }

  // Live iterates come every 250 ms while the solver thread gets its core, and less often (up to
  // every 2 s) while drawing them takes more than a quarter of it (a software renderer): the
  // interval doubles below a 0.75 share of the wall-clock time, halves above 0.9, else stays.
  void livePacingBacksOffWhileDrawingStarvesTheSolver() {
    LivePacing pacing(0.25, 2.0);
    pacing.start(10.0, 3.0);
    QVERIFY(!pacing.due(10.2, 3.2));
    QVERIFY(pacing.due(10.25, 3.25));  // a full core: stays at the shortest
    QCOMPARE(pacing.interval(), 0.25);
    double wall = 10.25, cpu = 3.25;
    std::vector<double> intervals;
    auto step = [&](double share) {
      QVERIFY(!pacing.due(wall + 0.99 * pacing.interval(), cpu));
      wall += pacing.interval();
      cpu += share * pacing.interval();
      QVERIFY(pacing.due(wall, cpu));
      intervals.push_back(pacing.interval());
    };
    for (int i = 0; i < 5; ++i) step(0.3);  // the renderer takes 70 % of the solver's core
    step(0.8);                               // between the thresholds: no change
    for (int i = 0; i < 4; ++i) step(1.0);  // drawing became cheap again
    const std::vector<double> expected{0.5, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 0.5, 0.25, 0.25};
    QCOMPARE(intervals, expected);
  }

  // While a solve runs, a progress bar in the status bar estimates how far it has come: the
  // largest violation on a log scale from the first iterate's to the tolerance. It rises during
  // the jump's solve and goes when the solve ends.
  void solveProgressBarRisesWhileSolving() {
    SolveProgress estimate(1e-7);  // 0 at the first violation, 1/2 halfway in decades, 1 at the tolerance
    QCOMPARE(estimate.update(1e-1), 0.0);
    QVERIFY(std::abs(estimate.update(1e-4) - 0.5) < 1e-12);
    QCOMPARE(estimate.update(1e-9), 1.0);

    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    auto* bar = w.findChild<QProgressBar*>("solveProgress");
    QVERIFY(bar && !bar->isVisible());
    std::vector<int> seen;
    bool hiddenDuringSolve = false;
    connect(w.solverJob(), &SolverJob::iterate, &w, [&] {
      seen.push_back(bar->value());
      hiddenDuringSolve |= !bar->isVisible();
    });
    // The jump's violation passes halfway to the tolerance (in decades) only in its last ~10 % of
    // LM iterations; iterates paced by the solver's share of the CPU (up to 2 s apart while
    // another process loads the machine, as ctest -j2 does) could all come before that.
    w.solverJob()->liveIntervalMs = w.solverJob()->longestLiveIntervalMs = 20;
    w.solve();
    QVERIFY(bar->isVisible());
    QTRY_VERIFY_WITH_TIMEOUT(!w.solverJob()->isRunning() && !bar->isVisible(), scaled(120000));
    QVERIFY(w.document()->motion() && w.document()->motion()->converged);
    QVERIFY(seen.size() >= 3);
    QVERIFY(!hiddenDuringSolve);
    QVERIFY2(*std::max_element(seen.begin(), seen.end()) >= 500, qPrintable(QString::number(seen.back())));
  }

  // A solver iterate is drawn by one ordinary, coalesced paint of the window, never by a paint
  // forced in the middle of the event loop: each paint of the whole window is a full composition
  // (15-25 ms under Xvfb with the OpenGL viewport in it), and the progress bar's synchronous
  // repaint plus the chart scene's immediate dispatch of the window's update made the event loop
  // wait 50-90 ms per iterate.
  void aSolverIterateIsDrawnWithoutForcedPaints() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1400, 900)));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    QVERIFY(w.document()->motion());
    auto* bar = w.findChild<QProgressBar*>("solveProgress");
    auto* graph = w.findChild<GraphView*>();
    QVERIFY(bar && graph && graph->scene());
    bar->show();  // as during a solve
    QTest::qWait(200);
    WindowPaintCounter paints;
    w.installEventFilter(&paints);
    for (int k = 1; k <= 3; ++k) {
      auto iterate = std::make_shared<SolvedMotion>(*w.document()->motion());
      iterate->iterations = 10 * k;
      iterate->maxViolation = std::pow(10.0, -2 * k);
      iterate->converged = false;
      emit w.solverJob()->iterate(iterate);
      QCOMPARE(paints.count, 0);  // nothing painted inside the handler (the progress bar did)
      // The chart's scene processes its changed items from the event loop; it must leave the
      // window's paint to the event loop too (it dispatched it at once).
      QCoreApplication::sendPostedEvents(graph->scene(), QEvent::MetaCall);
      QCOMPARE(paints.count, 0);
      QTRY_VERIFY(paints.count >= 1);  // and the iterate is drawn
      QTest::qWait(100);
      paints.count = 0;
    }
    // Starting a solve (at every edit while a pin is dragged, with auto-solve on) resets the bar
    // without painting the window there and then either.
    w.solve();
    QCOMPARE(paints.count, 0);
    w.stopSolve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    w.removeEventFilter(&paints);
  }

  // The term list highlights the document's selection and nothing else: a term, the joint
  // limit row of a selected body, or no row (a body without limits); Delete then removes
  // exactly what is highlighted. (Seen: the list highlighted one term while the form showed,
  // and Delete removed, another.)
  void termListHighlightsTheSelection() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    Document& doc = *w.document();
    QTreeWidget* list = w.constraints()->list();
    doc.selectTerm("landing");
    QVERIFY(list->currentItem());
    QCOMPARE(list->currentItem()->text(0), QString("landing"));
    doc.selectTerm({});
    doc.selectBody(0, "head");  // its joint j3 has limits: their row
    QVERIFY(list->currentItem());
    QCOMPARE(list->currentItem()->text(0), QString("j3"));
    // Its form says where the limits are edited, and brings the builder forward.
    auto* hint = w.constraints()->form()->findChild<QLabel*>("limitHint");
    QVERIFY(hint);
    QVERIFY(hint->text().contains("j3") && hint->text().contains("head"));
    auto* builderDock = w.findChild<QDockWidget*>("builderDock");
    auto* sceneDock = w.findChild<QDockWidget*>("sceneDock");
    sceneDock->raise();
    QTRY_VERIFY(builderDock->visibleRegion().isEmpty());
    QTest::mouseClick(w.constraints()->form()->findChild<QPushButton*>("editLimitInBuilder"), Qt::LeftButton);
    QTRY_VERIFY(!builderDock->visibleRegion().isEmpty());
    QCOMPARE(doc.selectedBody(), std::string("head"));
    doc.selectBody(0, "base");  // the root: no limit row
    QVERIFY(!w.constraints()->form()->findChild<QLabel*>("limitHint"));
    QVERIFY(!list->currentItem());
    QVERIFY(list->selectedItems().isEmpty());
    const size_t terms = doc.scene().terms.size();
    w.constraints()->removeSelected();
    QCOMPARE(doc.scene().terms.size(), terms);
    doc.selectTerm("takeoff");
    w.constraints()->removeSelected();
    QCOMPARE(doc.scene().terms.size(), terms - 1);
    QVERIFY(std::none_of(doc.scene().terms.begin(), doc.scene().terms.end(), [](const TermSpec& t) { return t.id == "takeoff"; }));
    QVERIFY(!list->currentItem());
  }

  // File > Open Example lists every scene in resources/scenes by its name, and each opens
  // untitled (Save asks where to keep the copy).
  void examplesMenuOpensEveryShippedScene() {
    MainWindow w;
    w.solveOnOpen = false;
    auto* menu = w.findChild<QMenu*>("examplesMenu");
    QVERIFY(menu);
    QStringList shipped;
    for (const QFileInfo& info : QDir(SPACETIME_SOURCE_DIR "/resources/scenes").entryInfoList({"*.json"}, QDir::Files, QDir::Name)) {
      QFile f(info.filePath());
      QVERIFY(f.open(QIODevice::ReadOnly));
      shipped << QJsonDocument::fromJson(f.readAll()).object().value("name").toString();
    }
    QStringList listed;
    for (QAction* a : menu->actions()) {
      listed << a->text();
      a->trigger();
      QCOMPARE(QString::fromStdString(w.document()->scene().name), a->text());
      QVERIFY(w.document()->filePath().isEmpty());
      QVERIFY(!w.document()->scene().characters.empty());
    }
    QCOMPARE(listed, shipped);
    QVERIFY(shipped.size() >= 7);
  }

  // Posing: with the pose tool (R), a drag on the lamp's head around its joint turns j3 by the
  // angle the mouse sweeps around the joint on screen, and nothing else; the viewport shows
  // the pose; K at t = 0 replaces the start key with it (one key there, not two), and that pose
  // is the pose the solve starts from (the default guess through the keys) and the solved motion
  // meets. Changing the time drops a pose not keyed.
  void poseToolTurnsAJointAndKKeysIt() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.viewport()->frameAll();
    Document& doc = *w.document();
    QVERIFY(!doc.motion());
    QAction* poseTool = w.findChild<QAction*>("poseTool");
    QVERIFY(poseTool);
    poseTool->trigger();
    QVERIFY(w.viewport()->poseTool());
    const Model<double>& model = doc.models()[0];
    const Eigen::VectorXd before = doc.posesNow()[0];
    const int head = model.bodyIndex("head");
    const std::optional<PoseJoint> joint = poseJoint(model, before, head);
    QVERIFY(joint);
    QCOMPARE(joint->dof, model.dofIndex("j3"));
    glm::vec3 centre(0.0f);
    for (const Solid& s : w.viewport()->renderScene().solids)
      if (s.body == "head" && !s.ghost) centre = glm::vec3(s.transform[3]);
    const QPointF c = w.viewport()->toPixel(glm::vec3(joint->pivot.x(), joint->pivot.y(), joint->pivot.z()));
    const QPointF p0 = w.viewport()->toPixel(centre);
    const double radius = std::hypot(p0.x() - c.x(), p0.y() - c.y());
    QVERIFY(radius > 10);
    // An arc of +0.3 rad (counter-clockwise on screen) around the joint, in 10 moves.
    const double a0 = std::atan2(-(p0.y() - c.y()), p0.x() - c.x()), sweep = 0.3;
    auto at = [&](double a) { return QPointF(c.x() + radius * std::cos(a), c.y() - radius * std::sin(a)); };
    QTest::mousePress(w.viewport(), Qt::LeftButton, {}, p0.toPoint());
    for (int k = 1; k <= 10; ++k) {
      const QPointF p = at(a0 + sweep * k / 10);
      QMouseEvent move(QEvent::MouseMove, p, w.viewport()->mapToGlobal(p), Qt::NoButton, Qt::LeftButton, Qt::NoModifier);
      QApplication::sendEvent(w.viewport(), &move);
    }
    QTest::mouseRelease(w.viewport(), Qt::LeftButton, {}, at(a0 + sweep).toPoint());
    QVERIFY(doc.posed());
    QCOMPARE(doc.selectedBody(), std::string("head"));
    const Eigen::VectorXd posed = doc.posed()->q;
    const glm::vec3 toViewer = w.viewport()->camera().eye() - w.viewport()->camera().target;
    const double sign = glm::dot(glm::vec3(joint->axis.x(), joint->axis.y(), joint->axis.z()), toViewer) > 0 ? 1 : -1;
    const int j3 = joint->dof;
    // Pixel rounding of the press and release points: within 0.02 rad of the swept angle.
    QVERIFY2(std::abs(posed[j3] - before[j3] - sign * sweep) < 0.02, qPrintable(QString::number(posed[j3] - before[j3])));
    for (int d = 0; d < posed.size(); ++d)
      if (d != j3) QCOMPARE(posed[d], before[d]);
    // The viewport draws the posed head.
    const Eigen::Vector3d headNow = bodyToWorld(model, posed, head, Eigen::Vector3d::Zero());
    const Eigen::Vector3d tip = bodyToWorld(model, posed, head, Eigen::Vector3d(0.1, 0, 0));
    bool drawn = false;
    for (const Solid& s : w.viewport()->renderScene().solids)
      if (s.body == "head" && !s.ghost) {
        const glm::vec3 shown = glm::vec3(s.transform * glm::vec4(0, 0, 0, 1));
        drawn = (Eigen::Vector3d(shown.x, shown.y, shown.z) - headNow).norm() < 0.2;
      }
    QVERIFY(drawn && (tip - headNow).norm() > 0.05);

    // K at t = 0 replaces start_pose (one key at t = 0) with the posed values.
    const size_t terms = doc.scene().terms.size();
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    QTest::keyClick(QApplication::focusWidget() ? QApplication::focusWidget() : &w, Qt::Key_K);
    QCOMPARE(doc.scene().terms.size(), terms);
    QVERIFY(!doc.posed());
    const TermSpec* key = nullptr;
    int keysAtStart = 0;
    for (const TermSpec& t : doc.scene().terms)
      if (t.kind == TermKind::Keyframe && t.time == 0) key = &t, ++keysAtStart;
    QCOMPARE(keysAtStart, 1);
    QCOMPARE(key->id, std::string("start_pose"));
    QVERIFY2(w.statusText().contains("Replaced key 'start_pose'"), qPrintable(w.statusText()));
    for (const auto& [dof, v] : key->values) QCOMPARE(v, posed[model.dofIndex(dof)]);

    // The solve starts from that pose: the default guess passes through the keys.
    std::string error;
    const auto problem = SpacetimeProblem::build(doc.scene(), &error);
    QVERIFY2(problem, error.c_str());
    QVERIFY2((problem->jointState(0, 0.0, 0) - posed).cwiseAbs().maxCoeff() < 1e-3,
             qPrintable(QString::number((problem->jointState(0, 0.0, 0) - posed).cwiseAbs().maxCoeff())));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    QTRY_VERIFY(doc.motion() && doc.motion()->converged);
    QVERIFY((doc.posesNow()[0] - posed).cwiseAbs().maxCoeff() < 1e-5);

    // A pose not keyed is gone when the time changes.
    w.viewport()->frameAll();
    QTest::mousePress(w.viewport(), Qt::LeftButton, {}, w.viewport()->toPixel(centre).toPoint());
    QTest::mouseMove(w.viewport(), (w.viewport()->toPixel(centre) + QPointF(0, 40)).toPoint());
    QTest::mouseRelease(w.viewport(), Qt::LeftButton, {}, (w.viewport()->toPixel(centre) + QPointF(0, 40)).toPoint());
    QVERIFY(doc.posed());
    doc.setCurrentTime(0.1);
    QVERIFY(!doc.posed());
  }

  // Posing by inverse kinematics: with the pose tool, Shift+drag on the lamp's head pulls the
  // grabbed point through the plane facing the camera and the arm's joints follow, the base (the
  // root) held: the point ends under the mouse.
  void shiftDragPullsABodyPointByInverseKinematics() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.viewport()->frameAll();
    Document& doc = *w.document();
    w.findChild<QAction*>("poseTool")->trigger();
    const Model<double>& model = doc.models()[0];
    const Eigen::VectorXd before = doc.posesNow()[0];
    const int head = model.bodyIndex("head");
    // Where the press hits the head, and the plane the point then moves in.
    const BodyGrab grab = grabBody(w, "head");
    QVERIFY(grab.ok);
    const QPointF p0 = grab.pixel;
    const Eigen::Vector3d local = grab.local;
    const float width = static_cast<float>(w.viewport()->width()), height = static_cast<float>(w.viewport()->height());
    glm::vec3 o, dir;
    const glm::vec3 normal = glm::normalize(w.viewport()->camera().eye() - w.viewport()->camera().target);
    const QPoint p1 = (p0 + QPointF(-40, 25)).toPoint();
    shiftDrag(w, p0, p1);
    QVERIFY(doc.posed());
    const Eigen::VectorXd posed = doc.posed()->q;
    // On screen the grabbed point is under the mouse. (In space it is within 2 mm of the mouse's
    // ray in that plane: a planar lamp's point moves in its own plane, which the camera, looking
    // slightly down, does not face exactly.)
    w.viewport()->camera().ray(p1.x(), p1.y(), width, height, &o, &dir);
    const glm::vec3 target = o + dir * (glm::dot(grab.point - o, normal) / glm::dot(dir, normal));
    const Eigen::Vector3d reached = bodyToWorld(model, posed, head, local);
    const QPointF shown = w.viewport()->toPixel(glm::vec3(reached.x(), reached.y(), reached.z()));
    QVERIFY2(std::hypot(shown.x() - p1.x(), shown.y() - p1.y()) < 1.0,
             qPrintable(QString("%1 %2").arg(shown.x() - p1.x()).arg(shown.y() - p1.y())));
    QVERIFY((reached - Eigen::Vector3d(target.x, target.y, target.z)).norm() < 2e-3);
    for (const char* root : {"base_x", "base_y", "base_rz"}) QCOMPARE(posed[model.dofIndex(root)], before[model.dofIndex(root)]);
    QVERIFY((posed - before).cwiseAbs().maxCoeff() > 0.05);
  }

  // Shift+drag on a character standing on the ground: its contacts' points at this time stay
  // planted, every joint moves and the root translates. Pulling the biped's pelvis down crouches
  // it on its soles: the pelvis point follows the mouse, the soles' four points do not move.
  void shiftDragOnAStandingBipedCrouchesItOnItsFeet() {
    MainWindow w;
    QVERIFY(openScene(w, ":/scenes/biped_jump.json", QSize(1200, 800)));
    w.viewport()->frameAll();
    Document& doc = *w.document();
    QCOMPARE(doc.currentTime(), 0.0);  // both feet on the ground
    w.findChild<QAction*>("poseTool")->trigger();
    const Model<double>& model = doc.models()[0];
    // Unsolved, the editor shows the rest pose (straight legs: no crouch to first order); the
    // start key is the standing pose.
    Eigen::VectorXd key = Eigen::VectorXd::Zero(model.dofCount());
    for (const TermSpec& t : doc.scene().terms)
      if (t.id == "start_pose")
        for (const auto& [dof, value] : t.values) key[model.dofIndex(dof)] = value;
    doc.setPosed(0, key);
    const Eigen::VectorXd before = doc.posesNow()[0];
    QCOMPARE(before, key);
    const int pelvis = model.bodyIndex("pelvis");
    auto soles = [&](const Eigen::VectorXd& q) {
      std::vector<Eigen::Vector3d> out;
      for (const char* foot : {"l_foot", "r_foot"})
        for (const double x : {-0.06, 0.16}) out.push_back(bodyToWorld(model, q, model.bodyIndex(foot), Eigen::Vector3d(x, -0.05, 0)));
      return out;
    };
    const BodyGrab grab = grabBody(w, "pelvis");
    QVERIFY(grab.ok);
    const QPointF p0 = grab.pixel;
    const Eigen::Vector3d local = grab.local;
    const QPoint p1 = (p0 + QPointF(0, 30)).toPoint();
    shiftDrag(w, p0, p1);
    QVERIFY(doc.posed());
    const Eigen::VectorXd posed = doc.posed()->q;
    const Eigen::Vector3d reached = bodyToWorld(model, posed, pelvis, local);
    const QPointF shown = w.viewport()->toPixel(glm::vec3(reached.x(), reached.y(), reached.z()));
    QVERIFY2(std::hypot(shown.x() - p1.x(), shown.y() - p1.y()) < 1.0,
             qPrintable(QString("%1 %2").arg(shown.x() - p1.x()).arg(shown.y() - p1.y())));
    QVERIFY2(posed[model.dofIndex("pelvis_y")] < before[model.dofIndex("pelvis_y")] - 0.01,
             qPrintable(QString::number(posed[model.dofIndex("pelvis_y")] - before[model.dofIndex("pelvis_y")])));
    QCOMPARE(posed[model.dofIndex("pelvis_rz")], before[model.dofIndex("pelvis_rz")]);  // moved straight down
    const std::vector<Eigen::Vector3d> a = soles(before), b = soles(posed);
    for (size_t i = 0; i < a.size(); ++i) QVERIFY2((a[i] - b[i]).norm() < 1e-6, qPrintable(QString::number((a[i] - b[i]).norm())));
  }

  // A contact's points from the viewport: the form's "Add by clicking the body", then a click on
  // the base adds the clicked point (in the base's frame) as one undo step; "Remove the last"
  // takes it off again, and the last point cannot go.
  void contactPointsAreAddedByClickingTheBody() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.viewport()->frameAll();
    Document& doc = *w.document();
    doc.selectTerm("takeoff");
    auto points = [&] {
      for (const TermSpec& t : doc.scene().terms)
        if (t.id == "takeoff") return t.points;
      return std::vector<Eigen::Vector3d>();
    };
    const std::vector<Eigen::Vector3d> before = points();
    QCOMPARE(before.size(), size_t(2));
    auto* add = w.constraints()->form()->findChild<QPushButton*>("addContactPoint");
    QVERIFY(add);
    add->click();
    QCOMPARE(w.viewport()->contactPointTool(), std::string("takeoff"));
    // The base's centre on screen, and where that ray hits it.
    glm::vec3 centre(0.0f);
    for (const Solid& s : w.viewport()->renderScene().solids)
      if (s.body == "base" && !s.ghost) centre = glm::vec3(s.transform[3]);
    const QPoint at = w.viewport()->toPixel(centre).toPoint();
    glm::vec3 o, dir;
    w.viewport()->camera().ray(at.x(), at.y(), static_cast<float>(w.viewport()->width()),
                               static_cast<float>(w.viewport()->height()), &o, &dir);
    const std::optional<Pick> hit = pickSolid(w.viewport()->renderScene(), o, dir);
    QVERIFY(hit);
    const int commands = doc.undoStack()->count();
    QVERIFY(w.statusText().contains("Click the body"));
    QTest::mouseClick(w.viewport(), Qt::LeftButton, {}, at);
    QCOMPARE(doc.undoStack()->count(), commands + 1);
    QVERIFY(w.viewport()->contactPointTool().empty());
    QVERIFY2(w.statusText().contains("point added"), qPrintable(w.statusText()));  // not the stale request
    const std::vector<Eigen::Vector3d> after = points();
    QCOMPARE(after.size(), size_t(3));
    const Model<double>& model = doc.models()[0];
    const Eigen::Vector3d expected =
        worldToBody(model, doc.posesNow()[0], model.bodyIndex("base"), Eigen::Vector3d(hit->point.x, hit->point.y, hit->point.z));
    QVERIFY((after[2] - expected).norm() < 1e-9);
    QVERIFY(std::abs(after[2].x()) < 0.15 && std::abs(after[2].z()) <= 0.08 + 1e-6);  // on the base
    auto* remove = w.constraints()->form()->findChild<QPushButton*>("removeContactPoint");
    QVERIFY(remove && remove->isEnabled());
    remove->click();
    QCOMPARE(points(), before);
    remove = w.constraints()->form()->findChild<QPushButton*>("removeContactPoint");
    remove->click();
    QCOMPARE(points().size(), size_t(1));
    remove = w.constraints()->form()->findChild<QPushButton*>("removeContactPoint");
    QVERIFY(!remove->isEnabled());
    // A click on empty space ends the tool with nothing added, and says so.
    doc.selectTerm("takeoff");
    w.constraints()->form()->findChild<QPushButton*>("addContactPoint")->click();
    QTest::mouseClick(w.viewport(), Qt::LeftButton, {}, QPoint(3, 3));
    QVERIFY(w.viewport()->contactPointTool().empty());
    QCOMPARE(points().size(), size_t(1));
    QVERIFY2(w.statusText().contains("no point added"), qPrintable(w.statusText()));
  }

  // Home frames all even when the builder's tree has the focus (the tree took the key to go to
  // its first row).
  void homeInAFocusedTreeFramesAll() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&w));
    w.viewport()->frameAll();
    const OrbitCamera framed = w.viewport()->camera();
    w.viewport()->camera().zoom(3.0f);
    w.viewport()->camera().pan(0.4f, 0.2f);
    QTreeWidget* tree = w.builder()->tree();
    tree->setFocus();
    QTRY_VERIFY(tree->hasFocus());
    QTest::keyClick(tree, Qt::Key_Home);
    QVERIFY(std::abs(w.viewport()->camera().distance - framed.distance) < 1e-5f);
    QVERIFY(glm::length(w.viewport()->camera().target - framed.target) < 1e-5f);
  }

  // View > Follow the character (F): the camera keeps its offset from the character's centre
  // of mass as the time changes, so the jump's landing 0.6 m ahead stays in view; off, the
  // camera stays put.
  void cameraFollowsTheCharacter() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.solve();
    QVERIFY(w.solverJob()->waitForFinished(scaled(120000)));
    QTRY_VERIFY(w.document()->motion() && w.document()->motion()->converged);
    Document& doc = *w.document();
    doc.setCurrentTime(0.0);
    w.viewport()->renderScene();
    auto com = [&] {
      const Model<double>& model = doc.models()[0];
      Data<double> d(model);
      forwardKinematics(model, d, doc.posesNow()[0].data());
      return centerOfMass(model, d);
    };
    const Eigen::Vector3d com0 = com();
    const glm::vec3 target0 = w.viewport()->camera().target;
    QAction* follow = w.findChild<QAction*>("followCharacter");
    QVERIFY(follow);
    follow->trigger();
    QVERIFY(w.viewport()->follow());
    doc.setCurrentTime(1.2);
    w.viewport()->renderScene();
    const Eigen::Vector3d com1 = com();
    const glm::vec3 moved = w.viewport()->camera().target - target0;
    QVERIFY(com1.x() - com0.x() > 0.5);
    QVERIFY2(std::abs(moved.x - (com1.x() - com0.x())) < 1e-4, qPrintable(QString::number(moved.x)));
    QVERIFY(std::abs(moved.y - (com1.y() - com0.y())) < 1e-4);
    follow->trigger();
    const glm::vec3 target1 = w.viewport()->camera().target;
    doc.setCurrentTime(0.0);
    w.viewport()->renderScene();
    QVERIFY(glm::length(w.viewport()->camera().target - target1) < 1e-6f);
  }

  void clickingABodySelectsIt() {
    MainWindow w;
    QVERIFY(openLuxo(w, QSize(1200, 800)));
    w.viewport()->frameAll();
    // The head's centre in the zero pose, projected, then clicked.
    const RenderScene& rs = w.viewport()->renderScene();
    glm::vec3 centre(0.0f);
    for (const Solid& s : rs.solids)
      if (s.body == "head" && !s.ghost) centre = glm::vec3(s.transform[3]);
    QTest::mouseClick(w.viewport(), Qt::LeftButton, {}, w.viewport()->toPixel(centre).toPoint());
    QVERIFY2(w.document()->selectedBody() == "head", w.document()->selectedBody().c_str());
  }
};

int main(int argc, char** argv) {
  useOpenGL33CoreByDefault();
  qputenv("SPACETIME_NO_RECOVERY", "1");  // no modal recovery prompt; the test recovers by hand
  QApplication app(argc, argv);
  QStandardPaths::setTestModeEnabled(true);  // settings and autosaves under ~/.qttest
  QApplication::setOrganizationName("SpacetimeTest");
  QApplication::setApplicationName("SpacetimeTest");
  EditorTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "editor_test.moc"
