#include "ui/builder_panel.h"

#include <QFile>
#include <QHeaderView>
#include <QMenu>
#include <QScrollArea>
#include <QSplitter>
#include <QToolButton>
#include <QVBoxLayout>
#include <functional>
#include <set>

#include "core/scene_io.h"
#include "core/shape_mesh.h"

namespace spacetime::ui {

namespace {

// Locating a body by character index and id inside a scene being edited.
BodySpec* findBody(Scene& s, int c, const std::string& id) {
  if (c < 0 || c >= static_cast<int>(s.characters.size())) return nullptr;
  for (BodySpec& b : s.characters[c].bodies)
    if (b.id == id) return &b;
  return nullptr;
}
const BodySpec* findBody(const Scene& s, int c, const std::string& id) {
  return findBody(const_cast<Scene&>(s), c, id);
}

// Renames a body everywhere it is referred to: children's parents and the terms.
void renameBody(Scene& s, int c, const std::string& from, const std::string& to) {
  CharacterSpec& ch = s.characters[c];
  for (BodySpec& b : ch.bodies) {
    if (b.id == from) b.id = to;
    if (b.parent == from) b.parent = to;
  }
  for (TermSpec& t : s.terms)
    if (t.character == ch.id && t.body == from) t.body = to;
}

void renameJoint(Scene& s, int c, const std::string& from, const std::string& to) {
  for (BodySpec& b : s.characters[c].bodies)
    if (b.joint.id == from) b.joint.id = to;
  for (TermSpec& t : s.terms)
    if (t.character == s.characters[c].id)
      for (auto& [dof, value] : t.values)
        if (dof == from) dof = to;
}

bool validId(const std::string& id) {
  if (id.empty()) return false;
  for (char ch : id)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-')) return false;
  return true;
}

}  // namespace

BuilderPanel::BuilderPanel(Document* doc, QWidget* parent) : QWidget(parent), doc_(doc) {
  setObjectName("builderPanel");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  auto* buttons = new QHBoxLayout;
  auto button = [&](const QString& text, const QString& tip, auto slot) {
    auto* b = new QToolButton;
    b->setText(text);
    b->setToolTip(tip);
    b->setObjectName(text);
    connect(b, &QToolButton::clicked, this, slot);
    buttons->addWidget(b);
    return b;
  };
  button(tr("+ Character"), tr("Add a planar character with one body"), [this] { addCharacter(); });
  button(tr("+ Body"), tr("Add a body jointed to the selected body"), [this] { addBody(); });
  button(tr("Remove"), tr("Remove the selected body and its children"), [this] { removeBody(); });
  auto* presets = new QToolButton;
  presets->setText(tr("Presets"));
  presets->setPopupMode(QToolButton::InstantPopup);
  auto* menu = new QMenu(presets);
  menu->addAction(tr("Particle"), this, [this] { applyPreset(":/scenes/particle.json"); });
  menu->addAction(tr("Planar Luxo"), this, [this] { applyPreset(":/scenes/luxo_jump.json"); });
  menu->addAction(tr("3D Luxo"), this, [this] { applyPreset(":/scenes/luxo_3d.json"); });
  menu->addAction(tr("Planar biped"), this, [this] { applyPreset(":/scenes/biped_jump.json"); });
  menu->addAction(tr("Planar quadruped"), this, [this] { applyPreset(":/scenes/quadruped_hop.json"); });
  menu->addAction(tr("3D humanoid"), this, [this] { applyPreset(":/scenes/humanoid_jump.json"); });
  presets->setMenu(menu);
  buttons->addWidget(presets);
  buttons->addStretch();
  layout->addLayout(buttons);

  tree_ = new QTreeWidget;
  tree_->setHeaderLabels({tr("Body"), tr("Joint")});
  tree_->header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  form_ = new PropertyForm(doc_, kMergeBodyField);
  QScrollArea* scroll = form_->inScrollArea();
  auto* split = new QSplitter(Qt::Vertical);
  split->addWidget(tree_);
  split->addWidget(scroll);
  split->setSizes({220, 400});
  layout->addWidget(split, 1);

  connect(tree_, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    if (syncing_ || !item) return;
    doc_->selectBody(item->data(0, Qt::UserRole).toInt(), item->data(0, Qt::UserRole + 1).toString().toStdString());
  });
  connect(doc_, &Document::sceneChanged, this, [this] {
    rebuildTree();
    rebuildForm();
  });
  connect(doc_, &Document::selectionChanged, this, [this] {
    rebuildTree();
    rebuildForm();
  });
  rebuildTree();
  rebuildForm();
}

