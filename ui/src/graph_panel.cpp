#include "ui/graph_panel.h"

#include <QChart>
#include <QFileDialog>
#include <QHBoxLayout>
#include <QLineSeries>
#include <QMessageBox>
#include <QPushButton>
#include <QSplitter>
#include <QTreeWidgetItemIterator>
#include <QValueAxis>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <iterator>

#include "core/atomic_file.h"
#include "dynamics/algorithms.h"
#include "solver/formula_series.h"

namespace spacetime::ui {

namespace {

const char* kAxes = "xyz";

// Linear interpolation of a series at t.
double valueAt(const PlotSeries& s, double t) {
  if (s.times.empty()) return 0;
  const auto it = std::lower_bound(s.times.begin(), s.times.end(), t);
  if (it == s.times.begin()) return s.values.front();
  if (it == s.times.end()) return s.values.back();
  const size_t i = it - s.times.begin();
  const double a = (t - s.times[i - 1]) / (s.times[i] - s.times[i - 1]);
  return (1 - a) * s.values[i - 1] + a * s.values[i];
}

}  // namespace

double niceTickInterval(double span, int ticks) {
  if (!(span > 0) || !std::isfinite(span)) return 1;
  const double raw = span / std::max(1, ticks);
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / decade;
  return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * decade;
}

ValueAxisRange valueAxisRange(double lo, double hi) {
  if (!(lo <= hi) || !std::isfinite(lo) || !std::isfinite(hi)) { lo = -1; hi = 1; }
  const double scale = std::max({1.0, std::abs(lo), std::abs(hi)});
  if (hi - lo < 1e-6 * scale) {
    lo -= 0.5 * scale;
    hi += 0.5 * scale;
  }
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad, niceTickInterval(hi - lo + 2 * pad)};
}

bool computeSeries(const Document& doc, const QString& key, PlotSeries* out, QString* error) {
  const std::shared_ptr<const SolvedMotion> motion = doc.motion();
  if (!motion) {
    *error = QObject::tr("no motion yet: solve first");
    return false;
  }
  const QStringList parts = key.split('/');
  const QString kind = parts.value(0);
  out->name = key;
  if (kind == "force") {
    for (const CharacterAnimation& a : motion->animation.characters) {
      bool found = false;
      for (const ContactTrack& track : a.contacts) {
        if (QString::fromStdString(track.term) != parts.value(1)) continue;
        if (!found) {
          out->times = a.times;
          out->values.assign(a.times.size(), 0.0);
          found = true;
        }
        const int axis = static_cast<int>(QString(kAxes).indexOf(parts.value(2)));
        for (size_t f = 0; f < a.times.size(); ++f) out->values[f] += track.force[f][axis];
      }
      if (found) {
        out->name = QString("%1 force %2 (N)").arg(parts.value(1), parts.value(2));
        out->unit = "N";
        return true;
      }
    }
    *error = QObject::tr("no contact %1 in the motion").arg(parts.value(1));
    return false;
  }
  const int c = parts.value(1).toInt();
  if (c < 0 || c >= static_cast<int>(motion->animation.characters.size()) || c >= static_cast<int>(doc.models().size())) {
    *error = QObject::tr("no character %1").arg(c);
    return false;
  }
  const CharacterAnimation& a = motion->animation.characters[c];
  const Model<double>& model = doc.models()[c];
  out->times = a.times;
  out->values.clear();
  const Eigen::Index frames = static_cast<Eigen::Index>(a.times.size());
  if (kind == "q" || kind == "qd" || kind == "qdd" || kind == "tau") {
    const int d = model.dofIndex(parts.value(2).toStdString());
    if (d < 0) {
      *error = QObject::tr("no dof %1").arg(parts.value(2));
      return false;
    }
    const Eigen::MatrixXd& m = kind == "q" ? a.q : kind == "qd" ? a.qd : kind == "qdd" ? a.qdd : a.tau;
    for (Eigen::Index f = 0; f < frames; ++f) out->values.push_back(m(f, d));
    out->name = kind + "." + parts.value(2);
    // A sliding joint's quantities are lengths and forces; turning ones' angles and torques.
    const bool slides = model.bodies[model.dofBody[d]].joint.type == JointType::Prismatic;
    const QString position = slides ? "m" : "rad";
    out->unit = kind == "q" ? position : kind == "qd" ? position + "/s" : kind == "qdd" ? position + "/s²" : slides ? "N" : "N·m";
    return true;
  }
  if (kind == "pos" || kind == "vel" || kind == "com") {
    const int body = kind == "com" ? -1 : model.bodyIndex(parts.value(2).toStdString());
    const int axis = static_cast<int>(QString(kAxes).indexOf(parts.value(kind == "com" ? 2 : 3)));
    if ((kind != "com" && body < 0) || axis < 0) {
      *error = QObject::tr("bad quantity %1").arg(key);
      return false;
    }
    Data<double> data(model);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.dofCount());
    for (Eigen::Index f = 0; f < frames; ++f) {
      const Eigen::VectorXd q = a.q.row(f).transpose(), qd = a.qd.row(f).transpose();
      forwardKinematics(model, data, q.data(), qd.data(), zero.data());
      const Eigen::Vector3d v = kind == "com"  ? centerOfMass(model, data)
                                : kind == "pos" ? pointPosition(data, body, Eigen::Vector3d::Zero().eval())
                                                : pointVelocity(data, body, Eigen::Vector3d::Zero().eval());
      out->values.push_back(v[axis]);
    }
    out->name = kind == "com" ? QString("com.%1").arg(kAxes[axis]) : QString("%1(%2).%3").arg(kind, parts.value(2)).arg(kAxes[axis]);
    out->unit = kind == "vel" ? "m/s" : "m";
    return true;
  }
  if (kind == "residual") {
    const double weight = model.totalMass() * std::max(1.0, doc.scene().gravity.norm());
    for (Eigen::Index f = 0; f < frames; ++f) {
      double worst = 0;
      for (int d = 0; d < model.dofCount(); ++d)
        if (!a.actuated[d]) worst = std::max(worst, std::abs(a.tau(f, d)) / weight);
      out->values.push_back(worst);
    }
    out->name = QObject::tr("physics residual (× weight)");
    out->unit = QObject::tr("× weight");
    return true;
  }
  if (kind == "formula") {
    const QString text = parts.mid(2).join('/');
    const FormulaSeries fs = evaluateFormulaSeries(doc.scene(), a, text.toStdString());
    if (!fs.error.empty()) {
      *error = QString::fromStdString(fs.error);
      return false;
    }
    out->values = fs.values;
    out->name = text;
    out->unit = QObject::tr("formula");
    return true;
  }
  *error = QObject::tr("unknown quantity %1").arg(key);
  return false;
}

