// PropertyForm: a form of editors, each bound to one field of the scene by a getter and a
// setter. An edit goes through Document::edit as one undo command, merged while the same field
// keeps changing (spin arrows, typing); refresh() shows the scene's values without emitting.
// The builder and the constraints panel describe their objects' properties with it.
#pragma once

#include <QFormLayout>
#include <QLabel>
#include <QScrollArea>
#include <QStringList>
#include <QWidget>
#include <functional>
#include <vector>

#include "ui/document.h"

namespace spacetime::ui {

class PropertyForm : public QWidget {
  Q_OBJECT
 public:
  PropertyForm(Document* doc, int mergeKind, QWidget* parent = nullptr);

  void clear();
  void addDouble(const QString& label, std::function<double(const Scene&)> get,
                 std::function<void(Scene&, double)> set, double min, double max, double step,
                 int decimals = 3, const QString& suffix = {});
  void addVector(const QString& label, std::function<Eigen::Vector3d(const Scene&)> get,
                 std::function<void(Scene&, const Eigen::Vector3d&)> set, double min, double max,
                 double step, int decimals = 3);
  void addText(const QString& label, std::function<std::string(const Scene&)> get,
               std::function<void(Scene&, const std::string&)> set);
  void addChoice(const QString& label, const QStringList& choices, std::function<int(const Scene&)> get,
                 std::function<void(Scene&, int)> set);
  void addBool(const QString& label, std::function<bool(const Scene&)> get,
               std::function<void(Scene&, bool)> set);
  void addWidget(const QString& label, QWidget* widget);

  void refresh();
  // The editor widgets in row order (tests drive them like a user would).
  QWidget* editor(const QString& label) const;
  // The form in a vertical scroll area for a docked panel: it scrolls up and down, never
  // sideways (rows too narrow for label and field put the field under its label).
  QScrollArea* inScrollArea();
  // Why the last value typed was refused, shown under the form; empty after an accepted edit.
  QString message() const { return message_->isHidden() ? QString() : message_->text(); }

 private:
  struct Row {
    QString label;
    QWidget* widget;
    std::function<void()> refresh;
  };
  void commit(const QString& label, int row, const std::function<void(Scene&)>& change);
  void refuse(const QString& why);  // shows why, and the fields the scene's values again

  Document* doc_;
  int mergeKind_;
  QFormLayout* layout_;
  QLabel* message_;  // why the last value typed was refused (hidden after an accepted edit)
  std::vector<Row> rows_;
  bool refreshing_ = false;
};

}  // namespace spacetime::ui
