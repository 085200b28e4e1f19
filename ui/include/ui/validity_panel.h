// The validity panel: is the solved motion physically valid between the samples too? It lists
// the engine's validity checklist (solver/validity.h) for the document's final or loaded
// solution - the dense-grid residual, pins, contacts, clearances, formula constraints, the
// forward simulation of every flight and every impact - each with its value, its limit and a
// pass/fail mark, worst first, with a one-line verdict on top. Iterates in flight are not
// checked; the panel says so.
#pragma once

#include <QLabel>
#include <QTreeWidget>
#include <QWidget>

#include "ui/document.h"

namespace spacetime::ui {

class ValidityPanel : public QWidget {
  Q_OBJECT
 public:
  explicit ValidityPanel(Document* doc, QWidget* parent = nullptr);

  QTreeWidget* list() const { return list_; }
  QString verdict() const { return verdict_->text(); }

 private:
  void refresh();

  Document* doc_;
  QLabel* verdict_;
  QTreeWidget* list_;
};

}  // namespace spacetime::ui
