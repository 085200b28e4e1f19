#include "ui/timeline.h"

#include <QHBoxLayout>
#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QSignalBlocker>
#include <QStyle>
#include <QVBoxLayout>
#include <cmath>

namespace spacetime::ui {

namespace {
constexpr double kMargin = 12;     // pixels left and right of the time axis
constexpr double kMarkerRow = 22;  // y of the marker row
constexpr double kLaneTop = 34, kLaneHeight = 10;
}  // namespace

TimelineBar::TimelineBar(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("timelineBar");
  setMinimumHeight(60);
  setMouseTracking(true);
  for (auto signal : {&Document::sceneChanged, &Document::selectionChanged})
    connect(doc_, signal, this, qOverload<>(&QWidget::update));
  connect(doc_, &Document::currentTimeChanged, this, qOverload<>(&QWidget::update));
}

double TimelineBar::xAt(double t) const {
  const Scene& s = doc_->scene();
  return kMargin + (t - s.startTime) / (s.endTime - s.startTime) * (width() - 2 * kMargin);
}

double TimelineBar::timeAt(double x) const {
  const Scene& s = doc_->scene();
  return s.startTime + (x - kMargin) / std::max(1.0, width() - 2 * kMargin) * (s.endTime - s.startTime);
}

std::vector<std::string> TimelineBar::contactTerms() const {
  std::vector<std::string> ids;
  for (const TermSpec& t : doc_->scene().terms)
    if (t.kind == TermKind::Contact) ids.push_back(t.id);
  return ids;
}

QRectF TimelineBar::contactBar(const std::string& id) const {
  const std::vector<std::string> ids = contactTerms();
  for (size_t lane = 0; lane < ids.size(); ++lane) {
    if (ids[lane] != id) continue;
    for (const TermSpec& t : doc_->scene().terms)
      if (t.id == id)
        return QRectF(QPointF(xAt(t.start), kLaneTop + lane * (kLaneHeight + 3)),
                      QPointF(xAt(t.end), kLaneTop + lane * (kLaneHeight + 3) + kLaneHeight));
  }
  return {};
}

void TimelineBar::paintEvent(QPaintEvent*) {
  QPainter p(this);
  p.setRenderHint(QPainter::Antialiasing);
  p.fillRect(rect(), QColor(38, 40, 44));
  const Scene& s = doc_->scene();
  // Ticks every 0.1 s, labelled every 0.5 s.
  p.setPen(QColor(120, 124, 130));
  const double span = s.endTime - s.startTime;
  const double stepT = span > 5 ? 1.0 : 0.1;
  for (double t = std::ceil(s.startTime / stepT) * stepT; t <= s.endTime + 1e-9; t += stepT) {
    const double x = xAt(t);
    const bool major = std::abs(std::remainder(t, stepT * 5)) < 1e-6;
    p.drawLine(QPointF(x, 0), QPointF(x, major ? 10 : 5));
    if (major) p.drawText(QPointF(x + 2, 11), QString::number(t, 'g', 3));
  }
  // Contact bars, one lane each.
  for (const std::string& id : contactTerms()) {
    const QRectF r = contactBar(id);
    const bool sel = id == doc_->selectedTerm();
    p.setPen(sel ? QColor(255, 170, 60) : QColor(60, 150, 80));
    p.setBrush(sel ? QColor(120, 170, 90) : QColor(70, 140, 85));
    p.drawRoundedRect(r, 3, 3);
  }
  // Where the solver let go of a free contact end: a bright tick across the contact's lane (the
  // bar keeps the scene's end, the search's starting point).
  if (const auto motion = doc_->motion(); motion && motionFitsScene(*motion, s))
    for (const CharacterAnimation& a : motion->animation.characters)
      for (const ContactTrack& track : a.contacts) {
        const QRectF r = contactBar(track.term);
        if (!track.freeEnd || track.pointIndex != 0 || r.isNull()) continue;
        const double x = xAt(track.end);
        p.setPen(QPen(QColor(250, 250, 120), 2));
        p.drawLine(QPointF(x, r.top() - 2), QPointF(x, r.bottom() + 2));
      }
  // Markers.
  for (const TermSpec& t : s.terms) {
    const bool sel = t.id == doc_->selectedTerm();
    p.setPen(Qt::NoPen);
    const double x = xAt(t.time);
    switch (t.kind) {
      case TermKind::Pin: {
        p.setBrush(sel ? QColor(255, 140, 25) : QColor(255, 215, 50));
        QPainterPath tri;
        tri.moveTo(x, kMarkerRow + 6);
        tri.lineTo(x - 5, kMarkerRow - 4);
        tri.lineTo(x + 5, kMarkerRow - 4);
        tri.closeSubpath();
        p.drawPath(tri);
        if (t.until) p.fillRect(QRectF(x, kMarkerRow - 1, xAt(*t.until) - x, 2), QColor(255, 215, 50));
        break;
      }
      case TermKind::Keyframe: {
        p.setBrush(sel ? QColor(255, 140, 25) : QColor(120, 180, 255));
        QPainterPath d;
        d.moveTo(x, kMarkerRow - 6);
        d.lineTo(x + 5, kMarkerRow);
        d.lineTo(x, kMarkerRow + 6);
        d.lineTo(x - 5, kMarkerRow);
        d.closeSubpath();
        p.drawPath(d);
        break;
      }
      case TermKind::Rest:
        p.setBrush(sel ? QColor(255, 140, 25) : QColor(200, 200, 200));
        p.drawEllipse(QPointF(x, kMarkerRow), 3.5, 3.5);
        break;
      default: break;
    }
  }
  // The cursor.
  const double cx = xAt(doc_->currentTime());
  p.setPen(QPen(QColor(255, 80, 60), 2));
  p.drawLine(QPointF(cx, 0), QPointF(cx, height()));
}

void TimelineBar::mousePressEvent(QMouseEvent* e) {
  const QPointF pos = e->position();
  drag_ = Drag::Scrub;
  for (const std::string& id : contactTerms()) {
    const QRectF r = contactBar(id).adjusted(-4, 0, 4, 0);
    if (!r.contains(pos)) continue;
    dragTerm_ = id;
    ++dragSerial_;
    doc_->beginContinuousEdit(dragMergeId());
    doc_->selectTerm(id);
    if (std::abs(pos.x() - r.left() - 4) < 5) drag_ = Drag::Start;
    else if (std::abs(pos.x() - r.right() + 4) < 5) drag_ = Drag::End;
    else {
      drag_ = Drag::Move;
      dragOffset_ = timeAt(pos.x()) - timeAt(r.left() + 4);
    }
    return;
  }
  doc_->setCurrentTime(timeAt(pos.x()));
}

void TimelineBar::mouseMoveEvent(QMouseEvent* e) {
  const double t = timeAt(e->position().x());
  const Scene& s = doc_->scene();
  const std::string id = dragTerm_;
  const int merge = dragMergeId();
  const double minLength = 0.02 * (s.endTime - s.startTime);
  switch (drag_) {
    case Drag::Scrub: doc_->setCurrentTime(t); break;
    case Drag::Move:
      doc_->edit(tr("Move contact"), [&](Scene& sc) {
        for (TermSpec& c : sc.terms)
          if (c.id == id) {
            const double length = c.end - c.start;
            c.start = std::clamp(t - dragOffset_, sc.startTime, sc.endTime - length);
            c.end = c.start + length;
          }
      }, merge);
      break;
    case Drag::Start:
      doc_->edit(tr("Resize contact"), [&](Scene& sc) {
        for (TermSpec& c : sc.terms)
          if (c.id == id) c.start = std::clamp(t, sc.startTime, c.end - minLength);
      }, merge);
      break;
    case Drag::End:
      doc_->edit(tr("Resize contact"), [&](Scene& sc) {
        for (TermSpec& c : sc.terms)
          if (c.id == id) c.end = std::clamp(t, c.start + minLength, sc.endTime);
      }, merge);
      break;
    case Drag::None: break;
  }
}

void TimelineBar::mouseReleaseEvent(QMouseEvent*) {
  if (drag_ == Drag::Move || drag_ == Drag::Start || drag_ == Drag::End) doc_->endContinuousEdit();
  drag_ = Drag::None;
}

Timeline::Timeline(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("timeline");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  bar_ = new TimelineBar(doc_);
  layout->addWidget(bar_);
  auto* controls = new QHBoxLayout;
  // The style's media icons, not text glyphs: fonts without U+23EE (⏮) drew empty boxes.
  auto tool = [&](QStyle::StandardPixmap icon, const QString& tip) {
    auto* b = new QToolButton;
    b->setIcon(style()->standardIcon(icon));
    b->setToolTip(tip);
    b->setAccessibleName(tip);
    controls->addWidget(b);
    return b;
  };
  connect(tool(QStyle::SP_MediaSkipBackward, tr("Start")), &QToolButton::clicked, this, [this] { doc_->setCurrentTime(doc_->scene().startTime); });
  connect(tool(QStyle::SP_MediaSeekBackward, tr("Previous frame (Left)")), &QToolButton::clicked, this, [this] { step(-1); });
  playButton_ = tool(QStyle::SP_MediaPlay, tr("Play / pause (Space)"));
  connect(playButton_, &QToolButton::clicked, this, &Timeline::togglePlay);
  connect(tool(QStyle::SP_MediaSeekForward, tr("Next frame (Right)")), &QToolButton::clicked, this, [this] { step(1); });
  connect(tool(QStyle::SP_MediaSkipForward, tr("End")), &QToolButton::clicked, this, [this] { doc_->setCurrentTime(doc_->scene().endTime); });
  loop_ = new QCheckBox(tr("Loop"));
  loop_->setChecked(true);
  controls->addWidget(loop_);
  speed_ = new QComboBox;
  speed_->addItems({"0.1×", "0.25×", "0.5×", "1×", "2×"});
  speed_->setCurrentIndex(3);
  speed_->setToolTip(tr("Playback speed"));
  controls->addWidget(speed_);
  fps_ = new QSpinBox;
  fps_->setRange(1, static_cast<int>(Scene::kMaxFrameRate));
  fps_->setValue(static_cast<int>(std::lround(doc_->scene().frameRate)));
  fps_->setSuffix(tr(" fps"));
  fps_->setToolTip(tr("The scene's frame rate: stepping, image sequences, BVH and glTF export"));
  // The scene's frame rate, edited here as an undoable scene change (arrow clicks merge).
  connect(fps_, &QSpinBox::valueChanged, this, [this](int v) {
    if (std::lround(doc_->scene().frameRate) != v)
      doc_->edit(tr("Frame rate"), [v](Scene& s) { s.frameRate = v; }, kMergeFrameRate);
  });
  connect(doc_, &Document::sceneChanged, this, [this] {
    const QSignalBlocker quiet(fps_);
    fps_->setValue(static_cast<int>(std::lround(doc_->scene().frameRate)));
  });
  controls->addWidget(fps_);
  label_ = new QLabel;
  label_->setMinimumWidth(140);
  controls->addWidget(label_);
  controls->addStretch();
  layout->addLayout(controls);
  timer_.setInterval(16);
  connect(&timer_, &QTimer::timeout, this, &Timeline::tick);
  connect(doc_, &Document::currentTimeChanged, this, &Timeline::updateLabel);
  connect(doc_, &Document::sceneChanged, this, &Timeline::updateLabel);
  updateLabel();
}

double Timeline::speed() const {
  static const double speeds[] = {0.1, 0.25, 0.5, 1.0, 2.0};
  return speeds[std::clamp(speed_->currentIndex(), 0, 4)];
}

void Timeline::play() {
  if (doc_->currentTime() >= doc_->scene().endTime) doc_->setCurrentTime(doc_->scene().startTime);
  clock_.start();
  timer_.start();
  playButton_->setIcon(style()->standardIcon(QStyle::SP_MediaPause));
}

void Timeline::pause() {
  timer_.stop();
  playButton_->setIcon(style()->standardIcon(QStyle::SP_MediaPlay));
}

void Timeline::togglePlay() { isPlaying() ? pause() : play(); }

void Timeline::step(int frames) {
  pause();
  const double dt = 1.0 / doc_->scene().frameRate;
  // Snap to the frame grid so stepping lands on the frames an export would write.
  const double s = doc_->scene().startTime;
  const double frame = std::round((doc_->currentTime() - s) / dt) + frames;
  doc_->setCurrentTime(s + frame * dt);
}

void Timeline::tick() {
  const double dt = clock_.restart() * 1e-3 * speed();
  const Scene& s = doc_->scene();
  double t = doc_->currentTime() + dt;
  if (t > s.endTime) {
    if (loops()) t = s.startTime + std::fmod(t - s.startTime, s.endTime - s.startTime);
    else {
      t = s.endTime;
      pause();
    }
  }
  doc_->setCurrentTime(t);
}

void Timeline::updateLabel() {
  const Scene& s = doc_->scene();
  label_->setText(QString("%1 / %2 s").arg(doc_->currentTime(), 0, 'f', 3).arg(s.endTime, 0, 'f', 3));
}

}  // namespace spacetime::ui
