// The graph widget: plots any quantity of the motion over time - joint q, qd, qdd, tau; a body
// origin's position and velocity; the centre of mass; contact forces; the physics residual
// (the unactuated generalized forces as a fraction of the weight); and typed formulas - several
// series at once, with a time cursor synced with the timeline, the values under the mouse, and
// CSV export of what is plotted. Series follow the live iterates as the solver refines them.
#pragma once

#include <QChartView>
#include <QColor>
#include <QLineEdit>
#include <QTreeWidget>
#include <QWidget>
#include <functional>
#include <set>

#include "ui/document.h"

namespace spacetime::ui {

struct PlotSeries {
  QString name;
  QString unit;  // the y axis it is plotted on: one axis per unit ("rad", "N·m", "m/s", ...)
  std::vector<double> times, values;
};

// The values of one quantity over the motion. Keys: "q/<c>/<dof>", "qd/..", "qdd/..", "tau/..",
// "pos/<c>/<body>/<axis>", "vel/<c>/<body>/<axis>", "com/<c>/<axis>", "force/<term>/<axis>",
// "residual/<c>", "formula/<c>/<text>". False with a reason if the key does not apply.
bool computeSeries(const Document& doc, const QString& key, PlotSeries* out, QString* error);

// The spacing of an axis's ticks over a span: 1, 2 or 5 times a power of ten, giving about
// `ticks` ticks, so that the labels read 0, 5, 10 and not 5.59, 12.8, 19.9.
double niceTickInterval(double span, int ticks = 5);

// The value axis over data in [lo, hi]: padded 5 %, a flat series (an idle joint's zero torque)
// in a band of its own size or 1, whichever is larger, ticks at niceTickInterval. Empty data
// (lo > hi): [-1, 1].
struct ValueAxisRange {
  double min = -1, max = 1, tickInterval = 0.5;
};
ValueAxisRange valueAxisRange(double lo, double hi);

// The colour of a series: its name's own colour from a fixed palette, so a series keeps its
// colour when others are added or removed (Qt Charts' theme hands colours out in order, and
// every colour moved when a series was added). `taken` are the colours of the series before it
// in the plot: a name whose colour is taken gets the next free one.
QColor seriesColour(const QString& name, const std::vector<QColor>& taken);

class GraphView : public QChartView {
  Q_OBJECT
 public:
  using QChartView::QChartView;
  double cursorTime = 0;
  const std::vector<PlotSeries>* series = nullptr;
  QString hoverText;  // the values under the mouse, drawn in the corner
  std::function<void(double)> timeClicked;  // a left click in the plot: the time under it

 protected:
  void drawForeground(QPainter* painter, const QRectF& rect) override;
  void mouseMoveEvent(QMouseEvent* e) override;
  void mousePressEvent(QMouseEvent* e) override;
};

class GraphPanel : public QWidget {
  Q_OBJECT
 public:
  explicit GraphPanel(Document* doc, QWidget* parent = nullptr);

  void setChecked(const QString& key, bool checked);
  bool addFormula(const QString& formula, QString* error);  // for the selected character
  const std::vector<PlotSeries>& plotted() const { return plotted_; }
  QString plottedCsv() const;
  bool exportCsv(const QString& path, QString* error) const;
  QTreeWidget* quantities() const { return tree_; }
  GraphView* view() const { return view_; }

 private:
  void rebuildTree();
  void replot();

  Document* doc_;
  QTreeWidget* tree_;
  GraphView* view_;
  QLineEdit* formula_;
  std::set<QString> checked_;
  std::vector<QString> formulas_;  // keys of user formulas
  std::vector<PlotSeries> plotted_;
  bool syncing_ = false;
  bool defaultsChosen_ = false;
};

}  // namespace spacetime::ui
