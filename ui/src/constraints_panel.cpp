#include "ui/constraints_panel.h"

#include <QPushButton>

#include <QHBoxLayout>

#include <QHeaderView>
#include <QLabel>
#include <QMenu>
#include <QScrollArea>
#include <QSplitter>
#include <QToolButton>
#include <QVBoxLayout>

#include "core/shape_mesh.h"
#include "ui/render_scene.h"

namespace spacetime::ui {

namespace {

TermSpec* findTerm(Scene& s, const std::string& id) {
  for (TermSpec& t : s.terms)
    if (t.id == id) return &t;
  return nullptr;
}
const TermSpec* findTerm(const Scene& s, const std::string& id) { return findTerm(const_cast<Scene&>(s), id); }

QString when(const TermSpec& t) {
  auto n = [](double v) { return QString::number(v, 'g', 4); };
  switch (t.kind) {
    case TermKind::Pin: return t.until ? n(t.time) + "–" + n(*t.until) + " s" : n(t.time) + " s";
    case TermKind::Keyframe:
    case TermKind::Rest: return n(t.time) + " s";
    case TermKind::Contact:
    case TermKind::Clearance: return n(t.start) + "–" + n(t.end) + " s";
    case TermKind::Formula: return t.interval ? n(t.start) + "–" + n(t.end) + " s" : n(t.time) + " s";
  }
  return {};
}

}  // namespace

ConstraintsPanel::ConstraintsPanel(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("constraintsPanel");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  auto* buttons = new QHBoxLayout;
  auto* add = new QToolButton;
  add->setText(tr("Add"));
  add->setPopupMode(QToolButton::InstantPopup);
  auto* menu = new QMenu(add);
  menu->addAction(tr("Pin the selected body here"), this, [this] { addPin(); });
  // K is the window's shortcut (Edit > Key the current pose); here it is only shown. A second
  // window-wide K made Qt report "Ambiguous shortcut overload" and K did nothing.
  QAction* key = menu->addAction(tr("Key the current pose"), this, [this] { keyCurrentPose(); });
  key->setShortcut(QKeySequence(Qt::Key_K));
  key->setShortcutContext(Qt::WidgetShortcut);
  menu->addAction(tr("Rest"), this, [this] { addRest(); });
  menu->addAction(tr("Contact"), this, [this] { addContact(); });
  menu->addAction(tr("Clearance"), this, [this] { addClearance(); });
  menu->addAction(tr("Formula"), this, [this] { addFormula(); });
  add->setMenu(menu);
  buttons->addWidget(add);
  auto* remove = new QToolButton;
  remove->setText(tr("Delete"));
  connect(remove, &QToolButton::clicked, this, [this] { removeSelected(); });
  buttons->addWidget(remove);
  buttons->addStretch();
  layout->addLayout(buttons);

  list_ = new QTreeWidget;
  list_->setRootIsDecorated(false);
  list_->setHeaderLabels({tr("Term"), tr("Kind"), tr("When")});
  list_->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  form_ = new PropertyForm(doc_, kMergeTermField);
  QScrollArea* scroll = form_->inScrollArea();
  auto* split = new QSplitter(Qt::Vertical);
  split->addWidget(list_);
  split->addWidget(scroll);
  split->setSizes({260, 360});
  layout->addWidget(split, 1);

  connect(list_, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    if (syncing_ || !item) return;
    const QString kind = item->data(0, Qt::UserRole + 1).toString();
    if (kind == "limit") {
      doc_->selectBody(item->data(0, Qt::UserRole + 2).toInt(), item->data(0, Qt::UserRole).toString().toStdString());
      doc_->selectTerm({});
    } else {
      doc_->selectTerm(item->data(0, Qt::UserRole).toString().toStdString());
    }
  });
  connect(list_, &QTreeWidget::itemChanged, this, [this](QTreeWidgetItem* item, int column) {
    if (syncing_ || column != 0 || item->data(0, Qt::UserRole + 1).toString() == "limit") return;
    setEnabled(item->data(0, Qt::UserRole).toString().toStdString(), item->checkState(0) == Qt::Checked);
  });
  connect(doc_, &Document::sceneChanged, this, [this] { rebuildList(); rebuildForm(); });
  connect(doc_, &Document::selectionChanged, this, [this] { rebuildList(); rebuildForm(); });
  rebuildList();
  rebuildForm();
}

