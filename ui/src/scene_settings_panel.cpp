#include "ui/scene_settings_panel.h"

#include <QScrollArea>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>

namespace spacetime::ui {

namespace {
// The shortest clip a scene can have: a transcription needs at least one segment of it.
constexpr double kShortestClip = 0.05;
}  // namespace

SceneSettingsPanel::SceneSettingsPanel(Document* doc, QWidget* parent)
    : QWidget(parent), doc_(doc), form_(new PropertyForm(doc, kMergeSceneField)) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  QScrollArea* scroll = form_->inScrollArea();
  layout->addWidget(scroll);

  PropertyForm& f = *form_;
  f.addText(tr("Name"), [](const Scene& s) { return s.name; }, [](Scene& s, const std::string& v) { s.name = v; });
  // The clip: its end stays after its start (the loader's rule), by at least kShortestClip.
  f.addDouble(tr("Clip start"), [](const Scene& s) { return s.startTime; },
              [](Scene& s, double v) {
                s.startTime = std::min(v, s.endTime - kShortestClip);
                s.transcription.knots.clear();  // the refinement's knots were the old clip's
              }, -1e3, 1e3, 0.1, 3, tr(" s"));
  f.addDouble(tr("Clip end"), [](const Scene& s) { return s.endTime; },
              [](Scene& s, double v) {
                s.endTime = std::max(v, s.startTime + kShortestClip);
                s.transcription.knots.clear();
              }, -1e3, 1e3, 0.1, 3, tr(" s"));
  f.addDouble(tr("Frame rate"), [](const Scene& s) { return s.frameRate; },
              [](Scene& s, double v) { s.frameRate = v; }, 1, Scene::kMaxFrameRate, 1, 2, tr(" fps"));
  f.addVector(tr("Gravity"), [](const Scene& s) { return s.gravity; },
              [](Scene& s, const Eigen::Vector3d& v) { s.gravity = v; }, -100, 100, 0.1, 3);
  f.addBool(tr("Ground"), [](const Scene& s) { return s.groundEnabled; }, [](Scene& s, bool v) { s.groundEnabled = v; });
  f.addDouble(tr("Ground height"), [](const Scene& s) { return s.groundHeight; },
              [](Scene& s, double v) { s.groundHeight = v; }, -1e3, 1e3, 0.01, 3, tr(" m"));
  f.addBool(tr("Bodies above the ground"), [](const Scene& s) { return s.solver.bodiesAboveGround; },
            [](Scene& s, bool v) { s.solver.bodiesAboveGround = v; });
  f.addDouble(tr("Effort weight"), [](const Scene& s) { return s.objective.effort; },
              [](Scene& s, double v) { s.objective.effort = v; }, 0, 1e6, 0.1, 4);
  f.addDouble(tr("Power weight"), [](const Scene& s) { return s.objective.power; },
              [](Scene& s, double v) { s.objective.power = v; }, 0, 1e6, 0.1, 4);
  f.addDouble(tr("Smoothness weight"), [](const Scene& s) { return s.objective.smoothness; },
              [](Scene& s, double v) { s.objective.smoothness = v; }, 0, 1e6, 1e-4, 6);
  f.addChoice(tr("Smooth in"), {tr("acceleration"), tr("jerk")},
              [](const Scene& s) { return s.objective.smoothnessOrder - 2; },
              [](Scene& s, int v) { s.objective.smoothnessOrder = v + 2; });
  // Where the solve starts: it refines the transcription by itself when the motion needs it.
  f.addDouble(tr("Control points per second"), [](const Scene& s) { return s.transcription.controlPointsPerSecond; },
              [](Scene& s, double v) {
                // A rate typed in replaces the refinement's non-uniform knots.
                s.transcription.controlPointsPerSecond = v;
                s.transcription.knots.clear();
              }, 1, 200, 5, 1);
  QStringList samples;
  for (int k = 1; k <= TranscriptionSpec::kMaxSamplesPerSegment; ++k) samples << QString::number(k);
  f.addChoice(tr("Samples per segment"), samples, [](const Scene& s) { return s.transcription.samplesPerSegment - 1; },
              [](Scene& s, int v) { s.transcription.samplesPerSegment = v + 1; });
  // The spline's segments: the rate's, or where the solve split them (Document::acceptResult).
  auto* segments = new QLabel;
  segments->setObjectName("segments");
  segments->setWordWrap(true);
  f.addWidget(tr("Segments"), segments);
  auto showSegments = [this, segments] {
    const Scene& s = doc_->scene();
    const int n = std::max(1, static_cast<int>(std::lround(s.transcription.segments(s.startTime, s.endTime))));
    segments->setText(s.transcription.knots.empty()
                          ? tr("%1, uniform").arg(n)
                          : tr("%1, split where the solve refined the transcription").arg(n));
  };
  showSegments();
  connect(doc_, &Document::sceneChanged, segments, showSegments);
  // Extra unknowns for characters on several feet (solver/leg_bubbles.cpp); the solve also turns
  // them on by itself after a stall.
  f.addBool(tr("Leg bubbles"), [](const Scene& s) { return s.transcription.legBubbles; },
            [](Scene& s, bool v) { s.transcription.legBubbles = v; });
  // SolverSpec::kMethods in order: "al", "ipopt", "sqp", "witkin-kass".
  f.addChoice(tr("Solver method"), {tr("augmented Lagrangian"), tr("interior point (IPOPT)"), tr("SQP"),
                                        tr("Witkin-Kass (every iterate restored)")},
              [](const Scene& s) {
                const auto* m = std::find(std::begin(SolverSpec::kMethods), std::end(SolverSpec::kMethods), s.solver.method);
                return m == std::end(SolverSpec::kMethods) ? 0 : static_cast<int>(m - std::begin(SolverSpec::kMethods));
              },
              [](Scene& s, int v) { s.solver.method = SolverSpec::kMethods[v]; });
  f.addDouble(tr("Solver tolerance"), [](const Scene& s) { return s.solver.tolerance; },
              [](Scene& s, double v) { s.solver.tolerance = v; }, 1e-10, 1e-2, 1e-7, 10);
  f.addDouble(tr("Time budget"), [](const Scene& s) { return s.solver.maxSeconds; },
              [](Scene& s, double v) { s.solver.maxSeconds = v; }, 1, SolverSpec::kMaxSeconds, 60, 0, tr(" s"));
  f.addDouble(tr("Most refinements"), [](const Scene& s) { return double(s.solver.maxRefinements); },
              [](Scene& s, double v) { s.solver.maxRefinements = static_cast<int>(v); }, 0, SolverSpec::kMaxRefinements, 1, 0);
  f.addDouble(tr("Most multiplier updates"), [](const Scene& s) { return double(s.solver.maxOuterIterations); },
              [](Scene& s, double v) { s.solver.maxOuterIterations = static_cast<int>(v); }, 1, 1000, 10, 0);
  f.refresh();
  connect(doc_, &Document::sceneChanged, form_, &PropertyForm::refresh);
}

}  // namespace spacetime::ui