void BuilderPanel::rebuildTree() {
  syncing_ = true;
  tree_->clear();
  const Scene& s = doc_->scene();
  for (size_t c = 0; c < s.characters.size(); ++c) {
    const CharacterSpec& ch = s.characters[c];
    auto* top = new QTreeWidgetItem(tree_, {QString::fromStdString(ch.id), QString::fromStdString(toString(ch.root))});
    top->setData(0, Qt::UserRole, static_cast<int>(c));
    top->setData(0, Qt::UserRole + 1, QString());
    std::map<std::string, QTreeWidgetItem*> items;
    for (const BodySpec& b : ch.bodies) {
      QTreeWidgetItem* parent = b.parent.empty() ? top : items.count(b.parent) ? items[b.parent] : top;
      const QString joint = b.parent.empty() ? tr("root")
                                             : QString::fromStdString(toString(b.joint.kind) + " " + b.joint.id);
      auto* item = new QTreeWidgetItem(parent, {QString::fromStdString(b.id), joint});
      item->setData(0, Qt::UserRole, static_cast<int>(c));
      item->setData(0, Qt::UserRole + 1, QString::fromStdString(b.id));
      items[b.id] = item;
      if (static_cast<int>(c) == doc_->selectedCharacter() && b.id == doc_->selectedBody())
        tree_->setCurrentItem(item);
    }
    if (static_cast<int>(c) == doc_->selectedCharacter() && doc_->selectedBody().empty())
      tree_->setCurrentItem(top);
  }
  tree_->expandAll();
  syncing_ = false;
}

void BuilderPanel::rebuildForm() {
  const int c = doc_->selectedCharacter();
  const std::string body = doc_->selectedBody();
  const Scene& s = doc_->scene();
  const bool exists = c >= 0 && c < static_cast<int>(s.characters.size()) &&
                      (body.empty() || findBody(s, c, body));
  if (c == formCharacter_ && body == formBody_ && exists) {
    form_->refresh();
    return;
  }
  form_->clear();
  formCharacter_ = exists ? c : -2;
  formBody_ = exists ? body : std::string();
  if (!exists) return;
  if (body.empty()) characterForm(c);
  else bodyForm(c, body);
  form_->refresh();
}

void BuilderPanel::characterForm(int c) {
  form_->addText(tr("Character"), [c](const Scene& s) { return s.characters[c].id; },
                 [c](Scene& s, const std::string& v) {
                   if (!validId(v) || s.character(v)) return;
                   for (TermSpec& t : s.terms)
                     if (t.character == s.characters[c].id) t.character = v;
                   for (FormulaObjective& f : s.objective.formulas)
                     if (f.character == s.characters[c].id) f.character = v;
                   s.characters[c].id = v;
                 });
  form_->addChoice(tr("Root"), {tr("Fixed"), tr("Planar floating"), tr("3D floating"), tr("Translation 3D")},
                   [c](const Scene& s) { return static_cast<int>(s.characters[c].root); },
                   [c](Scene& s, int v) { s.characters[c].root = static_cast<RootKind>(v); });
  form_->addBool(tr("Root actuated"), [c](const Scene& s) { return s.characters[c].rootActuated; },
                 [c](Scene& s, bool v) { s.characters[c].rootActuated = v; });
}