void ConstraintsPanel::rebuildList() {
  syncing_ = true;
  list_->clear();
  QTreeWidgetItem* current = nullptr;  // the row of the document's selection, if it has one
  const Scene& s = doc_->scene();
  for (const TermSpec& t : s.terms) {
    auto* item = new QTreeWidgetItem(list_, {QString::fromStdString(t.id), QString::fromStdString(toString(t.kind)), when(t)});
    item->setFlags(item->flags() | Qt::ItemIsUserCheckable);
    item->setCheckState(0, t.enabled ? Qt::Checked : Qt::Unchecked);
    item->setData(0, Qt::UserRole, QString::fromStdString(t.id));
    item->setData(0, Qt::UserRole + 1, QString::fromStdString(toString(t.kind)));
    if (t.id == doc_->selectedTerm()) current = item;
  }
  // Joint position, torque and speed limits live on the joints (edited in the builder); listed here too.
  for (size_t c = 0; c < s.characters.size(); ++c)
    for (const BodySpec& b : s.characters[c].bodies) {
      if (b.parent.empty() || (!b.joint.limits && !b.joint.torqueLimit && !b.joint.speedLimit)) continue;
      QString range;
      if (b.joint.limits) range = QString("[%1, %2]").arg(b.joint.limits->first).arg(b.joint.limits->second);
      if (b.joint.torqueLimit) range += QString(" |τ|≤%1").arg(*b.joint.torqueLimit);
      if (b.joint.speedLimit) range += QString(" |q̇|≤%1").arg(*b.joint.speedLimit);
      auto* item = new QTreeWidgetItem(list_, {QString::fromStdString(b.joint.id), tr("limit"), range});
      item->setData(0, Qt::UserRole, QString::fromStdString(b.id));
      item->setData(0, Qt::UserRole + 1, QString("limit"));
      item->setData(0, Qt::UserRole + 2, static_cast<int>(c));
      if (doc_->selectedTerm().empty() && static_cast<int>(c) == doc_->selectedCharacter() && b.id == doc_->selectedBody())
        current = item;
    }
  // The highlighted row is always the document's selection, or none: left to itself the list
  // highlighted its first row while the form showed, and Delete removed, the selected term.
  list_->setCurrentItem(current);
  if (!current) list_->clearSelection();
  syncing_ = false;
}

void ConstraintsPanel::rebuildForm() {
  const std::string id = doc_->selectedTerm();
  const TermSpec* term = findTerm(doc_->scene(), id);
  const bool exists = term != nullptr;
  // The same term with as many rows (points, key values) as the form has: refresh its values.
  const std::pair<size_t, size_t> rows = exists ? std::pair{term->points.size(), term->values.size()} : std::pair<size_t, size_t>{};
  if (exists && id == formTerm_ && rows == formRows_) {
    form_->refresh();
    return;
  }
  form_->clear();
  formTerm_ = exists ? id : std::string();
  formRows_ = rows;
  if (!exists) {
    // A joint's limits are the joint's properties, edited with the rest of its body in the
    // builder: say so rather than show an empty form (seen: a highlighted limit row, no form).
    const QTreeWidgetItem* row = list_->currentItem();
    if (row && row->data(0, Qt::UserRole + 1).toString() == "limit") {
      auto* hint = new QLabel(tr("Joint %1's limits belong to body %2: edit them in the Builder.")
                                  .arg(row->text(0), row->data(0, Qt::UserRole).toString()));
      hint->setObjectName("limitHint");
      hint->setWordWrap(true);
      form_->addWidget({}, hint);
      auto* open = new QPushButton(tr("Edit in Builder"));
      open->setObjectName("editLimitInBuilder");
      connect(open, &QPushButton::clicked, this, &ConstraintsPanel::showBuilder);
      form_->addWidget({}, open);
    }
    return;
  }
  termForm(id);
  form_->refresh();
}