QColor seriesColour(const QString& name, const std::vector<QColor>& taken) {
  // Twelve colours apart from each other on the white plot (Tableau's and ColorBrewer's).
  static const QColor palette[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                   {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127},
                                   {188, 189, 34},  {23, 190, 207}, {0, 0, 128},    {128, 128, 0}};
  constexpr size_t n = std::size(palette);
  const size_t first = qHash(name) % n;
  for (size_t k = 0; k < n; ++k) {
    const QColor& c = palette[(first + k) % n];
    if (std::find(taken.begin(), taken.end(), c) == taken.end()) return c;
  }
  return palette[first];  // more series than colours
}

void GraphView::mousePressEvent(QMouseEvent* e) {
  if (e->button() == Qt::LeftButton && timeClicked && chart() && !chart()->series().isEmpty() &&
      chart()->plotArea().contains(e->position())) {
    timeClicked(chart()->mapToValue(e->position(), chart()->series().front()).x());
    e->accept();
    return;
  }
  QChartView::mousePressEvent(e);
}

void GraphView::drawForeground(QPainter* painter, const QRectF&) {
  if (!chart() || chart()->series().isEmpty()) return;
  const QRectF area = chart()->plotArea();
  const QPointF p = chart()->mapToPosition(QPointF(cursorTime, 0), chart()->series().front());
  painter->setPen(QPen(QColor(255, 80, 60), 1.5));
  painter->drawLine(QPointF(p.x(), area.top()), QPointF(p.x(), area.bottom()));
  if (!hoverText.isEmpty()) {
    painter->setPen(QColor(30, 30, 30));
    painter->drawText(area.adjusted(6, 4, -6, -4), Qt::AlignTop | Qt::AlignRight, hoverText);
  }
}

void GraphView::mouseMoveEvent(QMouseEvent* e) {
  if (chart() && !chart()->series().isEmpty() && series) {
    const double t = chart()->mapToValue(e->position(), chart()->series().front()).x();
    QStringList lines{QString("t = %1 s").arg(t, 0, 'f', 3)};
    for (const PlotSeries& s : *series) lines << QString("%1 = %2").arg(s.name).arg(valueAt(s, t), 0, 'g', 5);
    hoverText = lines.join('\n');
    viewport()->update();
  }
  QChartView::mouseMoveEvent(e);
}