void BuilderPanel::bodyForm(int c, const std::string& id) {
  // Getters and setters find the body by id at the time they run.
  auto body = [c, id](const Scene& s) -> const BodySpec& {
    static const BodySpec none;
    const BodySpec* b = findBody(s, c, id);
    return b ? *b : none;
  };
  auto edit = [c, id](Scene& s, const std::function<void(BodySpec&)>& f) {
    if (BodySpec* b = findBody(s, c, id)) f(*b);
  };
  const bool isRoot = body(doc_->scene()).parent.empty();
  form_->addText(tr("Body"), [body](const Scene& s) { return body(s).id; },
                 [this, c, id](Scene& s, const std::string& v) {
                   if (!validId(v) || findBody(s, c, v)) return;
                   renameBody(s, c, id, v);
                   QMetaObject::invokeMethod(this, [this, c, v] { doc_->selectBody(c, v); }, Qt::QueuedConnection);
                 });
  if (!isRoot) {
    form_->addText(tr("Joint name"), [body](const Scene& s) { return body(s).joint.id; },
                   [c, body](Scene& s, const std::string& v) {
                     if (!validId(v)) return;
                     for (const std::string& n : s.characters[c].dofNames())
                       if (n == v) return;
                     renameJoint(s, c, body(s).joint.id, v);
                   });
    form_->addChoice(tr("Joint"), {tr("Revolute"), tr("Prismatic"), tr("Helical"), tr("Fixed")},
                     [body](const Scene& s) { return static_cast<int>(body(s).joint.kind); },
                     [edit](Scene& s, int v) { edit(s, [v](BodySpec& b) { b.joint.kind = static_cast<JointKind>(v); }); });
    form_->addVector(tr("Axis"), [body](const Scene& s) { return body(s).joint.axis; },
                     [edit](Scene& s, const Eigen::Vector3d& v) {
                       if (v.norm() > 1e-9) edit(s, [v](BodySpec& b) { b.joint.axis = v; });
                     }, -1, 1, 0.1, 3);
    form_->addVector(tr("Offset"), [body](const Scene& s) { return body(s).joint.origin; },
                     [edit](Scene& s, const Eigen::Vector3d& v) { edit(s, [v](BodySpec& b) { b.joint.origin = v; }); },
                     -10, 10, 0.01, 3);
    form_->addBool(tr("Actuated"), [body](const Scene& s) { return body(s).joint.actuated; },
                   [edit](Scene& s, bool v) { edit(s, [v](BodySpec& b) { b.joint.actuated = v; }); });
    form_->addBool(tr("Limits"), [body](const Scene& s) { return body(s).joint.limits.has_value(); },
                   [edit](Scene& s, bool v) {
                     edit(s, [v](BodySpec& b) {
                       if (v) b.joint.limits = std::make_pair(-1.5, 1.5);
                       else b.joint.limits.reset();
                     });
                   });
    form_->addDouble(tr("Lower"), [body](const Scene& s) { return body(s).joint.limits ? body(s).joint.limits->first : 0.0; },
                     [edit](Scene& s, double v) { edit(s, [v](BodySpec& b) { if (b.joint.limits) b.joint.limits->first = v; }); },
                     -100, 100, 0.05);
    form_->addDouble(tr("Upper"), [body](const Scene& s) { return body(s).joint.limits ? body(s).joint.limits->second : 0.0; },
                     [edit](Scene& s, double v) { edit(s, [v](BodySpec& b) { if (b.joint.limits) b.joint.limits->second = v; }); },
                     -100, 100, 0.05);
    form_->addDouble(tr("Torque limit"), [body](const Scene& s) { return body(s).joint.torqueLimit.value_or(0.0); },
                     [edit](Scene& s, double v) {
                       edit(s, [v](BodySpec& b) {
                         if (v > 0) b.joint.torqueLimit = v;
                         else b.joint.torqueLimit.reset();
                       });
                     }, 0, 1e5, 1, 2, tr(" (0: none)"));
    form_->addDouble(tr("Speed limit"), [body](const Scene& s) { return body(s).joint.speedLimit.value_or(0.0); },
                     [edit](Scene& s, double v) {
                       edit(s, [v](BodySpec& b) {
                         if (v > 0) b.joint.speedLimit = v;
                         else b.joint.speedLimit.reset();
                       });
                     }, 0, 1e4, 1, 2, tr(" (0: none)"));
  }
  form_->addChoice(tr("Geometry"), {tr("None"), tr("Box"), tr("Sphere"), tr("Capsule"), tr("Cylinder")},
                   [body](const Scene& s) { return static_cast<int>(body(s).geometry.kind); },
                   [edit](Scene& s, int v) {
                     edit(s, [v](BodySpec& b) {
                       b.geometry.kind = static_cast<GeometryKind>(v);
                       if (b.geometry.size.minCoeff() <= 0) b.geometry.size = Eigen::Vector3d(0.05, 0.2, 0.05);
                     });
                   });
  form_->addVector(tr("Size"), [body](const Scene& s) { return body(s).geometry.size; },
                   [edit](Scene& s, const Eigen::Vector3d& v) {
                     // Only the components the shape uses must be positive: a capsule's size is
                     // (radius, length, 0), and requiring all three refused every edit of it.
                     edit(s, [v](BodySpec& b) {
                       const int used = b.geometry.kind == GeometryKind::Box      ? 3
                                        : b.geometry.kind == GeometryKind::Sphere ? 1
                                                                                  : 2;
                       if (v.head(used).minCoeff() > 0) b.geometry.size = v;
                     });
                   }, 0.001, 10, 0.01, 3);
  form_->addChoice(tr("Shape axis"), {"x", "y", "z"}, [body](const Scene& s) { return body(s).geometry.axis; },
                   [edit](Scene& s, int v) { edit(s, [v](BodySpec& b) { b.geometry.axis = v; }); });
  form_->addVector(tr("Shape offset"), [body](const Scene& s) { return body(s).geometry.offset; },
                   [edit](Scene& s, const Eigen::Vector3d& v) { edit(s, [v](BodySpec& b) { b.geometry.offset = v; }); },
                   -10, 10, 0.01, 3);
  form_->addChoice(tr("Mass from"), {tr("Mass"), tr("Density")},
                   [body](const Scene& s) { return body(s).density ? 1 : 0; },
                   [edit](Scene& s, int v) {
                     edit(s, [v](BodySpec& b) {
                       if (v == 1) { b.mass.reset(); b.density = 1000.0; }
                       else { b.density.reset(); b.mass = 1.0; }
                     });
                   });
  form_->addDouble(tr("Mass"), [body](const Scene& s) { return body(s).mass.value_or(0.0); },
                   [edit](Scene& s, double v) { edit(s, [v](BodySpec& b) { if (!b.density && v > 0) b.mass = v; }); },
                   0.001, 1e5, 0.1, 3, " kg");
  form_->addDouble(tr("Density"), [body](const Scene& s) { return body(s).density.value_or(0.0); },
                   [edit](Scene& s, double v) { edit(s, [v](BodySpec& b) { if (b.density && v > 0) b.density = v; }); },
                   0, 1e5, 10, 1, " kg/m³");
  form_->addVector(tr("Colour"), [body](const Scene& s) { return body(s).color; },
                   [edit](Scene& s, const Eigen::Vector3d& v) { edit(s, [v](BodySpec& b) { b.color = v; }); }, 0, 1, 0.05, 2);
}