void ConstraintsPanel::termForm(const std::string& id) {
  const TermSpec& term = *findTerm(doc_->scene(), id);
  auto get = [id](const Scene& s) -> const TermSpec& {
    static const TermSpec none;
    const TermSpec* t = findTerm(s, id);
    return t ? *t : none;
  };
  auto edit = [id](Scene& s, const std::function<void(TermSpec&)>& f) {
    if (TermSpec* t = findTerm(s, id)) f(*t);
  };
  auto timeRow = [&](const QString& label, double TermSpec::*field) {
    form_->addDouble(label, [get, field](const Scene& s) { return get(s).*field; },
                     [edit, field](Scene& s, double v) { edit(s, [&](TermSpec& t) { t.*field = v; }); },
                     -1e3, 1e3, 0.01, 3, " s");
  };
  const Scene& scene = doc_->scene();
  const CharacterSpec* ch = scene.character(term.character);
  QStringList bodies;
  if (ch)
    for (const BodySpec& b : ch->bodies) bodies << QString::fromStdString(b.id);
  auto bodyRow = [&](bool optional) {
    QStringList choices = bodies;
    if (optional) choices.prepend(tr("(whole character)"));
    form_->addChoice(tr("Body"), choices,
                     [get, choices](const Scene& s) {
                       const int i = static_cast<int>(choices.indexOf(QString::fromStdString(get(s).body)));
                       return i < 0 ? 0 : i;
                     },
                     [edit, choices, optional](Scene& s, int v) {
                       edit(s, [&](TermSpec& t) { t.body = optional && v == 0 ? std::string() : choices[v].toStdString(); });
                     });
  };
  auto vectorRow = [&](const QString& label, Eigen::Vector3d TermSpec::*field) {
    form_->addVector(label, [get, field](const Scene& s) { return get(s).*field; },
                     [edit, field](Scene& s, const Eigen::Vector3d& v) { edit(s, [&](TermSpec& t) { t.*field = v; }); },
                     -100, 100, 0.01, 3);
  };
  form_->addText(tr("Id"), [get](const Scene& s) { return get(s).id; },
                 [this, id](Scene& s, const std::string& v) {
                   if (v.empty() || findTerm(s, v)) return;
                   findTerm(s, id)->id = v;
                   QMetaObject::invokeMethod(this, [this, v] { doc_->selectTerm(v); }, Qt::QueuedConnection);
                 });
  form_->addBool(tr("Enabled"), [get](const Scene& s) { return get(s).enabled; },
                 [edit](Scene& s, bool v) { edit(s, [&](TermSpec& t) { t.enabled = v; }); });
  switch (term.kind) {
    case TermKind::Pin:
      bodyRow(false);
      timeRow(tr("Time"), &TermSpec::time);
      form_->addDouble(tr("Hold until"), [get](const Scene& s) { return get(s).until.value_or(get(s).time); },
                       [edit](Scene& s, double v) {
                         edit(s, [&](TermSpec& t) {
                           if (v > t.time) t.until = v;
                           else t.until.reset();
                         });
                       }, -1e3, 1e3, 0.01, 3, " s");
      vectorRow(tr("Body point"), &TermSpec::point);
      vectorRow(tr("Target"), &TermSpec::position);
      for (int a = 0; a < 3; ++a)
        form_->addBool(tr("Hold %1").arg(QChar("xyz"[a])), [get, a](const Scene& s) { return get(s).axes[a]; },
                       [edit, a](Scene& s, bool v) { edit(s, [&](TermSpec& t) { t.axes[a] = v; }); });
      break;
    case TermKind::Keyframe:
      timeRow(tr("Time"), &TermSpec::time);
      for (size_t k = 0; k < term.values.size(); ++k)
        form_->addDouble(QString::fromStdString(term.values[k].first),
                         [get, k](const Scene& s) { return k < get(s).values.size() ? get(s).values[k].second : 0.0; },
                         [edit, k](Scene& s, double v) {
                           edit(s, [&](TermSpec& t) { if (k < t.values.size()) t.values[k].second = v; });
                         }, -1e3, 1e3, 0.01, 4);
      break;
    case TermKind::Rest:
      bodyRow(true);
      timeRow(tr("Time"), &TermSpec::time);
      break;
    case TermKind::Contact:
      bodyRow(false);
      timeRow(tr("Start"), &TermSpec::start);
      timeRow(tr("End"), &TermSpec::end);
      form_->addDouble(tr("Friction μ"), [get](const Scene& s) { return get(s).friction; },
                       [edit](Scene& s, double v) { edit(s, [&](TermSpec& t) { t.friction = v; }); }, 0, 10, 0.05, 2);
      // Touch-down with an impact (root velocity jump, ground impulse) when the contact begins
      // after the clip's start; off, the points must already be at rest when it begins.
      form_->addBool(tr("Impact at start"), [get](const Scene& s) { return get(s).impact; },
                     [edit](Scene& s, bool v) { edit(s, [&](TermSpec& t) { t.impact = v; }); });
      // The solver chooses the lift-off instant near End (within the collocation intervals
      // either side of it) instead of holding the points down exactly until End.
      form_->addBool(tr("Free lift-off"), [get](const Scene& s) { return get(s).freeEnd; },
                     [edit](Scene& s, bool v) { edit(s, [&](TermSpec& t) { t.freeEnd = v; }); });
      for (size_t k = 0; k < term.points.size(); ++k)
        form_->addVector(tr("Point %1").arg(k + 1),
                         [get, k](const Scene& s) { return k < get(s).points.size() ? get(s).points[k] : Eigen::Vector3d::Zero().eval(); },
                         [edit, k](Scene& s, const Eigen::Vector3d& v) {
                           edit(s, [&](TermSpec& t) { if (k < t.points.size()) t.points[k] = v; });
                         }, -100, 100, 0.01, 3);
      {
        // More points by clicking the body in the viewport; the last one off (one stays).
        auto* buttons = new QWidget;
        auto* row = new QHBoxLayout(buttons);
        row->setContentsMargins(0, 0, 0, 0);
        auto* pick = new QPushButton(tr("Add by clicking the body"));
        pick->setObjectName("addContactPoint");
        connect(pick, &QPushButton::clicked, this, [this, id] { emit pickContactPoint(id); });
        auto* drop = new QPushButton(tr("Remove the last"));
        drop->setObjectName("removeContactPoint");
        drop->setEnabled(term.points.size() > 1);
        connect(drop, &QPushButton::clicked, this, [this, id] {
          doc_->edit(tr("Remove contact point"), [&](Scene& s) {
            if (TermSpec* t = findTerm(s, id); t && t->points.size() > 1) t->points.pop_back();
          });
        });
        row->addWidget(pick);
        row->addWidget(drop);
        form_->addWidget(tr("Points"), buttons);
      }
      break;
    case TermKind::Clearance:
      bodyRow(false);
      vectorRow(tr("Body point"), &TermSpec::point);
      timeRow(tr("Start"), &TermSpec::start);
      timeRow(tr("End"), &TermSpec::end);
      form_->addChoice(tr("Stay"), {tr("above a height"), tr("outside a box")},
                       [get](const Scene& s) { return get(s).box ? 1 : 0; },
                       [edit](Scene& s, int v) { edit(s, [&](TermSpec& t) { t.box = v == 1; }); });
      form_->addDouble(tr("Height"), [get](const Scene& s) { return get(s).height; },
                       [edit](Scene& s, double v) { edit(s, [&](TermSpec& t) { t.height = v; }); }, -100, 100, 0.01, 3, " m");
      vectorRow(tr("Box min"), &TermSpec::boxMin);
      vectorRow(tr("Box max"), &TermSpec::boxMax);
      break;
    case TermKind::Formula:
      form_->addText(tr("Formula"), [get](const Scene& s) { return get(s).expression; },
                     [edit](Scene& s, const std::string& v) { edit(s, [&](TermSpec& t) { t.expression = v; }); });
      form_->addChoice(tr("Relation"), {"=", "<=", ">="},
                       [get](const Scene& s) { return get(s).relation == '=' ? 0 : get(s).relation == '<' ? 1 : 2; },
                       [edit](Scene& s, int v) { edit(s, [&](TermSpec& t) { t.relation = "=<>"[v]; }); });
      form_->addDouble(tr("Value"), [get](const Scene& s) { return get(s).value; },
                       [edit](Scene& s, double v) { edit(s, [&](TermSpec& t) { t.value = v; }); }, -1e6, 1e6, 0.01, 4);
      form_->addBool(tr("Over an interval"), [get](const Scene& s) { return get(s).interval; },
                     [edit](Scene& s, bool v) {
                       edit(s, [&](TermSpec& t) {
                         t.interval = v;
                         if (v && !(t.end > t.start)) { t.start = t.time; t.end = t.time + 0.1; }
                       });
                     });
      timeRow(tr("Time"), &TermSpec::time);
      timeRow(tr("Start"), &TermSpec::start);
      timeRow(tr("End"), &TermSpec::end);
      break;
  }
}

