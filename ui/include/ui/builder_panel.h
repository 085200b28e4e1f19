// The actor builder: the characters' body trees, and a form for the selected character (id,
// root type) or body (id, joint type and axis, offset, limits, geometry and size, mass or
// density, actuated or not). Add, remove and rename bodies; start from a preset (particle,
// planar Luxo, 3D Luxo, planar biped, planar quadruped). Every change is an undo command; the
// viewport previews it live.
#pragma once

#include <QTreeWidget>
#include <QWidget>

#include "ui/document.h"
#include "ui/property_form.h"

namespace spacetime::ui {

class BuilderPanel : public QWidget {
  Q_OBJECT
 public:
  explicit BuilderPanel(Document* doc, QWidget* parent = nullptr);

  // The panel's commands (its buttons call these; tests too).
  void addCharacter();
  void addBody();     // a child of the selected body (or of the selected character's root)
  void removeBody();  // the selected body and its subtree, and the terms that refer to them
  bool applyPreset(const QString& resource);  // a scene from resources/scenes/, as one edit
  QTreeWidget* tree() const { return tree_; }
  PropertyForm* form() const { return form_; }

 signals:
  // What a command did beyond the obvious (a removal's subtree and terms), for the status bar.
  void said(const QString& message);

 private:
  void rebuildTree();
  void rebuildForm();
  void characterForm(int c);
  void bodyForm(int c, const std::string& body);

  Document* doc_;
  QTreeWidget* tree_;
  PropertyForm* form_;
  int formCharacter_ = -2;
  std::string formBody_;
  bool syncing_ = false;
};

}  // namespace spacetime::ui