GraphPanel::GraphPanel(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("graphPanel");
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  auto* splitter = new QSplitter;
  layout->addWidget(splitter);
  auto* left = new QWidget;
  auto* leftLayout = new QVBoxLayout(left);
  leftLayout->setContentsMargins(0, 0, 0, 0);
  tree_ = new QTreeWidget;
  tree_->setHeaderHidden(true);
  leftLayout->addWidget(tree_, 1);
  auto* formulaRow = new QHBoxLayout;
  formula_ = new QLineEdit;
  formula_->setPlaceholderText(tr("formula, e.g. pos(head).y - com.y"));
  formulaRow->addWidget(formula_, 1);
  auto* plot = new QPushButton(tr("Plot"));
  formulaRow->addWidget(plot);
  leftLayout->addLayout(formulaRow);
  auto* csv = new QPushButton(tr("Export CSV…"));
  leftLayout->addWidget(csv);
  splitter->addWidget(left);

  auto* chart = new QChart;
  chart->legend()->setAlignment(Qt::AlignBottom);
  chart->setMargins(QMargins(4, 4, 4, 4));
  view_ = new GraphView(chart);
  view_->setRenderHint(QPainter::Antialiasing, false);  // software-rendered: keep repaints cheap
  // The chart repaints with the rest of the window, never on its own. By default a scene whose
  // items changed sends the window's pending UpdateRequest at once (QGraphicsScene
  // _q_processDirtyItems -> dispatchPendingUpdateRequests), so one replot painted and flushed the
  // whole window two or three times in a row - with the OpenGL viewport in the window each flush
  // is a full composition, 15-25 ms under Xvfb, and the event loop waited 50-90 ms per solver
  // iterate. With NoViewportUpdate the scene leaves the viewport alone, and the scene's changed()
  // (emitted from the event loop) asks for an ordinary, coalesced update.
  view_->setViewportUpdateMode(QGraphicsView::NoViewportUpdate);
  connect(chart->scene(), &QGraphicsScene::changed, view_->viewport(), qOverload<>(&QWidget::update));
  view_->setMouseTracking(true);
  view_->series = &plotted_;
  view_->timeClicked = [this](double t) { doc_->setCurrentTime(t); };  // clamped to the clip
  splitter->addWidget(view_);
  splitter->setStretchFactor(1, 3);
  splitter->setSizes({180, 600});

  auto addFormulaFromField = [this] {
    QString error;
    if (!addFormula(formula_->text(), &error)) QMessageBox::warning(this, tr("Formula"), error);
    else formula_->clear();
  };
  connect(plot, &QPushButton::clicked, this, addFormulaFromField);
  connect(formula_, &QLineEdit::returnPressed, this, addFormulaFromField);
  connect(csv, &QPushButton::clicked, this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Export plotted data"), "plot.csv", tr("CSV (*.csv)"));
    QString error;
    if (!path.isEmpty() && !exportCsv(path, &error)) QMessageBox::warning(this, tr("Export"), error);
  });
  connect(tree_, &QTreeWidget::itemChanged, this, [this](QTreeWidgetItem* item) {
    if (syncing_) return;
    const QString key = item->data(0, Qt::UserRole).toString();
    if (key.isEmpty()) return;
    if (item->checkState(0) == Qt::Checked) checked_.insert(key);
    else checked_.erase(key);
    replot();
  });
  connect(doc_, &Document::sceneChanged, this, [this] { rebuildTree(); replot(); });
  connect(doc_, &Document::motionChanged, this, &GraphPanel::replot);
  connect(doc_, &Document::currentTimeChanged, this, [this](double t) {
    view_->cursorTime = t;
    view_->viewport()->update();
  });
  rebuildTree();
}