bool ConstraintsPanel::selectedTarget(int* character, std::string* body) const {
  const Scene& s = doc_->scene();
  if (s.characters.empty()) return false;
  *character = doc_->selectedCharacter();
  if (*character < 0 || *character >= static_cast<int>(s.characters.size())) *character = 0;
  *body = doc_->selectedBody();
  if (body->empty() || !s.characters[*character].body(*body)) *body = s.characters[*character].bodies.front().id;
  return true;
}

TermSpec ConstraintsPanel::newTerm(const char* stem, TermKind kind, int character) const {
  TermSpec term;
  term.id = doc_->uniqueTermId(stem);
  term.kind = kind;
  term.character = doc_->scene().characters[character].id;
  return term;
}

std::string ConstraintsPanel::addTerm(const QString& text, TermSpec term) {
  doc_->edit(text, [&](Scene& s) { s.terms.push_back(term); });
  doc_->selectTerm(term.id);
  return term.id;
}

std::string ConstraintsPanel::addPin() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body) || doc_->models().size() <= static_cast<size_t>(c)) return {};
  const Model<double>& model = doc_->models()[c];
  const double t = doc_->currentTime();
  const Eigen::VectorXd q = doc_->posesNow()[c];
  TermSpec pin = newTerm("pin", TermKind::Pin, c);
  pin.body = body;
  pin.time = t;
  // The body's tip (a hand, a head), not its origin, which is the joint.
  if (const BodySpec* b = doc_->scene().characters[c].body(body)) pin.point = geometryTip(b->geometry);
  pin.position = bodyToWorld(model, q, model.bodyIndex(body), pin.point);
  if (doc_->scene().characters[c].root == RootKind::Planar) pin.axes = {true, true, false};
  return addTerm(tr("Add pin"), pin);
}

