// The validity panel (see validity_panel.h).
#include "ui/validity_panel.h"

#include <QHeaderView>
#include <QShowEvent>
#include <QVBoxLayout>
#include <algorithm>

#include "core/scene_io.h"

namespace spacetime::ui {

ValidityPanel::ValidityPanel(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("validityPanel");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  verdict_ = new QLabel;
  verdict_->setWordWrap(true);
  layout->addWidget(verdict_);
  list_ = new QTreeWidget;
  list_->setRootIsDecorated(false);
  list_->setHeaderLabels({tr("Check"), tr("Value"), tr("Limit")});
  // Check names are long and the dock is narrow: columns fit their contents and the list
  // scrolls sideways; every row's tooltip says it in full.
  list_->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  list_->header()->setStretchLastSection(false);
  layout->addWidget(list_, 1);
  // A check that knows where it is worst takes the timeline there.
  connect(list_, &QTreeWidget::itemClicked, this, [this](QTreeWidgetItem* item) {
    const QVariant t = item->data(0, Qt::UserRole);
    if (t.isValid()) doc_->setCurrentTime(t.toDouble());
  });
  connect(doc_, &Document::motionChanged, this, &ValidityPanel::refresh);
  connect(doc_, &Document::sceneChanged, this, &ValidityPanel::refresh);
  connect(doc_, &Document::validityChanged, this, &ValidityPanel::refresh);
  refresh();
}

QTreeWidget* ValidityPanel::list() {
  if (stale_) rebuild();
  return list_;
}

QString ValidityPanel::verdict() {
  if (stale_) rebuild();
  return verdict_->text();
}

void ValidityPanel::showEvent(QShowEvent* e) {
  QWidget::showEvent(e);
  if (stale_) rebuild();
}

void ValidityPanel::refresh() {
  stale_ = true;
  if (isVisible()) rebuild();
}

void ValidityPanel::rebuild() {
  stale_ = false;
  list_->clear();
  const std::shared_ptr<const SolvedMotion> motion = doc_->motion();
  if (!motion || !motion->validity) {
    verdict_->setText(!motion          ? tr("Solve to check the motion.")
                      : motion->solved ? tr("Checking the motion…")
                                       : tr("Solving… the motion is checked when the solve ends."));
    return;
  }
  std::vector<ValidityCheck> checks = validityChecklist(*motion->validity);
  // Failures first, the worst (furthest beyond its limit) on top.
  auto excess = [](const ValidityCheck& c) { return c.limit > 0 ? c.value / c.limit : c.value; };
  std::stable_sort(checks.begin(), checks.end(), [&](const ValidityCheck& a, const ValidityCheck& b) {
    if (a.pass != b.pass) return !a.pass;
    return !a.pass && excess(a) > excess(b);
  });
  // A solve that stopped short lists its unmet constraints on top: they say what to change.
  const QBrush red(QColor(200, 40, 30));
  for (const ViolatedConstraint& v : motion->violated) {
    auto* item = new QTreeWidgetItem(list_);
    item->setText(0, tr("unmet: %1").arg(QString::fromStdString(v.label)));
    item->setText(1, QString::number(v.violation, 'g', 3));
    item->setText(2, tr("= 0"));
    item->setIcon(0, style()->standardIcon(QStyle::SP_MessageBoxCritical));
    item->setForeground(1, red);
    const QString tip = tr("%1 is off by %2 (metres, radians or a fraction of the weight) where the solve stopped")
                            .arg(QString::fromStdString(v.label)).arg(v.violation, 0, 'g', 3);
    for (int column = 0; column < 3; ++column) item->setToolTip(column, tip);
  }
  int failing = 0;
  for (const ValidityCheck& c : checks) {
    const bool yesNo = c.yesNo;
    auto* item = new QTreeWidgetItem(list_);
    item->setText(0, QString::fromStdString(c.name));
    item->setText(1, yesNo ? (c.pass ? tr("yes") : tr("no"))
                           : QString("%1 %2").arg(c.value, 0, 'g', 3).arg(QString::fromStdString(c.unit)));
    item->setText(2, yesNo ? QString() : QString("≤ %1").arg(c.limit, 0, 'g', 3));
    item->setIcon(0, style()->standardIcon(c.pass ? QStyle::SP_DialogApplyButton : QStyle::SP_MessageBoxWarning));
    item->setForeground(1, c.pass ? palette().text() : red);
    QString tip = QString("%1: %2 %3").arg(item->text(0), item->text(1), item->text(2));
    if (c.time) {
      item->setData(0, Qt::UserRole, *c.time);
      tip += tr("\nworst at t = %1 s: click to go there").arg(*c.time, 0, 'f', 3);
    }
    for (int column = 0; column < 3; ++column) item->setToolTip(column, tip);
    if (!c.pass) ++failing;
  }
  // "Valid" only when every check passes and the solve met every constraint: a stopped solve's
  // unmet rows above must never sit under a "valid" verdict.
  const int unmet = static_cast<int>(motion->violated.size());
  QString verdict;
  if (unmet > 0)
    verdict = tr("Not valid: the solve stopped with %n constraint(s) unmet (listed first; when the violation "
                 "stalled, they conflict with each other). ", nullptr, unmet) +
              (failing == 0 ? tr("The %1 checks below pass.").arg(checks.size())
                            : tr("%1 of %2 checks fail.").arg(failing).arg(checks.size()));
  else if (failing > 0)
    verdict = tr("%1 of %2 checks fail: the motion is not physical between the samples "
                 "or does not meet its terms.").arg(failing).arg(checks.size());
  else if (!motion->converged)
    verdict = tr("All %1 checks pass, but the solve stopped before converging: solve again to finish it.")
                  .arg(checks.size());
  else
    verdict = tr("Physically valid: all %1 checks pass.").arg(checks.size());
  // A solve that refined its transcription says why, and where the motion shown lives.
  const std::vector<TranscriptionAttempt>& tried = motion->transcriptions;
  const auto kept = std::find_if(tried.begin(), tried.end(), [](const TranscriptionAttempt& a) { return a.kept; });
  if (tried.size() > 1 && kept != tried.end()) {
    verdict += tr(" The solve refined the transcription %1, because %2; ")
                   .arg(tried.size() == 2 ? tr("once") : tr("%1 times").arg(tried.size() - 1),
                        QString::fromStdString(tried[1].why));
    // The finest transcription's motion is not always the one kept: its solve may have run out
    // of time or stalled further from the constraints.
    const TranscriptionAttempt& last = tried.back();
    verdict += last.kept ? tr("this motion is at %1.").arg(QString::fromStdString(describeResolution(last)))
                         : tr("the solve at %1 stopped (%2), so this motion is the one at %3.")
                               .arg(QString::fromStdString(describeResolution(last)),
                                    QString::fromStdString(last.converged ? "converged, not valid" : toString(last.status)),
                                    QString::fromStdString(describeResolution(*kept)));
  }
  // After an edit the motion on screen is still the last solve's, checked against its own scene.
  if (motion->scene && sceneToJson(*motion->scene) != sceneToJson(doc_->scene()))
    verdict = tr("The scene changed since this solve; these checks are of the solved scene. ") + verdict;
  verdict_->setText(verdict);
}

}  // namespace spacetime::ui