void GraphPanel::rebuildTree() {
  syncing_ = true;
  tree_->clear();
  const Scene& s = doc_->scene();
  if (!defaultsChosen_ && !s.characters.empty()) {
    // Start with the first character's joint torques: the plot an animator looks at first.
    for (const BodySpec& b : s.characters[0].bodies)
      if (!b.parent.empty() && b.joint.kind != JointKind::Fixed && b.joint.actuated)
        checked_.insert("tau/0/" + QString::fromStdString(b.joint.id));
    defaultsChosen_ = true;
  }
  auto leaf = [this](QTreeWidgetItem* parent, const QString& text, const QString& key) {
    auto* item = new QTreeWidgetItem(parent, {text});
    item->setData(0, Qt::UserRole, key);
    item->setFlags(item->flags() | Qt::ItemIsUserCheckable);
    item->setCheckState(0, checked_.count(key) ? Qt::Checked : Qt::Unchecked);
    return item;
  };
  for (size_t c = 0; c < s.characters.size(); ++c) {
    const CharacterSpec& ch = s.characters[c];
    const QString cs = QString::number(c);
    auto* top = new QTreeWidgetItem(tree_, {QString::fromStdString(ch.id)});
    auto* joints = new QTreeWidgetItem(top, {tr("Joints")});
    for (const std::string& dof : ch.dofNames()) {
      auto* j = new QTreeWidgetItem(joints, {QString::fromStdString(dof)});
      for (const char* k : {"q", "qd", "qdd", "tau"}) leaf(j, k, QString("%1/%2/%3").arg(k, cs, QString::fromStdString(dof)));
    }
    auto* bodies = new QTreeWidgetItem(top, {tr("Bodies")});
    for (const BodySpec& b : ch.bodies) {
      auto* bi = new QTreeWidgetItem(bodies, {QString::fromStdString(b.id)});
      for (const char* k : {"pos", "vel"})
        for (int a = 0; a < 3; ++a)
          leaf(bi, QString("%1.%2").arg(k).arg(kAxes[a]), QString("%1/%2/%3/%4").arg(k, cs, QString::fromStdString(b.id)).arg(kAxes[a]));
    }
    auto* com = new QTreeWidgetItem(top, {tr("Centre of mass")});
    for (int a = 0; a < 3; ++a) leaf(com, QString(kAxes[a]), QString("com/%1/%2").arg(cs).arg(kAxes[a]));
    leaf(top, tr("Physics residual"), "residual/" + cs);
  }
  auto* contacts = new QTreeWidgetItem(tree_, {tr("Contact forces")});
  for (const TermSpec& t : s.terms)
    if (t.kind == TermKind::Contact) {
      auto* ci = new QTreeWidgetItem(contacts, {QString::fromStdString(t.id)});
      for (int a = 0; a < 3; ++a) leaf(ci, QString(kAxes[a]), QString("force/%1/%2").arg(QString::fromStdString(t.id)).arg(kAxes[a]));
    }
  auto* formulas = new QTreeWidgetItem(tree_, {tr("Formulas")});
  for (const QString& key : formulas_) leaf(formulas, key.section('/', 2), key);
  // Open the branches that hold something plotted.
  for (QTreeWidgetItemIterator it(tree_); *it; ++it)
    if ((*it)->checkState(0) == Qt::Checked)
      for (QTreeWidgetItem* p = (*it)->parent(); p; p = p->parent()) p->setExpanded(true);
  syncing_ = false;
}

void GraphPanel::setChecked(const QString& key, bool checked) {
  if (checked) checked_.insert(key);
  else checked_.erase(key);
  rebuildTree();
  replot();
}

bool GraphPanel::addFormula(const QString& text, QString* error) {
  const int c = std::max(0, doc_->selectedCharacter());
  const QString key = QString("formula/%1/%2").arg(c).arg(text.trimmed());
  PlotSeries probe;
  if (!computeSeries(*doc_, key, &probe, error)) return false;
  if (std::find(formulas_.begin(), formulas_.end(), key) == formulas_.end()) formulas_.push_back(key);
  setChecked(key, true);
  return true;
}