void BuilderPanel::addCharacter() {
  const std::string id = doc_->uniqueBodyId("character");
  const std::string body = doc_->uniqueBodyId("body");
  const int index = static_cast<int>(doc_->scene().characters.size());
  doc_->edit(tr("Add character"), [&](Scene& s) {
    CharacterSpec c;
    c.id = id;
    c.root = RootKind::Planar;
    BodySpec b;
    b.id = body;
    b.geometry.kind = GeometryKind::Box;
    b.geometry.size = Eigen::Vector3d(0.2, 0.1, 0.1);
    // The box rests on its origin, so a new character stands on the ground instead of sinking
    // half into it.
    b.geometry.offset = Eigen::Vector3d(0, 0.5 * b.geometry.size.y(), 0);
    b.mass = 1.0;
    c.bodies.push_back(b);
    s.characters.push_back(c);
  });
  doc_->selectBody(index, body);
}

void BuilderPanel::addBody() {
  const Scene& s = doc_->scene();
  int c = doc_->selectedCharacter();
  if (c < 0 || c >= static_cast<int>(s.characters.size())) return;
  const CharacterSpec& ch = s.characters[c];
  const std::string parent = doc_->selectedBody().empty() ? ch.bodies.front().id : doc_->selectedBody();
  const std::string id = doc_->uniqueBodyId("body");
  std::string joint = "j1";
  for (int k = 1;; ++k) {
    joint = "j" + std::to_string(k);
    const auto names = ch.dofNames();
    if (std::find(names.begin(), names.end(), joint) == names.end()) break;
  }
  // A new link stands on its parent's tip (the end of its geometry along +y), not in the air
  // above it or inside it.
  const BodySpec* p = findBody(s, c, parent);
  const Eigen::Vector3d tip = p ? geometryTip(p->geometry) : Eigen::Vector3d::Zero();
  doc_->edit(tr("Add body"), [&](Scene& sc) {
    BodySpec b;
    b.id = id;
    b.parent = parent;
    b.joint.id = joint;
    b.joint.kind = JointKind::Revolute;
    b.joint.axis = Eigen::Vector3d::UnitZ();
    b.joint.origin = tip;
    b.geometry.kind = GeometryKind::Capsule;
    b.geometry.size = Eigen::Vector3d(0.025, 0.2, 0);
    b.geometry.axis = 1;
    b.geometry.offset = Eigen::Vector3d(0, 0.1, 0);
    b.mass = 0.5;
    b.color = Eigen::Vector3d(0.55, 0.7, 0.9);
    // Appending keeps the order parent-before-child that the loader and the dynamics need.
    sc.characters[c].bodies.push_back(b);
  });
  doc_->selectBody(c, id);
}