std::string ConstraintsPanel::keyCurrentPose() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body) || doc_->models().size() <= static_cast<size_t>(c)) return {};
  if (doc_->posed()) c = doc_->posed()->character;  // the pose being made is what K keys
  const double t = doc_->currentTime();
  const Eigen::VectorXd q = doc_->posesNow()[c];
  const std::string character = doc_->scene().characters[c].id;
  std::vector<std::pair<std::string, double>> values;
  const std::vector<std::string> dofs = doc_->scene().characters[c].dofNames();
  for (size_t d = 0; d < dofs.size(); ++d) values.emplace_back(dofs[d], q[static_cast<Eigen::Index>(d)]);
  // A key fixes every dof at t, so another key of the character at t is replaced (two would be
  // redundant constraints, and the solve ended not converged), and a pin on it at t is implied
  // or contradicted: it goes, and the status bar says so.
  auto sameInstant = [&](const TermSpec& term) {
    return term.enabled && term.character == character && std::abs(term.time - t) < 1e-9;
  };
  std::string rekeyed;
  QStringList pins;
  for (const TermSpec& term : doc_->scene().terms) {
    if (!sameInstant(term)) continue;
    if (term.kind == TermKind::Keyframe && rekeyed.empty()) rekeyed = term.id;
    if (term.kind == TermKind::Pin) pins << QString("'%1'").arg(QString::fromStdString(term.id));
  }
  TermSpec key = newTerm("key", TermKind::Keyframe, c);
  key.time = t;
  key.values = values;
  const std::string id = rekeyed.empty() ? key.id : rekeyed;
  doc_->edit(rekeyed.empty() ? tr("Key the current pose") : tr("Re-key the pose"), [&](Scene& s) {
    std::erase_if(s.terms, [&](const TermSpec& term) {
      return sameInstant(term) && (term.kind == TermKind::Pin || (term.kind == TermKind::Keyframe && term.id != id));
    });
    if (rekeyed.empty()) s.terms.push_back(key);
    for (TermSpec& term : s.terms)
      if (term.id == id) term.values = values;
  });
  doc_->selectTerm(id);
  QString message = rekeyed.empty() ? tr("Keyed the pose of '%1' at t = %2 s as '%3'")
                                    : tr("Replaced key '%3' of '%1' at t = %2 s with the current pose");
  message = message.arg(QString::fromStdString(character)).arg(t, 0, 'g', 4).arg(QString::fromStdString(id));
  if (!pins.isEmpty())
    message += tr("; removed pin %1 there (the key fixes every joint; Ctrl+Z brings it back)").arg(pins.join(", "));
  emit said(message);
  return id;
}

