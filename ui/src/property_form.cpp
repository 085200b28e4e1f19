#include "ui/property_form.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QVBoxLayout>
#include <algorithm>
#include <QLineEdit>
#include <QWheelEvent>

namespace spacetime::ui {

PropertyForm::PropertyForm(Document* doc, int mergeKind, QWidget* parent)
    : QWidget(parent), doc_(doc), mergeKind_(mergeKind), layout_(new QFormLayout), message_(new QLabel) {
  auto* outer = new QVBoxLayout(this);
  outer->setContentsMargins(4, 4, 4, 4);
  layout_->setContentsMargins(0, 0, 0, 0);
  layout_->setFieldGrowthPolicy(QFormLayout::AllNonFixedFieldsGrow);
  layout_->setRowWrapPolicy(QFormLayout::WrapLongRows);
  outer->addLayout(layout_);
  message_->setWordWrap(true);
  message_->setStyleSheet("color: #d04030;");
  message_->hide();
  outer->addWidget(message_);
}

QScrollArea* PropertyForm::inScrollArea() {
  auto* scroll = new QScrollArea;
  scroll->setWidget(this);
  scroll->setWidgetResizable(true);
  scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  return scroll;
}

void PropertyForm::refuse(const QString& why) {
  message_->setText(why);
  message_->show();
  refresh();  // the field shows the value the scene kept
}

void PropertyForm::clear() {
  message_->hide();
  while (layout_->rowCount() > 0) layout_->removeRow(0);
  rows_.clear();
}

void PropertyForm::commit(const QString& label, int row, const std::function<void(Scene&)>& change) {
  if (refreshing_) return;
  message_->hide();
  doc_->edit(tr("Change %1").arg(label), change, mergeKind_ + row + 1);
}

void PropertyForm::refresh() {
  refreshing_ = true;
  for (Row& r : rows_) r.refresh();
  refreshing_ = false;
}

QWidget* PropertyForm::editor(const QString& label) const {
  for (const Row& r : rows_)
    if (r.label == label) return r.widget;
  return nullptr;
}

namespace {
// A form's fields take the mouse wheel only once they have the keyboard focus (a click or Tab):
// unfocused, the wheel scrolls the form, as in Blender and Maya. Qt's fields edit their value
// under a passing wheel, and scrolling a long form changed Mass, Density or a contact's end -
// each a silent edit and, with auto-solve, a re-solve.
template <class Field>
class FocusedWheelField : public Field {
 public:
  FocusedWheelField() { this->setFocusPolicy(Qt::StrongFocus); }

