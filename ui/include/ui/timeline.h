// The timeline: a time bar with the current-time cursor, markers for pins, keyframes and rests,
// and contact intervals as bars you drag (move) or drag by an end (resize), one merged undo
// command per drag; below it play/pause (Space), step (Left/Right, one frame), loop, playback
// speed and the frame rate used for stepping and for image-sequence export.
#pragma once

#include <QCheckBox>
#include <QComboBox>
#include <QElapsedTimer>
#include <QLabel>
#include <QSpinBox>
#include <QTimer>
#include <QToolButton>
#include <QWidget>

#include "ui/document.h"

namespace spacetime::ui {

class TimelineBar : public QWidget {
  Q_OBJECT
 public:
  explicit TimelineBar(Document* doc, QWidget* parent = nullptr);
  QSize sizeHint() const override { return {600, 70}; }
  double timeAt(double x) const;
  double xAt(double t) const;
  // The rectangle of a contact term's bar (for tests and hit testing).
  QRectF contactBar(const std::string& term) const;

 protected:
  void paintEvent(QPaintEvent*) override;
  void mousePressEvent(QMouseEvent* e) override;
  void mouseMoveEvent(QMouseEvent* e) override;
  void mouseReleaseEvent(QMouseEvent* e) override;

 private:
  std::vector<std::string> contactTerms() const;
  Document* doc_;
  enum class Drag { None, Scrub, Move, Start, End } drag_ = Drag::None;
  std::string dragTerm_;
  double dragOffset_ = 0;
  int dragSerial_ = 0;
  // The undo merge id of the contact drag under way: its moves become one command.
  int dragMergeId() const { return kMergeContactDrag + (dragSerial_ & 0xFFFFF); }
};

class Timeline : public QWidget {
  Q_OBJECT
 public:
  explicit Timeline(Document* doc, QWidget* parent = nullptr);

  bool isPlaying() const { return timer_.isActive(); }
  void play();
  void pause();
  void togglePlay();
  void step(int frames);
  int framesPerSecond() const { return fps_->value(); }  // the scene's frame rate, rounded
  double speed() const;
  bool loops() const { return loop_->isChecked(); }
  TimelineBar* bar() const { return bar_; }

 private:
  void tick();
  void updateLabel();

  Document* doc_;
  TimelineBar* bar_;
  QToolButton* playButton_;
  QCheckBox* loop_;
  QComboBox* speed_;
  QSpinBox* fps_;
  QLabel* label_;
  QTimer timer_;
  QElapsedTimer clock_;
};

}  // namespace spacetime::ui