std::string ConstraintsPanel::addRest() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body)) return {};
  TermSpec rest = newTerm("rest", TermKind::Rest, c);
  rest.time = doc_->currentTime();
  return addTerm(tr("Add rest"), rest);
}

std::string ConstraintsPanel::addContact() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body)) return {};
  const Scene& s = doc_->scene();
  TermSpec contact = newTerm("contact", TermKind::Contact, c);
  contact.body = body;
  // The bottom of the body's geometry: a box's base corners (two for a planar character, which
  // one point would leave pivoting), a sphere's lowest point.
  contact.points = {Eigen::Vector3d::Zero()};
  if (const BodySpec* b = s.characters[c].body(body))
    contact.points = geometryBaseCorners(b->geometry, s.characters[c].root == RootKind::Planar);
  const double span = 0.2 * (s.endTime - s.startTime);
  contact.start = std::max(s.startTime, doc_->currentTime() - span / 2);
  contact.end = std::min(s.endTime, contact.start + span);
  return addTerm(tr("Add contact"), contact);
}

std::string ConstraintsPanel::addClearance() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body)) return {};
  const Scene& s = doc_->scene();
  TermSpec clearance = newTerm("clearance", TermKind::Clearance, c);
  clearance.body = body;
  clearance.start = s.startTime;
  clearance.end = s.endTime;
  clearance.height = s.groundHeight;
  return addTerm(tr("Add clearance"), clearance);
}

std::string ConstraintsPanel::addFormula() {
  int c;
  std::string body;
  if (!selectedTarget(&c, &body)) return {};
  TermSpec f = newTerm("formula", TermKind::Formula, c);
  f.expression = "pos(" + body + ").y";
  f.relation = '>';
  f.value = doc_->scene().groundHeight;
  f.time = doc_->currentTime();
  return addTerm(tr("Add formula"), f);
}

void ConstraintsPanel::removeSelected() {
  const std::string id = doc_->selectedTerm();
  if (!findTerm(doc_->scene(), id)) return;
  doc_->edit(tr("Delete %1").arg(QString::fromStdString(id)),
             [&](Scene& s) { std::erase_if(s.terms, [&](const TermSpec& t) { return t.id == id; }); });
  doc_->selectTerm({});
}

void ConstraintsPanel::setEnabled(const std::string& id, bool enabled) {
  doc_->edit(enabled ? tr("Enable %1").arg(QString::fromStdString(id)) : tr("Disable %1").arg(QString::fromStdString(id)),
             [&](Scene& s) {
               if (TermSpec* t = findTerm(s, id)) t->enabled = enabled;
             });
}

}  // namespace spacetime::ui
