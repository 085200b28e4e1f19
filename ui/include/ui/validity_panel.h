// The validity panel: is the solved motion physically valid between the samples too? It lists
// the engine's validity checklist (solver/validity.h) for the document's final or loaded
// solution - the dense-grid residual, pins, contacts, clearances, formula constraints, the
// forward simulation of every flight and every impact - each with its value, its limit and a
// pass/fail mark, worst first, with a one-line verdict on top. Clicking a check that knows
// where it is worst (the dense-grid residual, a formula, a diverging flight, an impact) moves the
// timeline there. Iterates in flight are not checked; the panel says so.
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

  // Both bring the panel up to date first (it rebuilds lazily, see refresh()).
  QTreeWidget* list();
  QString verdict();

 protected:
  void showEvent(QShowEvent* e) override;

 private:
  // Marks the checklist out of date and rebuilds it now only if the panel is on screen: it is
  // usually a hidden tab, and every solve and edit would otherwise rebuild it for nobody.
  void refresh();
  void rebuild();

  Document* doc_;
  QLabel* verdict_;
  QTreeWidget* list_;
  bool stale_ = true;
};

}  // namespace spacetime::ui