void GraphPanel::replot() {
  std::vector<PlotSeries> plotted;
  for (const QString& key : checked_) {
    PlotSeries s;
    QString error;
    if (computeSeries(*doc_, key, &s, &error)) plotted.push_back(std::move(s));
  }
  QChart* chart = view_->chart();
  // One y axis per unit, in the order the units first appear, alternately left and right: metres
  // and newton-metres on one unitless axis hid the smaller of them.
  std::vector<QString> units;
  for (const PlotSeries& s : plotted)
    if (std::find(units.begin(), units.end(), s.unit) == units.end()) units.push_back(s.unit);
  auto unitIndex = [&](const QString& unit) {
    return static_cast<qsizetype>(std::find(units.begin(), units.end(), unit) - units.begin());
  };
  // The same series as before (every solver iterate, every edit that keeps the plotted set):
  // replace their points and ranges in place. Rebuilding series and axes costs QtCharts a
  // relayout and new axis labels, several milliseconds per iterate on the interface thread.
  QList<QAbstractSeries*> lines = chart->series();
  QList<QAbstractAxis*> yAxes = chart->axes(Qt::Vertical);
  bool sameSeries = lines.size() == static_cast<qsizetype>(plotted.size()) &&
                    chart->axes(Qt::Horizontal).size() == 1 && yAxes.size() == static_cast<qsizetype>(units.size());
  for (size_t i = 0; sameSeries && i < plotted.size(); ++i) sameSeries = lines[i]->name() == plotted[i].name;
  for (size_t u = 0; sameSeries && u < units.size(); ++u) sameSeries = yAxes[u]->titleText() == units[u];
  auto* x = sameSeries ? qobject_cast<QValueAxis*>(chart->axes(Qt::Horizontal).value(0)) : nullptr;
  if (!x) {
    chart->removeAllSeries();
    for (QAbstractAxis* axis : chart->axes()) chart->removeAxis(axis);
    x = new QValueAxis;
    x->setTitleText(tr("time (s)"));
    x->setLabelFormat("%.2f");
    chart->addAxis(x, Qt::AlignBottom);
    yAxes.clear();
    for (size_t u = 0; u < units.size(); ++u) {
      auto* y = new QValueAxis;
      y->setLabelFormat("%.3g");
      y->setTitleText(units[u]);
      chart->addAxis(y, u % 2 == 0 ? Qt::AlignLeft : Qt::AlignRight);
      yAxes.push_back(y);
    }
    lines.clear();
    std::vector<QColor> taken;
    for (const PlotSeries& s : plotted) {
      auto* line = new QLineSeries;
      line->setName(s.name);
      taken.push_back(seriesColour(s.name, taken));
      line->setColor(taken.back());
      chart->addSeries(line);
      line->attachAxis(x);
      line->attachAxis(yAxes[unitIndex(s.unit)]);
      lines.push_back(line);
    }
  }
  std::vector<double> lo(units.size(), 1e300), hi(units.size(), -1e300);
  for (size_t k = 0; k < plotted.size(); ++k) {
    const PlotSeries& s = plotted[k];
    const qsizetype u = unitIndex(s.unit);
    QList<QPointF> points;
    points.reserve(static_cast<qsizetype>(s.times.size()));
    for (size_t i = 0; i < s.times.size(); ++i) {
      points.append(QPointF(s.times[i], s.values[i]));
      lo[u] = std::min(lo[u], s.values[i]);
      hi[u] = std::max(hi[u], s.values[i]);
    }
    static_cast<QLineSeries*>(lines[static_cast<qsizetype>(k)])->replace(points);
  }
  plotted_ = std::move(plotted);
  x->setRange(doc_->scene().startTime, doc_->scene().endTime);
  // Range and interval change with fixed ticks in between: Qt lays the axis out after each
  // setter, and a flat series' leftover interval (~5e-10) over the next plot's range asked for
  // ~1e9 ticks - the editor froze with its memory growing ~300 MB/s.
  for (size_t u = 0; u < units.size(); ++u) {
    auto* y = static_cast<QValueAxis*>(yAxes[static_cast<qsizetype>(u)]);
    const ValueAxisRange range = valueAxisRange(lo[u], hi[u]);
    y->setTickType(QValueAxis::TicksFixed);
    y->setRange(range.min, range.max);
    y->setTickAnchor(0);
    y->setTickInterval(range.tickInterval);
    y->setTickType(QValueAxis::TicksDynamic);
  }
  view_->cursorTime = doc_->currentTime();
  view_->viewport()->update();
}

QString GraphPanel::plottedCsv() const {
  QString out = "time";
  for (const PlotSeries& s : plotted_) out += ",\"" + QString(s.name).replace('"', "'") + "\"";
  out += "\n";
  if (plotted_.empty()) return out;
  for (size_t i = 0; i < plotted_.front().times.size(); ++i) {
    out += QString::number(plotted_.front().times[i], 'g', 9);
    for (const PlotSeries& s : plotted_) out += "," + QString::number(i < s.values.size() ? s.values[i] : 0.0, 'g', 12);
    out += "\n";
  }
  return out;
}

bool GraphPanel::exportCsv(const QString& path, QString* error) const {
  std::string why;
  if (writeFileAtomically(path.toStdString(), plottedCsv().toStdString(), &why)) return true;
  *error = QString::fromStdString(why);
  return false;
}

}  // namespace spacetime::ui
