// The constraints panel: every term of the scene - pins, keyframes, rests, contacts,
// clearances, formula terms - and the joints' limits, with their properties. Add a term at
// the current time (a pin at the selected body's origin, "key the current pose", a rest, a
// contact, a clearance, a formula), enable or disable it, delete it. Every change is an undo
// command.
#pragma once

#include <QTreeWidget>
#include <QWidget>

#include "ui/document.h"
#include "ui/property_form.h"

namespace spacetime::ui {

class ConstraintsPanel : public QWidget {
  Q_OBJECT
 public:
  explicit ConstraintsPanel(Document* doc, QWidget* parent = nullptr);

  // The panel's commands. Each returns the new term's id (empty if nothing was added).
  std::string addPin();         // the selected body's origin where it is at the current time
  // A keyframe of the pose shown now (an unkeyed pose from the pose tool, else the motion's) of
  // the posed or selected character; it replaces a key of that character at this instant, and
  // removes its pins there.
  std::string keyCurrentPose();
  std::string addRest();
  std::string addContact();     // the selected body's base corners on the ground around now
  std::string addClearance();
  std::string addFormula();
  void removeSelected();
  void setEnabled(const std::string& term, bool enabled);
  QTreeWidget* list() const { return list_; }
  PropertyForm* form() const { return form_; }

 signals:
  // What a command did beyond the obvious (a key that replaced another, pins it removed).
  void said(const QString& message);
  // The contact's "Add by clicking the body": the viewport's next click on it adds the point.
  void pickContactPoint(const std::string& term);
  // A joint limit row's "Edit in Builder": its body is selected; the builder should come forward.
  void showBuilder();

 private:
  void rebuildList();
  void rebuildForm();
  void termForm(const std::string& id);
  // A new term of `kind` for character `character`, with a fresh id made from `stem`.
  TermSpec newTerm(const char* stem, TermKind kind, int character) const;
  std::string addTerm(const QString& text, TermSpec term);
  // The selected character (index) and body, or the first ones.
  bool selectedTarget(int* character, std::string* body) const;

  Document* doc_;
  QTreeWidget* list_;
  PropertyForm* form_;
  std::string formTerm_;
  std::pair<size_t, size_t> formRows_;  // the form's term's points and key values when built
  bool syncing_ = false;
};

}  // namespace spacetime::ui