void BuilderPanel::removeBody() {
  const Scene& s = doc_->scene();
  const int c = doc_->selectedCharacter();
  const std::string id = doc_->selectedBody();
  if (c < 0 || c >= static_cast<int>(s.characters.size())) return;
  if (id.empty() || findBody(s, c, id)->parent.empty()) {
    // The root body (or the character itself): remove the whole character and its terms.
    const std::string cid = s.characters[c].id;
    const auto terms = std::count_if(s.terms.begin(), s.terms.end(), [&](const TermSpec& t) { return t.character == cid; });
    emit said(tr("Removed character '%1' with its %2 bodies and %3 terms (Ctrl+Z brings them back)")
                  .arg(QString::fromStdString(cid)).arg(s.characters[c].bodies.size()).arg(terms));
    doc_->edit(tr("Remove character"), [&](Scene& sc) {
      sc.characters.erase(sc.characters.begin() + c);
      std::erase_if(sc.terms, [&](const TermSpec& t) { return t.character == cid; });
      std::erase_if(sc.objective.formulas, [&](const FormulaObjective& f) { return f.character == cid; });
    });
    doc_->selectBody(-1, {});
    return;
  }
  std::set<std::string> doomed{id}, joints;
  for (const BodySpec& b : s.characters[c].bodies)  // parents come before children
    if (doomed.count(b.parent)) doomed.insert(b.id);
  for (const BodySpec& b : s.characters[c].bodies)
    if (doomed.count(b.id)) joints.insert(b.joint.id);
  const std::string cid = s.characters[c].id;
  const std::string parent = findBody(s, c, id)->parent;
  // Removing is undoable, so it does not ask; it says what went with the body, which a subtree
  // hides (the status bar: "Removed 'upper_arm', 1 body under it and 2 terms (Ctrl+Z ...)").
  const auto terms = std::count_if(s.terms.begin(), s.terms.end(),
                                   [&](const TermSpec& t) { return t.character == cid && doomed.count(t.body) > 0; });
  emit said(tr("Removed '%1', %2 bodies under it and %3 terms on them (Ctrl+Z brings them back)")
                .arg(QString::fromStdString(id)).arg(doomed.size() - 1).arg(terms));
  doc_->edit(tr("Remove body"), [&](Scene& sc) {
    std::erase_if(sc.characters[c].bodies, [&](const BodySpec& b) { return doomed.count(b.id) > 0; });
    std::erase_if(sc.terms, [&](const TermSpec& t) { return t.character == cid && doomed.count(t.body) > 0; });
    for (TermSpec& t : sc.terms)
      if (t.character == cid)
        std::erase_if(t.values, [&](const auto& v) { return joints.count(v.first) > 0; });
  });
  doc_->selectBody(c, parent);
}

bool BuilderPanel::applyPreset(const QString& resource) {
  QFile f(resource);
  if (!f.open(QIODevice::ReadOnly)) return false;
  const SceneLoadResult r = parseScene(f.readAll().toStdString(), resource.toStdString());
  if (!r.scene) return false;
  Scene preset = *r.scene;
  preset.solution.reset();
  doc_->edit(tr("Preset %1").arg(QString::fromStdString(preset.name)), [&](Scene& s) { s = preset; });
  doc_->selectBody(0, {});
  doc_->setCurrentTime(doc_->scene().startTime);
  return true;
}

}  // namespace spacetime::ui