 protected:
  void wheelEvent(QWheelEvent* e) override {
    if (this->hasFocus()) Field::wheelEvent(e);
    else e->ignore();  // to the scroll area around the form
  }
};

QDoubleSpinBox* spinBox(double min, double max, double step, int decimals) {
  auto* s = new FocusedWheelField<QDoubleSpinBox>;
  s->setRange(min, max);
  s->setSingleStep(step);
  s->setDecimals(decimals);
  s->setKeyboardTracking(false);  // commit on Enter, focus loss or arrows, not per keystroke
  return s;
}
}  // namespace

void PropertyForm::addDouble(const QString& label, std::function<double(const Scene&)> get,
                             std::function<void(Scene&, double)> set, double min, double max,
                             double step, int decimals, const QString& suffix) {
  // The field takes any number down to -max, so a value below the smallest allowed is refused
  // with a message: a spin box limited to [min, max] silently turned a typed -1 kg into 1 kg.
  auto* s = spinBox(std::min(min, -max), max, step, decimals);
  s->setSuffix(suffix);
  const int row = static_cast<int>(rows_.size());
  connect(s, &QDoubleSpinBox::valueChanged, this, [=, this](double v) {
    if (refreshing_) return;
    if (v < min) {
      refuse(tr("%1 must be at least %2%3: %4%3 was not applied.")
                 .arg(label, QString::number(min), suffix, QString::number(v)));
      return;
    }
    commit(label, row, [&](Scene& sc) { set(sc, v); });
  });
  rows_.push_back({label, s, [=, this] { s->setValue(get(doc_->scene())); }});
  layout_->addRow(label, s);
}

void PropertyForm::addVector(const QString& label, std::function<Eigen::Vector3d(const Scene&)> get,
                             std::function<void(Scene&, const Eigen::Vector3d&)> set, double min,
                             double max, double step, int decimals) {
  auto* box = new QWidget;
  auto* h = new QHBoxLayout(box);
  h->setContentsMargins(0, 0, 0, 0);
  h->setSpacing(2);
  const int row = static_cast<int>(rows_.size());
  std::array<QDoubleSpinBox*, 3> spins{};
  for (int i = 0; i < 3; ++i) {
    spins[i] = spinBox(min, max, step, decimals);
    spins[i]->setObjectName(QString("xyz"[i]));
    // Three fields side by side fit a docked panel without scrolling sideways: no arrow
    // buttons (the keyboard's arrows and the focused wheel still step) and no width floor
    // from the range's longest text.
    spins[i]->setButtonSymbols(QAbstractSpinBox::NoButtons);
    spins[i]->setMinimumWidth(40);
    spins[i]->setSizePolicy(QSizePolicy::Ignored, QSizePolicy::Fixed);
    h->addWidget(spins[i]);
    connect(spins[i], &QDoubleSpinBox::valueChanged, this, [=, this](double v) {
      commit(label, row, [&](Scene& sc) {
        Eigen::Vector3d x = get(sc);
        x[i] = v;
        set(sc, x);
      });
    });
  }
  rows_.push_back({label, box, [=, this] {
                     const Eigen::Vector3d v = get(doc_->scene());
                     for (int i = 0; i < 3; ++i) spins[i]->setValue(v[i]);
                   }});
  layout_->addRow(label, box);
}

void PropertyForm::addText(const QString& label, std::function<std::string(const Scene&)> get,
                           std::function<void(Scene&, const std::string&)> set) {
  auto* e = new QLineEdit;
  const int row = static_cast<int>(rows_.size());
  connect(e, &QLineEdit::editingFinished, this, [=, this] {
    const std::string v = e->text().trimmed().toStdString();
    if (v == get(doc_->scene())) return;
    commit(label, row, [&](Scene& sc) { set(sc, v); });
  });
  rows_.push_back({label, e, [=, this] {
                     const QString v = QString::fromStdString(get(doc_->scene()));
                     if (e->text() != v) e->setText(v);
                   }});
  layout_->addRow(label, e);
}

void PropertyForm::addChoice(const QString& label, const QStringList& choices,
                             std::function<int(const Scene&)> get, std::function<void(Scene&, int)> set) {
  auto* c = new FocusedWheelField<QComboBox>;
  c->addItems(choices);
  const int row = static_cast<int>(rows_.size());
  connect(c, &QComboBox::currentIndexChanged, this,
          [=, this](int v) { commit(label, row, [&](Scene& sc) { set(sc, v); }); });
  rows_.push_back({label, c, [=, this] { c->setCurrentIndex(get(doc_->scene())); }});
  layout_->addRow(label, c);
}

void PropertyForm::addBool(const QString& label, std::function<bool(const Scene&)> get,
                           std::function<void(Scene&, bool)> set) {
  auto* c = new QCheckBox;
  const int row = static_cast<int>(rows_.size());
  connect(c, &QCheckBox::toggled, this,
          [=, this](bool v) { commit(label, row, [&](Scene& sc) { set(sc, v); }); });
  rows_.push_back({label, c, [=, this] { c->setChecked(get(doc_->scene())); }});
  layout_->addRow(label, c);
}

void PropertyForm::addWidget(const QString& label, QWidget* widget) {
  rows_.push_back({label, widget, [] {}});
  layout_->addRow(label, widget);
}

}  // namespace spacetime::ui
